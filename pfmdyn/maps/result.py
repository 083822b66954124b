"""A map's results: the run's :class:`MapResult` (summary fields and text) and the maps as labelled
arrays (:func:`open_result` gives an :class:`xarray.Dataset`)."""
from __future__ import annotations

import os

import numpy as np

from ..fitting.result import Result
from .readers import require
from .store import open_group

__all__ = ["MapResult", "open_result"]


class MapResult(Result):
    """What a run of ``pfmdyn map`` did (:func:`pfmdyn.maps.driver.run_map`): its fields (blocks and
    pixels fitted, pixels per second, the model, the fraction of pixels explained, the median gap,
    the output; ``to_dict()``), the map's pixel ``shape`` and the summary line (``report()``).

    >>> r = MapResult({"blocks_run": 1, "blocks_done": 1, "blocks_total": 1, "pixels_per_s": 200.0,
    ...                "model": "elastic", "explained_fraction": 1.0, "median_gap": 0.93, "out": "o/maps.zarr"},
    ...               shape=(8, 8))
    >>> r.report()
    '8x8 pixels, model elastic: 1 blocks fitted (200 pixels/s), 1/1 done; explained 100.0 %, median gap 0.93; maps in o/maps.zarr'
    """

    def report(self) -> str:
        """The summary line ``pfmdyn map`` prints."""
        s = self
        explained = (f"explained {100 * s['explained_fraction']:.1f} %"
                     + (f" ({100 * s['at_bound_fraction']:.1f} % at a parameter bound: unexplained)"
                        if s.get("at_bound_fraction") else "") + f", median gap {s['median_gap']:.3g}"
                     + (f", median nulling bias {s['median_nulling_bias']:.3g} V" if "median_nulling_bias" in s else ""))
        ny, nx = self.shape
        return (f"{ny}x{nx} pixels, model {s['model']}: {s['blocks_run']} blocks fitted ({s['pixels_per_s']:.0f} "
                f"pixels/s), {s['blocks_done']}/{s['blocks_total']} done; {explained}; maps in {s['out']}")


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
