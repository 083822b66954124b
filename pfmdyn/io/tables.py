"""Input of ``pfmdyn discrepancy``: cantilever metadata plus a spectrum or a resonances table.

Format (SI units)::

    # spring_constant: 2.4
    # length: 223e-6
    # width: 24e-6                  <- optional: no resonance depends on it
    # tip_height: 1e-5               <- commands assume a typical PFM probe's when none is given
    # free_resonance: 63200         <- first free flexural resonance (a table's free mode 1 row gives it too)
    # description: optional text
    frequency_hz,bias_v,x,y             <- spectrum (or amplitude,phase_deg), several biases
    ...
    mode,condition,frequency_hz         <- or resonances, condition = free | contact
    1,free,63200
    ...

A resonances table may hold free modes only (the contact springs are then not determined)
and as little as one row (the report says what it leaves undetermined). Rows may come in any
order (they are sorted by condition, then mode); a repeated (condition, mode) with a
different frequency is an error. Columns may come in any order; the frequency column may
carry its unit (``frequency_hz``, ``frequency_khz``, ``frequency_mhz``), an optional
``quality_factor`` (or ``q``) column gives each mode's Q (blank where unknown, ``inf`` for a
mode measured without damping), and an optional ``quality_factor_uncertainty`` metadata key
its relative uncertainty (default 5 %). Any other column is left out, and the commands say so
(:func:`ignored_note`); so is one beside a spectrum's columns.

Spellings are forgiven as for spectra (:mod:`pfmdyn.io.columns`): separators, ``%`` comments,
``key = value``, values with their unit (``length: 223 um``, ``f1: 63.2 kHz``), the older
key spellings (``length_m``, ``free_resonance_hz``: :func:`pfmdyn.names.canonical`),
conditions ``air``/``non-contact`` and ``in contact``.  Metadata outside any cantilever's
range, and frequencies far from ``free_resonance``, are errors: they are in another unit than
the file says.

:func:`read` reads these CSV files; ``overrides`` (metadata keys, from the command line)
win over the file's values.  Instrument files (.ibw, .nid, .h5/.hdf5 and drive sweeps
.txt/.dat: :data:`pfmdyn.io.kinds.INSTRUMENT_KINDS`) give their resonance table through
:func:`pfmdyn.analysis.thermal.instrument_resonances` (a thermal tune's peaks are fitted
there); :func:`pfmdyn.discrepancy.inputs.read` takes either kind.

Spectra are read by :func:`pfmdyn.io.spectra.read_spectra` (it owns the spectrum rules);
this module checks the metadata, rejects unknown columns and too little data.  Every
problem is one :class:`~pfmdyn.errors.UserError` line.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..names import NAMES, canonical, checked
from .discrepancy_data import Metadata, ResonanceData, SpectrumData
from .columns import column, metadata_number, read_table
from .record import MissingFieldError
from .spectra import read_spectra
from .kinds import INSTRUMENT_KINDS, file_kind

__all__ = ["REQUIRED_KEYS", "Metadata", "SpectrumData", "ResonanceData", "read", "check_resonance_rows", "ignored_note"]

REQUIRED_KEYS = ("spring_constant", "length", "tip_height", "free_resonance")
OPTIONAL_KEYS = ("width", "frequency_uncertainty_hz", "quality_factor_uncertainty")
"""The width is read when given but never required: no resonance depends on it."""
RESONANCE_COLUMNS = ("mode", "condition", "frequency_hz")
OPTIONAL_RESONANCE_COLUMNS = ("quality_factor",)
FREQUENCY_UNITS = {"frequency_hz": 1.0, "frequency_khz": 1e3, "frequency_mhz": 1e6}
"""Frequency column names of a resonances table and their factor to Hz."""
COLUMN_ALIASES = {"q": "quality_factor", "quality": "quality_factor", "q_factor": "quality_factor",
                  "cond": "condition", "state": "condition", "boundary_condition": "condition",
                  "mode_number": "mode", "mode_no": "mode", "mode_index": "mode"}
CONDITION_ALIASES = {"air": "free", "non_contact": "free", "noncontact": "free", "out_of_contact": "free",
                     "in_contact": "contact", "engaged": "contact"}
SPECTRUM_BAND, TABLE_BAND = (0.05, 200.0), (0.3, 200.0)
"""Where measured frequencies lie, in units of the free resonance f1: a spectrum may stay below
f1 (not 20x below); a table's modes are free mode 1 (f1) or above."""
MIN_SPECTRUM_ROWS = 20
MIN_SPECTRUM_FREQUENCIES = 10
MIN_RESONANCES = 1
"""A table may be short (e.g. free mode 1 and contact mode 1 from an image's metadata): the
discrepancy report says which parameters so few rows leave undetermined."""


def _metadata(where: str, meta: dict, overrides: dict | None = None, required=REQUIRED_KEYS) -> Metadata:
    """The file's metadata with ``overrides`` over it, checked; a key not ``required`` and not given is None."""
    meta = {canonical(key) or key: value for key, value in meta.items()}
    meta.update({canonical(key) or key: value for key, value in (overrides or {}).items() if value is not None})
    _require(where, [key for key in required if key not in meta])
    values = {}
    for key in REQUIRED_KEYS + OPTIONAL_KEYS:
        if key not in meta:
            continue
        values[key] = meta[key] if isinstance(meta[key], float) else metadata_number(where, key, str(meta[key]))
        if key in NAMES:
            values[key] = _plausible(where, key, values[key])
        elif not (math.isfinite(values[key]) and values[key] > 0):
            raise UserError(f"{where}: metadata '{key}' must be positive and finite")
    return Metadata(**{key: values.get(key) for key in REQUIRED_KEYS + OPTIONAL_KEYS},
                    description=meta.get("description", ""))


def _require(where: str, missing) -> None:
    """A :class:`~pfmdyn.io.record.MissingFieldError` naming the ``missing`` keys (a command may fill its defaults
    and read again, as for an instrument file)."""
    if missing:
        raise MissingFieldError(f"{where}: missing metadata key(s) {', '.join(missing)}"
                                f" (lines '# key: value' before the header)", tuple(missing))


def _plausible(where: str, key: str, value: float) -> float:
    """``value`` checked against the range no cantilever leaves (:func:`pfmdyn.names.checked`):
    outside it, a number in another unit (um for m, kHz for Hz), and the message says how to give it.

    >>> _plausible("d.csv", "length", 223.0)
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: d.csv: length must be in (1e-06, 0.01] m, got 223.0; give it in m (or with its unit, e.g. 'length: 223 um')
    """
    try:
        return checked(key, value, where)
    except UserError as exc:
        unit = NAMES[key].unit
        raise UserError(f"{exc}; give it in {unit} (or with its unit, e.g. '{key}: 223 um')", exc.quantity) from None


def read(path, overrides: dict | None = None, required=REQUIRED_KEYS) -> SpectrumData | ResonanceData:
    """Read a discrepancy input file (format in the module docstring).

    ``overrides``: metadata keys (:data:`REQUIRED_KEYS`) given on the command line,
    applied over the file's values; ``required``: the keys that must then be known (a caller with
    defaults of its own asks fewer; the rest are None when not given).  A resonances table's free
    mode 1 row is its free resonance when the metadata holds none.

    >>> import tempfile, os
    >>> text = ("# spring_constant: 2.4\\n# length: 2e-4\\n# width: 3e-5\\n"
    ...         "# tip_height: 1e-5\\n# free_resonance: 6e4\\nmode,condition,frequency_hz\\n"
    ...         "1,free,6e4\\n2,free,3.7e5\\n1,contact,4e5\\n")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "r.csv")
    ...     _ = open(name, "w").write(text)
    ...     data = read(name)
    >>> data.kind, data.condition.tolist()
    ('resonances', ['free', 'free', 'contact'])
    """
    path = Path(path)
    if file_kind(path) in INSTRUMENT_KINDS:
        raise UserError(f"{path}: an instrument file, not a CSV table (read its resonances with "
                        "pfmdyn.discrepancy.inputs.read)")
    table = read_table(path)
    meta, header = table.metadata, table.header
    names = [_column(c) for c in header]
    if {"mode", "condition"} & set(names):
        free_row = tuple(key for key in required if key != "free_resonance")
        return _resonances(path, _metadata(str(path), meta, overrides, free_row), names, table.rows,
                           "free_resonance" in required)
    unknown = [c for c in header if column(c) is None]
    known = {found[0] for found in map(column, header) if found}
    if unknown and not ({"frequency_hz", "bias_v"} <= known and ({"x", "y"} <= known or {"amplitude", "phase_deg"}
                                                                 <= known)):
        # Checked before the metadata: a file of another kind (e.g. a thermal ASD) is told so.
        hint = ("; give frequencies as 'frequency_hz' (or frequency_khz, frequency_mhz)"
                if any(c.lower().startswith("frequency") for c in unknown) else "")
        raise UserError(f"{path}: not a PFM spectrum or resonances table: unknown column(s) "
                        f"{', '.join(repr(c) for c in unknown)}{hint}; expected frequency_hz, bias_v and x, y or "
                        "amplitude, phase_deg (or mode, condition, frequency_hz)")
    metadata = _metadata(str(path), meta, overrides, required)
    spectra = read_spectra(path, biases_per_frequency=1)
    if len(spectra.frequency_hz) < MIN_SPECTRUM_ROWS:
        raise UserError(f"{path}: {len(spectra.frequency_hz)} data rows; at least "
                        f"{MIN_SPECTRUM_ROWS} are needed to fit the model")
    count = len(np.unique(spectra.frequency_hz))
    if count < MIN_SPECTRUM_FREQUENCIES:
        raise UserError(f"{path}: {count} distinct frequenc{'y' if count == 1 else 'ies'}; a spectrum needs at least "
                        f"{MIN_SPECTRUM_FREQUENCIES} to show its resonances")
    if not np.any(spectra.response):
        raise UserError(f"{path}: the response ({', '.join(spectra.response_columns)}) is zero in every row")
    check_band(str(path), spectra.frequency_hz, metadata.free_resonance, SPECTRUM_BAND)
    return SpectrumData(metadata, spectra.frequency_hz, spectra.bias_v, spectra.response,
                        ignored_columns=tuple(unknown))


def ignored_note(data) -> str | None:
    """The note a command prints of the columns of a table it did not read (None: every column read).

    >>> ignored_note(SpectrumData(None, None, None, None, ignored_columns=("note",)))
    "column 'note' not read (none of the table's: frequency_hz, bias_v and x, y or amplitude, phase_deg)"
    """
    columns = getattr(data, "ignored_columns", ())
    if not columns:
        return None
    expected = ("frequency_hz, bias_v and x, y or amplitude, phase_deg" if data.kind == "spectrum" else
                "mode, condition, frequency_hz and quality_factor")
    return (f"column{'s' * (len(columns) > 1)} {', '.join(repr(c) for c in columns)} not read (none of the "
            f"table's: {expected})")


def check_band(where: str, frequency_hz, f1: float, band: tuple[float, float]) -> None:
    """Frequencies outside ``band`` (multiples of the free resonance ``f1``) are in another unit
    than the column (or ``free_resonance``) says."""
    low, high = float(np.min(frequency_hz)), float(np.max(frequency_hz))
    if high < band[0] * f1 or low > band[1] * f1:
        raise UserError(f"{where}: frequencies {low:.6g}-{high:.6g} Hz lie far from the free resonance "
                        f"{f1:.6g} Hz of the metadata; check their units (frequency_hz or frequency_khz "
                        "column, free_resonance in Hz)")


def _column(name: str) -> str:
    """Canonical name of a resonances-table column (case, spaces and aliases forgiven); a
    frequency column keeps its unit (``frequency_khz``)."""
    spectral = column(name)
    if spectral and spectral[0] == "frequency_hz":
        return f"frequency_{spectral[2]}"
    key = "_".join(name.strip().lower().replace("(", " ").replace(")", " ").split())
    return COLUMN_ALIASES.get(key, key)


def _resonances(path, metadata, header, rows, free_required: bool = True) -> ResonanceData:
    freq_cols = [c for c in header if c in FREQUENCY_UNITS]
    allowed = ("mode", "condition") + tuple(FREQUENCY_UNITS) + OPTIONAL_RESONANCE_COLUMNS
    unknown = [c for c in header if c not in allowed]
    missing = [c for c in ("mode", "condition") if c not in header] + ([] if freq_cols else ["frequency_hz"])
    if missing:
        raise UserError(f"{path}: resonances table lacks the column(s) {', '.join(missing)}")
    repeated = sorted({c for c in header if header.count(c) > 1}) or freq_cols[1:]
    if repeated:
        raise UserError(f"{path}: column {repeated[0]} given more than once (one frequency column, each "
                        "column once)")
    idx = [header.index(c) for c in ("mode", "condition", freq_cols[0])]
    unit = FREQUENCY_UNITS[freq_cols[0]]
    q_idx = header.index("quality_factor") if "quality_factor" in header else None
    modes, conds, freqs, qs = [], [], [], []
    for n, cells in rows:
        if len(cells) > len(header) and not any(cells[len(header):]):
            cells = cells[:len(header)]
        if len(cells) != len(header):
            raise UserError(f"{path}, line {n}: expected {len(header)} fields, got {len(cells)}")
        mode, cond, freq = (cells[i] for i in idx)
        cond = "_".join(cond.lower().replace("-", " ").split())
        cond = CONDITION_ALIASES.get(cond, cond)
        if cond not in ("free", "contact"):
            raise UserError(f"{path}, line {n}: condition must be 'free' or 'contact', got '{cond}'")
        try:
            modes.append(int(float(mode)) if float(mode).is_integer() else int(mode))
            freqs.append(float(freq) * unit)
            qs.append(float(cells[q_idx]) if q_idx is not None and cells[q_idx] else math.nan)
        except ValueError:
            raise UserError(f"{path}, line {n}: mode must be an integer, {freq_cols[0]} and "
                            "quality_factor numbers") from None
        if modes[-1] < 1 or not (math.isfinite(freqs[-1]) and freqs[-1] > 0):
            raise UserError(f"{path}, line {n}: mode >= 1 and a finite {freq_cols[0]} > 0 required")
        if not (math.isnan(qs[-1]) or qs[-1] > 0.5):
            raise UserError(f"{path}, line {n}: quality_factor must be a number > 0.5 (inf: undamped) "
                            f"(or blank), got '{cells[q_idx]}'")
        conds.append(cond)
    modes, conds, freqs, qs = np.array(modes), np.array(conds), np.array(freqs), np.array(qs)
    if metadata.free_resonance is None:
        first = freqs[(conds == "free") & (modes == 1)]
        if len(first):
            metadata = replace(metadata, free_resonance=_plausible(str(path), "free_resonance", float(first[0])))
        elif free_required:
            _require(str(path), ["free_resonance"])
    if len(freqs) and metadata.free_resonance is not None:
        check_band(str(path), freqs, metadata.free_resonance, TABLE_BAND)
    order = check_resonance_rows(str(path), modes, conds, freqs, MIN_RESONANCES, qs if q_idx is not None else None)
    return ResonanceData(metadata, modes[order], conds[order], freqs[order],
                         quality_factor=qs[order] if q_idx is not None else None, ignored_columns=tuple(unknown))


def check_resonance_rows(where, modes, conds, freqs, minimum, qs=None) -> np.ndarray:
    """Row order sorting by (condition, mode); duplicates that disagree (frequency, or Q when
    ``qs`` is given) and too few rows are errors."""
    # Free modes alone still constrain the effects that change mode ratios (a tip mass).
    if len(freqs) < minimum:
        raise UserError(f"{where}: {len(freqs)} resonances; at least {minimum} are needed")
    order = np.lexsort((modes, conds == "contact"))
    values = [(f,) if qs is None else (f, q) for f, q in zip(freqs, qs if qs is not None else freqs)]
    seen, keep = {}, []
    for i in order:
        key = (str(conds[i]), int(modes[i]))
        if key in seen and not np.array_equal(seen[key], values[i], equal_nan=True):
            what = "frequencies" if seen[key][0] != values[i][0] else "quality factors"
            raise UserError(f"{where}: {key[0]} mode {key[1]} given twice with different {what}")
        if key not in seen:
            keep.append(i)
        seen[key] = values[i]
    return np.array(keep, int)
