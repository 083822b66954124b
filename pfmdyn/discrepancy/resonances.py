"""The discrepancy loop for a resonances table (free and contact modes), and the paper's data.

The model is the set of undamped characteristic roots (generated
:func:`pfmdyn.generated.tip_setback.characteristic`, found by
:func:`pfmdyn.discrepancy.model.resonances`): free modes with the contact springs off,
contact modes with them on.  Frequencies follow ``f = f1 (beta / beta1)**2`` with ``f1``
the metadata's free resonance and ``beta1`` the first free root of the same model, so the
free mode 1 is reproduced by construction.  Residuals are ``(f_model - f) / sigma`` with
``sigma`` the metadata's ``frequency_uncertainty_hz`` (default 0.1 % of each frequency);
the gap is their RMS.  With ``sigma`` known, the criterion is ``BIC = chi2 + k ln n``.
Damping and background leave undamped resonances unchanged and are not candidates.  A
table of free modes only leaves the springs undetermined: they are not fitted (nor counted
in BIC), and tilt and lateral_stiffness, which act only through them, are not candidates.

:func:`paper_tables` holds the resonances of Section VI.1 of the paper as input files.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares
from tqdm import tqdm

from ..io.tables import Metadata, ResonanceData
from .model import Model, resonances

__all__ = ["CANDIDATES", "SPRINGS", "fit_resonances", "analyse_resonances", "paper_tables"]

CANDIDATES = ("tip_mass", "tip_setback", "tilt")
_SEEDS = {"mu": (0.02, 0.1, 0.3, 1.0), "gamma": (0.97, 0.92, 0.85, 0.75), "alpha": (-0.3, 0.3)}
BIC_THRESHOLD = 10.0


def _sigma(data: ResonanceData) -> np.ndarray:
    u = data.metadata.frequency_uncertainty_hz
    return np.full(len(data.frequency_hz), u) if u else 1e-3 * data.frequency_hz


@lru_cache(maxsize=1024)
def _free_modes(meta: Metadata, mu: float, gamma: float, f_max: float, refine: bool) -> np.ndarray:
    """Free resonances (Hz) below ``f_max``; read-only (cached and shared).

    Free modes ignore the springs and the tilt, so the many fits that vary only those
    (starts, finite-difference Jacobians) reuse one root search.
    """
    roots = resonances(Model(meta, ("tip_mass", "tip_setback")), [0.0, 0.0, mu, gamma], False, f_max, refine)
    roots.flags.writeable = False
    return roots


def _residual(model, internal, data, refine=True) -> np.ndarray:
    out = np.empty(len(data.frequency_hz))
    f_max = 1.5 * data.frequency_hz.max()
    v = model.values(internal)
    for contact in (False, True):
        sel = data.condition == ("contact" if contact else "free")
        if not sel.any():
            continue
        roots = (resonances(model, internal, True, f_max, refine=refine) if contact
                 else _free_modes(model.meta, float(v["mu"]), float(v["gamma"]), f_max, refine))
        modes = data.mode[sel] - 1
        # A missing mode counts as a predicted frequency of f_max: a large, smooth penalty.
        pred = np.where(modes < len(roots), roots[np.minimum(modes, max(len(roots) - 1, 0))]
                        if len(roots) else f_max, f_max)
        out[sel] = pred - data.frequency_hz[sel]
    return out / _sigma(data)


SPRINGS = ("k1", "k2")
"""Contact springs: they act on contact modes only, so free-only tables leave them undetermined."""


def fit_resonances(model: Model, data: ResonanceData) -> dict:
    """Fit the springs and the model's effect parameters to the resonances (multi-start).

    Without contact rows the springs are held fixed (any value: free modes ignore them)
    and reported with ``value`` None and ``determined`` False; they do not count in BIC.
    Returns a dict with ``internal``, ``chi2``, ``bic``, ``gap``, ``parameters``.

    >>> free = paper_tables()["tip 2"]
    >>> result = fit_resonances(Model(free.metadata, ("tip_mass",)), free)
    >>> result["parameters"]["k1"]["determined"], round(result["parameters"]["mu"]["value"], 2)
    (False, 0.05)
    """
    m = model.meta
    params = model.parameters
    n_springs = 1 if model.vertical_only else 2
    contact = bool(np.any(data.condition == "contact"))
    a = np.log10(m.k) + np.linspace(-1, 5, 19)
    b = np.log10(m.k * m.L**2 / m.H**2) + np.linspace(-4, 2, 7)
    if not contact:
        springs = [np.array([a[9], b[3]][:n_springs])]      # held fixed; free modes ignore them
    elif model.vertical_only:
        springs = [np.array([x]) for x in a]
    else:
        springs = [np.array([x, y]) for x in a for y in b]
    # k2 added by lateral_stiffness (vertical-only start) is seeded over the spring grid b.
    seeds = dict(_SEEDS, k2=tuple(b))
    extra = [np.array([])]
    for p in params[n_springs:]:
        extra = [np.append(e, v) for e in extra for v in seeds[p.name]]
    grid = [np.concatenate([s, e]) for s in springs for e in extra]
    # Only the fitted coordinates move; fixed springs stay at their grid value.
    fitted = np.array([contact or p.name not in SPRINGS for p in params])

    def full(x, template):
        out = template.copy()
        out[fitted] = x
        return out

    ranked = sorted((float(np.sum(_residual(model, g, data, refine=False) ** 2)), i)
                    for i, g in enumerate(grid))
    bounds = (np.array([p.lower for p in params])[fitted], np.array([p.upper for p in params])[fitted])
    if fitted.any():
        fits = []
        for _, i in ranked[:3]:
            res = least_squares(lambda x: _residual(model, full(x, grid[i]), data), grid[i][fitted],
                                bounds=bounds, diff_step=1e-7, max_nfev=100)
            fits.append((res.cost, full(res.x, grid[i]), res.jac))
        _, internal, jac = min(fits, key=lambda t: t[0])
    else:
        internal, jac = grid[ranked[0][1]], np.zeros((len(data.frequency_hz), 0))
    residual = _residual(model, internal, data)
    chi2, n, k = float(np.sum(residual**2)), len(data.frequency_hz), int(fitted.sum())
    cov = np.linalg.pinv(jac.T @ jac)
    values, j = {}, 0
    for i, p in enumerate(params):
        if not fitted[i]:
            values[p.name] = {"value": None, "stderr": None, "unit": p.unit, "determined": False}
            continue
        sd = math.sqrt(max(cov[j, j], 0.0))
        values[p.name] = {"value": float(p.value(internal[i])), "stderr": float(p.stderr(internal[i], sd)),
                          "unit": p.unit, "determined": True}
        j += 1
    return {"model": model, "internal": internal, "chi2": chi2, "bic": chi2 + k * math.log(n),
            "gap": float(math.sqrt(np.mean(residual**2))), "residual": residual,
            "parameters": values}


def _locate(data: ResonanceData, result: dict) -> dict:
    r = result["residual"]
    free = data.condition == "free"
    share = float(np.sum(r[free] ** 2) / max(np.sum(r**2), 1e-300))
    worst = int(np.argmax(np.abs(r)))
    return {"worst": f"{data.condition[worst]} mode {data.mode[worst]}",
            "share_free_modes": share,
            "signature": "mode-ratio error" if share > 0.5 else "peak shift"}


def analyse_resonances(data: ResonanceData, vertical_only: bool = False, progress: bool = True) -> dict:
    """Discrepancy loop on a resonances table; same report keys as the spectrum loop.

    Examples
    --------
    See ``tests/test_discrepancy.py`` (FE resonances, and the paper's tips 1 and 2).
    """
    current = fit_resonances(Model(data.metadata, (), vertical_only), data)
    baseline, steps = current, []
    library = list(CANDIDATES) + (["lateral_stiffness"] if vertical_only else [])
    if not np.any(data.condition == "contact"):
        # Tilt and k2 act through the contact springs only: no free-mode signature.
        library = [e for e in library if e not in ("tilt", "lateral_stiffness")]
    bar = tqdm(desc="discrepancy", unit="fit", disable=not progress)
    while True:
        where = _locate(data, current)
        candidates = [e for e in library if e not in current["model"].effects]
        if not candidates:
            break
        trials = {}
        for e in candidates:
            trials[e] = fit_resonances(Model(data.metadata, current["model"].effects + (e,), vertical_only), data)
            bar.update()
        gains = {e: current["bic"] - t["bic"] for e, t in trials.items()}
        best = max(gains, key=gains.get)
        table = [{"effect": e, "bic": trials[e]["bic"], "delta_bic": gains[e], "gap": trials[e]["gap"]}
                 for e in candidates]
        if gains[best] <= BIC_THRESHOLD:
            steps.append({"effect": None, "located": where, "candidates": table,
                          "decision": f"stop: best gain {gains[best]:.1f} <= {BIC_THRESHOLD}"})
            break
        steps.append({"effect": best, "located": where, "candidates": table,
                      "gap_before": current["gap"], "gap_after": trials[best]["gap"],
                      "criterion_gain": gains[best], "parameters": trials[best]["parameters"]})
        current = trials[best]
    bar.close()
    return {"missing_effects": list(current["model"].effects), "gap_before": baseline["gap"],
            "gap_after": current["gap"],
            "gap_definition": "RMS of (f_model - f_measured) / frequency uncertainty",
            "criterion": f"BIC = chi2 + k ln n; add if gain > {BIC_THRESHOLD}", "steps": steps,
            "parameters": current["parameters"], "baseline_parameters": baseline["parameters"],
            "measured_hz": data.frequency_hz.tolist(),
            "baseline_hz": (data.frequency_hz + baseline["residual"] * _sigma(data)).tolist(),
            "predicted_hz": (data.frequency_hz + current["residual"] * _sigma(data)).tolist()}


def paper_tables() -> dict[str, ResonanceData]:
    """Section VI.1 resonances as input tables (tip 1: contact and non-contact; tip 2: free).

    The cantilever is the one specified for tip 2 (w = 24 um, L = 223 um, k = 2.4 N/m;
    the paper's h = 3 um is the thickness).  Tip height is not given: 10 um is assumed.
    Tip 2 has no contact resonances in the text, so only its free modes are tabulated.
    """
    def table(free, contact, sigma):
        modes = list(range(1, len(free) + 1)) + list(range(1, len(contact) + 1))
        conds = ["free"] * len(free) + ["contact"] * len(contact)
        meta = Metadata(2.4, 223e-6, 24e-6, 10e-6, free[0] * 1e3, "Jesse et al. 2006, Section VI.1",
                        sigma)
        return ResonanceData(meta, np.array(modes), np.array(conds), np.array(free + contact) * 1e3)

    return {"tip 1": table([63.2, 368.33, 1031.70], [407.95, 1075.020], 300.0),
            "tip 2": table([54.55, 346.73, 980.55], [], 100.0)}
