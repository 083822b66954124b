"""Nanosurf ``.nid`` files, read with :mod:`NSFopen` (the ``nsfopen`` package).

A thermal tune (``[DataSet-Info]`` section "-- Thermal Tuning --") holds the measured
amplitude spectral density ("Spectrum FFT", m/sqrt(Hz) against Hz) and the instrument's fit
("Spectrum Fit"), whose result is written as text with units: ``Frequency:=179.8kHz``,
``Q Factor:=442``, ``Spring Constant:=27.13 N/m``.  Images and spectroscopy files are
listed with their channels.
"""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import MissingExtraError, UserError
from .record import InstrumentRecord, make_channel, make_record, si_spectrum, si_value

__all__ = ["read_nid", "thermal_conditions"]

# Thermal-tune fit keys (colon and case ignored) -> (pfmdyn field, SI unit of the field).
_THERMAL_KEYS = {"frequency": ("free_resonance", "Hz"), "q factor": ("free_quality_factor", ""),
                 "spring constant": ("spring_constant", "N/m")}
# Scan settings of images and spectroscopy files.
_SCAN_KEYS = {"tip voltage": ("tip_bias", "V"), "vibration freq.": ("drive_frequency", "Hz"),
              "spring constant": ("spring_constant", "N/m")}


def _unit(text: str) -> str:
    """A unit as Nanosurf wrote it, repaired if UTF-8 was read as Latin-1; degrees as 'deg'."""
    try:
        text = text.encode("latin-1").decode("utf-8")
    except (UnicodeEncodeError, UnicodeDecodeError):
        pass
    return "deg" if text.strip() == "°" else text.strip()


def _fields(info: dict, keys: dict) -> dict:
    found = {}
    for key, value in info.items():
        target = keys.get(str(key).strip().rstrip(":").strip().lower())
        if target:
            number = si_value(value, target[1])
            if number is not None:
                found[target[0]] = number
    return found


def _load(path: Path):
    try:
        from NSFopen.read import read
    except ImportError:
        raise MissingExtraError("nsfopen", "files") from None
    try:
        with warnings.catch_warnings():
            # NSFopen calls pandas APIs that newer pandas deprecates; not the user's concern.
            warnings.simplefilter("ignore")
            return read(str(path))
    except Exception as exc:    # NSFopen raises assorted errors on files it cannot parse
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise UserError(f"{path}: not a readable Nanosurf NID file (truncated or damaged?): {reason}") from None


def _sections(nid) -> dict:
    try:
        return dict(nid.param["HeaderDump"])
    except (KeyError, TypeError):
        return {}


def _channels(nid, sections) -> list[tuple]:
    """(name tuple, data array, unit, dataset header) for each channel, in file order."""
    out = []
    keys = [k for k in sections if re.fullmatch(r"DataSet-\d+:\d+", k)]
    headers = [sections[k] for k in sorted(keys, key=lambda k: tuple(int(n) for n in re.findall(r"\d+", k)))]
    # NSFopen names a channel (group, direction, signal); a header says "Scan forward" or
    # "Spec backward" and the signal.  Match on those: files with processed data sets (force
    # curves' slopes, adhesion) hold headers NSFopen does not turn into channels.
    by_name = {}
    for header in headers:
        frame = str(header.get("Frame", "")).lower().split()
        if len(frame) == 2:
            group = {"scan": "image", "spectrum": "sweep"}.get(frame[0], frame[0])
            by_name.setdefault((group, frame[1], str(header.get("Dim2Name", "")).lower()), header)
    for i, (name, values) in enumerate(nid.data.items()):
        key = tuple(str(p).lower() for p in name) if isinstance(name, tuple) else None
        positional = headers[i] if len(headers) == len(nid.data) else {}
        header = by_name.get(key, positional)
        out.append((name, _array(values), _unit(str(header.get("Dim2Unit", ""))), header))
    return out


def _array(values) -> np.ndarray:
    """A channel as a float array; curves of unequal length (force spectroscopy stops each
    approach at its own trigger) are padded with NaN to the longest.

    >>> _array([np.ones(3), np.ones(2)]).tolist()
    [[1.0, 1.0, 1.0], [1.0, 1.0, nan]]
    """
    try:
        return np.asarray(values, dtype=float)
    except ValueError:
        rows = [np.ravel(np.asarray(v, dtype=float)) for v in values]
        out = np.full((len(rows), max(len(r) for r in rows)), np.nan)
        for i, r in enumerate(rows):
            out[i, :len(r)] = r
        return out


def read_nid(path) -> InstrumentRecord:
    """Read a Nanosurf ``.nid`` file: channels with units; for a thermal tune, its fit and spectrum."""
    path = Path(path)
    nid = _load(path)
    sections = _sections(nid)
    channels = _channels(nid, sections)
    if not channels:
        raise UserError(f"{path}: the NID file holds no data sets")
    info = sections.get("DataSet-Info", {}) or {}
    thermal = any("thermal tuning" in str(k).lower() for k in info)
    group = str(channels[0][0][0]).lower() if isinstance(channels[0][0], tuple) else ""
    found, notes, spectrum = {}, [], None
    if thermal:
        kind = "thermal spectrum"
        found = _fields(info, _THERMAL_KEYS)
        name, data, unit, header = channels[0]
        n = data.shape[-1]
        f0 = float(header.get("Dim0Min", 0.0))
        frequency = f0 + np.linspace(0.0, float(header.get("Dim0Range", n - 1)), n)
        spectrum = si_spectrum(path, frequency, _unit(str(header.get("Dim0Unit", ""))) or "Hz",
                               data.reshape(-1, n)[0], unit)
        lever = info.get("Cantilever type")
        if lever:
            notes.append(f"cantilever type {lever}: its length and width are not in the file")
    else:
        kind = "image" if group.startswith("image") else "curve" if group.startswith("spec") else "spectrum"
        found = _fields(info, _SCAN_KEYS)
        curves = [data for name, data, _, _ in channels
                  if isinstance(name, tuple) and str(name[0]).lower().startswith("spec")]
        if kind == "image" and curves:
            notes.append(f"also holds {len(curves[0])} spectroscopy curves per channel")
    listed = [make_channel(" ".join(str(p) for p in name) if isinstance(name, tuple) else str(name), unit,
                      data.shape[1:] if data.ndim > 1 and data.shape[0] == 1 else data.shape)
              for name, data, unit, _ in channels]
    return make_record(path, kind, "Nanosurf (NID)", listed, found, notes, spectrum)


def thermal_conditions(path) -> dict:
    """What a thermal tune's header says of its conditions: ``temperature`` (K, from the "Cantilever
    temperature" in degrees C) and ``environment`` (``"air"``, ``"liquid"``, lower case), each when written.

    >>> thermal_conditions("missing.nid")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: missing.nid: no such file
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    info = _sections(_load(path)).get("DataSet-Info", {}) or {}
    out = {}
    for key, value in info.items():
        key = str(key).strip().rstrip(":").lower()
        if key == "cantilever temperature":
            match = re.fullmatch(r"\s*([-+0-9.eE]+)\s*(.*)", str(value))
            unit = _unit(match.group(2)) if match else ""
            if match and unit in ("°C", "deg", "degC", "C"):
                out["temperature"] = float(match.group(1)) + 273.15
            elif match and unit == "K":
                out["temperature"] = float(match.group(1))
        elif key == "measurement environment":
            out["environment"] = str(value).strip().lower()
    return out
