"""Contact stiffness from contact resonances of the paper's lever, vectorised (maps).

Model: the elastic-contact family (Eqs. 4a,b and 5 of Jesse, Baddorf, Kalinin 2006; vertical
spring ``k1`` and longitudinal spring ``k2`` at tip height ``H``; massless tip at the free end
of an untilted lever), whose resonances are the zeros ``z > 0`` of the generated
characteristic function ``F(z; a, b)`` with ``a = k1/k`` and ``b = k2 H**2/(k L**2)``.  A
resonance at ``f`` on a lever whose first free resonance is ``f1`` has
``z = z1 sqrt(f/f1)`` (``z1 = 1.8751...``, since ``omega ~ z**2``).  Any other lever (tip set
back, heavy, tilted) and two or more modes are :mod:`pfmdyn.analysis.contact_resonance`'s,
and ``pfmdyn stiffness``'s report is :mod:`pfmdyn.analysis.stiffness_report`.

``F`` is affine in ``a`` (and bilinear in ``a, b``): ``F = A(z) + a B(z)``, with ``A``, ``B``
evaluated from the generated function itself (at ``a = 0`` and ``a = 1``), the paper's lever's
closed form: the one-segment case of the composed characteristic, cos, sin and exp per pixel
instead of a linear system (ten times faster on a map).  The inversion is the whole lever's,
:func:`pfmdyn.analysis.contact_resonance.k1_candidates`.  Hence:

* **one contact mode** (``b`` given, default 0): ``a = -A(z)/B(z)``, in closed form,
  vectorised over any array of frequencies (a map);
* **k2 tied to k1** (``k2 = c k1``, e.g. Mindlin): a quadratic in ``a`` per value
  (:func:`coupled_contact_stiffness`), with the uniqueness of its positive root checked.

Why the answer is unique (the *branch proof*, :func:`branch_proof`): where ``B(z) != 0``
exactly one ``a`` makes ``z`` a resonance (``B(z) = 0`` inside a branch would need
``A(z) = 0`` too, making ``z`` a resonance for every ``a``, which the certified distinct
limits exclude).  Branch ``n`` runs
continuously from its certified soft limit (``a = 0``: roots of ``A``) to its certified
stiff limit (``a -> oo``: roots of ``B``, the pinned end when ``b = 0``); being the graph of
the single-valued inverse ``a(z) = -A/B`` it is injective, hence strictly monotonic, in
``a``.  A measured ratio strictly between the limits of mode ``n`` is therefore reached at
exactly one ``k1 > 0``, and the recovered ``k1`` is confirmed by the ``n``-th certified
root of :func:`pfmdyn.roots.core.family_roots` (for single results).  Ratios outside the
limits are no k1 of this model: the message names the effect that could explain them.

Uncertainties: first-order propagation of the frequency (and spring-constant) standard
uncertainties, with derivatives by complex step of the same generated functions.

Hertz: ``k1 = (6 E*^2 R P)^(1/3)`` (derived in ``derivations/contact_mechanics.py``,
:func:`hertz_stiffness`), so ``E* = sqrt(k1^3/(6 R P))`` (:func:`reduced_modulus`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache

import numpy as np

from ..errors import UserError
from ..generated import formulas
from ..names import checked
from ..generated.characteristic import BETA1_FREE, elastic
from .contact_resonance import k1_candidates

__all__ = ["StiffnessResult", "BranchProof", "k1_limits", "coupled_limits", "z_from_frequency",
           "k1_over_k_from_z", "contact_stiffness", "coupled_contact_stiffness", "out_of_range_message",
           "branch_proof", "mindlin_k2_over_k1", "reduced_modulus", "reduced_modulus_uncertainty"]

_STEP = 1e-30      # complex step: exact first derivatives, no cancellation


@dataclass(frozen=True)
class BranchProof:
    """Certified limits of branch ``mode`` of the k1 sweep at fixed ``k2_ratio``, as z and as f/f1."""

    mode: int
    k2_ratio: float
    soft_z: float
    stiff_z: float
    soft_ratio: float
    stiff_ratio: float
    certified_z: float | None = None

    def text(self) -> str:
        """One paragraph saying why the solution is unique."""
        out = (f"mode {self.mode}: certified limits f/f1 = {self.soft_ratio:.6g} (k1 = 0) and "
               f"{self.stiff_ratio:.6g} (k1 -> inf) at k2 H^2/(k L^2) = {self.k2_ratio:g}; the characteristic "
               "function is affine in k1, so each resonance between the limits belongs to exactly one k1 "
               "and the branch is strictly monotonic in k1: the solution is unique")
        if self.certified_z is not None:
            out += f"; check: certified root {self.mode} at the recovered k1 is z = {self.certified_z:.12g}"
        return out


@dataclass(frozen=True)
class StiffnessResult:
    """k1 (N/m) with its standard uncertainty ``k1_stderr``, k1/k, the z used and the branch limits (arrays)."""

    k1: np.ndarray
    k1_stderr: np.ndarray
    k1_over_k: np.ndarray
    z: np.ndarray
    proof: BranchProof


def _characteristic(z, a, b):
    """``F(z; a, b)`` of the paper's lever (module docstring)."""
    return elastic(z, np, k1_over_k=a, k2_ratio=b)


def _a_of_z(z, b):
    """``a = -A/B`` (:func:`pfmdyn.analysis.contact_resonance.k1_candidates`); at ``z + i h`` its
    imaginary part is ``h da/dz`` (complex step)."""
    return k1_candidates(lambda a: _characteristic(z, a, b), 1.0, 1)[0]


def z_from_frequency(frequency, free_resonance):
    """``z = z1 sqrt(f/f1)``: the dimensionless root of a resonance at ``f`` (Hz).

    >>> round(float(z_from_frequency(4e5, 1e5)), 10)
    3.7502081374
    """
    return formulas.beta_from_frequency(np.asarray(frequency, dtype=float), np.asarray(free_resonance, dtype=float),
                                        BETA1_FREE)


def k1_over_k_from_z(z, k2_ratio: float = 0.0):
    """``k1/k = -A(z)/B(z)`` (module docstring), vectorised; no range check.

    >>> round(float(k1_over_k_from_z(3.0)), 6)
    7.117618
    """
    with np.errstate(under="ignore", divide="ignore", invalid="ignore"):
        return _a_of_z(np.asarray(z, dtype=float), float(k2_ratio))


def _exact(value: float) -> str:
    return str(Fraction(value).limit_denominator(10**15)) if value else "0"


def k1_limits(modes: int, k2_ratio: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Certified soft (k1 = 0) and stiff (k1 -> oo) limits of the first ``modes`` branches, as z.

    >>> soft, stiff = k1_limits(2)
    >>> soft.round(4).tolist(), stiff.round(4).tolist()
    ([1.8751, 4.6941], [3.9266, 7.0686])
    """
    # One cached certification (at least 4 modes) serves every caller at this k2 ratio.
    soft, stiff = _k1_limits(max(int(modes), 4), float(k2_ratio))
    return soft[:modes], stiff[:modes]


def _certified_roots(g, modes: int) -> np.ndarray:
    from ..generated import characteristic
    from ..roots.core import certify

    flint_g = lambda s: g(s, characteristic.FLINT)    # noqa: E731
    balls, _ = certify(flint_g, modes, 17, f_exact=flint_g)
    return np.array([float(b.mid()) for b in balls])


@lru_cache(maxsize=256)
def _k1_limits(modes: int, k2_ratio: float) -> tuple[np.ndarray, np.ndarray]:
    from ..roots.core import characteristic_function

    f_soft = characteristic_function("elastic", k1_over_k=0, k2_ratio=_exact(k2_ratio))
    big = 2**64
    f_big = characteristic_function("elastic", k1_over_k=big, k2_ratio=_exact(k2_ratio))
    # B = (F(big) - F(0))/big exactly (F affine in k1); a huge value keeps ball radii negligible.
    return _certified_roots(f_soft, modes), _certified_roots(lambda z, m: (f_big(z, m) - f_soft(z, m)) / big, modes)


@lru_cache(maxsize=8)
def coupled_limits(modes: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Certified limits when k2 grows with k1: free end (both 0) and the roots of ``S`` (both -> oo).

    ``S``, the coefficient of ``k1 k2``, vanishes where ``cos z cosh z = 1``: tip held in
    height and slope, the clamped-clamped beam.

    >>> [v.round(4).tolist() for v in coupled_limits(2)]
    [[1.8751, 4.6941], [4.73, 7.8532]]
    """
    from ..roots.core import characteristic_function

    # The roots of F(z; big, big) are those of S to ~1/big (far below double precision); the
    # exact difference of four F's would cancel terms of order z**4 inside the balls.
    big = 2**64
    stiff = characteristic_function("elastic", k1_over_k=big, k2_ratio=big)
    soft = characteristic_function("elastic", k1_over_k=0, k2_ratio=0)
    return _certified_roots(soft, modes), _certified_roots(lambda z, m: stiff(z, m) / big**2, modes)


def _ratio(z):
    return formulas.frequency_from_beta(np.asarray(z), 1.0, BETA1_FREE)


def branch_proof(mode: int, k2_ratio: float = 0.0, k1_over_k: float | None = None) -> BranchProof:
    """The limits of branch ``mode``; with ``k1_over_k``, also its certified root there.

    >>> p = branch_proof(1)
    >>> round(p.soft_ratio, 6), round(p.stiff_ratio, 4)
    (1.0, 4.3851)
    """
    soft, stiff = k1_limits(mode + 1, float(k2_ratio))
    root = None
    if k1_over_k is not None:
        from ..roots.core import family_roots
        result = family_roots("elastic", mode, 17, k1_over_k=_exact(k1_over_k), k2_ratio=_exact(k2_ratio))
        root = float(result.roots[mode - 1]) if result.certified else None
    return BranchProof(mode, float(k2_ratio), float(soft[mode - 1]), float(stiff[mode - 1]),
                       float(_ratio(soft[mode - 1])), float(_ratio(stiff[mode - 1])), root)


def out_of_range_message(ratio: float, mode: int, soft_ratio: float, stiff_ratio: float, next_soft_ratio: float,
                         lateral: str) -> str:
    """Why a contact/free ratio of ``mode`` is no k1 of the model, naming the effect that could explain it.

    ``soft_ratio``, ``stiff_ratio``: the branch's limits at k1 = 0 and k1 -> oo; ``lateral``
    says how k2 was held (words).

    >>> out_of_range_message(0.9, 1, 1.0, 4.385, 6.267, "k2 = 0").split(":")[0]
    'contact/free ratio 0.9 of mode 1 is at or below its free limit 1'
    """
    if ratio <= soft_ratio:
        return (f"contact/free ratio {ratio:.6g} of mode {mode} is at or below its free limit {soft_ratio:.6g}: "
                "no contact stiffness lowers a resonance; an added mass at the tip (or liquid loading), a free "
                "resonance measured elsewhere, or a lower mode could explain it")
    beyond = f"between that limit and free mode {mode + 1} ({next_soft_ratio:.6g})" \
        if ratio < next_soft_ratio else "beyond it"
    return (f"contact/free ratio {ratio:.6g} of mode {mode} is above its stiff limit {stiff_ratio:.6g} "
            f"with {lateral} ({beyond}): k1 alone cannot reach it; a lateral contact stiffness (k2, "
            "k2_over_k1 or poisson, or a second contact mode), the tip set back from the end, or the peak "
            "being a higher mode could explain it")


def contact_stiffness(contact_resonance, free_resonance, spring_constant, *, mode: int = 1, k2_ratio: float = 0.0,
                      contact_uncertainty=0.0, free_resonance_uncertainty=0.0, spring_constant_uncertainty=0.0,
                      out_of_range: str = "raise", certify_root: bool = False) -> StiffnessResult:
    """Vertical contact stiffness k1 (N/m) from contact resonances of one mode, vectorised.

    Parameters
    ----------
    contact_resonance : array_like, contact resonance(s) of mode ``mode`` (Hz), any shape (a map)
    free_resonance : first free resonance (Hz), broadcast against ``contact_resonance``
    spring_constant : k (N/m), broadcast
    mode : flexural mode number of the contact resonance (1-based)
    k2_ratio : longitudinal contact stiffness ``k2 H**2/(k L**2)`` held fixed (default 0)
    contact_uncertainty, free_resonance_uncertainty, spring_constant_uncertainty : standard uncertainties
        (Hz, Hz, N/m)
    out_of_range : ``"raise"`` (a :class:`UserError` naming the effect) or ``"nan"`` (NaN there, for maps)
    certify_root : also compute the certified root at the recovered k1 (scalar input only)

    Returns
    -------
    StiffnessResult

    Examples
    --------
    >>> r = contact_stiffness(300e3, 75e3, 2.0, contact_uncertainty=100.0)
    >>> round(float(r.k1), 4), round(float(r.k1_stderr), 4)
    (109.7483, 0.393)
    >>> contact_stiffness([300e3, 350e3], 75e3, 2.0, out_of_range="nan").k1.round(3).tolist()
    [109.748, nan]
    """
    if out_of_range not in ("raise", "nan"):
        raise ValueError("out_of_range must be 'raise' or 'nan'")
    if not (isinstance(mode, (int, np.integer)) and mode >= 1):
        raise UserError(f"mode must be a positive integer, got {mode!r}")
    if not (math.isfinite(k2_ratio) and k2_ratio >= 0):
        raise UserError(f"k2 ratio must be non-negative and finite, got {k2_ratio}")
    fc = np.asarray(contact_resonance, dtype=float)
    f1 = np.asarray(free_resonance, dtype=float)
    k = np.asarray(spring_constant, dtype=float)
    for name, value in (("contact frequency", fc), ("free resonance", f1), ("spring constant", k)):
        bad = ~(np.isfinite(value) & (value > 0))
        if np.any(bad) and (out_of_range == "raise" or name != "contact frequency"):
            raise UserError(f"{name} must be positive and finite (Hz, N/m)")
    proof = branch_proof(mode, k2_ratio)
    next_soft = float(_ratio(k1_limits(mode + 1, float(k2_ratio))[0][mode]))
    with np.errstate(invalid="ignore", divide="ignore", under="ignore"):
        z = z_from_frequency(fc, f1)
        inside = (z > proof.soft_z) & (z < proof.stiff_z)
        if out_of_range == "raise" and not np.all(inside):
            ratio = float(np.ravel(_ratio(z))[np.argmin(np.ravel(inside))])
            raise UserError(out_of_range_message(ratio, mode, proof.soft_ratio, proof.stiff_ratio, next_soft,
                                                  f"k2 H^2/(k L^2) = {k2_ratio:g}"))
        zc = np.where(inside, z, 0.5 * (proof.soft_z + proof.stiff_z))
        a = _a_of_z(zc + 1j * _STEP, float(k2_ratio))
        a, dadz = a.real, a.imag / _STEP
        rel_z = 0.5 * np.hypot(np.asarray(contact_uncertainty) / fc, np.asarray(free_resonance_uncertainty) / f1)
        k1 = a * k
        sigma = np.hypot(k * dadz * zc * rel_z, a * np.asarray(spring_constant_uncertainty))
        k1, sigma, a = (np.where(inside, v, np.nan) for v in (k1, sigma, a))
    if certify_root and np.ndim(k1) == 0 and inside:
        proof = branch_proof(mode, k2_ratio, float(a))
    return StiffnessResult(k1, sigma, a, z, proof)


def mindlin_k2_over_k1(poisson_ratio):
    """k2/k1 of a rigid sphere on an isotropic sample: ``2 (1 - nu)/(2 - nu)``.

    The inverse of derivations/contact_mechanics.py: mindlin_ratio (k1/k2, Hertz normal and
    Mindlin tangential stiffness), generated (generated/formulas.py).

    >>> round(mindlin_k2_over_k1(0.3), 6)
    0.823529
    """
    return formulas.mindlin_k2_over_k1(checked("poisson", poisson_ratio))


def coupled_contact_stiffness(contact_resonance, free_resonance, spring_constant, *, k2_over_k1: float,
                              length: float, tip_height: float, mode: int = 1, contact_uncertainty=0.0,
                              free_resonance_uncertainty=0.0, out_of_range: str = "raise") -> StiffnessResult:
    """k1 when the longitudinal stiffness follows it, ``k2 = c k1`` (e.g. Mindlin), vectorised.

    Then ``b = c (H/L)**2 a`` and ``F = P + a (Q + c' R) + c' a**2 S = 0`` (``c' = c H**2/L**2``):
    a quadratic in ``a`` per pixel.  Between the certified limits (:func:`coupled_limits`)
    a resonance is accepted when the quadratic has exactly one positive root (checked per
    value: the path is not affine, so uniqueness is verified, not assumed); two positive
    roots are reported as ambiguous (NaN or an error).

    >>> r = coupled_contact_stiffness(5.0 * 60e3, 60e3, 1.0, k2_over_k1=0.8235, length=240e-6, tip_height=15e-6)
    >>> round(float(r.k1), 3)
    394.337
    """
    if out_of_range not in ("raise", "nan"):
        raise ValueError("out_of_range must be 'raise' or 'nan'")
    if not all(v > 0 and math.isfinite(v) for v in (k2_over_k1, length, tip_height)):
        raise UserError("k2/k1, lever length and tip height must be positive and finite")
    c = formulas.k2_ratio(k2_over_k1, 1.0, tip_height, length)     # b per unit a = k1/k
    soft, stiff = coupled_limits(max(4, mode + 1))
    fc, f1, k = (np.asarray(v, dtype=float) for v in (contact_resonance, free_resonance, spring_constant))
    with np.errstate(invalid="ignore", divide="ignore", under="ignore"):
        z = z_from_frequency(fc, f1)
        # at z + i h: the roots' imaginary parts are h da/dz (complex step)
        roots = np.stack(k1_candidates(lambda a: _characteristic(z + 1j * _STEP, a, c * a), 1.0, 2))
        positive = np.isfinite(roots) & (roots.real > 0)
        count = positive.sum(axis=0)
        inside = (z > soft[mode - 1]) & (z < stiff[mode - 1]) & (count == 1)
        if out_of_range == "raise" and not np.all(inside):
            bad = np.ravel(~inside).argmax()
            ratio = float(np.ravel(_ratio(z))[bad])
            if np.ravel(count)[bad] == 2:
                raise UserError(f"contact/free ratio {ratio:.6g}: two k1 values give this resonance when k2 = "
                                f"{k2_over_k1:g} k1; a second contact mode decides")
            raise UserError(f"contact/free ratio {ratio:.6g} of mode {mode} is outside ({_ratio(soft[mode - 1]):.6g}, "
                            f"{_ratio(stiff[mode - 1]):.6g}), what k1 with k2 = {k2_over_k1:g} k1 can produce: "
                            "a tip mass, the tip set back from the end, or another mode could explain it")
        root = np.where(positive[0], roots[0], roots[1])
        a, dadz = root.real, root.imag / _STEP
        sigma = k * np.abs(dadz) * z * 0.5 * np.hypot(np.asarray(contact_uncertainty) / fc,
                                                      np.asarray(free_resonance_uncertainty) / f1)
        k1, sigma, a = (np.where(inside, v, np.nan) for v in (a * k, sigma, a))
    proof = BranchProof(mode, float("nan"), float(soft[mode - 1]), float(stiff[mode - 1]),
                        float(_ratio(soft[mode - 1])), float(_ratio(stiff[mode - 1])))
    return StiffnessResult(k1, sigma, a, z, proof)


def reduced_modulus(k1, tip_radius, normal_load):
    """Reduced modulus E* (Pa) of a Hertz contact of stiffness k1 (N/m), tip radius R (m), load P (N).

    Inverts ``k1 = (6 E*^2 R P)^(1/3)`` (derivations/contact_mechanics.py: hertz_stiffness),
    generated (generated/formulas.py).

    >>> round(float(reduced_modulus(100.0, 25e-9, 100e-9)), -6)   # Pa
    8165000000.0
    """
    k1, r, p = (np.asarray(v, dtype=float) for v in (k1, tip_radius, normal_load))
    if np.any(r <= 0) or np.any(p <= 0):
        raise UserError("tip radius and load must be positive (m, N)")
    return formulas.reduced_modulus(k1, r, p)


def reduced_modulus_uncertainty(k1, k1_uncertainty, tip_radius, normal_load):
    """Standard uncertainty of :func:`reduced_modulus` from that of k1 (R and P taken as exact).

    The slope dE*/dk1 is the complex-step derivative of the generated Hertz inversion, so it
    follows whatever that relation is.

    >>> e, de = reduced_modulus(100.0, 25e-9, 100e-9), reduced_modulus_uncertainty(100.0, 1.0, 25e-9, 100e-9)
    >>> round(float(de / e), 6)   # E* ~ k1**(3/2): 1.5 % per 1 % of k1
    0.015
    """
    k1, r, p = (np.asarray(v, dtype=float) for v in (k1, tip_radius, normal_load))
    reduced_modulus(k1, r, p)                       # same input checks
    h = 1e-20 * np.maximum(np.abs(k1), 1.0)
    slope = np.imag(formulas.reduced_modulus(k1 + 1j * h, r, p)) / h
    return np.abs(slope) * np.asarray(k1_uncertainty, dtype=float)
