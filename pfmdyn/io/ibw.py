"""Asylum Research ``.ibw`` files (Igor binary waves), read with :mod:`igor2`.

An Asylum image is one wave of shape ``(x, y, layers)``: each layer a channel named in the
wave's dimension labels, the instrument's settings in the wave note (see
:mod:`pfmdyn.io.asylum`).  Waves whose first dimension is in Hz are spectra.
"""
from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..errors import MissingExtraError, UserError
from . import asylum
from .record import Channel, InstrumentRecord, make_record

__all__ = ["read_ibw"]


def _text(value) -> str:
    """igor2 gives units and labels as bytes or arrays of single bytes."""
    if isinstance(value, np.ndarray):
        value = b"".join(v if isinstance(v, bytes) else bytes(v) for v in value.ravel())
    if isinstance(value, bytes):
        value = value.split(b"\0")[0].decode("latin-1")
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
    try:
        wave = binarywave.load(str(path))["wave"]
    except Exception as exc:    # igor2 raises struct, value and index errors on damaged files
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise UserError(f"{path}: not a readable Igor binary wave (truncated or damaged?): {reason}") from None
    finally:
        logger.setLevel(level)
    _check_length(path, wave)
    data = wave.get("wData")
    expected = int(np.prod([n for n in np.ravel(wave["wave_header"].get("nDim", [0])) if n > 0] or [0]))
    if not isinstance(data, np.ndarray) or data.dtype.kind not in "iufc" or data.size != expected:
        raise UserError(f"{path}: not a readable Igor binary wave (truncated or damaged?): "
                        f"the data block does not hold the {expected} points its header announces")
    return wave


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
    header = wave["wave_header"]
    extended = wave.get("dimension_units")
    units = []
    for i in range(ndim):
        unit = ""
        if "dimUnits" in header:        # version 5: 4 bytes per dimension
            unit = _text(np.asarray(header["dimUnits"])[i])
        elif i == 0 and "xUnits" in header:
            unit = _text(header["xUnits"])
        if not unit and isinstance(extended, (list, tuple)) and i < len(extended):
            unit = _text(extended[i])
        units.append(unit)
    return units


def _data_unit(wave: dict) -> str:
    return _text(wave.get("data_units") or b"") or _text(wave["wave_header"].get("dataUnits", b""))


def _labels(wave: dict, dim: int, count: int) -> list[str]:
    """Names of the ``count`` entries along dimension ``dim`` (Asylum layers or columns)."""
    labels = wave.get("labels") or []
    names = []
    if len(labels) > dim and labels[dim]:
        # Entry 0 labels the dimension itself; entries 1.. its entries.
        names = [asylum.channel_name(_text(b)) for b in list(labels[dim])[1:]]
    return [names[i] if i < len(names) and names[i] else f"channel{i}" for i in range(count)]


def _is_image(data: np.ndarray, units: list, note: dict) -> bool:
    """x and y in metres, or the note's scan size matching the first two dimensions."""
    if data.ndim < 2 or min(data.shape[:2]) < 2:
        return False
    if units[0] == units[1] == "m":
        return True
    return note.get("ScanPoints") == str(data.shape[0]) and note.get("ScanLines") == str(data.shape[1])


def read_ibw(path) -> InstrumentRecord:
    """Read an Asylum ``.ibw`` file: channels with units and the cantilever fields of its note."""
    path = Path(path)
    wave = _load(path)
    data = np.asarray(wave.get("wData"))
    name = _text(wave["wave_header"].get("bname", b"")) or path.stem
    note = asylum.parse_note(_text_note(wave.get("note", b"")))
    found = asylum.cantilever_fields(note)
    if data.size == 0:
        raise UserError(f"{path}: the wave holds no data")
    units = _dimension_units(wave, data.ndim)
    instrument = "Asylum Research (Igor binary wave)"
    spectrum = None
    if _is_image(data, units, note):
        layers = data.shape[2] if data.ndim == 3 else 1
        labels = _labels(wave, 2, layers) if data.ndim == 3 else [name]
        channels = [Channel(label, asylum.channel_unit(label) or _data_unit(wave), data.shape[:2])
                    for label in labels]
        kind = "image"
    else:
        if data.ndim == 2 and data.shape[1] > 1:    # columns named by the labels of dimension 1
            labels = _labels(wave, 1, data.shape[1])
            channels = [Channel(label, asylum.channel_unit(label) or _data_unit(wave), data.shape[:1])
                        for label in labels]
        else:
            channels = [Channel(name, _data_unit(wave), data.shape)]
        if units[0] == "Hz" and data.ndim == 1:
            header = wave["wave_header"]
            x0, dx = float(np.ravel(header.get("sfB", header.get("hsB", 0)))[0]), float(np.ravel(header.get("sfA", header.get("hsA", 1)))[0])
            spectrum = (x0 + dx * np.arange(data.size), data.astype(float), _data_unit(wave))
            kind = "spectrum"
        else:       # force curves and other waves against time or distance
            kind = "curve"
    return make_record(path, kind, instrument, channels, found, spectrum=spectrum)


def _text_note(note) -> str:
    # The note is latin-1 text with carriage-return line ends (Igor's Windows/Mac heritage).
    return note.decode("latin-1") if isinstance(note, bytes) else str(note)
