"""Drive-frequency sweeps written as text: Cytomass/pyIMD ``.txt`` and Nanonis ``.dat``.

Both are ``key<TAB>value`` header lines followed by a tab-separated table whose column
names carry their units, ``Amplitude (V)``:

* Cytomass ``.txt``: the table follows the line ``Sweep data``; header keys end in a colon
  (``Q factor:``, ``Peak amplitude frequency (Hz):``).
* Nanonis oscillation control ``.dat``: the table follows ``[DATA]``; the frequency is
  ``OC M1 Center Freq. (Hz)`` plus ``OC M1 Freq. Shift (Hz)``; the fit is ``f_res (Hz)``, ``Q``.

No library of the field reads the Cytomass format, and the Nanonis one is a plain table, so
this module parses both directly (with :mod:`numpy`).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..names import checked
from .kinds import SWEEP_TABLE_STARTS
from .record import (
    FIELDS,
    InstrumentRecord,
    make_channel,
    make_record,
    si_spectrum,
    si_unit,
    si_value,
)

__all__ = ["read_sweep", "read_sweep_table", "SweepTable", "split_unit"]

# Header key (colon and unit stripped) -> pfmdyn field.  The resonance is the free lever's (in liquid).
_KEYS = {"Peak amplitude frequency": "amplitude_peak", "Q factor": "free_quality_factor",
         "f_res": "free_resonance", "Q": "free_quality_factor"}
# Cytomass's peak-amplitude frequency is where the measured amplitude peaks, not the resonance: read as
# ``amplitude_peak``, beside which a fit's peak is put (never its resonance).
_PEAK_KEY = "Peak amplitude frequency"
# Nanonis's input calibration: the amplitude column is in metres only through it; 1 m/V means volts as read.
_CALIBRATION_KEY = "Oscillation Control>Input Calibration"
# Header keys naming the fluid around the lever (``air``, ``water`` or ``DENSITY,VISCOSITY``).
_MEDIUM_KEYS = ("Medium", "Environment")


@dataclass(frozen=True)
class SweepTable:
    """A drive sweep as measured: ``frequency_hz``, the response ``amplitude`` in ``unit`` (SI when
    pfmdyn knows the unit), ``phase_deg`` (None: the file has amplitude only), the header's own fit
    ``fields`` (``free_resonance``, ``free_quality_factor``), ``medium`` (the header's word, None when
    it does not say), ``instrument`` and ``notes``."""

    path: str
    frequency_hz: np.ndarray
    amplitude: np.ndarray
    unit: str
    phase_deg: np.ndarray | None
    fields: dict
    medium: str | None
    instrument: str
    notes: tuple = ()

    @property
    def header_frequency(self) -> tuple[str, float] | None:
        """The header's own frequency and what it is: ``free_resonance`` (Nanonis ``f_res``) or
        ``amplitude_peak`` (Cytomass, Nanosurf); None when the header has neither.

        >>> SweepTable("s.txt", np.array([1.0]), np.array([2.0]), "V", None, {"amplitude_peak": 7e4}, None, "x").header_frequency
        ('amplitude_peak', 70000.0)
        """
        return next(((k, self.fields[k]) for k in ("free_resonance", "amplitude_peak") if k in self.fields), None)

    @property
    def response(self) -> np.ndarray:
        """The complex response ``amplitude exp(i phase)`` (the amplitude itself without a phase).

        >>> t = SweepTable("s.txt", np.array([1.0]), np.array([2.0]), "V", np.array([90.0]), {}, None, "x")
        >>> complex(t.response[0]).imag
        2.0
        """
        if self.phase_deg is None:
            return self.amplitude
        return self.amplitude * np.exp(1j * np.radians(self.phase_deg))


def split_unit(column: str) -> tuple[str, str]:
    """``'Amplitude (V)'`` -> ``('Amplitude', 'V')``; no parentheses -> unit ''.

    >>> split_unit("OC M1 Freq. Shift (Hz)"), split_unit("Index")
    (('OC M1 Freq. Shift', 'Hz'), ('Index', ''))
    """
    match = re.fullmatch(r"\s*(.*?)\s*\(([^()]*)\)\s*", column)
    return (match.group(1), match.group(2)) if match else (column.strip(), "")


def _split(path: Path) -> tuple[dict, list[str], np.ndarray]:
    try:
        lines = re.split(r"\r\n|\r|\n", path.read_text(encoding="latin-1"))
    except OSError as exc:
        raise UserError(f"{path}: cannot read the file ({exc})") from None
    starts = [i for i, line in enumerate(lines) if line.strip() in SWEEP_TABLE_STARTS]
    if not starts or starts[0] + 1 >= len(lines):
        raise UserError(f"{path}: not a drive sweep (no 'Sweep data' or '[DATA]' line before a table)")
    header = {}
    for line in lines[:starts[0]]:
        cells = [c.strip() for c in line.split("\t")]
        if len(cells) >= 2 and cells[0] and cells[1]:
            header[cells[0].rstrip(":").strip()] = cells[1]
    columns = [c.strip() for c in lines[starts[0] + 1].split("\t") if c.strip()]
    rows = []
    for n, line in enumerate(lines[starts[0] + 2:], start=1):
        cells = [c for c in line.strip().split("\t") if c.strip()]
        if not cells:
            continue
        try:
            row = [float(c) for c in cells]
        except ValueError:
            raise UserError(f"{path}: table row {n} is not numbers: {line.strip()[:60]!r}") from None
        if len(row) != len(columns):
            raise UserError(f"{path}: table row {n} has {len(row)} values for {len(columns)} columns")
        rows.append(row)
    if not rows:
        raise UserError(f"{path}: the sweep table has no rows")
    return header, columns, np.array(rows)


def _parse(path: Path):
    """Header fields, their notes, the table's columns as (name, unit), the table and the drive frequency."""
    header, columns, table = _split(path)
    names = [split_unit(c) for c in columns]
    found, notes = {}, []
    for key, value in header.items():
        name, unit = split_unit(key)
        if name in _KEYS:
            # A unit in the key ('(kHz)') scales the value; a unit of the wrong kind is reported.
            number = si_value(f"{value} {unit}", FIELDS[_KEYS[name]][1])
            if number is None and value.strip().lower() != "nan":
                notes.append(f"header '{key}' = {value!r} not understood as {FIELDS[_KEYS[name]][1] or 'a number'}")
            elif number is not None:
                try:        # a header value no lever has (a Q of -3) is no fit of the instrument's to compare with
                    found.setdefault(_KEYS[name], checked(_KEYS[name], number))
                except UserError as exc:
                    notes.append(f"header '{key}' = {value.strip()} left out: {exc}")
    converted = [si_unit(unit) for _, unit in names]
    hz = [i for i, c in enumerate(converted) if c and c[0] == "Hz"]
    if not hz:
        raise UserError(f"{path}: no frequency column (a column in Hz or kHz) in the sweep table")
    # Nanonis gives a centre frequency and a shift from it; their sum is the drive frequency.
    frequency = sum(table[:, i] * converted[i][1] for i in hz)
    others = [i for i in range(len(names)) if i not in hz]
    nanonis = any(k.startswith("Oscillation Control") for k in header)
    instrument = "Nanonis oscillation control" if nanonis else "Cytomass frequency sweep"
    return header, found, notes, names, table, frequency, others, instrument


def _uncalibrated(header: dict, unit: str, notes: list) -> str:
    """The amplitude's unit: V where the column says metres through Nanonis's default input calibration
    of 1 m/V (none applied: the detector's volts), with a note; else ``unit``."""
    calibration = next((v for k, v in header.items() if split_unit(k)[0] == _CALIBRATION_KEY), None)
    if unit == "m" and calibration is not None and si_value(calibration, "") == 1.0:
        notes.append(f"amplitude in V: the header's input calibration is {calibration} m/V (none applied)")
        return "V"
    return unit


def read_sweep(path) -> InstrumentRecord:
    """Read a Cytomass ``.txt`` or Nanonis ``.dat`` drive sweep: channels and the resonance fit (the
    amplitude's unit as :func:`read_sweep_table` gives it).

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "s.dat")
    ...     _ = open(name, "w").write("f_res (Hz)\\t7e4\\nOscillation Control>Input Calibration (m/V)\\t1E+0\\n[DATA]\\n"
    ...                               "OC M1 Freq. Shift (Hz)\\tOC D1 Amplitude (m)\\n1e4\\t4\\n2e4\\t5\\n")
    ...     r = read_sweep(name)
    >>> [c.unit for c in r.channels], r.notes
    (['V'], ("amplitude in V: the header's input calibration is 1E+0 m/V (none applied)",))
    """
    path = Path(path)
    header, found, notes, names, table, frequency, others, instrument = _parse(path)
    units = [names[i][1] for i in others]
    if others:          # the amplitude: the first column after the frequencies
        units[0] = _uncalibrated(header, units[0], notes)
    channels = [make_channel(names[i][0], unit, (len(table),)) for i, unit in zip(others, units)]
    if "amplitude_peak" in found:
        notes.append(f"amplitude peak: the header's '{_PEAK_KEY}', where the amplitude peaks, not the resonance "
                     "(at a Q of a few they differ by per cents); pfmdyn discrepancy fits the resonance")
    spectrum = si_spectrum(path, frequency, "Hz", table[:, others[0]], units[0]) if others else None
    return make_record(path, "spectrum", instrument, channels, found, notes, spectrum)


def read_sweep_table(path) -> SweepTable:
    """A drive sweep's measured points: the first non-frequency column is the amplitude, a column in
    degrees (``Phase (deg)``) the phase; rows sorted by frequency, with the header's own fit.

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "s.txt")
    ...     _ = open(name, "w").write("Q factor:\\t3.1\\nSweep data\\nFrequency (Hz)\\tAmplitude (mV)\\tPhase (deg)\\n"
    ...                               "2e4\\t5\\t10\\n1e4\\t4\\t20\\n")
    ...     t = read_sweep_table(name)
    >>> t.frequency_hz.tolist(), t.amplitude.tolist(), t.unit, t.phase_deg.tolist(), t.fields
    ([10000.0, 20000.0], [0.004, 0.005], 'V', [20.0, 10.0], {'free_quality_factor': 3.1})
    """
    path = Path(path)
    header, found, notes, names, table, frequency, others, instrument = _parse(path)
    phases = [i for i in others if si_unit(names[i][1]) == ("deg", 1.0)]
    amplitudes = [i for i in others if i not in phases]
    if not amplitudes:
        raise UserError(f"{path}: no amplitude column in the sweep table")
    _, amplitude, unit = si_spectrum(path, frequency, "Hz", table[:, amplitudes[0]], names[amplitudes[0]][1])
    order = np.argsort(frequency, kind="stable")
    finite = np.isfinite(frequency) & np.isfinite(table[:, others]).all(axis=1)
    wrong = np.flatnonzero(~finite | (np.where(finite, frequency, 1.0) <= 0) | (np.where(finite, amplitude, 0.0) < 0))
    if wrong.size:
        row = wrong[0]
        what = ("a value that is not a finite number" if not finite[row] else "a frequency <= 0" if frequency[row] <= 0
                else "a negative amplitude (a lock-in's magnitude is >= 0)")
        raise UserError(f"{path}: table row {row + 1} holds {what}")
    if np.unique(frequency).size < len(frequency):
        raise UserError(f"{path}: the sweep repeats a drive frequency")
    medium = next((header[k] for k in _MEDIUM_KEYS if header.get(k)), None)
    phase = table[order, phases[0]] if phases else None
    unit = _uncalibrated(header, unit, notes)
    return SweepTable(str(path), frequency[order], amplitude[order], unit, phase, found, medium, instrument,
                      tuple(notes))
