"""The discrepancy loop for a resonances table (free and contact modes), and the paper's data.

The model is the set of undamped characteristic roots (generated
:func:`pfmdyn.generated.tip_setback.characteristic`, found by
:func:`pfmdyn.discrepancy_model.resonances`): free modes with the contact springs off,
contact modes with them on.  Frequencies follow ``f = f1 (beta / beta1)**2`` with ``f1``
the metadata's free resonance and ``beta1`` the first free root of the same model, so the
free mode 1 is reproduced by construction.  Residuals are ``(f_model - f) / sigma`` with
``sigma`` the metadata's ``frequency_uncertainty_hz`` (default 0.1 % of each frequency);
the gap is their RMS.  With ``sigma`` known, the criterion is ``BIC = chi2 + k ln n``.
Damping and background leave undamped resonances unchanged and are not candidates.

:func:`paper_tables` holds the resonances of Section VI.1 of the paper as input files.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from tqdm import tqdm

from .discrepancy_io import Metadata, ResonanceData
from .discrepancy_model import Model, resonances

__all__ = ["CANDIDATES", "fit_resonances", "analyse_resonances", "paper_tables"]

CANDIDATES = ("tip_mass", "tip_setback", "tilt")
_SEEDS = {"mu": (0.02, 0.1, 0.3, 1.0), "gamma": (0.97, 0.92, 0.85, 0.75), "alpha": (-0.3, 0.3)}
BIC_THRESHOLD = 10.0


def _sigma(data: ResonanceData) -> np.ndarray:
    u = data.metadata.frequency_uncertainty_hz
    return np.full(len(data.frequency_hz), u) if u else 1e-3 * data.frequency_hz


def _residual(model, internal, data, refine=True) -> np.ndarray:
    out = np.empty(len(data.frequency_hz))
    f_max = 1.5 * data.frequency_hz.max()
    for contact in (False, True):
        sel = data.condition == ("contact" if contact else "free")
        if not sel.any():
            continue
        roots = resonances(model, internal, contact, f_max, refine=refine)
        modes = data.mode[sel] - 1
        # A missing mode counts as a predicted frequency of f_max: a large, smooth penalty.
        pred = np.where(modes < len(roots), roots[np.minimum(modes, max(len(roots) - 1, 0))]
                        if len(roots) else f_max, f_max)
        out[sel] = pred - data.frequency_hz[sel]
    return out / _sigma(data)


def fit_resonances(model: Model, data: ResonanceData) -> dict:
    """Fit the springs and the model's effect parameters to the resonances (multi-start).

    Returns a dict with ``internal``, ``chi2``, ``bic``, ``gap``, ``parameters``.
    """
    m = model.meta
    a = np.log10(m.k) + np.linspace(-1, 5, 19)
    b = np.log10(m.k * m.L**2 / m.H**2) + np.linspace(-4, 2, 7)
    springs = [np.array([x]) for x in a] if model.vertical_only else [np.array([x, y]) for x in a for y in b]
    extra = [np.array([])]
    for p in model.parameters[len(springs[0]):]:
        extra = [np.append(e, v) for e in extra for v in _SEEDS[p.name]]
    grid = [np.concatenate([s, e]) for s in springs for e in extra]
    ranked = sorted((float(np.sum(_residual(model, g, data, refine=False) ** 2)), i)
                    for i, g in enumerate(grid))
    params = model.parameters
    bounds = (np.array([p.lower for p in params]), np.array([p.upper for p in params]))
    best = min((least_squares(lambda x: _residual(model, x, data), grid[i], bounds=bounds,
                              diff_step=1e-7, max_nfev=100) for _, i in ranked[:3]),
               key=lambda r: r.cost)
    chi2, n, k = 2 * best.cost, len(data.frequency_hz), len(params)
    cov = np.linalg.pinv(best.jac.T @ best.jac)
    values = {}
    for i, p in enumerate(params):
        sd = math.sqrt(max(cov[i, i], 0.0))
        values[p.name] = {"value": p.value(best.x[i]), "stderr": p.stderr(best.x[i], sd), "unit": p.unit}
    residual = _residual(model, best.x, data)
    return {"model": model, "internal": best.x, "chi2": chi2, "bic": chi2 + k * math.log(n),
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
