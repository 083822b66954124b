"""The maps' Zarr store, the same with Zarr 2.x and 3.x.

Output groups are written in Zarr's format 2 whichever Zarr is installed, so that a map written
under Zarr 3 can be resumed, read or opened by an environment with Zarr 2 and the other way round;
inputs are read in either format.  Every map carries its ``units``, ``description`` and ``dims``
(``("y", "x")`` followed by the names of any trailing axes) in its attributes.
"""
from __future__ import annotations

import numpy as np

from .readers import require

__all__ = ["create_map", "open_group", "write_array", "zarr_major"]


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
        array = group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill_value)
    else:
        array = group.full(name, fill_value=fill_value, shape=shape, chunks=chunks, dtype=dtype)
    array.attrs.update(attrs)
    return array


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
