"""The maps' Zarr store, the same with Zarr 2.x and 3.x.

Output groups are written in Zarr's format 2 whichever Zarr is installed, so that a map written
under Zarr 3 can be resumed, read or opened by an environment with Zarr 2 and the other way round;
inputs are read in either format.  Every map carries its ``units``, ``description`` and ``dims``
(``("y", "x")`` followed by the names of any trailing axes) in its attributes.
"""
from __future__ import annotations

import numpy as np

from .readers import require

__all__ = ["create_map", "create_maps", "open_group", "set_attributes", "write_array", "write_regions", "zarr_major"]


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


def create_map(group, name: str, shape, chunks, fill_value=np.nan, dtype="f8", **attrs):
    """An array ``name`` of ``shape`` filled with ``fill_value``, with ``attrs``.

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> create_map(group, "k1", (4, 6), (2, 2), units="N/m").shape
    (4, 6)
    """
    if zarr_major() >= 3:
        return group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value,
                                  attributes=attrs)
    array = group.full(name, fill_value=fill_value, shape=shape, chunks=chunks, dtype=dtype)
    array.attrs.update(attrs)
    return array


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

    def array(group, name, shape, chunks, fill_value=np.nan, dtype="f8", **attrs):
        return group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value,
                                  attributes=attrs)

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
    """An array ``name`` holding ``data`` (one chunk), with ``attrs``.

    >>> import tempfile
    >>> group = open_group(tempfile.mkdtemp() + "/m.zarr", "w")
    >>> write_array(group, "k1", np.ones((2, 3)), units="N/m").attrs["units"]
    'N/m'
    """
    data = np.asarray(data)
    array = create_map(group, name, data.shape, data.shape or None, fill_value=0, dtype=data.dtype, **attrs)
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
