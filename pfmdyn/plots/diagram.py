"""Figures of a frequency-bias response diagram (:mod:`pfmdyn.analysis.diagram`); the caller saves them."""
from __future__ import annotations

import numpy as np

from ..analysis.diagram import ResponseMap


KINDS = ("amplitude", "phase", "dominance", "rgb")


def _rgb_image(response: ResponseMap) -> np.ndarray:
    """Shares (R local, G non-local, B electromechanical) scaled so the largest is 1.

    Dividing by the per-pixel maximum rather than the sum shows a dominant mechanism at full
    intensity and an even mixture as a bright blend, instead of darkening every mixture.
    """
    shares = response.shares()
    with np.errstate(invalid="ignore"):
        image = shares / shares.max(axis=-1, keepdims=True)
    return np.nan_to_num(image)


def plot_diagram(response: ResponseMap, kind: str, *, title: str = "", log_frequency: bool = False):
    """Draw one diagram of ``response``; the caller saves the figure.

    Parameters
    ----------
    response : ResponseMap
        From :func:`pfmdyn.analysis.diagram.response_map`.
    kind : {"amplitude", "phase", "dominance", "rgb"}
        ``|A|`` on a log colour scale (Fig. 6 a,c,e); phase of ``A`` in degrees;
        ``|A_piezo|/(|A_piezo| + |A_nl|)`` in grey (white electromechanical, Fig. 6 b,d,f);
        the three-colour map of Fig. 7 (blue electromechanical, red local, green non-local).
    title : str, optional
        Figure title.
    log_frequency : bool, optional
        Logarithmic frequency axis.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from pfmdyn.analysis.diagram import response_map, table1_cantilever
    >>> m = response_map(table1_cantilever("C"), np.linspace(1e4, 1e6, 40),
    ...                  np.linspace(-5, 5, 30), width=24e-6, local_force=14e-9)
    >>> len(plot_diagram(m, "rgb").axes)
    1
    """
    # Imported here so that the computational API does not pay for matplotlib.
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    ax = fig.subplots()
    bias, khz = response.bias_v, response.frequency_hz / 1e3
    mesh = dict(shading="nearest", rasterized=True)
    if kind == "amplitude":
        amplitude = np.abs(response.total)
        # Without losses the peaks are unbounded and the nulls exact zeros: percentiles keep
        # the colour scale on the map rather than on a few pixels next to a root.
        positive = amplitude[amplitude > 0]
        low, high = np.percentile(positive, [1.0, 99.5]) if positive.size else (1e-12, 1e-11)
        image = ax.pcolormesh(bias, khz, np.maximum(amplitude, low), cmap="inferno",
                              norm=LogNorm(low, max(high, low * 10)), **mesh)
        fig.colorbar(image, ax=ax, label="amplitude $|A|/V_{ac}$ (m/V)", extend="both")
    elif kind == "phase":
        image = ax.pcolormesh(bias, khz, np.angle(response.total, deg=True), cmap="twilight",
                              vmin=-180, vmax=180, **mesh)
        fig.colorbar(image, ax=ax, label="phase of $A$ (deg)", ticks=[-180, -90, 0, 90, 180])
    elif kind == "dominance":
        image = ax.pcolormesh(bias, khz, response.dominance(), cmap="gray", vmin=0, vmax=1, **mesh)
        fig.colorbar(image, ax=ax,
                     label=r"$|A_{piezo}|/(|A_{piezo}|+|A_{nl}|)$ (1 = electromechanical)")
    else:
        ax.pcolormesh(bias, khz, _rgb_image(response), **mesh)
        handles = [ax.fill_between([], [], color=c, label=label) for c, label in
                   [("blue", "electromechanical"), ("red", "local electrostatic"),
                    ("lime", "non-local electrostatic")]]
        ax.legend(handles=handles, loc="upper left", fontsize="small", framealpha=0.8)
    if log_frequency:
        ax.set_yscale("log")
    ax.set_xlabel(r"bias $V_{dc}$ (V)" if response.surface_potential_v == 0
                  else rf"bias $V_{{dc}}$ (V), $V_{{surf}}$ = {response.surface_potential_v:g} V")
    ax.set_ylabel("frequency (kHz)")
    ax.set_title(title, fontsize="medium")
    return fig
