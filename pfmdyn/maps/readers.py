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

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ..cantilever import Cantilever, Contact
from ..errors import MissingExtraError, UserError
from ..io.asylum import cantilever_fields
from ..io.hdf5 import is_usid_main
from ..io.record import attribute_texts, si_unit
from ..names import CONTACT, LEVER, canonical, checked, fill_defaults
from .bias import basis
from .beam import BeamMapModel
from .spec import bands as fit_bands
from .sho import SHOMapModel

__all__ = ["MapInput", "open_map", "read_block", "require", "scalar"]

REQUIRED = ("spring_constant", "free_resonance", "length")
"""Lever metadata every map needs (names of :mod:`pfmdyn.names`); the tip geometry, tilt and the
contact's k2 policy are optional (:data:`pfmdyn.names.LEVER`, :data:`pfmdyn.names.CONTACT`), a tip
height not given the default of every command (:func:`pfmdyn.names.fill_defaults`)."""


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
    assumed: dict = field(default_factory=dict)
    """The lever's values neither the file nor the command line gave, name -> why (the defaults)."""


_READ_ERRORS = (OSError, KeyError, ValueError, TypeError, IndexError, AttributeError, RuntimeError)
"""What h5py and zarr raise on a damaged or foreign layout (a broken B-tree or chunk, a dangling
reference, a group where a dataset belongs, text where numbers belong)."""


def _reason(exc: Exception) -> str:
    """An exception as a short single line: its type and first 120 characters."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())[:120]}"


class open_root:
    """Context manager giving the root group of an HDF5 file or a Zarr directory; what the
    libraries raise on a damaged or foreign layout inside the ``with`` becomes one
    :class:`~pfmdyn.errors.UserError` naming the file."""

    def __init__(self, path):
        self.path = path

    def __enter__(self):
        if not os.path.exists(self.path):
            raise UserError(f"{self.path}: no such file or directory")
        try:
            if os.path.isdir(self.path):
                return require("zarr").open_group(self.path, mode="r")
            self._file = require("h5py").File(self.path, "r")
        except UserError:       # the library not installed: already one line
            raise
        except (OSError, ValueError, KeyError) as exc:   # h5py: not HDF5; zarr: no group here
            kind = "Zarr group" if os.path.isdir(self.path) else "HDF5 file"
            raise UserError(f"{self.path}: not a readable {kind} ({' '.join(str(exc).split())[:120]}); maps are read "
                            "from HDF5 files and Zarr directories") from None
        return self._file

    def __exit__(self, kind, exc, traceback):
        if hasattr(self, "_file"):
            self._file.close()
        if isinstance(exc, _READ_ERRORS) and not isinstance(exc, UserError):
            raise UserError(f"{self.path}: could not interpret the file ({_reason(exc)})") from None


def _usid_main(root):
    """Name of the first USID main dataset (:func:`pfmdyn.io.hdf5.is_usid_main`), or None."""
    found = []
    if hasattr(root, "visititems"):
        root.visititems(lambda name, obj: found.append(name) if is_usid_main(obj) else None)
    return found[0] if found else None


def _labels(table, key) -> list[str]:
    return attribute_texts(table.attrs.get(key, []))


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
    """Lever and contact metadata by name (:mod:`pfmdyn.names`; older spellings are read too):
    root attributes, else the first ``Measurement_*`` group's, under pfmdyn's names or Asylum's
    (as pycroscopy's translators keep them)."""
    found = {}
    groups = [root] + [root[k] for k in sorted(root.keys()) if k.startswith("Measurement")]
    for group in groups:
        attrs = dict(group.attrs)
        asylum, _ = cantilever_fields(attrs)
        for key, value in [*attrs.items(), *asylum.items()]:
            name = canonical(key)
            if name in LEVER + CONTACT and name not in found:
                found[name] = value
    return found


MIN_BAND = 3
"""Frequencies a band needs: its complex amplitude takes two real numbers of the band's
``2 n`` and k1, Q the rest (with fewer the fit reports a resonance the data cannot determine)."""


def _plain_axes(root, path):
    """Frequencies, biases (or None), pixel grid and sorting order of the plain layout."""
    if any(key.startswith("Measurement") for key in root.keys()) and "response" not in root:
        # pycroscopy's groups without a USID main dataset: an image's channels (NSID), no frequency axis to fit
        raise UserError(f"{path}: pycroscopy groups without a spectrum per pixel (an image's channels, as NSID holds a "
                        "single-frequency scan: nothing to fit); map reads band-excitation maps (response and "
                        "frequency_hz, or USID with a Frequency dimension), contact-frequency maps and DART .ibw images")
    for name in ("response", "frequency_hz"):
        if name not in root:
            raise UserError(f"{path}: missing dataset '{name}' (plain layout: response, frequency_hz;"
                            " or a USID main dataset)")
    axes = {name: np.asarray(root[name][...]) for name in ("frequency_hz", "bias_v") if name in root}
    for name, values in axes.items():
        if values.ndim != 1 or not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
            raise UserError(f"{path}: {name} must be a 1-D array of real numbers, got shape {values.shape} "
                            f"of {values.dtype}")
    f = axes["frequency_hz"].astype(float)
    bias = axes["bias_v"].astype(float) if "bias_v" in axes else None
    response = root["response"]
    shape, dtype = response.shape, response.dtype
    if not np.issubdtype(dtype, np.number):
        raise UserError(f"{path}: response must hold complex (or real) numbers, got {dtype}")
    expected = (f.size,) if bias is None else (bias.size, f.size)
    if len(shape) != 2 + len(expected) or shape[2:] != expected:
        raise UserError(f"{path}: response must have shape (ny, nx, {', '.join(map(str, expected))})"
                        f"{' (n_bias = len(bias_v))' if bias is not None else ''}, got {shape}"
                        f"{'; a bias axis needs a bias_v dataset' if bias is None and len(shape) == 4 else ''}")
    order = np.argsort(f, kind="stable")
    # frequencies are a set: any order, sorted here (the spectra follow on reading)
    columns, f = (None, f) if np.all(order == np.arange(f.size)) else (order, f[order])
    return f, bias, shape[:2], columns


def scalar(raw):
    """A one-element array attribute (HDF5 often stores a number so) as its element.

    >>> scalar(np.array([2.25e-4])), scalar("2")
    (np.float64(0.000225), '2')
    """
    return raw.reshape(-1)[0] if isinstance(raw, np.ndarray) and raw.size == 1 else raw


def open_map(path: str, overrides: dict | None = None, sho: bool = False) -> MapInput:
    """Read the map's layout, frequencies, biases and metadata (``overrides`` win over the file's);
    ``sho``: for the SHO fit (:class:`pfmdyn.maps.sho.SHOMapModel`), which needs no lever metadata.
    A tip height neither gives is the default (:attr:`MapInput.assumed`); its standard uncertainty
    (``overrides["tip_height_uncertainty"]``, else the assumed one's spread or 10 % of a given one, as
    ``pfmdyn stiffness`` takes it) enters k1's standard error (:attr:`BeamMapModel.tip_height_uncertainty`).

    Everything a fit needs is checked here, before anything is written: a malformed file, an
    empty or non-finite axis, inconsistent shapes or non-physical metadata are one
    :class:`~pfmdyn.errors.UserError` naming the file.

    >>> import tempfile, h5py
    >>> path = tempfile.mkdtemp() + "/be.h5"
    >>> with h5py.File(path, "w") as h:
    ...     h["response"], h["frequency_hz"] = np.ones((2, 3, 8), complex), np.linspace(3e5, 4e5, 8)
    ...     h.attrs.update(spring_constant_n_per_m=-2.0, length_m=225e-6, tip_height_m=1e-5, free_resonance_hz=75e3)
    >>> open_map(path)                              # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: .../be.h5: spring_constant must be in (0.0001, 10000] N/m, got -2.0
    >>> source = open_map(path, {"spring_constant": 2.0})
    >>> source.shape, round(source.model.tip_height_uncertainty, 12), source.assumed
    ((2, 3), 1e-06, {})
    """
    if not os.path.exists(path):
        raise UserError(f"{path}: no such file or directory")
    with open_root(path) as root:
        usid = None if "response" in root else _usid_main(root)
        f, bias, grid, columns = _plain_axes(root, path) if usid is None else _usid_grid(root, usid, path)
        attrs = _metadata(root)
    attrs.update(overrides or {})
    missing = [] if sho else [name for name in REQUIRED if name not in attrs]
    if missing:
        raise UserError(f"{path}: missing metadata {', '.join(missing)} (root attributes or command-line options)")
    _check_axes(path, grid, f, bias)
    if sho:
        return MapInput(path, SHOMapModel(frequency_hz=f, bias_v=bias), tuple(grid), usid or "response",
                        "usid" if usid else "plain", columns)
    try:
        values = {name: checked(name, scalar(attrs[name])) for name in LEVER if name in attrs}
        assumed = fill_defaults(values)
        lever = Cantilever.from_values({**values, "medium": attrs.get("medium")})
        contact = Contact(**{name: checked(name, scalar(attrs[name])) for name in CONTACT
                             if name in attrs and name != "k1"})
    except (TypeError, ValueError) as exc:      # UserError among them: named after the file, quantity kept
        raise UserError(f"{path}: {exc}", getattr(exc, "quantity", None)) from None
    from ..analysis.stiffness_report import tip_height_spread
    spread = attrs.get("tip_height_uncertainty", tip_height_spread(lever.tip_height, "tip_height" in assumed))
    model = BeamMapModel(lever, f, bias_v=bias, contact=contact, tip_height_uncertainty=spread)
    return MapInput(path, model, tuple(grid), usid or "response", "usid" if usid else "plain", columns, assumed)


def _check_axes(path, grid, f, bias):
    """One-line errors for an empty map, a bad frequency axis, too narrow a band or bad biases."""
    if 0 in grid:
        raise UserError(f"{path}: the map holds no pixels (shape {tuple(grid)})")
    if f.size == 0:
        raise UserError(f"{path}: the frequency axis is empty")
    if not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise UserError(f"{path}: frequency_hz must be positive and finite")
    if np.any(np.diff(f) == 0):
        raise UserError(f"{path}: frequency_hz holds {f[1:][np.diff(f) == 0][0]:g} Hz twice")
    narrow = [b for b in fit_bands(f) if b.stop - b.start < MIN_BAND]
    if narrow:
        raise UserError(f"{path}: the band at {f[narrow[0].start]:g} Hz holds {narrow[0].stop - narrow[0].start} "
                        f"frequencies; a band needs at least {MIN_BAND} to determine a resonance")
    try:
        basis(bias)                                  # one-line error unless two distinct finite biases
    except UserError as exc:
        raise UserError(f"{path}: {exc}", exc.quantity) from None


def read_block(source: MapInput, ys: slice, xs: slice) -> np.ndarray:
    """Spectra of the pixel block ``[ys, xs]``: ``(by, bx, n_freq)`` complex, or
    ``(by, bx, n_bias, n_freq)`` when the map has a bias axis.  A block the file cannot give
    (a damaged chunk) is one :class:`~pfmdyn.errors.UserError` naming the file and the pixels."""
    with open_root(source.path) as root:
        try:
            return _block(root[source.dataset], source, ys, xs)
        except _READ_ERRORS as exc:
            raise UserError(f"{source.path}: could not read pixels [{ys.start}:{ys.stop}, {xs.start}:{xs.stop}] "
                            f"({_reason(exc)})") from None


def _block(data, source: MapInput, ys: slice, xs: slice) -> np.ndarray:
    if source.layout == "plain":
        block = np.asarray(data[ys, xs])
        return block if source.columns is None else block[..., source.columns]
    nx = source.shape[1]
    rows = range(*ys.indices(source.shape[0]))
    x0, x1, _ = xs.indices(nx)
    block = np.stack([np.asarray(data[y * nx + x0:y * nx + x1, :]) for y in rows])
    spectra = block[..., source.columns]              # (by, bx, n_bias, n_freq)
    return spectra if source.model.bias_v is not None else spectra[..., 0, :]
