"""Physical-unit layer: a rectangular cantilever described in SI units, responses vs frequency in Hz.

The dimensionless frequency of the derivations is ``beta`` with ``beta**4 = omega**2 rho S
L**4 / EI``.  For a given cantilever it follows from the first free resonance ``f1``:
``beta = BETA1_FREE * sqrt(f / f1)``, ``BETA1_FREE = 1.8751040687...`` (the first root of
``1 + cos(beta) cosh(beta)``, stored in ``generated/characteristic.py``).  Losses are the
internal friction derived in ``derivations/damping.py`` (a complex modulus ``E (1 + i/Q)``),
applied by its generated substitution (``generated/damping.py``): ``beta**4 -> beta**4 /
(1 + i/Q)`` and ``k -> k (1 + i/Q)``, the model the discrepancy workflow and the maps fit.
Responses are complex.

The per-family methods (``elastic_response``, ``free_response``, ...) are made from the
family registry (``derivations/families.py``, field ``method``): each evaluates the family's
generated transfer function with this cantilever's ``beta``, ``k`` and ``L``.
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass

import numpy as np

from . import transfer
from .generated import damping, families, formulas
from .generated.characteristic import BETA1_FREE

__all__ = ["Cantilever", "BETA1_FREE"]


@dataclass(frozen=True)
class Cantilever:
    """An Euler-Bernoulli cantilever: spring constant (N/m), first free resonance (Hz), length (m).

    Parameters
    ----------
    spring_constant : float
        ``k = 3 EI / L**3`` in N/m.
    resonance_frequency : float
        First free flexural resonance ``f1`` in Hz.
    length : float
        ``L`` in m.
    quality_factor : float
        ``Q`` of the complex modulus ``E (1 + i/Q)`` (``inf``: lossless).

    Examples
    --------
    >>> c = Cantilever.from_geometry(length=225e-6, width=40e-6, thickness=3e-6,
    ...                              youngs_modulus=169e9, density=2330.0)
    >>> round(c.spring_constant, 3), round(c.resonance_frequency / 1e3, 2)   # N/m, kHz
    (4.006, 81.53)
    >>> round(float(c.beta(c.resonance_frequency).real), 10)
    1.8751040687
    """

    spring_constant: float
    resonance_frequency: float
    length: float
    quality_factor: float = math.inf

    def __post_init__(self):
        for name in ("spring_constant", "resonance_frequency", "length", "quality_factor"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0) or math.isnan(value):
                raise ValueError(f"{name} must be a positive number, got {value!r}")

    @classmethod
    def from_geometry(cls, *, length, width, thickness, youngs_modulus, density,
                      quality_factor=math.inf) -> "Cantilever":
        """Rectangular section from SI geometry and material (m, Pa, kg/m**3).

        ``k = E w t**3 / (4 L**3)``; ``f1 = BETA1_FREE**2 / (2 pi L**2) sqrt(E I / (rho S))``
        with ``I = w t**3 / 12`` and ``S = w t``.
        """
        for name, value in [("length", length), ("width", width), ("thickness", thickness),
                            ("youngs_modulus", youngs_modulus), ("density", density)]:
            if not value > 0:
                raise ValueError(f"{name} must be positive, got {value!r}")
        k = formulas.spring_constant_from_geometry(youngs_modulus, width, thickness, length)
        f1 = formulas.free_resonance_from_geometry(youngs_modulus, width, thickness, length,
                                                   density, BETA1_FREE)
        return cls(float(k), float(f1), length, quality_factor)

    def beta(self, frequency) -> np.ndarray:
        """Dimensionless frequency ``beta`` (complex) for frequencies in Hz (> 0).

        ``beta = BETA1_FREE sqrt(f / f1) (1 + i/Q)**(-1/4)``: the internal friction's
        substitution (``generated/damping.py``); the spring constant becomes ``k (1 + i/Q)``.

        >>> c = Cantilever(1.0, 1e5, 1e-4)
        >>> round(float(c.beta(4e5).real), 6)   # beta scales as sqrt(f)
        3.750208
        """
        return self._damped(frequency)[0]

    def _damped(self, frequency):
        """``(beta, k)`` with the internal friction substituted (``derivations/damping.py``)."""
        f = np.asarray(frequency, dtype=float)
        if not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise ValueError("frequency must be positive and finite (Hz)")
        r = f / self.resonance_frequency
        beta_factor, k_factor, _, _ = damping.factors(r, 1.0 / self.quality_factor, 0.0, 0.0)
        return (formulas.beta_from_frequency(f, self.resonance_frequency, BETA1_FREE) * beta_factor,
                self.spring_constant * k_factor)


_EXAMPLE = {"k1": 10.0, "k2": 5.0, "H": 1e-5}
"""Parameter values of the generated methods' doctests (N/m, m)."""
_OWN = ("k", "L")
"""Registry parameters the cantilever supplies itself."""


def _response_method(row):
    """``Cantilever.<row.method>``: the family's transfer at frequencies in Hz, with losses."""
    extra = [p for p in row.parameters if p not in _OWN]
    keyword = inspect.Parameter.KEYWORD_ONLY
    displacement = "deflection" in row.outputs   # then ``output`` chooses slope or displacement
    signature = inspect.Signature(
        [inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD) for p in ("self", "frequency")]
        + [inspect.Parameter(p, keyword) for p in extra]
        + ([inspect.Parameter("output", keyword, default="slope")] if displacement else []),
        return_annotation=f"transfer.{row.result}")

    def response(self, frequency, **kwargs):
        given = signature.bind(self, frequency, **kwargs).arguments
        beta, k = self._damped(frequency)
        values = transfer.check_parameters({p: given[p] for p in extra})
        return transfer.evaluate(row.module, beta, {"k": k, "L": self.length, **values},
                                 given.get("output"))

    call = ", ".join(["[1e3, 1e6]"] + [f"{p}={_EXAMPLE[p]!r}" for p in extra])
    fields = getattr(transfer, row.result)._fields
    response.__name__ = row.method
    response.__qualname__ = f"Cantilever.{row.method}"
    response.__signature__ = signature
    response.__doc__ = f"""Tip {'slope or displacement' if displacement else 'slope'} per unit {', '.join(row.drives)} \
({row.equations}) at ``frequency`` in Hz.

    :func:`pfmdyn.transfer.{row.function}` at this cantilever's ``beta`` and ``k`` with
    its internal friction substituted; parameters ({', '.join(extra) or 'none'}) as there.

    >>> r = Cantilever(1.0, 1e5, 1e-4, quality_factor=100.0).{row.method}({call})
    >>> r._fields, r[0].shape, r[0].dtype
    ({fields!r}, (2,), dtype('complex128'))
    """
    return response


for _row in families.FAMILIES:
    if _row.method:
        setattr(Cantilever, _row.method, _response_method(_row))
