"""Asylum Research ``.ibw`` files (Igor binary waves), read with :mod:`igor2`.

An Asylum image is one wave of shape ``(x, y, layers)``: each layer a channel named in the
wave's dimension labels, the instrument's settings in the wave note (see
:mod:`pfmdyn.io.asylum`).  Waves whose first dimension is in Hz are spectra.
"""
from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from ..errors import MissingExtraError, UserError
from . import asylum
from .record import (
    InstrumentRecord,
    decode_text,
    make_channel,
    make_record,
    si_spectrum,
    si_unit,
)

__all__ = ["read_ibw"]


def _text(value) -> str:
    """igor2 gives units and labels as bytes or arrays of single bytes (UTF-8 from Igor 7 on)."""
    if isinstance(value, np.ndarray):
        value = b"".join(v if isinstance(v, bytes) else bytes(v) for v in value.ravel())
    if isinstance(value, bytes):
        value = decode_text(value.split(b"\0")[0])
    return str(value).strip()


def _load(path: Path) -> dict:
    try:
        from igor2 import binarywave
    except ImportError:
        raise MissingExtraError("igor2", "files") from None
    # On a short data block igor2 logs the whole raw buffer and returns bytes: silence it, check below.
    logger = logging.getLogger("igor2")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    raw = path.read_bytes()
    version = _version(raw)
    if version == 7:
        # Igor Pro 8+ long names: a version-5 layout with variable-length names after it,
        # which igor2 does not accept; its fixed sections read as version 5.
        order = "little" if raw[0] == 7 else "big"
        raw = (5).to_bytes(2, order) + raw[2:]
    try:
        loaded = binarywave.load(io.BytesIO(raw))
        wave = dict(loaded["wave"], version=version)
    except Exception as exc:    # igor2 raises struct, value and index errors on damaged files
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise UserError(f"{path}: not a readable Igor binary wave (truncated or damaged?): {reason}") from None
    finally:
        logger.setLevel(level)
    _check_length(path, wave)
    if int(np.ravel(wave["wave_header"].get("type", 1))[0]) == 0:
        raise UserError(f"{path}: a text wave (Igor type 0), not measured data")
    data = wave.get("wData")
    header = wave["wave_header"]
    # versions 1-3 (Igor 1-4) are one-dimensional: npnts instead of nDim
    expected = (int(np.prod([n for n in np.ravel(header["nDim"]) if n > 0] or [0])) if "nDim" in header
                else int(np.ravel(header.get("npnts", 0))[0]))
    if not isinstance(data, np.ndarray) or data.dtype.kind not in "iufc" or data.size != expected:
        raise UserError(f"{path}: not a readable Igor binary wave (truncated or damaged?): "
                        f"the data block does not hold the {expected} points its header announces")
    return wave


def _version(raw: bytes) -> int:
    """The file's version (first two bytes, either byte order); 0 if neither reads as one."""
    for order in ("little", "big"):
        version = int.from_bytes(raw[:2], order)
        if version in (1, 2, 3, 5, 7):
            return version
    return 0


def _check_length(path: Path, wave: dict) -> None:
    """A version-5 file is at least as long as its header's section sizes add up to."""
    sizes = wave.get("bin_header", {})
    if "dimLabelsSize" not in sizes:
        return
    keys = ("wfmSize", "formulaSize", "noteSize", "dataEUnitsSize", "dimEUnitsSize", "dimLabelsSize",
            "sIndicesSize", "optionsSize1", "optionsSize2")
    needed = 64 + sum(int(np.sum(sizes.get(k, 0))) for k in keys)
    if path.stat().st_size < needed:
        raise UserError(f"{path}: not a readable Igor binary wave (truncated or damaged?): "
                        f"{path.stat().st_size} bytes, its header announces {needed}")


def _dimension_units(wave: dict, ndim: int) -> list[str]:
    """Each dimension's unit: in the header (up to 3 bytes) or, longer, in the extended units.

    igor2 gives the extended units of all dimensions as one byte string; the header's
    ``dimEUnitsSize`` says where each ends.
    """
    header = wave["wave_header"]
    extended = wave.get("dimension_units") or b""
    if isinstance(extended, bytes):
        sizes = np.cumsum([0] + [int(n) for n in np.ravel(wave.get("bin_header", {}).get("dimEUnitsSize", [0] * 4))])
        extended = [extended[sizes[i]:sizes[i + 1]] for i in range(len(sizes) - 1)]
    units = []
    for i in range(ndim):
        unit = ""
        if "dimUnits" in header:        # version 5: 4 bytes per dimension
            unit = _text(np.asarray(header["dimUnits"])[i])
        elif i == 0 and "xUnits" in header:
            unit = _text(header["xUnits"])
        if not unit and i < len(extended):
            unit = _text(extended[i])
        units.append(unit)
    return units


def _data_unit(wave: dict) -> str:
    return _text(wave.get("data_units") or b"") or _text(wave["wave_header"].get("dataUnits", b""))


_SECTIONS = ("wfmSize", "formulaSize", "noteSize", "dataEUnitsSize", "dimEUnitsSize")


def _file_labels(path: Path, wave: dict, dim: int) -> list[str] | None:
    """Dimension labels of a version-5 file, read from the file itself.

    Each label is a 32-byte field ending in NUL; Igor leaves whatever was in its buffer after
    the NUL, and igor2 joins those stale bytes to the label (``PhaseRetrace`` + ``race``).
    The labels follow the header, data, formula, note and extended units.
    """
    sizes = wave.get("bin_header", {})
    if "dimLabelsSize" not in sizes or wave.get("version") not in (5, 7):
        return None
    lengths = [int(n) for n in np.ravel(sizes["dimLabelsSize"])]
    offset = 64 + sum(int(np.sum(sizes.get(k, 0))) for k in _SECTIONS) + sum(lengths[:dim])
    with open(path, "rb") as fh:
        fh.seek(offset)
        raw = fh.read(lengths[dim])
    if wave["version"] == 7:        # each label as long as it is, NUL-terminated
        return [decode_text(label).strip() for label in raw.split(b"\0")[:-1]]
    return [decode_text(raw[i:i + 32].split(b"\0")[0]).strip() for i in range(0, len(raw) - 31, 32)]


def _labels(path: Path, wave: dict, dim: int, count: int) -> list[str] | None:
    """Names of the ``count`` entries along dimension ``dim`` (Asylum layers or columns); None if unlabelled."""
    names = _file_labels(path, wave, dim)
    if names is None:       # other versions: igor2's reading, stale bytes cut after Trace/Retrace
        labels = wave.get("labels") or []
        names = [asylum.channel_name(_text(b)) for b in labels[dim]] if len(labels) > dim else []
    # Entry 0 labels the dimension itself; entries 1.. its entries.
    names = names[1:]
    if not any(names):
        return None
    return [names[i] if i < len(names) and names[i] else f"channel{i}" for i in range(count)]


def _is_image(data: np.ndarray, units: list, note: dict) -> bool:
    """x and y lengths (any prefix), or the note's scan size matching the first two dimensions."""
    if data.ndim < 2 or min(data.shape[:2]) < 2:
        return False
    if all((si_unit(u) or ("",))[0] == "m" for u in units[:2]):
        return True
    return note.get("ScanPoints") == str(data.shape[0]) and note.get("ScanLines") == str(data.shape[1])


def _axis(wave: dict, dim: int, n: int) -> np.ndarray:
    """Values along dimension ``dim`` from the wave's scaling (start, step), in its own unit."""
    header = wave["wave_header"]
    start = np.ravel(header.get("sfB", header.get("hsB", 0.0)))
    step = np.ravel(header.get("sfA", header.get("hsA", 1.0)))
    return float(start[min(dim, start.size - 1)]) + float(step[min(dim, step.size - 1)]) * np.arange(n)


def read_ibw(path) -> InstrumentRecord:
    """Read an Asylum ``.ibw`` file: channels with units and the cantilever fields of its note.

    Layers (or columns) named by dimension labels are channels; an unlabelled wave is one
    channel.  A first (or, for images, third) dimension in a frequency unit makes a spectrum.
    """
    path = Path(path)
    wave = _load(path)
    data = np.asarray(wave.get("wData"))
    if data.size == 0:
        raise UserError(f"{path}: the wave holds no data")
    name = _text(wave["wave_header"].get("bname", b"")) or path.stem
    note = asylum.parse_note(decode_text(wave.get("note", b"")))
    found, notes = asylum.cantilever_fields(note)
    units = _dimension_units(wave, data.ndim)
    in_hz = [(si_unit(u) or ("",))[0] == "Hz" for u in units]
    image = _is_image(data, units, note)
    layer_dim = 2 if image else 1
    labels = _labels(path, wave, layer_dim, data.shape[layer_dim]) if data.ndim == layer_dim + 1 else None
    names, shape = (labels, data.shape[:layer_dim]) if labels else ([name], data.shape)
    named = [(label, asylum.layer_unit(label, _data_unit(wave))) for label in names]
    channels = [make_channel(label, unit, shape) for label, unit in named]
    spectrum = None
    if data.ndim == 3 and in_hz[2] and not labels:
        kind = "spectrum"        # a spectrum at each pixel (band excitation, tune maps)
        f = _axis(wave, 2, data.shape[2]) * si_unit(units[2])[1]
        notes.append(f"a spectrum of {data.shape[2]} frequencies ({f[0]:.6g} to {f[-1]:.6g} Hz) at each "
                     f"of {data.shape[0]} x {data.shape[1]} pixels")
    elif image:
        kind = "image"
        if data.ndim > 2 and not labels:
            notes.append(f"a stack of {data.shape[2]} images along '{units[2] or 'index'}'")
        notes += asylum.dart_note(names, note)
    elif in_hz[0]:
        kind = "spectrum"
        values = data if data.ndim == 1 else data.reshape(data.shape[0], -1)[:, 0]
        if data.ndim > 1 and not labels:
            notes.append(f"{data.size // data.shape[0]} spectra in the wave; the record's spectrum is the first")
        spectrum = si_spectrum(path, _axis(wave, 0, data.shape[0]), units[0], values, named[0][1])
    else:       # force curves and other waves against time or distance
        kind = "curve"
    for dim, unit in enumerate(units):
        if unit and si_unit(unit) is None:
            notes.append(f"dimension {dim} is in '{unit}', which pfmdyn cannot convert to SI; "
                         "not taken as a frequency or length axis")
    # Asylum's software writes its settings in the note; other Igor waves are said to be just that.
    asylum_note = bool(found) or any(key in note for key in ("ImagingMode", "ScanSize", "MicroscopeModel"))
    instrument = "Asylum Research (Igor binary wave)" if asylum_note else "Igor binary wave"
    return make_record(path, kind, instrument, channels, found, notes, spectrum)
