"""The fit of the model to a resonance table (free and contact modes): residuals, their
Jacobian and the multi-start least-squares fit.

The model is the set of undamped characteristic roots (the composed lever's
:func:`pfmdyn.composed.characteristic`, found by
:func:`pfmdyn.discrepancy.undamped_modes.resonances`): free modes with the contact springs off,
contact modes with them on.  Frequencies follow ``f = f1 (beta / beta1)**2`` with ``f1``
the metadata's free resonance and ``beta1`` the first free root of the same model, so the
free mode 1 is reproduced by construction.  Residuals are ``(f_model - f) / sigma`` with
``sigma`` the metadata's ``frequency_uncertainty_hz`` (default 0.1 % of each frequency);
the gap is their RMS.

Damping.  Each given Q adds a residual ``(1/Q_model - 1/Q) / sigma_Q`` (relative
uncertainty 5 % unless the metadata's ``quality_factor_uncertainty`` says otherwise), with
``Q_model`` from the complex roots of the generated damped characteristic
(:mod:`pfmdyn.discrepancy.quality`).

Springs (:func:`held_springs`).  Contact modes alone determine the springs: none leaves
both undetermined (not fitted, not counted in BIC); one contact mode determines one spring,
so ``k2`` is tied to ``k1`` at the Mindlin ratio and ``k1`` is reported with its
uncertainty (``k2`` as not determined, with the rule as its ``note``; the report's
``spring_rule`` repeats it); two or more fit both.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from ..cantilever import DEFAULT_POISSON, Contact
from ..fitting.projection import jacobian_covariance
from ..constants import Q_RELATIVE_UNCERTAINTY, RESONANCE_RELATIVE_UNCERTAINTY
from ..io.tables import ResonanceData
from .effects import spring_grid
from .quality import loss_and_roots, loss_factors
from .model import FitResult, Model, bounds
from .undamped_modes import resonance_sensitivity, resonances

__all__ = ["K2_OVER_K1", "SPRINGS", "contact_modes", "damping_seeds", "fit_resonances", "frequency_sigma",
           "held_springs", "rows_with_q"]

_SEEDS = {"mu": (0.02, 0.1, 0.3, 1.0), "gamma": (0.97, 0.92, 0.85, 0.75), "alpha": (-0.3, 0.3)}
"""Start values of the tip mass, set-back and tilt in the multi-start grid of :func:`fit_resonances`."""
SPRINGS = ("k1", "k2")
"""Contact springs: they act on contact modes only, so free-only tables leave them undetermined."""
K2_OVER_K1 = Contact().tie()
"""``k2 / k1`` when one contact mode must determine both springs (:meth:`pfmdyn.Contact.tie`: Mindlin at
:data:`pfmdyn.cantilever.DEFAULT_POISSON`)."""


def frequency_sigma(data: ResonanceData) -> np.ndarray:
    """Frequency uncertainty of each row; a damped mode's frequency is defined only to about
    ``f / (4 Q**2)`` (undamped, damped-oscillator ``f0`` or amplitude-peak frequency), added
    in quadrature where Q is given.

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3)
    >>> data = ResonanceData(meta, np.array([1, 1]), np.array(["free", "contact"]), np.array([54.55e3, 260e3]),
    ...                      quality_factor=np.array([150.0, np.nan]))
    >>> frequency_sigma(data).round(3).tolist()
    [54.553, 260.0]
    """
    u = data.metadata.frequency_uncertainty_hz
    sigma = np.full(len(data.frequency_hz), u) if u else RESONANCE_RELATIVE_UNCERTAINTY * data.frequency_hz
    if data.quality_factor is None:
        return sigma
    q = np.where(rows_with_q(data), data.quality_factor, np.inf)
    return np.hypot(sigma, data.frequency_hz / (4 * q**2))


def rows_with_q(data: ResonanceData) -> np.ndarray:
    """Rows whose Q is given (``inf``: a mode measured without damping).

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3)
    >>> data = ResonanceData(meta, np.array([1, 1]), np.array(["free", "contact"]), np.array([54.55e3, 260e3]),
    ...                      quality_factor=np.array([150.0, np.nan]))
    >>> rows_with_q(data).tolist()
    [True, False]
    """
    q = data.quality_factor
    return np.zeros(len(data.frequency_hz), bool) if q is None else ~np.isnan(q) & (q > 0)


def _q_sigma(data: ResonanceData) -> np.ndarray:
    """Uncertainty of each given ``1/Q`` (relative: :data:`pfmdyn.constants.Q_RELATIVE_UNCERTAINTY`;
    at least that of Q = 1e4, so that an undamped mode, Q = inf, has one too)."""
    rel = data.metadata.quality_factor_uncertainty or Q_RELATIVE_UNCERTAINTY
    return rel * np.maximum(1 / data.quality_factor[rows_with_q(data)], 1e-4)


def _scale_rows(data: ResonanceData) -> int:
    """Rows reproduced by construction: free mode 1 sets the frequency scale (module docstring)."""
    return int(np.any((data.condition == "free") & (data.mode == 1)))


def contact_modes(data: ResonanceData) -> int:
    """How many rows are contact modes.

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3)
    >>> contact_modes(ResonanceData(meta, np.array([1, 1]), np.array(["free", "contact"]), np.array([54.55e3, 260e3])))
    1
    """
    return int(np.sum(data.condition == "contact"))



def held_springs(model: Model, data: ResonanceData) -> dict[str, str]:
    """Springs the table cannot determine, held fixed, with the reason (the report's note).

    One contact mode determines one spring: with ``k1`` and ``k2`` in the model, ``k2`` is
    tied to ``k1`` at the Mindlin ratio (:data:`K2_OVER_K1`, a sphere on an isotropic
    sample, Poisson's ratio 0.3) and ``k1`` is fitted.  Holding ``k2`` at 0 instead would
    cap the contact-to-free ratio of mode 1 at the pinned-tip value 4.38, below what
    instruments record (4.7-6.2 in ``realdata/asylum_pfm_images``).  Without contact modes
    neither spring is fitted.

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3,
    ...                 description="free modes", frequency_uncertainty_hz=100.0)
    >>> free = ResonanceData(meta, np.array([1, 2, 3]), np.array(["free"] * 3),
    ...                      np.array([54.55, 346.73, 980.55]) * 1e3)
    >>> held_springs(Model(meta), free)["k2"][:24]
    'no contact mode in the t'
    """
    names = [p.name for p in model.parameters if p.name in SPRINGS]
    n_contact = contact_modes(data)
    if n_contact == 0:
        return {n: "no contact mode in the table: free modes do not depend on the contact springs"
                for n in names}
    if n_contact == 1 and len(names) == 2:
        return {"k2": f"tied to k1 at the Mindlin ratio k2 = {K2_OVER_K1:.3g} k1 (Poisson's ratio "
                      f"{DEFAULT_POISSON:g}): one contact mode determines one spring, k1"}
    return {}



@lru_cache(maxsize=1024)
def _free_modes(meta: Metadata, mu: float, gamma: float, f_max: float, refine: bool) -> np.ndarray:
    """Free resonances (Hz) below ``f_max``; read-only (cached and shared).

    Free modes ignore the springs and the tilt, so the many fits that vary only those
    (starts, finite-difference Jacobians) reuse one root search.
    """
    model = Model(meta, ("tip_mass", "tip_setback"))
    lower, _ = bounds(model)
    roots = resonances(model, [lower[0], lower[1], mu, gamma], False, f_max, refine)
    roots.flags.writeable = False
    return roots


def _predicted(model, internal, data, refine=True) -> np.ndarray:
    """Undamped resonance (Hz) of the model for each row; a missing mode counts as ``f_max``."""
    out = np.empty(len(data.frequency_hz))
    f_max = 1.5 * data.frequency_hz.max()
    v = model.coords(internal)
    for contact in (False, True):
        sel = data.condition == ("contact" if contact else "free")
        if not sel.any():
            continue
        roots = (resonances(model, internal, True, f_max, refine_roots=refine) if contact
                 else _free_modes(model.meta, float(v["mu"]), float(v["gamma"]), f_max, refine))
        modes = data.mode[sel] - 1
        # A missing mode is predicted at f_max: a large, smooth penalty.
        out[sel] = np.where(modes < len(roots), roots[np.minimum(modes, max(len(roots) - 1, 0))]
                            if len(roots) else f_max, f_max)
    return out


def _q_residual(model, internal, data, predicted, roots: dict | None = None) -> np.ndarray:
    """``(1/Q_model - 1/Q_measured) / sigma`` for the rows with a Q (:mod:`.quality`).

    ``roots``: the contact modes' complex roots are stored there (empty dict) or read from
    it as the starting guess (a finite-difference step from that model).
    """
    has_q = rows_with_q(data)
    loss = np.zeros(int(has_q.sum()))
    rows = np.flatnonzero(has_q)
    free = data.condition[rows] == "free"
    if free.any():
        loss[free] = loss_factors(model, internal, False, predicted[rows[free]])
    if (~free).any() and model.damping_mechanisms:
        guess = None if roots is None else roots.get("contact")
        loss[~free], rc = loss_and_roots(model, internal, True, predicted[rows[~free]], guess)
        if roots is not None and guess is None:
            roots["contact"] = rc
    return (loss - 1.0 / data.quality_factor[has_q]) / _q_sigma(data)


def _residual(model, internal, data, refine=True, with_q=True) -> np.ndarray:
    """Frequency residuals (one per row), then the Q residuals (one per row with a Q)."""
    pred = _predicted(model, internal, data, refine)
    r = (pred - data.frequency_hz) / frequency_sigma(data)
    if not with_q or not rows_with_q(data).any():
        return r
    return np.concatenate([r, _q_residual(model, internal, data, pred)])


def _jacobian(model, internal, data) -> np.ndarray:
    """``d residual / d internal``: implicit differentiation of the characteristic for the
    frequencies, forward differences of the damped roots for the Q rows."""
    internal = np.asarray(internal, float)
    n = len(data.frequency_hz)
    pred = _predicted(model, internal, data)
    freq = np.zeros((n, len(internal)))
    f_max = 1.5 * data.frequency_hz.max()
    for contact in (False, True):
        sel = (data.condition == ("contact" if contact else "free")) & (pred < f_max)
        if sel.any():
            freq[sel] = resonance_sensitivity(model, internal, contact, pred[sel])
    freq /= frequency_sigma(data)[:, None]
    if not rows_with_q(data).any():
        return freq
    q = np.zeros((int(rows_with_q(data).sum()), len(internal)))
    roots = {}
    base = _q_residual(model, internal, data, pred, roots)
    for j in np.flatnonzero(np.isfinite(internal)):
        h = 1e-6 * max(1.0, abs(internal[j]))
        xs = internal.copy()
        xs[j] += h
        # The mode moves with the parameter too: first order, from the frequency sensitivity.
        shifted = pred + freq[:, j] * frequency_sigma(data) * h
        q[:, j] = (_q_residual(model, xs, data, shifted, roots) - base) / h
    q[~np.isfinite(q)] = 0.0
    return np.vstack([freq, q])


def damping_seeds(data: ResonanceData) -> dict[str, tuple]:
    """Start values of the damping parameters from the table's Q values.

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3)
    >>> data = ResonanceData(meta, np.array([1, 1]), np.array(["free", "contact"]), np.array([54.55e3, 260e3]),
    ...                      quality_factor=np.array([150.0, np.nan]))
    >>> damping_seeds(data)["inv_q"]
    (0.006666666666666667,)
    """
    has_q = rows_with_q(data)
    if not has_q.any():
        return {"inv_q": (0.01,), "g": (0.02,), "fluid": (0.02,), "x": (0.01,)}
    q, r = data.quality_factor[has_q], data.frequency_hz[has_q] / data.metadata.free_resonance
    contact = data.condition[has_q] == "contact"
    x = float(np.median(1 / (q * r)[contact])) if contact.any() else 0.01
    return {"inv_q": (float(np.clip(np.median(1 / q), 1e-4, 0.4)),),
            "g": (float(np.clip(np.median(r / q), 1e-4, 0.9)),),
            "fluid": (float(np.clip(np.median(np.sqrt(r) / q), 1e-4, 0.9)),),
            "x": tuple(float(np.clip(v, 1e-4, 4.0)) for v in (x, 4 * x))}


def fit_resonances(model: Model, data: ResonanceData, start: np.ndarray | None = None,
                   local: list[np.ndarray] | None = None, vary: tuple[str, ...] | None = None) -> FitResult:
    """Fit the springs and the model's effect parameters to the resonances (multi-start).

    Springs the table cannot determine (:func:`held_springs`) are held fixed and reported
    with ``value`` None, ``determined`` False and a note; they do not count in BIC.
    Starts come from grids scaled to the cantilever (:func:`pfmdyn.discrepancy.effects.spring_grid`),
    damping parameters from the table's Q values, clipped into the bounds, so no lever is
    outside them; ``start`` (e.g. the current fit with a new effect at its null value) is
    one more.  ``local`` replaces the grid by these starts (an effect that leaves the
    resonances alone, such as damping, from the current fit), and ``vary`` (names) limits
    the parameters that move (a quick trial; the others keep their start values, while the
    criterion and the covariance count every fitted parameter).

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3,
    ...                 description="free modes", frequency_uncertainty_hz=100.0)
    >>> free = ResonanceData(meta, np.array([1, 2, 3]), np.array(["free"] * 3),
    ...                      np.array([54.55, 346.73, 980.55]) * 1e3)
    >>> result = fit_resonances(Model(meta, ("tip_mass",)), free)
    >>> result.parameters()["k1"]["determined"], round(result.parameters()["tip_mass_ratio"]["value"], 2)
    (False, 0.05)
    """
    params = model.parameters
    n_springs = 1 if model.vertical_only else 2
    held = held_springs(model, data)
    a, b = spring_grid(model.meta, 14, 5)
    names = [p.name for p in params]
    # One contact mode: k2 follows k1 (held_springs); internal coordinates are log10.
    tie = (names.index("k1"), names.index("k2"), math.log10(K2_OVER_K1)) if "k2" in held and "k1" not in held \
        else None
    if "k1" in held:
        springs = [np.array([a[7], b[2]][:n_springs])]      # held fixed; free modes ignore them
    elif model.vertical_only or tie:
        springs = [np.array([x, x + math.log10(K2_OVER_K1)][:n_springs]) for x in a]
    else:
        springs = [np.array([x, y]) for x in a for y in b]
    # k2 added by lateral_stiffness (vertical-only start) is seeded over the spring grid b.
    seeds = dict(_SEEDS, k2=tuple(b), **damping_seeds(data))
    extra = [np.array([])]
    for p in params[n_springs:]:
        extra = [np.append(e, v) for e in extra for v in seeds[p.name]]
    lower, upper = bounds(model)
    fitted = np.array([p.name not in held for p in params])
    grid = [np.where(fitted, np.clip(np.concatenate([s_, e]), lower, upper), np.concatenate([s_, e]))
            for s_ in springs for e in extra]
    if local:
        grid = [np.where(fitted, np.clip(g, lower, upper), g) for g in local]
    elif start is not None:
        grid.append(np.where(fitted, np.clip(start, lower, upper), grid[0]))

    moving = fitted & np.array([vary is None or p.name in vary for p in params])

    def full(x, template, mask=moving):
        out = template.copy()
        out[mask] = x
        if tie:
            out[tie[1]] = out[tie[0]] + tie[2]
        return out

    def jacobian(x, template, mask=moving):
        jac = _jacobian(model, full(x, template, mask), data)
        if tie:
            jac[:, tie[0]] += jac[:, tie[1]]
        return jac[:, mask]

    grid = [full(g[fitted], g, fitted) for g in grid]
    # Rank by the frequencies (cheap), then the best few by everything (Q rows included).
    ranked = sorted((float(np.sum(_residual(model, g, data, refine=False, with_q=False) ** 2)), i)
                    for i, g in enumerate(grid))
    shortlist = [i for _, i in ranked[:8]] + ([len(grid) - 1] if start is not None else [])
    ranked = sorted((float(np.sum(_residual(model, grid[i], data, refine=False) ** 2)), i)
                    for i in dict.fromkeys(shortlist))
    if moving.any():
        fits = []
        for _, i in ranked[:1 if local else 2]:
            res = least_squares(lambda x: _residual(model, full(x, grid[i]), data), grid[i][moving],
                                jac=lambda x: jacobian(x, grid[i]), bounds=(lower[moving], upper[moving]),
                                max_nfev=50)
            fits.append((res.cost, full(res.x, grid[i]), res.jac))
        _, internal, jac = min(fits, key=lambda t: t[0])
        if not np.array_equal(moving, fitted):
            jac = jacobian(internal[fitted], internal, fitted)
    else:
        internal = grid[ranked[0][1]]
        jac = np.zeros((len(_residual(model, internal, data)), 0))
    residual = _residual(model, internal, data)
    sigma = frequency_sigma(data)
    if rows_with_q(data).any():
        sigma = np.concatenate([sigma, _q_sigma(data)])
    return FitResult(model, internal, jacobian_covariance(jac), residual * sigma, sigma, int(fitted.sum()),
                     sigma_known=True, fitted=fitted, extra={"held": held, "by_construction": _scale_rows(data)})

