"""Physical-unit layer: a rectangular cantilever described in SI units, responses vs frequency in Hz.

The dimensionless frequency of the derivations is ``beta`` with ``beta**4 = omega**2 rho S
L**4 / EI``.  For a given cantilever it follows from the first free resonance ``f1``:
``beta = BETA1_FREE * sqrt(f / f1)``, ``BETA1_FREE = 1.8751040687...`` (the first root of
``1 + cos(beta) cosh(beta)``, stored in ``generated/characteristic.py``).  Losses enter
through a loss factor ``1/Q``: ``beta**4 -> beta**4 (1 - i/Q)``, which gives ``beta`` a
small imaginary part; responses are complex.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import transfer
from .generated import formulas
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
        ``Q`` of the loss factor ``1/Q`` (``inf``: lossless).

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

        >>> c = Cantilever(1.0, 1e5, 1e-4)
        >>> round(float(c.beta(4e5).real), 6)   # beta scales as sqrt(f)
        3.750208
        """
        f = np.asarray(frequency, dtype=float)
        if not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise ValueError("frequency must be positive and finite (Hz)")
        loss = (1 - 1j / self.quality_factor) ** 0.25
        return BETA1_FREE * np.sqrt(f / self.resonance_frequency) * loss

    def elastic_response(self, frequency, *, k1, k2, H) -> transfer.ElasticTransfer:
        """Tip slope per unit d1, d2, f0, q0 (elastic contact, Eq. 5) at ``frequency`` in Hz.

        >>> c = Cantilever(1.0, 1e5, 1e-4)
        >>> r = c.elastic_response([1e3, 1e6], k1=10.0, k2=5.0, H=1e-5)
        >>> r.vertical.dtype, r.vertical.shape
        (dtype('complex128'), (2,))
        """
        return transfer.tip_slope_transfer(self.beta(frequency), k=self.spring_constant,
                                           k1=k1, k2=k2, H=H, L=self.length)

    def free_response(self, frequency) -> transfer.FreeEndTransfer:
        """Tip slope per unit f0 and q0 of the free cantilever (Eqs. 21-22)."""
        return transfer.free_end_transfer(self.beta(frequency), k=self.spring_constant, L=self.length)

    def pinned_response(self, frequency) -> transfer.PinnedTransfer:
        """Tip slope per unit q0 of the supported cantilever (Eqs. 19-20)."""
        return transfer.pinned_transfer(self.beta(frequency), k=self.spring_constant)

    def frictionless_response(self, frequency, *, k1) -> transfer.FrictionlessTransfer:
        """Tip slope per unit d1, f0, q0 for frictionless contact (Eq. 23)."""
        return transfer.frictionless_transfer(self.beta(frequency), k=self.spring_constant,
                                              k1=k1, L=self.length)

    def sliding_friction_response(self, frequency, *, H) -> transfer.FrictionTransfer:
        """Tip slope per unit friction force (Eqs. 25-26)."""
        return transfer.sliding_friction_transfer(self.beta(frequency), k=self.spring_constant,
                                                  H=H, L=self.length)

    def indentation_response(self, frequency, *, k1, output="slope") -> transfer.IndentationTransfer:
        """Tip slope or displacement per unit d1 and f0 (Eqs. 27-28)."""
        return transfer.indentation_transfer(self.beta(frequency), k=self.spring_constant,
                                             k1=k1, L=self.length, output=output)
