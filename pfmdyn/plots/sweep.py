"""Figures of ``pfmdyn discrepancy`` on a drive sweep: the measured amplitude (and phase) with the
fitted base-driven lever, and the residual in noise levels; with a reference sweep, the reference
sweep and its fit beside the explained sweep and the lever that explains it.  On a thermal tune:
the measured spectral density with the thermally driven lever.

Built on :class:`matplotlib.figure.Figure` (no pyplot); the caller saves it.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_sweep", "plot_thermal"]


def plot_sweep(fit, table, comparison=None, after=None) -> Figure:
    """``fit`` (:class:`pfmdyn.discrepancy.sweep.SweepFit`) on ``table``; with ``comparison`` (its
    :class:`~pfmdyn.discrepancy.reference.SweepComparison`) and the ``after`` table, both sweeps.

    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.discrepancy.sweep import fit_sweep
    >>> from pfmdyn.io.sweeps import SweepTable
    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(4e4, 1e5, 80)
    >>> y = (0.3 - 2j) * Cantilever(8.0, 7.2e4, 1e-4, width=4e-5, medium=Medium.water()).base_driven(f).slope + 0.5
    >>> table = SweepTable("s.txt", f, np.abs(y), "V", np.degrees(np.angle(y)), {}, None, "synthetic")
    >>> fig = plot_sweep(fit_sweep(table, 8.0, 1e-4, Medium.water(), width=4e-5), table)
    >>> [a.get_ylabel() for a in fig.axes]
    ['amplitude (V)', 'phase (deg)', 'residual / noise']
    """
    shown = [(table, fit.data(table), fit.model(table.frequency_hz), "reference" if comparison else "sweep")]
    if comparison is not None:
        d = comparison.to_dict()
        gain = complex(*d["gain_after"])
        background = tuple(complex(*b) for b in d["background_after"])
        shown.append((after, fit.data(after), fit.model(after.frequency_hz, comparison.lever, gain, background),
                      f"after: {d['effect']}"))
    panels = 2 if fit.amplitude_only else 3
    fig = Figure(figsize=(7.5, 2.4 * panels + 1))
    axes = fig.subplots(panels, 1, sharex=True, gridspec_kw={"height_ratios": [3] + [2] * (panels - 1)})
    for i, (tab, y, model, label) in enumerate(shown):
        f = tab.frequency_hz / 1e3
        colour = f"C{i}"
        axes[0].plot(f, np.abs(y), ".", ms=3, color=colour, alpha=0.6, label=f"{label}: data")
        axes[0].plot(f, np.abs(model), "-", color=colour, lw=1.2, label=f"{label}: fit")
        if not fit.amplitude_only:
            axes[1].plot(f, np.degrees(np.angle(y)), ".", ms=3, color=colour, alpha=0.6)
            axes[1].plot(f, np.degrees(np.angle(model)), "-", color=colour, lw=1.2)
        residual = (y - model) / fit.sigma
        axes[-1].plot(f, np.abs(residual), "-", color=colour, lw=0.8)
    unit = table.unit or "1"
    axes[0].set_ylabel(f"amplitude ({unit})")
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"{table.path}: {fit['medium']}, resonance {fit.lever.free_resonance:.6g} Hz", fontsize=9)
    if not fit.amplitude_only:
        axes[1].set_ylabel("phase (deg)")
    axes[-1].axhline(1.0, color="0.6", lw=0.8, ls="--")
    axes[-1].set_ylabel("residual / noise")
    axes[-1].set_xlabel("frequency (kHz)")
    fig.tight_layout()
    return fig


def plot_thermal(fit) -> Figure:
    """``fit`` (:class:`pfmdyn.discrepancy.thermal.ThermalFit`): the band fitted, on a log axis, and the
    residual of ``log ASD`` in noise levels.

    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.discrepancy.thermal import fit_thermal
    >>> from pfmdyn.io.thermal_tune import ThermalTune
    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(100.0, 2e5, 2000)
    >>> asd = np.sqrt(1e-8 * Cantilever(2.0, 7e4, 2e-4, width=3e-5, medium=Medium.air()).thermal_noise(f, 300.0).slope)
    >>> fit = fit_thermal(ThermalTune("t.nid", f, asd, "m", {}, {}), 2.0, 2e-4, Medium.air(), 300.0, width=3e-5)
    >>> [a.get_ylabel() for a in plot_thermal(fit).axes]
    ['ASD (m/sqrt(Hz))', 'residual / noise']
    """
    fig = Figure(figsize=(7.5, 5.5))
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    f = fit.frequency_hz / 1e3
    top.semilogy(f, fit.asd, ".", ms=2, color="0.5", label="data")
    top.semilogy(f, fit.model_asd, "C0", lw=1.2, label=f"thermally driven lever, Q {fit['quality_factor']:.3g}")
    top.set_ylabel(f"ASD ({fit['unit']})")
    top.legend(fontsize=8)
    top.set_title(f"{fit['path']}: {fit['medium']}, resonance {fit.lever.free_resonance:.6g} Hz", fontsize=9)
    bottom.plot(f, np.log(fit.model_asd / fit.asd) / fit["noise"], lw=0.6, color="C0")
    bottom.axhline(0.0, color="0.6", lw=0.8)
    bottom.set_ylabel("residual / noise")
    bottom.set_xlabel("frequency (kHz)")
    fig.tight_layout()
    return fig
