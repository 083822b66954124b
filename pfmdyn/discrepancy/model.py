"""Model composition for ``pfmdyn discrepancy``: the paper's baseline plus named effects.

The baseline is Eq. 5 as printed: undamped, tip at the free end, massless tip, springs
``k1``, ``k2`` at tip height ``H``.  The measured response at frequency ``f`` and bias
``V`` is ``G theta``, with ``d1``, ``d2`` bias-independent and ``f0``, ``q0`` both
proportional to ``V - V_surf``.  ``G`` and the drives enter only as products, so the
model is linear in five complex coefficients of the columns::

    T_f, T_d2, T_q, V T_f, V T_q        (T_x = tip slope per unit x; T_d1 = k1 T_f)

which are solved by linear least squares inside the nonlinear fit of the other
parameters (variable projection).  Effects (:data:`EFFECTS`) add nonlinear parameters or
columns; all geometric ones share the generated two-segment solution
(:mod:`pfmdyn.generated.tip_setback`, which is Eq. 5 at ``gamma = 1``, ``mu = 0``, no tilt),
so they compose:

* ``damping``: ``beta**4 -> beta**4 (1 - i/Q)`` (complex modulus), parameter ``Q``;
* ``tip_mass``: point mass ``mu rho S L`` at the tip; the free resonance in the metadata
  is then that of the loaded beam, which sets the frequency scale;
* ``tip_setback``: tip at ``gamma L``, slope read at ``L``;
* ``tilt``: springs rotated by ``alpha`` into beam axes (:mod:`pfmdyn.derivations.tilt`);
* ``lateral_stiffness``: ``k2`` itself, for a vertical-only starting model;
* ``background``: additive cross-talk ``(b0 + b1 V) f / f_max``, two linear columns.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.optimize import brentq, least_squares

from ..generated import tip_setback
from ..generated.characteristic import BETA1_FREE

__all__ = ["Parameter", "EFFECTS", "Model", "Fit", "fit", "free_root", "resonances", "project"]


@dataclass(frozen=True)
class Parameter:
    """A nonlinear parameter: name, unit, internal transform, start values, bounds (internal)."""

    name: str
    unit: str
    log: bool
    starts: tuple[float, ...]
    lower: float
    upper: float
    inverse: bool = False

    def value(self, internal: float) -> float:
        """Physical value of an internal coordinate (log10 for scales, 1/x for ``Q``)."""
        if self.inverse:
            return math.inf if internal <= 0 else 1.0 / internal
        return 10.0**internal if self.log else internal

    def stderr(self, internal: float, sd: float) -> float:
        """Uncertainty of the physical value from that of the internal one (delta method)."""
        if self.inverse:
            return math.inf if internal <= 0 else sd / internal**2
        return self.value(internal) * math.log(10) * sd if self.log else sd


EFFECTS: dict[str, tuple[Parameter, ...]] = {
    # Internally the loss factor 1/Q: 0 (no damping) is inside the bounds, so the
    # undamped model is exactly nested.
    "damping": (Parameter("Q", "", False, (0.03, 0.005, 0.001), 0.0, 0.5, inverse=True),),
    "tip_mass": (Parameter("mu", "", False, (0.05, 0.3), 0.0, 3.0),),
    "tip_setback": (Parameter("gamma", "", False, (0.95, 0.85), 0.5, 1.0),),
    "tilt": (Parameter("alpha", "rad", False, (0.15, -0.15), -0.8, 0.8),),
    "lateral_stiffness": (Parameter("k2", "N/m", True, (), -3.0, 6.0),),
    "background": (),
}
"""Effect name -> its nonlinear parameters (``background`` is linear only)."""

_SPRINGS = (Parameter("k1", "N/m", True, (), -3.0, 6.0),)


@lru_cache(maxsize=4096)
def free_root(k, H, L, mu, gamma) -> float:
    """First free root ``beta`` with a tip mass ``mu`` at ``gamma L`` (1.8751... at ``mu = 0``).

    >>> round(free_root(1.0, 1e-5, 1e-4, 0.0, 1.0), 10)
    1.8751040687
    """
    if mu == 0.0:
        return BETA1_FREE
    char = lambda b: float(tip_setback.characteristic(b, k, 0.0, 0.0, 0.0, H, L, mu, gamma))  # noqa: E731
    return brentq(char, 0.3, BETA1_FREE + 1e-9, xtol=1e-14)


@dataclass(frozen=True)
class Model:
    """Baseline (with or without ``k2``) plus an ordered tuple of named effects."""

    meta: object
    effects: tuple[str, ...] = ()
    vertical_only: bool = False

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """Nonlinear parameters in order: k1, [k2], then each effect's."""
        base = _SPRINGS if self.vertical_only else _SPRINGS + EFFECTS["lateral_stiffness"]
        return base + tuple(p for e in self.effects for p in EFFECTS[e])

    def values(self, internal) -> dict[str, float]:
        """Physical parameter values by name, defaults for absent effects."""
        out = {"k2": 0.0, "Q": math.inf, "mu": 0.0, "gamma": 1.0, "alpha": 0.0}
        out.update({p.name: p.value(v) for p, v in zip(self.parameters, internal)})
        return out

    def beta(self, frequency_hz, v: dict):
        """Complex dimensionless frequency for the metadata's free resonance."""
        m = self.meta
        b1 = free_root(m.k, m.H, m.L, float(v["mu"]), float(v["gamma"]))
        loss = (1 - 1j / v["Q"]) ** 0.25 if math.isfinite(v["Q"]) else 1.0
        return b1 * np.sqrt(np.asarray(frequency_hz) / m.f1) * loss

    def springs(self, v: dict) -> tuple[float, float, float]:
        """``kvv, kll, kvl`` from ``k1, k2, alpha`` (tilt rotation)."""
        c, s = math.cos(v["alpha"]), math.sin(v["alpha"])
        k1, k2 = v["k1"], v["k2"]
        return k1 * c * c + k2 * s * s, k1 * s * s + k2 * c * c, (k1 - k2) * s * c

    def slopes(self, frequency_hz, internal):
        """Tip slope per unit (d1, d2, f0, q0) at each frequency: 4 complex arrays."""
        v = self.values(internal)
        m = self.meta
        with np.errstate(all="ignore"):
            return tip_setback.slope(self.beta(frequency_hz, v), m.k, *self.springs(v), m.H, m.L,
                                     v["mu"], v["gamma"])

    def design(self, freq_unique, inverse, bias, internal) -> np.ndarray:
        """Complex design matrix (rows, columns) of the linear coefficients."""
        _, t_d2, t_f, t_q = (t[inverse] for t in self.slopes(freq_unique, internal))
        cols = [t_f, t_d2, t_q, bias * t_f, bias * t_q]
        if "background" in self.effects:
            ramp = freq_unique[inverse] / freq_unique.max()
            cols += [ramp, bias * ramp]
        return np.stack(cols, axis=1)

    @property
    def n_linear(self) -> int:
        """Number of complex linear coefficients."""
        return 7 if "background" in self.effects else 5


def resonances(model: Model, internal, contact: bool, f_max: float, refine: bool = True) -> np.ndarray:
    """Undamped resonances (Hz) below ``f_max``: real zeros of the generated characteristic.

    Sign changes on a grid in ``beta`` bracket the roots; ``brentq`` refines them (or
    linear interpolation when ``refine`` is False, for coarse start-up searches).  The
    characteristic function is entire (no poles), so every sign change is a root.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(k=1.0, H=1e-5, L=1e-4, f1=1e4)
    >>> (resonances(Model(meta), [-9.0, -9.0], True, 7e4) / 1e4).round(4).tolist()   # 6.267:1
    [1.0, 6.2669]
    """
    v = model.values(internal)
    m = model.meta
    kvv, kll, kvl = model.springs(v) if contact else (0.0, 0.0, 0.0)
    b1 = free_root(m.k, m.H, m.L, float(v["mu"]), float(v["gamma"]))
    args = (m.k, kvv, kll, kvl, m.H, m.L, v["mu"], v["gamma"])
    grid = np.linspace(0.3, b1 * math.sqrt(f_max / m.f1), 300)
    with np.errstate(all="ignore"):
        vals = tip_setback.characteristic(grid, *args)
    idx = np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)
    lo, hi, flo, fhi = grid[idx], grid[idx + 1], vals[idx], vals[idx + 1]
    # Illinois regula falsi on all brackets at once (one vectorised call per iteration): when
    # the same end is replaced twice running, the end kept is given half its value, so both
    # ends move.  Halving only then keeps the superlinear order (halving at every step
    # would fall back to bisection-like linear convergence).
    replaced = np.zeros(len(idx))          # -1: lo replaced last time, +1: hi, 0: neither
    for _ in range(60 if refine and len(idx) else 0):
        mid = hi - fhi * (hi - lo) / (fhi - flo)
        with np.errstate(all="ignore"):
            fmid = tip_setback.characteristic(mid, *args)
        left = np.sign(fmid) == np.sign(flo)
        side = np.where(left, -1.0, 1.0)
        halve = np.where(side == replaced, 0.5, 1.0)
        lo, flo, fhi = np.where(left, mid, lo), np.where(left, fmid, flo * halve), np.where(left, fhi * halve, fhi)
        hi, fhi = np.where(left, hi, mid), np.where(left, fhi, fmid)
        replaced = side
        if np.all((hi - lo) < 1e-12 * hi) or np.all(fmid == 0):
            break
    roots = hi - fhi * (hi - lo) / (fhi - flo) if len(idx) else grid[idx]
    return m.f1 * (roots / b1) ** 2


@dataclass
class Fit:
    """Result of one fit: internal parameters, covariance, residuals and criteria."""

    model: Model
    internal: np.ndarray
    covariance: np.ndarray
    residual: np.ndarray
    prediction: np.ndarray
    rss: float
    n: int
    k: int

    @property
    def bic(self) -> float:
        """Gaussian BIC with the noise variance profiled out: ``n ln(RSS/n) + k ln n``."""
        return self.n * math.log(self.rss / self.n) + self.k * math.log(self.n)

    def parameters(self) -> dict[str, dict]:
        """Physical values with 1-sigma uncertainties (delta method from the internal ones)."""
        out = {}
        for i, p in enumerate(self.model.parameters):
            sd = math.sqrt(max(self.covariance[i, i], 0.0))
            out[p.name] = {"value": p.value(self.internal[i]), "stderr": p.stderr(self.internal[i], sd),
                           "unit": p.unit}
        return out


def project(A: np.ndarray, y: np.ndarray):
    """Linear least squares (column-scaled, reduced QR); returns coefficients and prediction.

    >>> A = np.array([[1.0, 0.0], [0.0, 1e-9], [1.0, 1e-9]])
    >>> c, pred = project(A, np.array([1.0, 2e-9, 1.0 + 2e-9]))
    >>> np.round(c.real, 6).tolist()
    [1.0, 2.0]
    """
    norms = np.linalg.norm(A, axis=0)
    norms[~(np.isfinite(norms) & (norms > 0))] = np.inf
    A = A / norms
    q, r = np.linalg.qr(A)
    # Near-dependent columns (tiny diagonal of R) get no coefficient rather than a huge one.
    diag = np.abs(np.diag(r))
    keep = diag > 1e-10 * diag.max()
    c = np.zeros(A.shape[1], complex)
    rhs = q.conj().T @ y
    c[keep] = np.linalg.solve(r[np.ix_(keep, keep)], rhs[keep])
    return c / norms, A @ c


def fit(model: Model, data, starts: list[np.ndarray], sigma: float) -> Fit:
    """Fit ``model`` to spectrum ``data`` from each start; keep the best (least RSS).

    Nonlinear parameters by :func:`scipy.optimize.least_squares` (trust region, bounds),
    the complex linear coefficients by projection at every evaluation.
    """
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    y, bias = data.response, data.bias_v
    params = model.parameters
    lower = np.array([p.lower for p in params])
    upper = np.array([p.upper for p in params])

    def residual(internal):
        A = model.design(freq_u, inverse, bias, internal)
        _, pred = project(A, y)
        r = (y - pred) / sigma
        r = np.concatenate([r.real, r.imag])
        return np.where(np.isfinite(r), r, 1e6)

    best = None
    for start in starts:
        x0 = np.clip(start, lower, upper)
        res = least_squares(residual, x0, bounds=(lower, upper), x_scale=1.0, method="trf",
                            diff_step=1e-7, max_nfev=200)
        if best is None or res.cost < best.cost:
            best = res
    n = 2 * len(y)
    k = len(params) + 2 * model.n_linear
    rss = 2 * best.cost * sigma**2
    J = best.jac
    dof = max(n - k, 1)
    try:
        cov = np.linalg.pinv(J.T @ J) * (2 * best.cost / dof)
    except np.linalg.LinAlgError:
        cov = np.full((len(params), len(params)), np.nan)
    _, pred = project(model.design(freq_u, inverse, bias, best.x), y)
    return Fit(model, best.x, cov, y - pred, pred, rss, n, k)
