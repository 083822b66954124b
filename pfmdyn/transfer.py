"""Transfer coefficients of every boundary-condition family, as NumPy functions.

Each function returns the tip slope ``theta = u0'(L)`` (or the tip twist, for torsion) per
unit drive, as a named tuple of arrays, for dimensionless frequency ``beta`` (``beta**4 =
omega**2 rho S L**4 / EI``; real, or complex with a small imaginary part for losses) and
parameters in SI units: ``k`` cantilever spring constant (N/m), ``k1``/``k2`` vertical and
longitudinal contact stiffness (N/m), ``H`` tip height (m), ``L`` cantilever length (m).
Arrays broadcast against each other.  Signs follow :mod:`pfmdyn.derivations.beam`.

The code is generated (``generated/``, by ``pfmdyn codegen``) from the SymPy derivations,
is accurate to about 1e-14 relative to the largest term for ``beta`` in [1e-6, 1e3], and
never imports SymPy.
"""
from __future__ import annotations

import importlib
from typing import NamedTuple

import numpy as np

from .generated import families

# The registry (derivations/families.py) names every wrapper and its result class.
__all__ = sorted({name for f in families.FAMILIES for name in (f.function, f.result) if name})


class ElasticTransfer(NamedTuple):
    """Tip slope per unit d1 (m), d2 (m), f0 (N), q0 (N/m): the four A_x/N of Eq. 5."""

    vertical: np.ndarray
    longitudinal: np.ndarray
    local_force: np.ndarray
    distributed_load: np.ndarray


class BaseTransfer(NamedTuple):
    """Driven at the base (the clamp moved by ``y0``, a dither piezo), per unit ``y0`` (m): the slope
    at the laser spot (1/m) and the deflection there relative to the base (m/m)."""

    slope: np.ndarray
    deflection: np.ndarray


class ThermalNoise(NamedTuple):
    """One-sided power spectral densities of the lever's thermal motion read at the laser spot: the
    slope (rad**2/Hz) and the deflection (m**2/Hz)."""

    slope: np.ndarray
    deflection: np.ndarray


class FrictionlessTransfer(NamedTuple):
    """Tip slope per unit d1, f0, q0 (Eq. 23)."""

    vertical: np.ndarray
    local_force: np.ndarray
    distributed_load: np.ndarray


class FrictionlessStiffTransfer(NamedTuple):
    """Tip slope per unit d1 and q0 with the tip following the surface (Eq. 24)."""

    vertical: np.ndarray
    distributed_load: np.ndarray


class FreeEndTransfer(NamedTuple):
    """Tip slope per unit f0 and q0 of the free cantilever (Eqs. 21-22)."""

    local_force: np.ndarray
    distributed_load: np.ndarray


class PinnedTransfer(NamedTuple):
    """Tip slope per unit q0 of the supported cantilever (Eqs. 19-20)."""

    distributed_load: np.ndarray


class FrictionTransfer(NamedTuple):
    """Tip slope per unit sliding-friction force f_l (N) (Eqs. 25-26)."""

    friction: np.ndarray


class IndentationTransfer(NamedTuple):
    """Tip slope or displacement per unit d1 and f0 (Eqs. 27-28)."""

    vertical: np.ndarray
    local_force: np.ndarray


class IndentationStiffTransfer(NamedTuple):
    """Tip slope per unit d1 with the tip following the surface (Eq. 29)."""

    vertical: np.ndarray


class TorsionTransfer(NamedTuple):
    """Tip twist per unit drive (d3 in m for elastic contact, f_lat in 1/m for a lateral force)."""

    lateral: np.ndarray


def _frequency(name: str, value) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "iufc":
        raise ValueError(f"{name} must be numeric, got dtype {arr.dtype}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    if np.any(np.real(arr) <= 0):
        raise ValueError(f"{name} must have a positive real part (beta -> 0 is the static limit)")
    return arr


def _parameter(name: str, value, *, zero_ok: bool = False) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real number or array, got dtype {arr.dtype}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    if np.any(arr < 0) or (not zero_ok and np.any(arr == 0)):
        raise ValueError(f"{name} must be {'non-negative' if zero_ok else 'positive'}, got {value!r}")
    return arr.astype(float)


_ZERO_OK = frozenset({"k1", "k2", "k2t"})
"""Parameters that may vanish (contact stiffnesses: no contact); all others must be positive."""
_OUTPUTS = {"slope": "slope", "displacement": "deflection", "twist": "twist"}
"""Public output name -> generated function (tip slope, tip deflection, tip twist)."""


def evaluate(family: str, beta, values: dict, output: str | None = None) -> tuple:
    """Internal path: the family's result at ``beta`` for parameters already checked.

    ``values`` maps each of the registry row's parameters to an array; unlike the public
    wrappers, complex values are accepted (the damped cantilever's ``k (1 + i/Q)``,
    :class:`pfmdyn.Cantilever`).  ``output``: ``"slope"``, ``"displacement"`` or ``"twist"``
    (default: the row's first output).

    >>> r = complex(evaluate("pinned", 1e-6, {"k": 1.0 + 0.01j}).distributed_load * 16 * (1 + 0.01j))
    >>> round(r.real, 12), round(r.imag, 12)   # -1/(16 k), k complex
    (-1.0, 0.0)
    """
    row = families.by_module(family)
    name = row.outputs[0] if output is None else _OUTPUTS.get(output)
    if name not in row.outputs:
        allowed = [o for o, n in _OUTPUTS.items() if n in row.outputs]
        raise ValueError(f"output must be {' or '.join(map(repr, allowed))}, got {output!r}")
    fn = getattr(importlib.import_module(f"{__package__}.generated.{family}"), name)
    return globals()[row.result](*fn(beta, *(values[p] for p in row.parameters)))


def check_parameters(values: dict) -> dict:
    """Each named parameter as a float array, or the wrappers' one-line error (contact
    stiffnesses may vanish, every other parameter must be positive).

    >>> check_parameters({"k1": 0.0, "L": 2e-4})
    {'k1': array(0.), 'L': array(0.0002)}
    """
    return {p: _parameter(p, v, zero_ok=p in _ZERO_OK) for p, v in values.items()}


def _checked(family: str, beta, output: str | None = None, *, frequency: str = "beta", **values) -> tuple:
    """Validate ``beta`` and every parameter, then :func:`evaluate`."""
    return evaluate(family, _frequency(frequency, beta), check_parameters(values), output)


def tip_slope_transfer(beta, *, k, k1, k2, H, L) -> ElasticTransfer:
    """Tip slope per unit drive for elastic tip-surface contact (Eqs. 5-10).

    Parameters
    ----------
    beta : array_like
        Dimensionless frequency, ``Re beta > 0``.
    k, k1, k2 : array_like
        Cantilever spring constant (> 0) and contact stiffnesses (>= 0), N/m.
    H, L : array_like
        Tip height and cantilever length (> 0), m.

    Returns
    -------
    ElasticTransfer
        ``(vertical, longitudinal, local_force, distributed_load)``: theta per unit d1,
        d2, f0, q0.

    References
    ----------
    Jesse, Baddorf, Kalinin (2006), Eq. 5 (theta = (A_v d1 + A_l d2 + A_e f0 + A_q q0)/N).

    Examples
    --------
    >>> t = tip_slope_transfer([1e-6, 3.0], k=1.0, k1=100.0, k2=50.0, H=1e-5, L=1e-4)
    >>> round(float(t.local_force[0] * 100.0 / t.vertical[0]), 12)   # A_v = k1 A_e
    1.0
    """
    return _checked("elastic_contact", beta, k=k, k1=k1, k2=k2, H=H, L=L)


def frictionless_transfer(beta, *, k, k1, L) -> FrictionlessTransfer:
    """Tip slope per unit d1, f0, q0 for frictionless contact, k2 = 0 (Eq. 23).

    Examples
    --------
    >>> t = frictionless_transfer(1e-6, k=1.0, k1=1.0, L=1.0)
    >>> round(float(t.vertical), 9)   # static: 3 k1 / (2 (k + k1) L)
    0.75
    """
    return _checked("frictionless", beta, k=k, k1=k1, L=L)


def frictionless_stiff_transfer(beta, *, k, L) -> FrictionlessStiffTransfer:
    """Tip slope per unit d1 and q0 for frictionless contact with k1 -> oo (Eq. 24).

    Examples
    --------
    >>> round(float(frictionless_stiff_transfer(1e-6, k=1.0, L=2.0).vertical), 9)   # 3/(2L)
    0.75
    """
    return _checked("frictionless_stiff", beta, k=k, L=L)


def free_end_transfer(beta, *, k, L) -> FreeEndTransfer:
    """Tip slope per unit f0 and q0 of the free cantilever (Eqs. 21-22).

    Examples
    --------
    >>> t = free_end_transfer(1e-6, k=2.0, L=1.0)
    >>> round(float(t.local_force), 9), round(float(t.distributed_load), 9)   # 3/(2kL), 1/(2k)
    (0.75, 0.25)
    """
    return _checked("free_end", beta, k=k, L=L)


def pinned_transfer(beta, *, k) -> PinnedTransfer:
    """Tip slope per unit q0 of the supported cantilever (Eqs. 19-20).

    Examples
    --------
    >>> round(float(pinned_transfer(1e-6, k=1.0).distributed_load), 9)   # -1/(16 k)
    -0.0625
    """
    return _checked("pinned", beta, k=k)


def sliding_friction_transfer(beta, *, k, H, L) -> FrictionTransfer:
    """Tip slope per unit friction force f_l (Eqs. 25-26).

    Examples
    --------
    >>> round(float(sliding_friction_transfer(1e-6, k=1.0, H=1.0, L=1.0).friction), 9)   # 3H/(kL**2)
    3.0
    """
    return _checked("sliding_friction", beta, k=k, H=H, L=L)


def indentation_transfer(beta, *, k, k1, L, output: str = "slope") -> IndentationTransfer:
    """Tip slope (Eq. 28) or tip displacement (Eq. 27) per unit d1 and f0, no distributed load.

    Parameters
    ----------
    output : {"slope", "displacement"}
        Beam-deflection (slope) or interferometric (displacement) detection.

    Examples
    --------
    >>> t = indentation_transfer(1e-6, k=1.0, k1=3.0, L=1.0, output="displacement")
    >>> round(float(t.vertical), 9)   # static: k1 / (k + k1)
    0.75
    """
    return _checked("indentation", beta, output, k=k, k1=k1, L=L)


def indentation_stiff_transfer(beta, *, k, L) -> IndentationStiffTransfer:
    """Tip slope per unit d1 when the tip follows the surface, k1 -> oo (Eq. 29).

    Examples
    --------
    >>> round(float(indentation_stiff_transfer(1e-6, k=1.0, L=1.0)[0]), 9)
    1.5
    """
    return _checked("indentation_stiff", beta, k=k, L=L)


def torsion_elastic_transfer(xi_L, *, k2t, H, L) -> TorsionTransfer:
    """Tip twist per unit lateral surface displacement d3, elastic lateral contact (Eq. 33).

    Parameters
    ----------
    xi_L : array_like
        Dimensionless torsional frequency ``xi L`` (``xi**2 = rho J omega**2 / c_T``).
    k2t : array_like
        ``H k2 / c_T`` (1/m**2), >= 0.
    H, L : array_like
        Tip height and length, m.

    Examples
    --------
    >>> round(float(torsion_elastic_transfer(1.0, k2t=1e12, H=1e-5, L=1e-4).lateral) * 1e-5, 2)
    1.0
    """
    return _checked("torsion_elastic", xi_L, frequency="xi_L", k2t=k2t, H=H, L=L)


def torsion_force_transfer(xi_L, *, L) -> TorsionTransfer:
    """Tip twist per unit normalised lateral force f_lat = F_lat H / c_T (Eq. 35): tan(xi L)/xi.

    Examples
    --------
    >>> import math
    >>> math.isclose(float(torsion_force_transfer(0.5, L=2.0).lateral), math.tan(0.5) * 2 / 0.5)
    True
    """
    return _checked("torsion_force", xi_L, frequency="xi_L", L=L)
