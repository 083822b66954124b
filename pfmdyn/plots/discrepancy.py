"""Figures of a discrepancy report (:mod:`pfmdyn.discrepancy.spectrum`, :mod:`.resonances`).

Built on :class:`matplotlib.figure.Figure` (no pyplot, so no GUI backend is selected); the
caller saves them.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_resonance_report", "plot_spectrum_report"]


def plot_spectrum_report(data, report) -> Figure:
    """Data, baseline, final model and residuals at the lowest and highest bias; ``report``
    (:class:`pfmdyn.discrepancy.report.DiscrepancyReport`) carries the baseline and final fits
    as ``fits``.

    >>> from types import SimpleNamespace
    >>> f = np.repeat(np.linspace(1e5, 2e5, 5), 2)
    >>> data = SimpleNamespace(frequency_hz=f, bias_v=np.tile([0.0, 1.0], 5), response=1 + f / 1e5 + 0j)
    >>> fit = SimpleNamespace(prediction=data.response, residual=0 * data.response)
    >>> plot_spectrum_report(data, SimpleNamespace(fits=(fit, fit))).axes[1].get_xlabel()
    'frequency (kHz)'
    """
    base, final = report.fits
    fig = Figure(figsize=(8, 7))
    axes = fig.subplots(2, 1, sharex=True)
    biases = np.unique(data.bias_v)[[0, -1]]
    for b in biases:
        sel = data.bias_v == b
        f = data.frequency_hz[sel] / 1e3
        axes[0].semilogy(f, np.abs(data.response[sel]), ".", ms=2, label=f"data {b:g} V")
        axes[0].semilogy(f, np.abs(base.prediction[sel]), "--", lw=1, label="baseline")
        axes[0].semilogy(f, np.abs(final.prediction[sel]), "-", lw=1, label="final model")
        axes[1].plot(f, np.abs(base.residual[sel]), lw=1, label=f"residual before ({b:g} V)")
        axes[1].plot(f, np.abs(final.residual[sel]), lw=1, label=f"residual after ({b:g} V)")
    # An undamped baseline fitted to damped data may collapse towards zero (or spike at its
    # poles); the log axis follows the data so that the model curves cannot squash them.
    shown = np.abs(data.response[np.isin(data.bias_v, biases)])
    shown = shown[shown > 0]
    if len(shown):
        axes[0].set_ylim(shown.min() / 3, shown.max() * 3)
    axes[0].set_ylabel("|response|")
    axes[1].set_ylabel("|residual|")
    axes[1].set_xlabel("frequency (kHz)")
    for ax in axes:
        ax.legend(fontsize=7)
    return fig


def plot_resonance_report(data, report) -> Figure:
    """Measured, baseline and final-model resonances and the residuals before and after.

    >>> from types import SimpleNamespace
    >>> data = SimpleNamespace(condition=["free", "contact"], mode=[1, 1])
    >>> report = {"measured_hz": [75e3, 310e3], "baseline_hz": [75e3, 300e3], "predicted_hz": [75e3, 309e3]}
    >>> [ax.get_ylabel() for ax in plot_resonance_report(data, report).axes]
    ['frequency (kHz)', 'model - data (Hz)']
    """
    labels = [f"{c} {m}" for c, m in zip(data.condition, data.mode)]
    x = np.arange(len(labels))
    measured = np.array(report["measured_hz"])
    fig = Figure(figsize=(7, 6))
    axes = fig.subplots(2, 1, sharex=True)
    axes[0].plot(x, measured / 1e3, "o", label="data")
    axes[0].plot(x, np.array(report["baseline_hz"]) / 1e3, "x", label="baseline")
    axes[0].plot(x, np.array(report["predicted_hz"]) / 1e3, "+", ms=12, label="final model")
    axes[1].bar(x - 0.2, np.array(report["baseline_hz"]) - measured, 0.4, label="residual before")
    axes[1].bar(x + 0.2, np.array(report["predicted_hz"]) - measured, 0.4, label="residual after")
    axes[0].set_ylabel("frequency (kHz)")
    axes[1].set_ylabel("model - data (Hz)")
    axes[1].set_xticks(x, labels)
    for ax in axes:
        ax.legend(fontsize=7)
    return fig
