"""Figure of ``pfmdyn spot``: the electrostatic-to-electromechanical slope ratio along the lever.

Left: ``|theta_q0 / theta_d1|`` against ``x_s/L`` at the chosen frequency, the certified blind
spots marked.  Right: the same ratio over ``x_s/L`` and frequency on a log colour scale (in
the manner of the paper's Figs. 6-7): the dark valleys are the blind spots as they move with
frequency; at a contact resonance every load excites the same mode shape and the ratio no
longer depends on the spot.
"""
from __future__ import annotations

import numpy as np

from ..analysis.spot import SpotResult

__all__ = ["plot_spot"]


def plot_spot(result: SpotResult, frequencies=None, ratio_map=None):
    """Draw the ratio at ``result.drive_frequency`` and, when given, its map over ``frequencies``.

    Parameters
    ----------
    result : SpotResult
        From :func:`pfmdyn.analysis.spot.spot_analysis`.
    frequencies : array_like, optional
        Frequencies (Hz) of the rows of ``ratio_map``.
    ratio_map : ndarray, optional
        ``theta_q0 / theta_d1`` of shape ``(len(frequencies), len(result.positions))``
        (:func:`pfmdyn.analysis.spot.ratio_map`).

    Returns
    -------
    matplotlib.figure.Figure
        The ratio along the lever and, with ``ratio_map``, its map beside it.

    Examples
    --------
    >>> from pfmdyn.analysis.spot import spot_analysis
    >>> from pfmdyn.cantilever import Cantilever, Contact
    >>> r = spot_analysis(Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5), Contact(k1=200.0), 20e3, positions=50)
    >>> len(plot_spot(r).axes)
    1
    """
    from matplotlib.figure import Figure

    panels = 1 if ratio_map is None else 2
    fig = Figure(figsize=(5.5 * panels, 4.2), layout="constrained")
    ax = fig.add_subplot(1, panels, 1)
    x = result.positions
    ax.semilogy(x, np.abs(result.ratio), color="k")
    for p in result.blind_spot.positions:
        ax.axvline(p, color="tab:red", ls="--", lw=1)
    ax.axvline(result.spot_position, color="tab:blue", lw=1, label=f"spot {result.spot_position:g} L")
    ax.legend(loc="best", fontsize="small")
    ax.set_xlabel("detection point $x_s/L$")
    ax.set_ylabel(r"$|\theta_{q0}/\theta_{d1}|$ (m$^2$/N)")
    spots = ", ".join(f"{p:.4f}" for p in result.blind_spot.positions) or "none"
    ax.set_title(f"{result.drive_frequency / 1e3:.4g} kHz: blind spot(s) {spots}", fontsize="medium")
    if ratio_map is not None:
        ax2 = fig.add_subplot(1, 2, 2)
        f = np.asarray(frequencies, float) / 1e3
        with np.errstate(divide="ignore"):
            image = np.log10(np.abs(ratio_map))
        mesh = ax2.pcolormesh(x, f, image, shading="auto", cmap="magma")
        fig.colorbar(mesh, ax=ax2, label=r"$\log_{10}|\theta_{q0}/\theta_{d1}|$")
        ax2.set_xlabel("detection point $x_s/L$")
        ax2.set_ylabel("frequency (kHz)")
    return fig
