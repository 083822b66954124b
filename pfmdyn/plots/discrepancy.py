"""PNG figures of a discrepancy report (:mod:`pfmdyn.discrepancy.spectrum`)."""
from __future__ import annotations

import numpy as np


def spectrum_figure(data, report):
    """Figure of data, baseline, final model and residuals at the lowest and highest bias."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    base, final = report["_fits"]
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
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


def plot_spectrum_report(data, report, path) -> None:
    import matplotlib.pyplot as plt
    fig = spectrum_figure(data, report)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_resonance_report(data, report, path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    labels = [f"{c} {m}" for c, m in zip(data.condition, data.mode)]
    x = np.arange(len(labels))
    measured = np.array(report["measured_hz"])
    fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
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
    fig.savefig(path, dpi=120)
    plt.close(fig)
