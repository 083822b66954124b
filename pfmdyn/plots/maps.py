"""Images of the per-pixel fit: one figure per quantity, with a colour bar in SI units.

Built on :class:`matplotlib.figure.Figure` (no pyplot, so no GUI backend is selected); the
caller saves or shows the figures.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_maps", "plot_dart"]

_SHOWN = ("k1", "k1_stderr", "k2", "quality_factor", "viscous_loss", "contact_loss", "amplitude", "phase",
          "electrostatic", "electrostatic_phase", "nulling_bias", "measured_resonance", "measured_quality_factor",
          "r2", "gap", "contact_resonance", "contact_quality_factor", "d_eff", "oscillator_k1_error",
          "oscillator_d_eff_error")


def plot_maps(result) -> dict[str, Figure]:
    """A figure per shown quantity of ``result`` (an :class:`xarray.Dataset` from
    :func:`pfmdyn.maps.open_result`) that has a fitted pixel, by name.  Maps with more axes than
    ``(y, x)`` (the SHO's biases or bands) show their first bias and band.

    >>> import xarray
    >>> ds = xarray.Dataset({"k1": (("y", "x"), np.ones((4, 4)), {"units": "N/m", "long_name": "k1"})})
    >>> list(plot_maps(ds))
    ['k1']
    """
    figures = {}
    for name in _SHOWN:
        if name not in result or not np.isfinite(result[name].values).any():    # e.g. k2 with one band
            continue
        array = result[name]
        extra = {dim: 0 for dim in array.dims if dim not in ("y", "x")}
        image_data = array.isel(extra).transpose("y", "x")
        fig = Figure(figsize=(4.2, 3.6), layout="constrained")
        ax = fig.add_subplot()
        image = ax.imshow(image_data.values, origin="lower", cmap="twilight" if name.endswith("phase") else "viridis")
        fig.colorbar(image, ax=ax, label=f"{name} ({array.attrs.get('units', '')})")
        ax.set_xlabel("x (pixel)")
        ax.set_ylabel("y (pixel)")
        if extra:
            ax.set_title(", ".join(f"{dim} {float(image_data[dim]) if dim in image_data.coords else 0:g}"
                                   for dim in extra), fontsize=9)
        figures[name] = fig
    return figures


_DART = ("contact_resonance", "contact_quality_factor", "k1", "contact_loss", "d_eff", "oscillator_k1_error",
         "oscillator_d_eff_error", "determined", "real_drive")
"""The DART figure's panels, in order; the flags (``determined``, ``real_drive``: where the drive's phase was
fitted with the contact) beside the values they qualify."""


def plot_dart(result) -> Figure:
    """One figure of a DART image's maps (:func:`pfmdyn.maps.dart.invert`, read by
    :func:`pfmdyn.maps.open_result`): the oscillator's resonance and Q, the lever's k1, contact loss
    and d_eff (a diverging scale: the domains' sign), how far the oscillator is from the lever, and where each
    pixel was determined and its drive taken real (``real_drive``).

    >>> import xarray
    >>> ds = xarray.Dataset({"d_eff": (("y", "x"), np.array([[1e-12, -1e-12]]), {"units": "m/V"})})
    >>> len(plot_dart(ds).axes)      # the panel and its colour bar
    2
    """
    names = [name for name in _DART if name in result]
    columns = min(4, max(len(names), 1))
    rows = -(-len(names) // columns)
    fig = Figure(figsize=(3.4 * columns, 2.9 * rows), layout="constrained")
    for i, name in enumerate(names):
        ax = fig.add_subplot(rows, columns, i + 1)
        values = result[name].transpose("y", "x").values
        limit = np.nanmax(np.abs(values)) if np.isfinite(values).any() else 1.0
        signed = name == "d_eff" or name.endswith("_error")
        image = ax.imshow(values, origin="lower", cmap="RdBu_r" if signed else "viridis",
                          **({"vmin": -limit, "vmax": limit} if signed else {}))
        fig.colorbar(image, ax=ax, label=result[name].attrs.get("units", ""))
        ax.set_title(name, fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    return fig
