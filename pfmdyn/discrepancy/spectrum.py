"""``pfmdyn discrepancy``: where the paper's model and a measurement disagree, and why.

The loop (issue 6): fit the baseline (:mod:`pfmdyn.discrepancy.model`); locate where the
residual concentrates (band, nearest resonance, signature); fit every candidate effect
of the library on top of the current model; keep the one with the largest BIC gain if
that gain exceeds :data:`BIC_THRESHOLD` (10: "very strong" evidence on the Kass-Raftery
scale), else stop.  Each step is reported.

The misfit ``gap`` is the noise-normalised RMS residual ``sqrt(mean |r|**2) / sigma``,
where ``sigma`` (the RMS of the complex noise) is estimated from the data alone: second
differences along frequency at each bias remove the smooth signal, and their median is
robust to resonance peaks, ``sigma**2 = median |y[i-1] - 2 y[i] + y[i+1]|**2 / (6 ln 2)``.
A model that explains the data reaches ``gap ~ 1``.
"""
from __future__ import annotations

import math

import numpy as np
from tqdm import tqdm

from ..io.tables import SpectrumData
from scipy.optimize import least_squares

from .model import EFFECTS, Fit, Model, project, fit, resonances

__all__ = ["BIC_THRESHOLD", "noise_sigma", "signature", "analyse", "summary"]

BIC_THRESHOLD = 10.0


def noise_sigma(frequency_hz, bias_v, response) -> float:
    """RMS complex noise from second differences along frequency (see module).

    >>> rng = np.random.default_rng(1)
    >>> f = np.repeat(np.arange(2000.0), 2); v = np.tile([0.0, 1.0], 2000)
    >>> y = np.sin(f / 300) + (rng.standard_normal(4000) + 1j * rng.standard_normal(4000)) / 2**0.5
    >>> round(noise_sigma(f, v, y), 1)
    1.0
    """
    d2 = []
    for b in np.unique(bias_v):
        sel = bias_v == b
        order = np.argsort(frequency_hz[sel])
        y = response[sel][order]
        d2.append(y[:-2] - 2 * y[1:-1] + y[2:])
    d2 = np.concatenate(d2)
    return float(math.sqrt(np.median(np.abs(d2) ** 2) / (6 * math.log(2))))


def gap(result: Fit, sigma: float) -> float:
    """Noise-normalised RMS residual of a fit."""
    return float(math.sqrt(np.mean(np.abs(result.residual) ** 2)) / sigma)


def signature(data: SpectrumData, result: Fit, sigma: float) -> dict:
    """Where the residual concentrates: band, share near resonances, and its shape.

    Resonances are the peaks of the fitted |response| summed over biases; the shape is
    ``peak width`` when the residual is even about the nearest resonance, ``peak shift``
    when odd, ``smooth trend`` when most residual lies away from every resonance.
    """
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    energy = np.bincount(inverse, np.abs(result.residual) ** 2) / sigma**2
    size = np.bincount(inverse, np.abs(result.prediction))
    peaks = [i for i in range(1, len(size) - 1) if size[i] >= size[i - 1] and size[i] >= size[i + 1]
             and size[i] > 3 * np.median(size)]
    cum = np.cumsum(energy) / energy.sum()
    band = [float(freq_u[np.searchsorted(cum, 0.1)]), float(freq_u[min(np.searchsorted(cum, 0.9), len(freq_u) - 1)])]
    near = np.zeros(len(freq_u), bool)
    for p in peaks:
        near |= np.abs(freq_u - freq_u[p]) < 0.05 * freq_u[p]
    share = float(energy[near].sum() / energy.sum()) if peaks else 0.0
    shape = "smooth trend"
    if share > 0.5:
        p = max(peaks, key=lambda i: energy[near & (np.abs(freq_u - freq_u[i]) < 0.05 * freq_u[i])].sum())
        win = np.abs(freq_u - freq_u[p]) < 0.05 * freq_u[p]
        offset = freq_u[win] - freq_u[p]
        w = energy[win]
        odd = abs(np.sum(w * np.sign(offset))) / w.sum()
        shape = "peak shift" if odd > 0.3 else "peak width"
    return {"band_hz": band, "resonances_hz": [float(freq_u[p]) for p in peaks],
            "share_near_resonances": share, "signature": shape}


_PROPOSALS = {"peak width": ["damping", "tip_mass", "tip_setback", "tilt", "background"],
              "peak shift": ["tip_mass", "tip_setback", "tilt", "damping", "background"],
              "smooth trend": ["background", "tip_setback", "damping", "tip_mass", "tilt"]}


def data_peaks(data: SpectrumData) -> np.ndarray:
    """Frequencies (Hz) of the peaks of the bias-summed |response| (5x above its median), interpolated.

    >>> from types import SimpleNamespace
    >>> f = np.repeat(np.linspace(1, 10, 91), 2); y = 1 / (f - 4.03) + 0j   # pole off the grid
    >>> data_peaks(SimpleNamespace(frequency_hz=f, bias_v=np.tile([0, 1], 91), response=y)).round(6).tolist()
    [4.03]
    """
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    size = np.bincount(inverse, np.abs(data.response))
    inner = np.arange(1, len(size) - 1)
    keep = (size[inner] >= size[inner - 1]) & (size[inner] > size[inner + 1]) & (size[inner] > 5 * np.median(size))
    out = []
    # Near a pole 1/|y| is a V, a |f - f_p|: its steeper side through the two points away
    # from the pole locates f_p to a fraction of the sampling step.
    for i in inner[keep]:
        g, f = 1 / size[i - 1:i + 2], freq_u[i - 1:i + 2]
        if g[2] < g[0]:     # pole between f[1] and f[2]: line through points 0 and 1
            a = (g[0] - g[1]) / (f[1] - f[0])
            out.append(min(f[1] + g[1] / a, f[2]) if a > 0 else f[1])
        else:               # pole between f[0] and f[1]: line through points 2 and 1
            a = (g[2] - g[1]) / (f[2] - f[1])
            out.append(max(f[1] - g[1] / a, f[0]) if a > 0 else f[1])
    return np.array(out)


def _peak_residual(model, internal, peaks, band, refine):
    """Log-frequency distance of each peak to the nearest resonance, then one entry for the
    resonances in the band that no peak explains (fixed length, for least squares)."""
    roots = resonances(model, internal, True, band[1] * 1.3, refine=refine)
    if not len(roots):
        return np.full(len(peaks) + 1, 10.0)
    inside = roots[(roots > band[0]) & (roots < band[1])]
    lp, lr = np.log(peaks), np.log(roots)
    there = [np.min(np.abs(lr - x)) for x in lp]
    back = math.sqrt(sum(np.min(np.abs(lp - x)) ** 2 for x in np.log(inside)))
    return np.array(there + [back])


def _resonance_starts(model: Model, data, extra: list[np.ndarray], count: int = 3) -> list[np.ndarray]:
    """Starts whose resonances match the data's peaks: grid over the springs times ``extra``
    (values of the remaining parameters), best ``count`` refined by least squares on peaks."""
    m = model.meta
    peaks = data_peaks(data)
    if not len(peaks):
        return []
    n_springs = 1 if model.vertical_only else 2
    a = np.log10(m.k) + np.linspace(-1, 4, 31)
    b = np.log10(m.k * m.L**2 / m.H**2) + np.linspace(-4, 1, 13)
    springs = [np.array([x]) for x in a] if n_springs == 1 else [np.array([x, y]) for x in a for y in b]
    grid = [np.concatenate([sp_, e]) for sp_ in springs for e in extra]
    band = (data.frequency_hz.min(), data.frequency_hz.max())
    ranked = sorted((float(np.sum(_peak_residual(model, g, peaks, band, False) ** 2)), i)
                    for i, g in enumerate(grid))
    params = model.parameters
    bounds = (np.array([p.lower for p in params]), np.array([p.upper for p in params]))
    starts = []
    for _, i in ranked[:count]:
        res = least_squares(lambda x: _peak_residual(model, x, peaks, band, True), grid[i],
                            bounds=bounds, diff_step=1e-6, max_nfev=60)
        starts.append(res.x)
    return starts


def _baseline(model: Model, data, sigma) -> Fit:
    """Global start for the springs, then a local fit.

    Undamped resonances make the misfit landscape in (k1, k2) needle-sharp, so starts come
    from matching the model's resonances to the peaks of the data
    (:func:`_resonance_starts`), and from a heavily damped fit (1/Q = 0.05, continuation).
    """
    m = model.meta
    a = np.log10(m.k) + np.linspace(-1, 4, 21)
    b = np.log10(m.k * m.L**2 / m.H**2) + np.linspace(-4, 1, 8)
    grid = [np.array([x]) for x in a] if model.vertical_only else [np.array([x, y]) for x in a for y in b]
    starts = _resonance_starts(model, data, [np.array([])])
    smooth = Model(m, ("damping",), model.vertical_only)
    quick = sorted((fit_cost(smooth, data, np.append(g, 0.05), sigma), i) for i, g in enumerate(grid))
    damped = fit(smooth, data, [np.append(grid[i], 0.05) for _, i in quick[:2]], sigma)
    starts.append(damped.internal[:-1])
    return fit(model, data, starts, sigma)


def fit_cost(model, data, internal, sigma) -> float:
    """RSS/sigma**2 at fixed nonlinear parameters (for the start grid)."""
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    A = model.design(freq_u, inverse, data.bias_v, np.asarray(internal))
    _, pred = project(A, data.response)
    r = np.abs(data.response - pred) ** 2
    return float(np.sum(r[np.isfinite(r)]) / sigma**2) if np.isfinite(r).any() else math.inf


_NULL = {"Q": 0.0, "mu": 0.0, "gamma": 1.0, "alpha": 0.0}
"""Internal value at which each effect parameter switches its effect off exactly."""


# Effects that move resonances get fresh resonance-matched starts over these values.
_SEEDS = {"mu": (0.05, 0.1, 0.2, 0.4, 0.8), "gamma": (0.97, 0.93, 0.88, 0.8, 0.7),
          "alpha": (-0.3, -0.15, 0.15, 0.3)}


def _with_effect(current: Fit, effect: str, data, sigma) -> Fit:
    model = Model(current.model.meta, current.model.effects + (effect,), current.model.vertical_only)
    new = EFFECTS[effect]
    m = model.meta
    if effect == "lateral_stiffness":
        # k2 moves the contact resonances: resonance-matched starts over (k1, k2).
        k2_grid = np.log10(m.k * m.L**2 / m.H**2) + np.linspace(-4, 1, 11)
        extra = [np.append(current.internal[1:], v) for v in k2_grid]
        return fit(model, data, _resonance_starts(model, data, extra, count=3), sigma)
    # The nested start (effect switched off) guarantees the fit is never worse.
    starts = [np.append(current.internal, [_NULL[p.name] for p in new])]
    if new and new[0].name in _SEEDS:
        springs = 1 if model.vertical_only else 2
        others = current.internal[springs:]
        extra = [np.concatenate([others, [v]]) for v in _SEEDS[new[0].name]]
        starts += _resonance_starts(model, data, extra, count=3)
    else:
        starts += [np.append(current.internal, [p.starts[i % len(p.starts)] for p in new])
                   for i in range(max([len(p.starts) for p in new] or [1]))]
    return fit(model, data, starts, sigma)


def analyse(data: SpectrumData, vertical_only: bool = False, progress: bool = True) -> dict:
    """Run the discrepancy loop on a spectrum; return the JSON-ready report.

    Examples
    --------
    See ``tests/test_discrepancy.py`` (finite-element data with hidden effects).
    """
    sigma = noise_sigma(data.frequency_hz, data.bias_v, data.response)
    current = _baseline(Model(data.metadata, (), vertical_only), data, sigma)
    baseline = current
    steps = []
    library = [e for e in EFFECTS if e != "lateral_stiffness" or vertical_only]
    with tqdm(desc="discrepancy", unit="fit", disable=not progress) as bar:
        while True:
            where = signature(data, current, sigma)
            candidates = [e for e in _PROPOSALS[where["signature"]] + library
                          if e in library and e not in current.model.effects]
            candidates = list(dict.fromkeys(candidates))
            if not candidates:
                break
            trials = {}
            for effect in candidates:
                trials[effect] = _with_effect(current, effect, data, sigma)
                bar.update()
            gains = {e: current.bic - t.bic for e, t in trials.items()}
            best = max(gains, key=gains.get)
            table = [{"effect": e, "bic": trials[e].bic, "delta_bic": gains[e],
                      "gap": gap(trials[e], sigma)} for e in candidates]
            if gains[best] <= BIC_THRESHOLD:
                steps.append({"effect": None, "located": where, "candidates": table,
                              "decision": f"stop: best gain {gains[best]:.1f} <= {BIC_THRESHOLD}"})
                break
            new = trials[best]
            steps.append({"effect": best, "located": where, "candidates": table,
                          "gap_before": gap(current, sigma), "gap_after": gap(new, sigma),
                          "criterion_gain": gains[best], "parameters": new.parameters()})
            current = new
    return {"missing_effects": list(current.model.effects), "gap_before": gap(baseline, sigma),
            "gap_after": gap(current, sigma), "gap_definition": "sqrt(mean |residual|^2) / sigma, "
            "sigma = RMS complex noise from second differences along frequency",
            "noise_sigma": sigma, "criterion": f"BIC = n ln(RSS/n) + k ln n; add if gain > {BIC_THRESHOLD}",
            "steps": steps, "parameters": current.parameters(),
            "baseline_parameters": baseline.parameters(), "_fits": (baseline, current)}


def summary(report: dict) -> str:
    """Readable multi-line summary of a report."""
    lines = [f"baseline gap {report['gap_before']:.2f} -> final gap {report['gap_after']:.2f} "
             f"(1 = noise level); missing effects: {', '.join(report['missing_effects']) or 'none'}"]
    for i, s in enumerate(report["steps"], 1):
        loc = s["located"]
        where = (f"residual in {loc['band_hz'][0] / 1e3:.1f}-{loc['band_hz'][1] / 1e3:.1f} kHz"
                 if "band_hz" in loc else f"largest residual at {loc['worst']}")
        head = f"step {i}: {where}, signature '{loc['signature']}'"
        if s["effect"] is None:
            lines.append(f"{head}; {s['decision']}")
        else:
            lines.append(f"{head}; added {s['effect']} (delta BIC {s['criterion_gain']:.1f}, "
                         f"gap {s['gap_before']:.2f} -> {s['gap_after']:.2f})")
    for name, p in report["parameters"].items():
        if p["value"] is None:      # e.g. springs from a table of free modes only
            lines.append(f"  {name} not determined by these data")
        else:
            lines.append(f"  {name} = {p['value']:.5g} +- {p['stderr']:.2g} {p['unit']}")
    return "\n".join(lines)
