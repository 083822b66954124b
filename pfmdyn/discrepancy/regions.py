"""Where a fit's misfit sits: the gap of each region of a spectrum beside the overall one.

The gap (:func:`pfmdyn.fitting.noise.gap`) is an RMS over every data value, so a misfit confined to
a resonance's few bins hides under a long floor fitted to the noise (the shared Nanosurf tune: gap
1.35 overall while the residual is about 10 noise levels at the resonance).  The regions
(:func:`regions`) are each resonance's half-power region (its centre +- half its half-power width,
at least :data:`MIN_POINTS` frequencies: the nearest), the rest of the spectrum and, when the data
come in bands (band excitation around each resonance, two windows of one sweep), each band.  A report gives the worst
region and its gap (:func:`worst_region`) and says "fitted to the noise" only when neither the
overall gap nor any region's is above :data:`~pfmdyn.fitting.noise.GAP_LIMIT` (:func:`gap_text`).
"""
from __future__ import annotations

import numpy as np

from ..fitting.noise import GAP_LIMIT, gap

__all__ = ["regions", "lever_resonances", "worst_region", "fitted_to_noise", "gap_text", "MIN_POINTS", "BAND_BREAK"]

MIN_POINTS = 5
"""Frequencies a resonance's region holds at least (a peak narrower than the sampling still has its
nearest bins): fewer values of pure noise would often read far above 1."""

BAND_BREAK = 10.0
"""A step between neighbouring frequencies this many times the median step separates two bands."""


def _kilohertz(low: float, high: float) -> str:
    return f"{low / 1e3:.6g}-{high / 1e3:.6g} kHz"


def regions(frequency_hz, resonances=(), bands: bool = True) -> list[dict]:
    """The regions of a spectrum measured at ``frequency_hz`` (one value per entry, repeats allowed:
    the biases of a spectrum): each resonance ``(centre_hz, half_power_width_hz)`` inside the span and
    the rest away from them, then each band when there are several (``bands`` False: one spectrum whose
    steps widen by design, a long tune's bins averaged away from its peak).  Each is ``{"region",
    "band_hz", "mask"}`` (``mask`` selects the values).

    >>> f = np.r_[np.linspace(90.0, 110.0, 41), np.linspace(290.0, 310.0, 41)]
    >>> for r in regions(f, [(100.0, 2.0)]):
    ...     print(r["region"])
    resonance at 0.1 kHz (half-power: 0.099-0.101 kHz)
    rest of the spectrum (away from the resonances)
    band 0.09-0.11 kHz
    band 0.29-0.31 kHz
    >>> int(regions(f, [(100.0, 2.0)])[0]["mask"].sum())         # 99-101 Hz, at 0.5 Hz steps
    5
    >>> len(regions(f, [(100.0, 2.0)], bands=False))             # the resonance and the rest only
    2
    """
    f = np.asarray(frequency_hz, float)
    unique = np.unique(f)
    out = []
    for centre, width in resonances:
        if not (np.isfinite(centre) and unique[0] <= centre <= unique[-1]):
            continue
        half = 0.5 * width if np.isfinite(width) and width > 0 else 0.0
        nearest = unique[np.argsort(np.abs(unique - centre), kind="stable")[:MIN_POINTS]]
        low, high = min(centre - half, nearest.min()), max(centre + half, nearest.max())
        out.append({"region": f"resonance at {centre / 1e3:.6g} kHz (half-power: {_kilohertz(low, high)})",
                    "band_hz": [float(low), float(high)],
                    "mask": (f >= low) & (f <= high)})
    if out:
        rest = ~np.any([r["mask"] for r in out], axis=0)
        if rest.any():
            out.append({"region": "rest of the spectrum (away from the resonances)",
                        "band_hz": [float(f[rest].min()), float(f[rest].max())], "mask": rest})
    if bands and len(unique) > 2:
        steps = np.diff(unique)
        breaks = np.flatnonzero(steps > BAND_BREAK * np.median(steps))
        if len(breaks):
            for low, high in zip(unique[np.r_[0, breaks + 1]], unique[np.r_[breaks, len(unique) - 1]]):
                out.append({"region": f"band {_kilohertz(low, high)}", "band_hz": [float(low), float(high)],
                            "mask": (f >= low) & (f <= high)})
    return out


def lever_resonances(lever, modes: int = 3) -> list[tuple[float, float]]:
    """``(centre_hz, half_power_width_hz)`` of a free lever's first ``modes`` in its medium (the damped
    resonance and ``f / Q``, :func:`pfmdyn.analysis.resonances.resonances`), those that have one.

    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.medium import Medium
    >>> lever = Cantilever(27.0, 1.8e5, 225e-6, width=40e-6, medium=Medium.air(313.15))
    >>> [(round(f, -2), round(w)) for f, w in lever_resonances(lever, 1)]
    [(180000.0, 380)]
    """
    from ..analysis.resonances import resonances

    free = resonances(lever, None, modes=modes).free
    return [(float(f), float(f / q)) for f, q in zip(free.damped_hz, free.q) if np.isfinite(f) and q > 0]


def worst_region(frequency_hz, energy, resonances=(), bands: bool = True) -> dict | None:
    """The region (:func:`regions`, ``bands`` as there) of the largest gap, ``energy`` the squared noise-normalised residual
    of each value (``|r / sigma|**2``): ``{"region", "band_hz", "values", "gap"}``; None when the
    spectrum has no region.

    >>> f = np.linspace(50.0, 150.0, 1001)
    >>> energy = np.where(abs(f - 100.0) < 1.0, 100.0, 1.0)        # 10 noise levels at the peak only
    >>> out = worst_region(f, energy, [(100.0, 2.0)])
    >>> out["region"], round(out["gap"], 2), round(float(gap(energy.sum(), energy.size)), 2)
    ('resonance at 0.1 kHz (half-power: 0.099-0.101 kHz)', 9.52, 1.7)
    """
    energy = np.asarray(energy, float)
    found = [dict(band_hz=r["band_hz"], region=r["region"], values=int(r["mask"].sum()),
                  gap=float(gap(np.sum(energy[r["mask"]]), r["mask"].sum())))
             for r in regions(frequency_hz, resonances, bands) if r["mask"].any()]
    return max(found, key=lambda r: r["gap"]) if found else None


def fitted_to_noise(overall_gap: float, worst: dict | None) -> bool:
    """Whether a fit explains its data to the noise: the overall gap and the worst region's (if any)
    within :data:`~pfmdyn.fitting.noise.GAP_LIMIT`.

    >>> fitted_to_noise(1.35, {"gap": 9.6}), fitted_to_noise(1.1, {"gap": 1.4}), fitted_to_noise(1.1, None)
    (False, True, True)
    """
    return overall_gap <= GAP_LIMIT and (worst is None or worst["gap"] <= GAP_LIMIT)


def gap_text(overall_gap: float, worst: dict | None) -> str:
    """The gap as a report states it: overall, and the worst region's when a region was measured;
    "fitted to the noise" only when :func:`fitted_to_noise`.

    >>> print(gap_text(1.35, {"region": "resonance at 179.7 kHz (half-power: 179.5-179.9 kHz)", "gap": 9.6}))
    gap 1.35 overall, 9.6 over the resonance at 179.7 kHz (half-power: 179.5-179.9 kHz): not fitted to the noise there
    >>> gap_text(1.02, {"region": "band 1-2 kHz", "gap": 1.3})
    'gap 1.02, at most 1.3 in a region (1: fitted to the noise)'
    """
    if worst is None:
        return f"gap {overall_gap:.3g}" + (" (1: fitted to the noise)" if overall_gap <= GAP_LIMIT else "")
    if fitted_to_noise(overall_gap, worst):
        return f"gap {overall_gap:.3g}, at most {worst['gap']:.3g} in a region (1: fitted to the noise)"
    text = f"gap {overall_gap:.3g} overall, {worst['gap']:.3g} over the {worst['region']}"
    return text + (": not fitted to the noise there" if overall_gap <= GAP_LIMIT else "")
