"""Figures of a frequency-bias deconvolution (:mod:`pfmdyn.analysis.deconvolve`); the caller saves them.

Figures are built with :class:`matplotlib.figure.Figure`, without pyplot, so no GUI backend is
ever selected and the global matplotlib state of a notebook importing this module is left alone.  Frequencies are shown in kHz and
bias in volts; the error map has bias horizontal and frequency vertical, like the response
diagrams of the paper (Figs. 13-14).
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..analysis.deconvolve import Deconvolution, SurfaceDisplacement


def plot_spectra(result: Deconvolution, unit: str = "a.u.", surface: SurfaceDisplacement | None = None) -> Figure:
    """Plot :math:`|G_{elec}|` and :math:`|d_{eff}|` against frequency on log scales (cf. Fig. 15 a,b).

    Parameters
    ----------
    result : Deconvolution
        From :func:`pfmdyn.analysis.deconvolve.deconvolve`.
    unit : str, optional
        Unit of the response, shown in the axis labels.
    surface : SurfaceDisplacement, optional
        With a lever given: the true surface displacement drawn over ``|d_eff|``, the
        frequencies where it is undetermined shaded.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels on one frequency axis, :math:`|G_{elec}|` above :math:`|d_{eff}|`.

    Examples
    --------
    >>> from pfmdyn.analysis.deconvolve import deconvolve
    >>> fit = deconvolve([1e5, 1e5, 2e5, 2e5], [0.0, 1.0, 0.0, 1.0], [1, 2, 1, 3], 0.0)
    >>> [ax.get_ylabel() for ax in plot_spectra(fit, unit="pm").axes]
    ['$|G_{elec}|$ (pm/V)', '$|d_{eff}|$ (pm)']
    """
    fig = Figure(figsize=(7, 6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    khz = result.frequency_hz / 1e3
    curves = (
        (top, result.g_elec, result.g_elec_se, f"$|G_{{elec}}|$ ({unit}/V)", "electrostatic slope", "C0"),
        (bottom, result.d_eff, result.d_eff_se, f"$|d_{{eff}}|$ ({unit})",
         f"electromechanical, $V_{{surf}}$ = {result.surface_potential_v:g} V", "C3"),
    )
    for ax, values, se, label, title, colour in curves:
        magnitude = np.abs(values)
        ax.plot(khz, magnitude, color=colour, lw=1.2)
        # The standard error applies per component; sqrt(2) of it bounds the magnitude's spread.
        band = np.sqrt(2) * np.nan_to_num(se)
        # The lower edge is floored so that a band wider than the value stays on the log axis.
        ax.fill_between(khz, np.maximum(magnitude - band, magnitude * 1e-3), magnitude + band,
                        color=colour, alpha=0.25, lw=0, label="±1 standard error")
        if (magnitude > 0).any():       # a slope that is zero everywhere (no bias dependence) stays linear
            ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.set_title(title, fontsize="medium")
        ax.grid(True, which="both", alpha=0.3)
    if surface is not None:
        bottom.plot(khz, np.abs(surface.d_eff), "k--", lw=1.0,
                    label=f"true surface displacement at $x_s/L$ = {surface.spot_position:g}")
        for i, (low, high, _) in enumerate(surface.undetermined):
            bottom.axvspan(low / 1e3, high / 1e3, color="0.5", alpha=0.2, lw=0,
                           label="calibration undetermined" if i == 0 else None)
        bottom.legend(loc="best", fontsize="small")
    top.legend(loc="best", fontsize="small")
    bottom.set_xlabel("frequency (kHz)")
    return fig


def plot_nulling_bias(result: Deconvolution) -> Figure:
    """Plot the nulling bias :math:`V_{null}(\\omega)` with its standard error and :math:`V_{surf}`.

    The bias axis is limited to a little beyond the measured bias range and the surface
    potential, because near the zeros of :math:`G_{elec}` the nulling bias is ill-determined
    and far outside; such points are drawn at the axis edge as open triangles.

    Parameters
    ----------
    result : Deconvolution
        From :func:`pfmdyn.analysis.deconvolve.deconvolve`.

    Returns
    -------
    matplotlib.figure.Figure
        One panel, the nulling bias against frequency.

    Examples
    --------
    >>> from pfmdyn.analysis.deconvolve import deconvolve
    >>> fit = deconvolve([1e5, 1e5, 2e5, 2e5], [0.0, 1.0, 0.0, 1.0], [1, 2, 1, 3], 0.0)
    >>> [ax.get_ylabel() for ax in plot_nulling_bias(fit).axes]
    ['nulling bias $V_{null}$ (V)']
    """
    fig = Figure(figsize=(7, 4), layout="constrained")
    ax = fig.subplots()
    khz = result.frequency_hz / 1e3
    span = [result.point_bias_v.min(), result.point_bias_v.max(), result.surface_potential_v]
    margin = 0.25 * (max(span) - min(span)) or 1.0
    low, high = min(span) - margin, max(span) + margin
    inside = (result.v_null >= low) & (result.v_null <= high)
    # NaN breaks the line, so it is not drawn through the off-scale points.
    ax.errorbar(khz, np.where(inside, result.v_null, np.nan), yerr=np.nan_to_num(result.v_null_se),
                fmt="o-", ms=3, lw=1, elinewidth=0.8, capsize=0, color="C0", label="$V_{null}$ ± standard error")
    labelled = False
    for mask, edge, marker in ((result.v_null > high, high, "^"), (result.v_null < low, low, "v")):
        if mask.any():
            ax.plot(khz[mask], np.full(mask.sum(), edge), marker, mfc="none", color="C0", clip_on=False,
                    label=None if labelled else "off scale")
            labelled = True
    ax.axhline(result.surface_potential_v, color="k", ls="--", lw=1, label="$V_{surf}$")
    ax.axhspan(result.point_bias_v.min(), result.point_bias_v.max(), color="0.9", zorder=0,
               label="measured bias range")
    ax.set_ylim(low, high)
    ax.set_xlabel("frequency (kHz)")
    ax.set_ylabel("nulling bias $V_{null}$ (V)")
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncols=4, fontsize="small", frameon=False)
    ax.grid(True, alpha=0.3)
    return fig


def plot_error_map(result: Deconvolution, unit: str = "a.u.") -> Figure:
    """Plot the error map :math:`R - (b + cV)` (in-phase and quadrature) over bias and frequency (cf. Fig. 14).

    Parameters
    ----------
    result : Deconvolution
        From :func:`pfmdyn.analysis.deconvolve.deconvolve`.
    unit : str, optional
        Unit of the residual's colour bar (that of the response).

    Returns
    -------
    matplotlib.figure.Figure
        The in-phase and the quadrature residual side by side, sharing one colour bar.

    Examples
    --------
    >>> from pfmdyn.analysis.deconvolve import deconvolve
    >>> fit = deconvolve([1e5, 1e5, 2e5, 2e5], [0.0, 1.0, 0.0, 1.0], [1, 2, 1, 3], 0.0)
    >>> [ax.get_title() for ax in plot_error_map(fit).axes[:2]]   # the third is the colour bar
    ['residual, in-phase x', 'residual, quadrature y']
    """
    fig = Figure(figsize=(9, 5), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    khz = result.point_frequency_hz / 1e3
    limit = np.max(np.abs([result.residual.real, result.residual.imag])) or 1.0
    grid = _regular_grid(result)
    for ax, part, name in zip(axes, (np.real, np.imag), ("in-phase x", "quadrature y")):
        values = part(result.residual)
        style = dict(cmap="RdBu_r", vmin=-limit, vmax=limit)
        if grid is None:
            image = ax.scatter(result.point_bias_v, khz, c=values, s=12, marker="s", **style)
        else:
            biases, frequencies, order = grid
            image = ax.pcolormesh(biases, frequencies / 1e3, values[order], shading="nearest", **style)
        ax.set_title(f"residual, {name}", fontsize="medium")
        ax.set_xlabel("tip bias (V)")
    axes[0].set_ylabel("frequency (kHz)")
    fig.colorbar(image, ax=axes, label=f"$R - (b + cV)$ ({unit})")
    return fig


def _regular_grid(result: Deconvolution):
    """Bias values, frequencies and point order if every frequency shares one bias set, else None."""
    frequencies = result.frequency_hz
    if len(result.point_bias_v) != len(frequencies) * result.n_bias[0] or np.any(result.n_bias != result.n_bias[0]):
        return None
    # Points are grouped by frequency; sort each row by bias to lay them out as an image.
    order = np.argsort(result.point_bias_v.reshape(len(frequencies), -1), axis=1, kind="stable")
    order += np.arange(len(frequencies))[:, None] * result.n_bias[0]
    biases = result.point_bias_v[order]
    if not np.all(biases == biases[0]):
        return None
    return biases[0], frequencies, order
