"""The maps' Zarr store, the same with Zarr 2.x and 3.x.

Output groups are written in Zarr's format 2 whichever Zarr is installed, so that a map written
under Zarr 3 can be resumed, read or opened by an environment with Zarr 2 and the other way round;
inputs are read in either format.  The groups follow xarray's Zarr convention, so that
``xarray.open_zarr`` opens them as a Dataset: every array names its dimensions in the attribute
``_ARRAY_DIMENSIONS`` (``("y", "x")`` followed by any trailing axes) and carries CF ``units`` and
``long_name``; a dimension's coordinate is the 1-D array of its name; the metadata is consolidated
(``.zmetadata``) once a group's arrays and attributes are written.
"""
from __future__ import annotations

import numpy as np

from ..errors import UserError
from .readers import require

__all__ = ["DIMENSIONS", "consolidate", "create_map", "create_maps", "map_names", "open_group", "set_attributes",
           "write_array", "write_coordinates", "write_maps", "write_regions", "zarr_major"]

DIMENSIONS = "_ARRAY_DIMENSIONS"
"""The attribute naming an array's dimensions in xarray's convention for Zarr format 2."""


def zarr_major() -> int:
    """Major version of the installed Zarr.

    >>> zarr_major() in (2, 3)
    True
    """
    return int(require("zarr").__version__.split(".")[0])


def open_group(path: str, mode: str = "r"):
    """Open (``"r"``, ``"r+"``) or create (``"a"``, ``"w"``) the Zarr group at ``path``; new
    groups in format 2.

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> "k1" in group
    False
    """
    options = {"zarr_format": 2} if zarr_major() >= 3 and mode in ("a", "w", "w-") else {}
    return require("zarr").open_group(path, mode=mode, **options)


def _with_dims(attrs: dict, dims) -> dict:
    return {**attrs, DIMENSIONS: list(dims)} if dims is not None else attrs


def create_map(group, name: str, shape, chunks, fill_value=np.nan, dtype="f8", dims=None, **attrs):
    """An array ``name`` of ``shape`` filled with ``fill_value``, with ``attrs`` (and ``dims``,
    its dimension names, in :data:`DIMENSIONS`).

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> array = create_map(group, "k1", (4, 6), (2, 2), dims=("y", "x"), units="N/m")
    >>> array.shape, array.attrs[DIMENSIONS]
    ((4, 6), ['y', 'x'])
    """
    attrs = _with_dims(attrs, dims)
    if zarr_major() >= 3:
        return group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value,
                                  attributes=attrs)
    array = group.full(name, fill_value=fill_value, shape=shape, chunks=chunks, dtype=dtype)
    array.attrs.update(attrs)
    return array


def rename_map(group, old: str, new: str, **attrs):
    """Give the map ``old`` the name ``new`` (its values, chunks and attributes kept, ``attrs`` over
    them): a store begun under an earlier name, resumed.

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> _ = create_map(group, "q", (2, 2), (1, 1), dims=("y", "x"), units="1")
    >>> group["q"][0, 0] = 7.0
    >>> array = rename_map(group, "q", "measured_q", long_name="a Q")
    >>> float(array[0, 0]), array.attrs["units"], array.attrs[DIMENSIONS], "q" in group
    (7.0, '1', ['y', 'x'], False)
    """
    array = group[old]
    values, chunks, fill = array[...], array.chunks, array.fill_value
    kept = {**array.attrs, **attrs}
    del group[old]
    renamed = create_map(group, new, values.shape, chunks, fill_value=fill, dtype=values.dtype, **kept)
    renamed[...] = values
    return renamed


def create_maps(path: str, maps: dict) -> None:
    """The arrays ``maps`` (name -> :func:`create_map`'s arguments after the name, as a dict) in
    the group at ``path``; under Zarr 3 created concurrently, in one trip to Zarr's event loop.

    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/m.zarr"
    >>> create_maps(path, {"k1": {"shape": (4, 6), "chunks": (2, 2), "units": "N/m"},
    ...                    "done": {"shape": (2, 3), "chunks": (1, 1), "fill_value": 0, "dtype": "u1"}})
    >>> group = open_group(path)
    >>> group["k1"].attrs["units"], group["done"].dtype.name
    ('N/m', 'uint8')
    """
    group = open_group(path, mode="a")
    if zarr_major() < 3:
        for name, arguments in maps.items():
            create_map(group, name, **arguments)
        return
    import asyncio

    import zarr.api.asynchronous as zarr_async
    from zarr.core.sync import sync

    def array(group, name, shape, chunks, fill_value=np.nan, dtype="f8", dims=None, **attrs):
        return group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value,
                                  attributes=_with_dims(attrs, dims))

    async def create():
        group = await zarr_async.open_group(store=path, mode="r+")
        await asyncio.gather(*(array(group, name, **arguments) for name, arguments in maps.items()))

    sync(create())


def set_attributes(node, attrs: dict) -> None:
    """Add ``attrs`` to the attributes of a Zarr group or array in one write (Zarr 3's
    ``attrs.update`` rewrites the metadata once per key).

    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/m.zarr"
    >>> set_attributes(open_group(path, "w"), {"model": "sho", "block": 128})
    >>> sorted(open_group(path).attrs.items())
    [('block', 128), ('model', 'sho')]
    """
    if zarr_major() >= 3:
        node.update_attributes(attrs)
    else:
        node.attrs.update(attrs)


def write_array(group, name: str, data, **attrs):
    """An array ``name`` holding ``data`` (one chunk), with ``attrs`` (``dims`` as for
    :func:`create_map`).  No fill value, every element being written: xarray reads an array's
    fill value as its missing value (a 0 among pixel indices would become NaN).

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> write_array(group, "k1", np.ones((2, 3)), units="N/m").attrs["units"]
    'N/m'
    """
    data = np.asarray(data)
    array = create_map(group, name, data.shape, data.shape or None, fill_value=None, dtype=data.dtype, **attrs)
    array[...] = data
    return array


def write_regions(path: str, region: tuple, maps: dict) -> None:
    """Write each of ``maps`` (name -> values) into ``region`` of the array of that name in the
    group at ``path``.  Under Zarr 3 all arrays are opened and written concurrently in one trip
    to Zarr's event loop (one trip per array costs as much as the writes of a block's fit).

    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/m.zarr"
    >>> group = open_group(path, "w")
    >>> for name in ("a", "b"):
    ...     _ = create_map(group, name, (2, 4), (2, 2))
    >>> write_regions(path, (slice(0, 2), slice(2, 4)), {"a": np.ones((2, 2)), "b": np.zeros((2, 2))})
    >>> open_group(path)["a"][...].tolist()
    [[nan, nan, 1.0, 1.0], [nan, nan, 1.0, 1.0]]
    """
    if zarr_major() < 3:
        group = open_group(path, mode="r+")
        for name, values in maps.items():
            group[name][region] = values
        return
    import asyncio

    import zarr.api.asynchronous as zarr_async
    from zarr.core.sync import sync

    async def write():
        group = await zarr_async.open_group(store=path, mode="r+")
        arrays = await asyncio.gather(*(group.getitem(name) for name in maps))
        await asyncio.gather(*(array.setitem(region, values) for array, values in zip(arrays, maps.values())))

    sync(write())


def write_coordinates(group, sizes: dict, bias_v=None, band_hz=None) -> None:
    """The coordinate arrays of the dimensions ``sizes`` (name -> length) a group's maps have:
    ``y`` and ``x`` (pixel indices), ``bias`` (the DC tip biases, V) and ``band`` (the bands'
    centre frequencies, Hz).

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> write_coordinates(group, {"y": 2, "x": 3, "bias": 2}, bias_v=[-1.0, 1.0])
    >>> group["x"][...].tolist(), group["bias"].attrs["units"], group["bias"].attrs[DIMENSIONS]
    ([0, 1, 2], 'V', ['bias'])
    """
    described = {"y": (np.arange(sizes.get("y", 0)), "1", "pixel row"),
                 "x": (np.arange(sizes.get("x", 0)), "1", "pixel column"),
                 "bias": (bias_v, "V", "DC tip bias"), "band": (band_hz, "Hz", "centre frequency of the band")}
    for dim in sizes:
        values, unit, text = described[dim]
        write_array(group, dim, np.asarray(values), dims=(dim,), units=unit, long_name=text)


def write_maps(path: str, maps: dict, attrs: dict | None = None) -> None:
    """A new group at ``path`` (whatever was there replaced) holding ``maps`` (name -> ``(values, units,
    long_name)``, ``(y, x)`` arrays of one shape), their coordinates and ``attrs``, consolidated.

    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/m.zarr"
    >>> write_maps(path, {"k1": (np.ones((2, 3)), "N/m", "contact stiffness")}, {"source": "scan.ibw"})
    >>> group = open_group(path)
    >>> map_names(group), group["k1"].attrs[DIMENSIONS], group.attrs["source"]
    (['k1'], ['y', 'x'], 'scan.ibw')
    >>> write_maps("/dev/null/m.zarr", {})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /dev/null/m.zarr: ...
    """
    try:
        group = open_group(path, "w")
        shape = None
        for name, (values, units, long_name) in maps.items():
            shape = np.shape(values)
            write_array(group, name, values, units=units, long_name=long_name, dims=("y", "x"))
        if shape is not None:
            write_coordinates(group, dict(zip(("y", "x"), shape)))
        if attrs:
            set_attributes(group, attrs)
        consolidate(path)
    except (OSError, ValueError, KeyError) as exc:   # a file in the way, a directory not writable (Zarr 2: KeyError)
        exc = exc.__cause__ or exc
        raise UserError(f"cannot write {path}: {' '.join(str(exc).split())[:120]}") from None


def map_names(group) -> list[str]:
    """The names of a group's maps, sorted: its arrays but the coordinates (an array named after
    its one dimension) and the blocks' ``done`` flags.

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> _ = write_array(group, "k1", np.ones((2, 3)), dims=("y", "x"))
    >>> write_coordinates(group, {"y": 2, "x": 3})
    >>> map_names(group)
    ['k1']
    """
    return [name for name in sorted(group.array_keys())
            if name != "done" and list(group[name].attrs.get(DIMENSIONS, ())) != [name]]


def consolidate(path: str) -> None:
    """Consolidate the metadata of the group at ``path`` into its ``.zmetadata`` (xarray reads
    a group's arrays from it in one request, and warns when it is missing).

    >>> import os, tempfile
    >>> path = tempfile.mkdtemp() + "/m.zarr"
    >>> _ = write_array(open_group(path, "w"), "k1", np.ones(2), dims=("x",))
    >>> consolidate(path)
    >>> ".zmetadata" in os.listdir(path)
    True
    """
    require("zarr").consolidate_metadata(path)
