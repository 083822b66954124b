"""Map inputs: the plain layout (HDF5 file or Zarr group) and pycroscopy's USID band-excitation layout.

Plain: ``response`` (ny, nx, n_freq) complex, ``frequency_hz`` (n_freq,; any order), cantilever metadata as
root attributes named as in the CSV metadata; with a bias axis ``response`` is (ny, nx, n_bias,
n_freq) and ``bias_v`` (n_bias,) gives the DC tip biases.  USID (as BGlib writes BE and BEPS
data): a main dataset (positions x spectral values, complex) whose attributes reference
``Position_Indices`` (columns labelled ``X``/``Y``, X fastest) and ``Spectroscopic_Values`` /
``Spectroscopic_Indices`` (a ``Frequency`` row, in Hz or a prefixed unit, and optionally a DC
bias row such as BGlib's ``DC_Offset``, in V or mV; spectral columns in any order); the
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
from .bias import basis
from .fit import BeamMapModel
from .sho import SHOMapModel

__all__ = ["MapInput", "open_map", "read_block", "require"]

METADATA = {"spring_constant_n_per_m": "k", "length_m": "L", "tip_height_m": "H", "free_resonance_hz": "f1"}
TIP = {"tip_position": "tip_position", "tip_mass_ratio": "tip_mass"}
"""Optional tip geometry: position over the lever length (default 1, at the free end) and mass
over the lever's (default 0)."""


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
    columns: np.ndarray | None = None
    """USID: the spectral columns in (bias, frequency) order, one row per bias step; plain: the
    order of ``frequency_hz`` that sorts it (None when already increasing)."""


class open_root:
    """Context manager giving the root group of an HDF5 file or a Zarr directory."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        if not os.path.exists(self.path):
            raise UserError(f"{self.path}: no such file or directory")
        try:
            if os.path.isdir(self.path):
                return require("zarr").open_group(self.path, mode="r")
            self._file = require("h5py").File(self.path, "r")
        except (OSError, ValueError, KeyError) as exc:   # h5py: not HDF5; zarr: no group here
            kind = "Zarr group" if os.path.isdir(self.path) else "HDF5 file"
            raise UserError(f"{self.path}: not a readable {kind} ({' '.join(str(exc).split())[:120]}); maps are read "
                            "from HDF5 files and Zarr directories") from None
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


_BIAS_LABELS = {"dcoffset", "dc", "bias", "dcbias", "vdc", "tipbias", "biasv"}
"""Spectroscopic labels of a DC bias row (lower case, without ``_``, `` `` or ``-``)."""


def _spectral_row(spec, labels, units, row, unit_si, path):
    """Values of one Spectroscopic_Values row in SI (``unit_si``: 'Hz' or 'V')."""
    unit = units[row] if row < len(units) else unit_si
    converted = si_unit(unit)
    if not converted or converted[0] != unit_si:
        raise UserError(f"{path}: USID {labels[row]} row is in {unit!r}, not in {unit_si}")
    return np.asarray(spec[row, :], float) * converted[1]


def _spectral_grid(root, main, path):
    """Frequencies, biases (or None) and the spectral columns in (bias, frequency) order.

    The columns form a full grid of the Frequency and bias steps (by their indices; a triangular
    bias waveform repeats values at different steps); other spectroscopic rows must hold one
    value.
    """
    spec = root[main.attrs["Spectroscopic_Values"]]
    labels, units = _labels(spec, "labels"), _labels(spec, "units")
    if "Frequency" not in labels:
        raise UserError(f"{path}: USID Spectroscopic_Values has no 'Frequency' row (labels {labels})")
    values = np.asarray(spec[...], float).reshape(len(labels), -1)
    index = (np.asarray(root[main.attrs["Spectroscopic_Indices"]][...]).reshape(values.shape)
             if "Spectroscopic_Indices" in main.attrs else values)
    key = [label.lower().replace("_", "").replace(" ", "").replace("-", "") for label in labels]
    rows = [labels.index("Frequency")] + [i for i, k in enumerate(key) if k in _BIAS_LABELS][:1]
    others = [labels[i] for i in range(len(labels)) if i not in rows and np.unique(values[i]).size > 1]
    if others:
        raise UserError(f"{path}: USID spectroscopic dimension(s) {', '.join(others)} vary; pfmdyn map takes "
                        "Frequency and one DC bias dimension (write one slice per file)")
    steps = [np.unique(index[i], return_inverse=True)[1].ravel() for i in rows]
    if len(rows) == 1:
        steps.append(np.zeros_like(steps[0]))     # one bias step
    n_steps = [int(s.max()) + 1 for s in steps]
    grid = np.full(n_steps[::-1], -1)             # (bias, frequency) -> column
    grid[tuple(steps[::-1])] = np.arange(values.shape[1])
    if np.any(grid < 0) or values.shape[1] != grid.size:
        raise UserError(f"{path}: USID spectral columns must form a full grid of Frequency and bias steps")
    f = _spectral_row(spec, labels, units, rows[0], "Hz", path)[grid]
    if np.any(f != f[:1]):
        raise UserError(f"{path}: USID frequencies differ between bias steps")
    order = np.argsort(f[0], kind="stable")
    bias = _spectral_row(spec, labels, units, rows[1], "V", path)[grid[:, 0]] if len(rows) > 1 else None
    return f[0][order], bias, grid[:, order]


def _usid_grid(root, name, path):
    main = root[name]
    f, bias, columns = _spectral_grid(root, main, path)
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
    if main.shape != (ny * nx, columns.size):
        raise UserError(f"{path}: USID main dataset has shape {main.shape}, expected ({ny * nx}, {columns.size})")
    return f, bias, (ny, nx), columns


def _metadata(root) -> dict:
    """Cantilever metadata: root attributes, else the first ``Measurement_*`` group's, under
    pfmdyn's names or Asylum's (as pycroscopy's translators keep them)."""
    found = {}
    groups = [root] + [root[k] for k in sorted(root.keys()) if k.startswith("Measurement")]
    for group in groups:
        attrs = dict(group.attrs)
        asylum, _ = cantilever_fields(attrs)
        for key in [*METADATA, *TIP]:
            value = attrs.get(key, asylum.get(key))
            if value is not None and key not in found:
                found[key] = value
    return found


def open_map(path: str, overrides: dict | None = None, sho: bool = False) -> MapInput:
    """Read the map's layout, frequencies, biases and metadata (``overrides`` win over the file's);
    ``sho``: for the SHO fit (:class:`pfmdyn.maps.sho.SHOMapModel`), which needs no lever metadata."""
    if not os.path.exists(path):
        raise UserError(f"{path}: no such file or directory")
    with open_root(path) as root:
        usid = None if "response" in root else _usid_main(root)
        columns = None
        if usid is None:
            for name in ("response", "frequency_hz"):
                if name not in root:
                    raise UserError(f"{path}: missing dataset '{name}' (plain layout: response, frequency_hz;"
                                    " or a USID main dataset)")
            f = np.asarray(root["frequency_hz"][...], float)
            bias = np.asarray(root["bias_v"][...], float) if "bias_v" in root else None
            shape = root["response"].shape
            expected = (f.size,) if bias is None else (bias.size, f.size)
            if len(shape) != 2 + len(expected) or shape[2:] != expected:
                raise UserError(f"{path}: response must have shape (ny, nx, {', '.join(map(str, expected))})"
                                f"{' (n_bias = len(bias_v))' if bias is not None else ''}, got {shape}"
                                f"{'; a bias axis needs a bias_v dataset' if bias is None and len(shape) == 4 else ''}")
            grid = shape[:2]
            order = np.argsort(f, kind="stable")
            # frequencies are a set: any order, sorted here (the spectra follow on reading)
            columns, f = (None, f) if np.all(order == np.arange(f.size)) else (order, f[order])
        else:
            f, bias, grid, columns = _usid_grid(root, usid, path)
        attrs = _metadata(root)
    attrs.update(overrides or {})
    if sho:
        _check_axes(path, f, bias)
        return MapInput(path, SHOMapModel(frequency_hz=f, bias_v=bias), tuple(grid), usid or "response",
                        "usid" if usid else "plain", columns)
    missing = [key for key in METADATA if key not in attrs]
    if missing:
        raise UserError(f"{path}: missing metadata {', '.join(missing)} (root attributes or command-line options)")
    _check_axes(path, f, bias)
    meta = {short: float(attrs[key]) for key, short in METADATA.items()}
    tip = {short: float(attrs[key]) for key, short in TIP.items() if key in attrs}
    if not 0.5 <= tip.get("tip_position", 1.0) <= 1.0 or not 0.0 <= tip.get("tip_mass", 0.0) < 10.0:
        raise UserError(f"{path}: tip_position must lie in [0.5, 1] (of the lever length) and tip_mass_ratio in "
                        f"[0, 10), got {tip}")
    return MapInput(path, BeamMapModel(frequency_hz=f, bias_v=bias, **meta, **tip), tuple(grid),
                    usid or "response", "usid" if usid else "plain", columns)


def _check_axes(path, f, bias):
    if not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise UserError(f"{path}: frequency_hz must be positive and finite")
    if np.any(np.diff(f) == 0):
        raise UserError(f"{path}: frequency_hz holds {f[1:][np.diff(f) == 0][0]:g} Hz twice")
    if bias is not None:
        basis(bias)                                  # one-line error unless two distinct finite biases


def read_block(source: MapInput, ys: slice, xs: slice) -> np.ndarray:
    """Spectra of the pixel block ``[ys, xs]``: ``(by, bx, n_freq)`` complex, or
    ``(by, bx, n_bias, n_freq)`` when the map has a bias axis."""
    with open_root(source.path) as root:
        data = root[source.dataset]
        if source.layout == "plain":
            block = np.asarray(data[ys, xs])
            return block if source.columns is None else block[..., source.columns]
        nx = source.shape[1]
        rows = range(*ys.indices(source.shape[0]))
        x0, x1, _ = xs.indices(nx)
        block = np.stack([np.asarray(data[y * nx + x0:y * nx + x1, :]) for y in rows])
        spectra = block[..., source.columns]              # (by, bx, n_bias, n_freq)
        return spectra if source.model.bias_v is not None else spectra[..., 0, :]
