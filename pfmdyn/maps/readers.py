"""Map inputs: the plain layout (HDF5 file or Zarr group) and pycroscopy's USID band-excitation layout.

Plain: ``response`` (ny, nx, n_freq) complex, ``frequency_hz`` (n_freq,), cantilever metadata as
root attributes named as in the CSV metadata.  USID (as BGlib writes BE data): a main dataset
(positions x spectral values, complex) whose attributes reference ``Position_Indices`` (columns
labelled ``X``/``Y``, X fastest) and ``Spectroscopic_Values`` (a ``Frequency`` row, in Hz or
a prefixed unit); the
cantilever metadata come from the root attributes, a ``Measurement_*`` group's (pfmdyn's or
Asylum's key names) or the command line.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import MissingExtraError, UserError
from ..io.asylum import cantilever_fields
from ..io.record import si_unit
from .fit import BeamMapModel

__all__ = ["MapInput", "open_map", "read_block", "require"]

METADATA = {"spring_constant_n_per_m": "k", "length_m": "L", "tip_height_m": "H", "free_resonance_hz": "f1"}


def require(module: str):
    """Import an optional dependency of the ``maps`` extra, or say which extra brings it."""
    try:
        return __import__(module)
    except ImportError:
        raise MissingExtraError(module, "maps") from None


@dataclass(frozen=True)
class MapInput:
    """Where the spectra are (file, dataset, layout) and the model metadata."""

    path: str
    model: BeamMapModel
    shape: tuple[int, int]
    dataset: str = "response"
    layout: str = "plain"


class open_root:
    """Context manager giving the root group of an HDF5 file or a Zarr directory."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        if os.path.isdir(self.path):
            return require("zarr").open_group(self.path, mode="r")
        self._file = require("h5py").File(self.path, "r")
        return self._file

    def __exit__(self, *exc):
        if hasattr(self, "_file"):
            self._file.close()


def _usid_main(root):
    """Name of the first USID main dataset (one carrying Spectroscopic_Values), or None."""
    found = []
    if hasattr(root, "visititems"):
        root.visititems(lambda name, obj: found.append(name) if "Spectroscopic_Values" in obj.attrs
                        and "Position_Indices" in obj.attrs else None)
    return found[0] if found else None


def _labels(table, key) -> list[str]:
    return [str(v.decode() if isinstance(v, bytes) else v) for v in np.ravel(table.attrs.get(key, []))]


def _usid_grid(root, name, path):
    main = root[name]
    spec = root[main.attrs["Spectroscopic_Values"]]
    labels, units = _labels(spec, "labels"), _labels(spec, "units")
    if "Frequency" not in labels:
        raise UserError(f"{path}: USID Spectroscopic_Values has no 'Frequency' row (labels {labels})")
    row = labels.index("Frequency")
    unit = units[row] if row < len(units) else "Hz"
    converted = si_unit(unit)
    if not converted or converted[0] != "Hz":
        raise UserError(f"{path}: USID Frequency row is in {unit!r}, not a frequency unit")
    f = np.asarray(spec[row, :], float) * converted[1]
    pos = root[main.attrs["Position_Indices"]]
    plabels = _labels(pos, "labels")
    if sorted(plabels) != ["X", "Y"]:
        raise UserError(f"{path}: USID Position_Indices must have columns X and Y (got {plabels})")
    idx = np.asarray(pos[...])
    x, y = idx[:, plabels.index("X")], idx[:, plabels.index("Y")]
    nx, ny = int(x.max()) + 1, int(y.max()) + 1
    yy, xx = np.divmod(np.arange(ny * nx), nx)
    # pyUSID lists the columns slowest first ([Y, X]); BGlib writes [X, Y]: rows X fastest either way.
    if idx.shape[0] != ny * nx or np.any(x != xx) or np.any(y != yy):
        raise UserError(f"{path}: USID positions must be a full grid with X fastest")
    return f, (ny, nx), main.shape


def _metadata(root) -> dict:
    """Cantilever metadata: root attributes, else the first ``Measurement_*`` group's, under
    pfmdyn's names or Asylum's (as pycroscopy's translators keep them)."""
    found = {}
    groups = [root] + [root[k] for k in sorted(root.keys()) if k.startswith("Measurement")]
    for group in groups:
        attrs = dict(group.attrs)
        asylum, _ = cantilever_fields(attrs)
        for key in METADATA:
            value = attrs.get(key, asylum.get(key))
            if value is not None and key not in found:
                found[key] = value
    return found


def open_map(path: str, overrides: dict | None = None) -> MapInput:
    """Read the map's layout, frequencies and metadata (``overrides`` win over the file's)."""
    if not os.path.exists(path):
        raise UserError(f"{path}: no such file or directory")
    with open_root(path) as root:
        usid = None if "response" in root else _usid_main(root)
        if usid is None:
            for name in ("response", "frequency_hz"):
                if name not in root:
                    raise UserError(f"{path}: missing dataset '{name}' (plain layout: response, frequency_hz;"
                                    " or a USID main dataset)")
            f = np.asarray(root["frequency_hz"][...], float)
            shape = root["response"].shape
            if len(shape) != 3 or shape[2] != f.size:
                raise UserError(f"{path}: response must have shape (ny, nx, {f.size}), got {shape}")
            grid = shape[:2]
        else:
            f, grid, shape = _usid_grid(root, usid, path)
            if shape != (grid[0] * grid[1], f.size):
                raise UserError(f"{path}: USID main dataset has shape {shape}, expected ({grid[0] * grid[1]}, {f.size})")
        attrs = _metadata(root)
    attrs.update(overrides or {})
    missing = [key for key in METADATA if key not in attrs]
    if missing:
        raise UserError(f"{path}: missing metadata {', '.join(missing)} (root attributes or command-line options)")
    if not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(np.diff(f) <= 0):
        raise UserError(f"{path}: frequency_hz must be positive, finite and increasing")
    meta = {short: float(attrs[key]) for key, short in METADATA.items()}
    return MapInput(path, BeamMapModel(frequency_hz=f, **meta), tuple(grid),
                    usid or "response", "usid" if usid else "plain")


def read_block(source: MapInput, ys: slice, xs: slice) -> np.ndarray:
    """Spectra of the pixel block ``[ys, xs]``, shape ``(by, bx, n_freq)`` complex."""
    with open_root(source.path) as root:
        data = root[source.dataset]
        if source.layout == "plain":
            return np.asarray(data[ys, xs, :])
        nx = source.shape[1]
        rows = range(*ys.indices(source.shape[0]))
        x0, x1, _ = xs.indices(nx)
        return np.stack([np.asarray(data[y * nx + x0:y * nx + x1, :]) for y in rows])
