"""A map's results: the run's :class:`MapResult` (summary fields and text) and the maps as labelled
arrays (:func:`open_result` gives an :class:`xarray.Dataset`)."""
from __future__ import annotations

import os

import numpy as np

from ..fitting.result import Result
from .readers import require
from .store import DIMENSIONS, map_names, open_group

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
    :class:`xarray.Dataset`, loaded: the maps ``xarray.open_zarr`` opens (the store follows its
    convention, :mod:`pfmdyn.maps.store`), read through Zarr so that Zarr 2 serves too (recent
    xarray opens Zarr stores only with Zarr 3), without the blocks' ``done`` flags.

    One variable per map, dims ``("y", "x")`` (pixels; with the SHO fit of several biases or
    bands also ``bias`` (V) and ``band`` (the band's centre frequency, Hz), the coordinates),
    CF-style ``units`` and ``long_name`` attributes; the run's settings (model, source, block, ...)
    are the dataset's attributes.  Blocks not fitted yet are NaN.

    Examples
    --------
    >>> import tempfile
    >>> from pfmdyn.maps.store import open_group, write_array
    >>> d = tempfile.mkdtemp()
    >>> group = open_group(d + "/maps.zarr", "w")
    >>> _ = write_array(group, "k1", np.full((2, 3), 150.0), dims=("y", "x"), units="N/m",
    ...                 long_name="vertical contact stiffness")
    >>> result = open_result(d)
    >>> result["k1"].dims, result["k1"].attrs["units"], float(result["k1"].mean())
    (('y', 'x'), 'N/m', 150.0)
    """
    xarray = require("xarray")
    group = open_group(os.path.join(out_dir, "maps.zarr"), "r")

    def variable(name):
        attrs = dict(group[name].attrs)
        return xarray.Variable(tuple(attrs.pop(DIMENSIONS)), np.asarray(group[name][...]), attrs)

    variables = {name: variable(name) for name in map_names(group)}
    coords = {dim: variable(dim) for dim in dict.fromkeys(d for v in variables.values() for d in v.dims) if dim in group}
    settings = {key: value for key, value in group.attrs.items()
                if key not in ("bias_v", "band_hz", "model_selection") and value is not None}
    return xarray.Dataset(variables, coords=coords, attrs=settings)
