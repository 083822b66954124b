"""A map's results as labelled arrays: :func:`open_result` gives an :class:`xarray.Dataset`."""
from __future__ import annotations

import os

import numpy as np

from .readers import require
from .store import open_group

__all__ = ["open_result"]


def open_result(out_dir: str):
    """The maps of ``out_dir/maps.zarr`` (written by ``pfmdyn map`` or ``pfmdyn stiffness``) as an
    :class:`xarray.Dataset`.

    One variable per map, dims ``("y", "x")`` (pixels; with the SHO fit of several biases or
    bands also ``bias`` (V) and ``band`` (the band's centre frequency, Hz)), CF-style ``units``
    and ``long_name`` attributes; the run's settings (model, source, block, ...) are the
    dataset's attributes.  Blocks not fitted yet are NaN.

    Examples
    --------
    >>> import tempfile
    >>> from pfmdyn.maps.store import open_group, write_array
    >>> d = tempfile.mkdtemp()
    >>> group = open_group(d + "/maps.zarr", "w")
    >>> _ = write_array(group, "k1", np.full((2, 3), 150.0), units="N/m", description="vertical contact stiffness")
    >>> result = open_result(d)
    >>> result["k1"].dims, result["k1"].attrs["units"], float(result["k1"].mean())
    (('y', 'x'), 'N/m', 150.0)
    """
    xarray = require("xarray")
    group = open_group(os.path.join(out_dir, "maps.zarr"), "r")
    attrs = dict(group.attrs)
    variables = {}
    for name in sorted(group.array_keys()):
        if name == "done":
            continue
        array = group[name]
        dims = tuple(array.attrs.get("dims", ("y", "x")[:array.ndim]))
        variables[name] = xarray.Variable(dims, np.asarray(array[...]),
                                          {"units": array.attrs.get("units", ""),
                                           "long_name": array.attrs.get("description", name)})
    coords = {}
    sizes = {dim: size for v in variables.values() for dim, size in zip(v.dims, v.shape)}
    if "bias" in sizes and attrs.get("bias_v") is not None:
        coords["bias"] = ("bias", np.asarray(attrs["bias_v"], float), {"units": "V", "long_name": "DC tip bias"})
    if "band" in sizes and attrs.get("band_hz") is not None:
        coords["band"] = ("band", np.asarray(attrs["band_hz"], float),
                          {"units": "Hz", "long_name": "centre frequency of the band"})
    settings = {key: value for key, value in attrs.items()
                if key not in ("bias_v", "band_hz", "model_selection") and value is not None}
    return xarray.Dataset(variables, coords=coords, attrs=settings)
