"""Figure of ``pfmdyn calibrate``: the thermal spectrum, the fitted first mode (data = fit + residual: the
oscillator, or the whole lever in a liquid), and the oscillator the instrument's own f and Q imply when the
file holds them."""
from __future__ import annotations

import numpy as np

from ..analysis.calibrate import Calibration
from ..analysis.thermal import oscillator_asd
from ..io.thermal_tune import ThermalTune

__all__ = ["plot_calibration"]


def plot_calibration(tune: ThermalTune, result: Calibration):
    """The spectrum around the first mode with the fit both methods use, on log axes.

    Examples
    --------
    >>> from pfmdyn.analysis.calibrate import calibrate
    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(0, 4e5, 8001)
    >>> tune = ThermalTune("t", f, oscillator_asd(f, 1.8e5, 440.0, 1e-15, 3e-14), "m", {}, {})
    >>> len(plot_calibration(tune, calibrate(tune, medium=Medium.air(), temperature=293.15)).axes)
    2
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result.peak
    if result.lever_fit is not None:        # the whole lever in its fluid, over the band it was fitted on
        lever = result.lever_fit
        f, y, fit = lever.frequency_hz, lever.asd, lever.model_asd
    else:
        half = max(30 * p.frequency_hz / p.quality_factor, 20 * (tune.frequency_hz[1] - tune.frequency_hz[0]))
        window = (tune.frequency_hz > p.frequency_hz - half) & (tune.frequency_hz < p.frequency_hz + half)
        f, y = tune.frequency_hz[window], tune.asd[window]
        fit = oscillator_asd(f, p.frequency_hz, p.quality_factor, p.amplitude, p.white)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    unit = f"{tune.unit}/√Hz"
    top.semilogy(f / 1e3, y, ".", ms=2, color="0.5", label="data")
    top.semilogy(f / 1e3, fit, "C0", label=f"fit ({result.model}): f {p.frequency_hz / 1e3:.2f} kHz, Q {p.quality_factor:.3g}")
    inst = result.instrument
    if "free_resonance" in inst and "free_quality_factor" in inst:
        q = inst["free_quality_factor"]
        # The instrument's oscillator with our peak height and floor: only its f and Q are its own.
        top.semilogy(f / 1e3, oscillator_asd(f, inst["free_resonance"], q, p.amplitude * p.quality_factor / q, p.white),
                     "C3--", label=f"instrument: f {inst['free_resonance'] / 1e3:.2f} kHz, Q {q:.0f}")
    k = [f"{name} k = {e.value:.3g} ± {e.stderr:.2g} N/m" if e.determined else f"{name}: undetermined"
         for name, e in (("thermal", result.thermal), ("Sader", result.sader))]
    top.set_title("; ".join(k), fontsize=9)
    top.set_ylabel(f"ASD ({unit})")
    top.legend(fontsize=8)
    bottom.plot(f / 1e3, y / fit - 1, ".", ms=2, color="0.5")
    bottom.axhline(0, color="C0")
    bottom.set_ylabel("data/fit - 1")
    bottom.set_xlabel("frequency (kHz)")
    fig.tight_layout()
    return fig
