"""The discrepancy loop for a resonances table (free and contact modes), and the paper's data.

The model is the set of undamped characteristic roots (generated
:func:`pfmdyn.generated.tip_setback.characteristic`, found by
:func:`pfmdyn.discrepancy.model.resonances`): free modes with the contact springs off,
contact modes with them on.  Frequencies follow ``f = f1 (beta / beta1)**2`` with ``f1``
the metadata's free resonance and ``beta1`` the first free root of the same model, so the
free mode 1 is reproduced by construction.  Residuals are ``(f_model - f) / sigma`` with
``sigma`` the metadata's ``frequency_uncertainty_hz`` (default 0.1 % of each frequency);
the gap is their RMS.  With ``sigma`` known, the criterion is ``BIC = chi2 + k ln n``; the
loop and its stopping rule are :func:`pfmdyn.discrepancy.select.run`'s.
Damping and background leave undamped resonances unchanged and are not candidates.  A
table of free modes only leaves the springs undetermined: they are not fitted (nor counted
in BIC), and tilt and lateral_stiffness, which act only through them, are not candidates.

:func:`paper_tables` holds the resonances of Section VI.1 of the paper as input files.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from ..generated import paper_inputs
from ..io.tables import Metadata, ResonanceData
from . import select
from .report import report
from .effects import EFFECTS, spring_grid
from .model import FitResult, Model, bounds, covariance, resonance_sensitivity, resonances

__all__ = ["CANDIDATES", "SPRINGS", "fit_resonances", "ResonanceProblem", "analyse_resonances", "paper_tables"]

CANDIDATES = ("tilt", "tip_mass", "tip_setback")
"""Effects a resonance table can show, in the order ties are broken (tilt is always present
in a real contact, set-back changes only contact modes, like tilt)."""
_SEEDS = {"mu": (0.02, 0.1, 0.3, 1.0), "gamma": (0.97, 0.92, 0.85, 0.75), "alpha": (-0.3, 0.3)}


def _sigma(data: ResonanceData) -> np.ndarray:
    u = data.metadata.frequency_uncertainty_hz
    return np.full(len(data.frequency_hz), u) if u else 1e-3 * data.frequency_hz


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


def _residual(model, internal, data, refine=True) -> np.ndarray:
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
        # A missing mode counts as a predicted frequency of f_max: a large, smooth penalty.
        pred = np.where(modes < len(roots), roots[np.minimum(modes, max(len(roots) - 1, 0))]
                        if len(roots) else f_max, f_max)
        out[sel] = pred - data.frequency_hz[sel]
    return out / _sigma(data)


def _jacobian(model, internal, data) -> np.ndarray:
    """``d residual / d internal`` by implicit differentiation of the characteristic."""
    out = np.zeros((len(data.frequency_hz), len(internal)))
    pred = data.frequency_hz + _residual(model, internal, data) * _sigma(data)
    f_max = 1.5 * data.frequency_hz.max()
    for contact in (False, True):
        sel = (data.condition == ("contact" if contact else "free")) & (pred < f_max)
        if sel.any():
            out[sel] = resonance_sensitivity(model, internal, contact, pred[sel])
    return out / _sigma(data)[:, None]


SPRINGS = ("k1", "k2")
"""Contact springs: they act on contact modes only, so free-only tables leave them undetermined."""


def fit_resonances(model: Model, data: ResonanceData) -> FitResult:
    """Fit the springs and the model's effect parameters to the resonances (multi-start).

    Without contact rows the springs are held fixed (any value: free modes ignore them)
    and reported with ``value`` None and ``determined`` False; they do not count in BIC.
    Starts come from grids scaled to the cantilever (:func:`pfmdyn.discrepancy.effects.spring_grid`)
    and are clipped into the bounds, so no lever is outside them.

    >>> free = paper_tables()["tip 2"]
    >>> result = fit_resonances(Model(free.metadata, ("tip_mass",)), free)
    >>> result.parameters()["k1"]["determined"], round(result.parameters()["mu"]["value"], 2)
    (False, 0.05)
    """
    params = model.parameters
    n_springs = 1 if model.vertical_only else 2
    contact = bool(np.any(data.condition == "contact"))
    a, b = spring_grid(model.meta, 14, 5)
    if not contact:
        springs = [np.array([a[7], b[2]][:n_springs])]      # held fixed; free modes ignore them
    elif model.vertical_only:
        springs = [np.array([x]) for x in a]
    else:
        springs = [np.array([x, y]) for x in a for y in b]
    # k2 added by lateral_stiffness (vertical-only start) is seeded over the spring grid b.
    seeds = dict(_SEEDS, k2=tuple(b))
    extra = [np.array([])]
    for p in params[n_springs:]:
        extra = [np.append(e, v) for e in extra for v in seeds[p.name]]
    lower, upper = bounds(model)
    grid = [np.clip(np.concatenate([s_, e]), lower, upper) for s_ in springs for e in extra]
    # Only the fitted coordinates move; fixed springs stay at their grid value.
    fitted = np.array([contact or p.name not in SPRINGS for p in params])

    def full(x, template):
        out = template.copy()
        out[fitted] = x
        return out

    ranked = sorted((float(np.sum(_residual(model, g, data, refine=False) ** 2)), i)
                    for i, g in enumerate(grid))
    if fitted.any():
        fits = []
        for _, i in ranked[:2]:
            res = least_squares(lambda x: _residual(model, full(x, grid[i]), data), grid[i][fitted],
                                jac=lambda x: _jacobian(model, full(x, grid[i]), data)[:, fitted],
                                bounds=(lower[fitted], upper[fitted]), max_nfev=50)
            fits.append((res.cost, full(res.x, grid[i]), res.jac))
        _, internal, jac = min(fits, key=lambda t: t[0])
    else:
        internal, jac = grid[ranked[0][1]], np.zeros((len(data.frequency_hz), 0))
    residual = _residual(model, internal, data)
    cov = covariance(jac)
    sigma = _sigma(data)
    return FitResult(model, internal, cov, residual * sigma, sigma, int(fitted.sum()), sigma_known=True,
                     fitted=fitted)


def _locate(data: ResonanceData, result: FitResult) -> dict:
    r = result.residual / result.sigma
    free = data.condition == "free"
    share = float(np.sum(r[free] ** 2) / max(np.sum(r**2), 1e-300))
    worst = int(np.argmax(np.abs(r)))
    return {"worst": f"{data.condition[worst]} mode {data.mode[worst]}",
            "share_free_modes": share,
            "signature": "mode-ratio error" if share > 0.5 else "peak shift"}


class ResonanceProblem:
    """What :func:`pfmdyn.discrepancy.select.run` needs for a resonance table.

    Damping and background leave undamped resonances unchanged and are not candidates;
    without contact rows neither are tilt and lateral_stiffness (they act through the
    contact springs only).
    """

    def __init__(self, data: ResonanceData, vertical_only: bool = False):
        self.data, self.vertical_only = data, vertical_only
        library = (["lateral_stiffness"] if vertical_only else []) + list(CANDIDATES)
        if not np.any(data.condition == "contact"):
            library = [e for e in library if e not in ("tilt", "lateral_stiffness")]
        self.library = library

    def baseline(self) -> FitResult:
        return fit_resonances(Model(self.data.metadata, (), self.vertical_only), self.data)

    def candidates(self, current: FitResult) -> list[str]:
        # A fit needs fewer parameters than resonances.
        room = len(self.data.frequency_hz) - current.k
        return [e for e in self.library if e not in current.model.effects and room > len(EFFECTS[e].parameters)]

    def trial(self, current: FitResult, name: str) -> FitResult:
        return fit_resonances(current.model.with_effect(name), self.data)

    def without(self, current: FitResult, component: str) -> FitResult:
        effects = list(current.model.effects)
        effects.remove(component)
        return fit_resonances(Model(self.data.metadata, tuple(effects), self.vertical_only), self.data)

    def locate(self, current: FitResult) -> dict:
        return _locate(self.data, current)


def analyse_resonances(data: ResonanceData, vertical_only: bool = False, progress: bool = True,
                       time_budget_s: float | None = None) -> dict:
    """Discrepancy loop on a resonances table; same report keys as the spectrum loop.

    Examples
    --------
    See ``tests/test_discrepancy.py`` (FE resonances, and the paper's tips 1 and 2).
    """
    result = select.run(ResonanceProblem(data, vertical_only), progress, time_budget_s)
    sigma = _sigma(data)
    base, final = result["baseline"], result["final"]
    return report(result, gap_definition="RMS of (f_model - f_measured) / frequency uncertainty",
                  measured_hz=data.frequency_hz.tolist(),
                  baseline_hz=(data.frequency_hz + base.residual).tolist(),
                  predicted_hz=(data.frequency_hz + final.residual).tolist(),
                  frequency_uncertainty_hz=sigma.tolist())


def paper_tables() -> dict[str, ResonanceData]:
    """Section VI.1 resonances as input tables (tip 1: contact and non-contact; tip 2: free).

    The cantilever is the one specified for tip 2 (w = 24 um, L = 223 um, k = 2.4 N/m;
    the paper's h = 3 um is the thickness).  Tip height is not given: 10 um is assumed.
    Tip 2 has no contact resonances in the text, so only its free modes are tabulated.
    """
    g = paper_inputs.TIP2_GEOMETRY

    def table(free, contact, sigma):
        free, contact = list(free), list(contact)
        modes = list(range(1, len(free) + 1)) + list(range(1, len(contact) + 1))
        conds = ["free"] * len(free) + ["contact"] * len(contact)
        meta = Metadata(g["k"], g["L"], g["w"], 10e-6, free[0] * 1e3, "Jesse et al. 2006, Section VI.1",
                        sigma)
        return ResonanceData(meta, np.array(modes), np.array(conds), np.array(free + contact) * 1e3)

    return {"tip 1": table(paper_inputs.TIP1_FREE_KHZ, paper_inputs.TIP1_CONTACT_KHZ, 300.0),
            "tip 2": table(paper_inputs.TIP2_FREE_KHZ, (), 100.0)}
