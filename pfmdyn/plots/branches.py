"""Figure of resonance branches against contact stiffness (:mod:`pfmdyn.roots.branches`); the caller saves it."""
from __future__ import annotations

import numpy as np

from ..roots.branches import FIGURE, LABELS, SWEPT, branch_limits, crossovers, frequency_ratio


def plot_branches(family: str, stiffness: np.ndarray, z: np.ndarray, **fixed):
    """Branches on log axes with dashed limits and the crossovers joined by a dotted line.

    Built on :class:`matplotlib.figure.Figure` (no pyplot), like :mod:`pfmdyn.plots.deconvolution`.

    >>> from pfmdyn.roots.branches import sweep
    >>> s = np.logspace(-3, 6, 20)
    >>> plot_branches("torsion-elastic", s, sweep("torsion-elastic", s, 2)).axes[0].get_xscale()
    'log'
    """
    from matplotlib.figure import Figure

    modes = z.shape[1]
    soft, stiff = branch_limits(family, modes, **fixed)
    s_cross, z_cross = crossovers(family, modes, **fixed)
    xlabel, soft_label, stiff_label = LABELS[SWEPT[family]]

    def freq(v):
        return frequency_ratio(family, np.asarray(v), soft[0])

    fig = Figure(figsize=(8.4, 5.0), dpi=150, layout="constrained")
    ax = fig.add_subplot()
    colors = [f"C{i}" for i in range(modes)]
    # beyond ten modes the colours repeat: one legend entry for all (a legend of 50 collapses the axes)
    labels = [f"mode {n + 1}" for n in range(modes)] if modes <= 10 else [f"modes 1-{modes}"] + [None] * (modes - 1)
    for n in range(modes):
        ax.axhline(freq(soft[n]), color="0.55", ls="--", lw=0.9, label=soft_label if n == 0 else None)
        ax.axhline(freq(stiff[n]), color="0.15", ls="--", lw=0.9, label=stiff_label if n == 0 else None)
        ax.plot(stiffness, freq(z[:, n]), color=colors[n], lw=2, label=labels[n])
    inside = (s_cross >= stiffness[0]) & (s_cross <= stiffness[-1])
    ax.plot(s_cross[inside], freq(z_cross[inside]), "k:", lw=1.2)
    ax.plot(s_cross[inside], freq(z_cross[inside]), "o", mfc="white", mec="k", ms=6,
            label="crossover (midway free to stiff)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(stiffness[0], stiffness[-1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel("resonance frequency  $f_n / f_1^{\\mathrm{free}}$")
    fixed_text = "".join(f", {k} = {v}" for k, v in fixed.items())
    ax.set_title(f"{family}{fixed_text}: first {modes} resonance branches (cf. {FIGURE[family]})", fontsize=10)
    ax.grid(True, which="major", color="0.9", lw=0.6)
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)    # keeps the branches clear
    return fig
