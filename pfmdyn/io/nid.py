"""Nanosurf ``.nid`` files, read with :mod:`NSFopen` (the ``nsfopen`` package).

A thermal tune (``[DataSet-Info]`` section "-- Thermal Tuning --") holds the measured
amplitude spectral density ("Spectrum FFT", m/sqrt(Hz) against Hz) and the instrument's fit
("Spectrum Fit"), whose result is written as text with units: ``Frequency:=179.8kHz``,
``Q Factor:=442``, ``Spring Constant:=27.13 N/m``.  A drive sweep ("Frequency sweep", the
Bode plot of the lever's resonance) holds the amplitude against the drive frequency and the
peak the software found (``Freq. peak=179.405kHz``).  Images and spectroscopy files are
listed with their channels.

Files of older software (easyScan 2) declare more channels per group than they store, which
NSFopen cannot read; such files are read from the layout itself: an INI header up to ``#!``,
then each listed data set as ``Points x Lines`` signed little-endian integers of ``SaveBits``,
scaled onto ``Dim2Min + [0, Dim2Range]``.
"""
from __future__ import annotations

import gc
import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import MissingExtraError, UserError
from .record import InstrumentRecord, make_channel, make_record, si_spectrum, si_value
from .sweeps import SweepTable

__all__ = ["read_nid", "thermal_conditions", "read_sweep_table"]

# Thermal-tune fit keys (colon and case ignored) -> (pfmdyn field, SI unit of the field).
_THERMAL_KEYS = {"frequency": ("free_resonance", "Hz"), "q factor": ("free_quality_factor", ""),
                 "spring constant": ("spring_constant", "N/m")}
# Scan settings of images and spectroscopy files.
_SCAN_KEYS = {"tip voltage": ("tip_bias", "V"), "vibration freq.": ("drive_frequency", "Hz"),
              "freq. peak": ("free_resonance", "Hz"),
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
    with warnings.catch_warnings():
        # NSFopen calls pandas APIs that newer pandas deprecates; not the user's concern.
        warnings.simplefilter("ignore")
        try:
            return read(str(path))
        except Exception as exc:    # NSFopen raises assorted errors on files it cannot parse
            reason = " ".join(str(exc).split()) or type(exc).__name__
        # a failed read leaves its file open: closed here, not at exit with a ResourceWarning on the terminal
        gc.collect()
    raise UserError(f"{path}: not a readable Nanosurf NID file (truncated or damaged?): {reason}")


def _open(path: Path, tune_from_layout: bool = False) -> tuple[dict, list[tuple]]:
    """The header's sections and the channels, (name, data, unit, header) in file order: by NSFopen,
    or from the layout when NSFopen cannot read the file or finds no channel in it.
    ``tune_from_layout``: a thermal tune from its layout when it can be read, for a caller that needs
    the header and the spectra but not NSFopen's channel names (the same numbers, without importing
    NSFopen's pandas: a fifth of a second of a command)."""
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    if tune_from_layout:
        try:
            sections, channels = _read_layout(path)
        except UserError:
            sections = {}
        if _is_thermal(sections):
            return sections, channels
    try:
        nid = _load(path)
    except MissingExtraError:
        raise
    except UserError:
        return _read_layout(path)
    sections = _sections(nid)
    channels = _channels(nid, sections)
    return (sections, channels) if channels else _read_layout(path)


def _ini(text: str) -> dict:
    """``[Section]`` -> {key: value} of an INI header; lines without ``=`` carry nothing."""
    sections, current = {}, None
    for line in re.split(r"\r\n|\r|\n", text):
        line = line.strip()
        if line.startswith("[") and line.endswith("]"):
            current = sections.setdefault(line[1:-1], {})
        elif current is not None and "=" in line:
            key, value = line.split("=", 1)
            current[key] = value.strip()
    return sections


def _read_layout(path: Path) -> tuple[dict, list[tuple]]:
    """Sections and channels read from the documented layout (see the module's docstring).

    >>> import tempfile, os
    >>> header = ("[DataSet]\\r\\nGroupCount=1\\r\\nGr0-Count=3\\r\\nGr0-Ch2=DataSet-0:2\\r\\n"
    ...           "[DataSet-0:2]\\r\\nPoints=2\\r\\nLines=1\\r\\nFrame=Frequency sweep\\r\\n"
    ...           "Dim2Name=Amplitude\\r\\nDim2Unit=V\\r\\nDim2Range=20\\r\\nDim2Min=-10\\r\\nSaveBits=16\\r\\n#!")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "sweep.nid")
    ...     _ = open(name, "wb").write(header.encode() + np.array([-32768, 0], "<i2").tobytes())
    ...     sections, channels = _read_layout(Path(name))
    >>> channels[0][0], channels[0][1].tolist(), channels[0][2]
    (('Frequency sweep', 'Amplitude'), [[-10.0, 0.0]], 'V')
    """
    raw = path.read_bytes()
    start = raw.find(b"#!")
    if not raw.startswith(b"[DataSet]") or start < 0:
        missing = "[DataSet] header" if not raw.startswith(b"[DataSet]") else "'#!' mark before the data"
        raise UserError(f"{path}: not a readable Nanosurf NID file: no {missing}")
    sections = _ini(raw[:start].decode("latin-1"))
    listing = sections.get("DataSet", {})
    offset, channels = start + 2, []
    try:
        for group in range(int(listing["GroupCount"])):
            for slot in range(int(listing.get(f"Gr{group}-Count", 0))):
                # easyScan 2 counts channels it did not save; only those listed are stored.
                name = listing.get(f"Gr{group}-Ch{slot}")
                if name is None:
                    continue
                header = sections[name]
                points, lines, bits = int(header["Points"]), int(header["Lines"]), int(header["SaveBits"])
                if bits not in (16, 32):
                    raise UserError(f"{path}: data set {name} is saved with {bits} bits; pfmdyn reads 16 or 32")
                count = points * max(lines, 1)
                if offset + count * bits // 8 > len(raw):
                    raise UserError(f"{path}: not a readable Nanosurf NID file: data set {name} needs "
                                    f"{count * bits // 8} bytes, {len(raw) - offset} are left (truncated?)")
                stored = np.frombuffer(raw, dtype=f"<i{bits // 8}", count=count, offset=offset)
                scale = 2.0 ** bits
                values = (stored + scale / 2) / scale * float(header.get("Dim2Range", scale)) \
                    + float(header.get("Dim2Min", -scale / 2))
                frame = str(header.get("Frame", name))
                channels.append(((frame, str(header.get("Dim2Name", ""))), values.reshape(max(lines, 1), points),
                                 _unit(str(header.get("Dim2Unit", ""))), header))
                offset += count * bits // 8
    except KeyError as exc:
        raise UserError(f"{path}: not a readable Nanosurf NID file: its header has no {exc.args[0]!r}") from None
    except UserError:
        raise
    except ValueError as exc:       # a header number that is not one
        raise UserError(f"{path}: not a readable Nanosurf NID file: {exc}") from None
    if not channels:
        raise UserError(f"{path}: the NID file holds no data sets")
    return sections, channels


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


def _is_sweep_frame(header: dict) -> bool:
    return str(header.get("Frame", "")).strip().lower().startswith("frequency sweep")


def _spectrum(path: Path, channel: tuple) -> tuple:
    """(frequency in Hz, values, unit) of a spectrum channel: its first line over ``Dim0Min + [0, Dim0Range]``."""
    _, data, unit, header = channel
    n = data.shape[-1]
    frequency = float(header.get("Dim0Min", 0.0)) + np.linspace(0.0, float(header.get("Dim0Range", n - 1)), n)
    return si_spectrum(path, frequency, _unit(str(header.get("Dim0Unit", ""))) or "Hz", data.reshape(-1, n)[0], unit)


def _is_thermal(sections: dict) -> bool:
    """Whether the header is a thermal tune's (its ``[DataSet-Info]`` lists "-- Thermal Tuning --")."""
    return any("thermal tuning" in str(k).lower() for k in sections.get("DataSet-Info", {}) or {})


def read_nid(path, tune_from_layout: bool = False) -> InstrumentRecord:
    """Read a Nanosurf ``.nid`` file: channels with units; for a thermal tune, its fit and spectrum
    (``tune_from_layout``: see :func:`_open`; the channels then have the layout's names)."""
    path = Path(path)
    sections, channels = _open(path, tune_from_layout)
    info = sections.get("DataSet-Info", {}) or {}
    thermal = _is_thermal(sections)
    group = str(channels[0][0][0]).lower() if isinstance(channels[0][0], tuple) else ""
    found, notes, spectrum = {}, [], None
    if thermal:
        kind = "thermal spectrum"
        found = _fields(info, _THERMAL_KEYS)
        spectrum = _spectrum(path, channels[0])
        lever = info.get("Cantilever type")
        if lever:
            notes.append(f"cantilever type {lever}: its length and width are not in the file")
        conditions = _conditions(info)
        if conditions:      # what calibrate and discrepancy take from the header
            notes.append("measured " + " ".join(
                ([f"in {conditions['environment']}"] if "environment" in conditions else [])
                + ([f"at {conditions['temperature'] - 273.15:g} C ({conditions['temperature']:g} K)"]
                   if "temperature" in conditions else [])))
    elif sweeps := [c for c in channels if _is_sweep_frame(c[3])]:
        kind = "spectrum"
        found = _fields(info, _SCAN_KEYS)
        spectrum = _spectrum(path, sweeps[0])
        notes.append("a drive sweep: 'Freq. peak' is the software's peak of it, not a fit")
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
    return _conditions(_open(Path(path), tune_from_layout=True)[0].get("DataSet-Info", {}) or {})


def _conditions(info: dict) -> dict:
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


def read_sweep_table(path) -> SweepTable:
    """A Nanosurf drive sweep as measured: the first "Frequency sweep" channel against the drive
    frequency, the software's peak as its fit, the medium when the header names air."""
    path = Path(path)
    record = read_nid(path)
    if record.spectrum is None or record.kind != "spectrum":
        raise UserError(f"{path}: the NID file holds no frequency sweep")
    frequency, amplitude, unit = record.spectrum
    if not (np.all(np.isfinite(amplitude)) and frequency.min() > 0 and np.all(np.diff(frequency) > 0)):
        raise UserError(f"{path}: the frequency sweep holds a non-finite value or a frequency <= 0")
    environment = thermal_conditions(path).get("environment")
    # "Liquid" does not say which liquid; the caller's --medium or default decides.
    medium = "air" if environment == "air" else None
    notes = list(record.notes) + ([f"measured in {environment}; which liquid is not written"]
                                  if environment and medium is None else [])
    # the software's "Freq. peak" is where the swept amplitude peaks: a peak, set beside our peak
    fields = {("amplitude_peak" if k == "free_resonance" else k): v for k, v in record.fields.items()}
    return SweepTable(str(path), frequency, amplitude, unit, None, fields, medium,
                      "Nanosurf frequency sweep", tuple(notes))
