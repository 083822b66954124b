"""Input of ``pfmdyn discrepancy``: cantilever metadata plus a spectrum or a resonances table.

Format (SI units)::

    # spring_constant_n_per_m: 2.4
    # length_m: 223e-6
    # width_m: 24e-6
    # tip_height_m: 1e-5
    # free_resonance_hz: 63200          <- first free flexural resonance
    # description: optional text
    frequency_hz,bias_v,x,y             <- spectrum (or amplitude,phase_deg), several biases
    ...
    mode,condition,frequency_hz         <- or resonances, condition = free | contact
    1,free,63200
    ...

A resonances table may hold free modes only; the contact springs are then not determined.
Rows may come in any order (they are sorted by condition, then mode); a repeated
(condition, mode) with a different frequency is an error.  An optional ``quality_factor``
column gives each mode's Q.  Instrument files (.ibw, .nid, .h5/.hdf5 and drive sweeps
.txt/.dat) are read by :func:`pfmdyn.io.instruments.to_discrepancy_input` (``pfmdyn
discrepancy`` dispatches them); :func:`check_resonance_rows` accepts their short tables
(one or two resonances).  ``overrides`` (metadata keys, from the
command line) win over the file's values.

Spectra are read by :func:`pfmdyn.io.spectra.read_spectra` (it owns the spectrum rules);
this module checks the metadata, rejects unknown columns and too little data.  Every
problem is one :class:`~pfmdyn.cli.UserError` line.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import UserError
from .spectra import EXPECTED_COLUMNS, read_spectra

__all__ = ["REQUIRED_KEYS", "Metadata", "SpectrumData", "ResonanceData", "read", "check_resonance_rows"]

REQUIRED_KEYS = ("spring_constant_n_per_m", "length_m", "width_m", "tip_height_m",
                 "free_resonance_hz")
RESONANCE_COLUMNS = ("mode", "condition", "frequency_hz")
OPTIONAL_RESONANCE_COLUMNS = ("quality_factor",)
INSTRUMENT_SUFFIXES = (".ibw", ".nid", ".h5", ".hdf5", ".txt", ".dat")
MIN_SPECTRUM_ROWS = 20
MIN_RESONANCES = 3


@dataclass(frozen=True)
class Metadata:
    """Cantilever description: k (N/m), L, width, H (m), first free resonance f1 (Hz)."""

    k: float
    L: float
    width: float
    H: float
    f1: float
    description: str = ""
    frequency_uncertainty_hz: float | None = None


@dataclass(frozen=True)
class SpectrumData:
    """Complex response at (frequency, bias) rows, plus metadata."""

    metadata: Metadata
    frequency_hz: np.ndarray
    bias_v: np.ndarray
    response: np.ndarray
    kind: str = "spectrum"


@dataclass(frozen=True)
class ResonanceData:
    """Measured resonances: mode number (1-based), condition ('free'/'contact'), Hz.

    ``quality_factor`` (one per row, NaN where unknown) when the source gives it, e.g. an
    instrument's thermal or contact tune fit.
    """

    metadata: Metadata
    mode: np.ndarray
    condition: np.ndarray
    frequency_hz: np.ndarray
    kind: str = "resonances"
    quality_factor: np.ndarray | None = None


def _metadata(where: str, meta: dict, overrides: dict | None = None) -> Metadata:
    meta = dict(meta)
    meta.update({key: value for key, value in (overrides or {}).items() if value is not None})
    missing = [key for key in REQUIRED_KEYS if key not in meta]
    if missing:
        raise UserError(f"{where}: missing metadata key(s) {', '.join(missing)}"
                        f" (lines '# key: value' before the header)")
    values = {}
    for key in REQUIRED_KEYS + ("frequency_uncertainty_hz",):
        if key not in meta:
            continue
        try:
            values[key] = float(meta[key])
        except ValueError:
            raise UserError(f"{where}: metadata '{key}' is '{meta[key]}', not a number") from None
        if not (math.isfinite(values[key]) and values[key] > 0):
            raise UserError(f"{where}: metadata '{key}' must be positive and finite")
    return Metadata(values["spring_constant_n_per_m"], values["length_m"], values["width_m"],
                    values["tip_height_m"], values["free_resonance_hz"],
                    meta.get("description", ""), values.get("frequency_uncertainty_hz"))


def _preamble(path: Path) -> tuple[dict, list[str], list[str]]:
    """Metadata, header fields and data lines (comments and blanks skipped)."""
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"{path}: cannot read the file ({exc})") from None
    meta, rest = {}, [line for line in lines if line.strip()]
    while rest and rest[0].lstrip().startswith("#"):
        key, colon, value = rest.pop(0).strip()[1:].partition(":")
        if colon and key.strip():
            meta[key.strip()] = value.strip()
    if not rest:
        raise UserError(f"{path}: no header line")
    header = [c.strip() for c in next(csv.reader([rest[0]]))]
    return meta, header, rest[1:]


def read(path, overrides: dict | None = None) -> SpectrumData | ResonanceData:
    """Read a discrepancy input file (format in the module docstring).

    ``overrides``: metadata keys (:data:`REQUIRED_KEYS`) given on the command line,
    applied over the file's values.

    >>> import tempfile, os
    >>> text = ("# spring_constant_n_per_m: 2.4\\n# length_m: 2e-4\\n# width_m: 3e-5\\n"
    ...         "# tip_height_m: 1e-5\\n# free_resonance_hz: 6e4\\nmode,condition,frequency_hz\\n"
    ...         "1,free,6e4\\n2,free,3.7e5\\n1,contact,4e5\\n")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "r.csv")
    ...     _ = open(name, "w").write(text)
    ...     data = read(name)
    >>> data.kind, data.condition.tolist()
    ('resonances', ['free', 'free', 'contact'])
    """
    path = Path(path)
    if path.suffix.lower() in INSTRUMENT_SUFFIXES:
        # pfmdyn.io.instruments imports this module's data classes: the command dispatches
        # instrument files (read_input) so that the two modules do not import each other.
        raise UserError(f"{path}: an instrument file; read it with pfmdyn.io.instruments.to_discrepancy_input")
    meta, header, rows = _preamble(path)
    metadata = _metadata(str(path), meta, overrides)
    if "mode" in header or "condition" in header:
        return _resonances(path, metadata, header, rows)
    unknown = [c for c in header if c not in EXPECTED_COLUMNS]
    if unknown:
        raise UserError(f"{path}: unknown column(s) {', '.join(unknown)}; expected frequency_hz, "
                        "bias_v and x, y or amplitude, phase_deg (or mode, condition, frequency_hz)")
    spectra = read_spectra(path, biases_per_frequency=1)
    if len(spectra.frequency_hz) < MIN_SPECTRUM_ROWS:
        raise UserError(f"{path}: {len(spectra.frequency_hz)} data rows; at least "
                        f"{MIN_SPECTRUM_ROWS} are needed to fit the model")
    return SpectrumData(metadata, spectra.frequency_hz, spectra.bias_v, spectra.response)


def _resonances(path, metadata, header, rows) -> ResonanceData:
    allowed = RESONANCE_COLUMNS + OPTIONAL_RESONANCE_COLUMNS
    problem = sorted(set(header) - set(allowed)) + sorted(set(RESONANCE_COLUMNS) - set(header))
    if problem or len(set(header)) != len(header):
        raise UserError(f"{path}: resonances table needs the columns mode, condition, frequency_hz "
                        f"(and optionally quality_factor) once each (problem: {', '.join(problem) or 'repeated column'})")
    idx = [header.index(c) for c in RESONANCE_COLUMNS]
    q_idx = header.index("quality_factor") if "quality_factor" in header else None
    modes, conds, freqs, qs = [], [], [], []
    for n, line in enumerate(rows, start=1):
        cells = [c.strip() for c in next(csv.reader([line]))]
        if len(cells) != len(header):
            raise UserError(f"{path}: data row {n}: expected {len(header)} fields")
        mode, cond, freq = (cells[i] for i in idx)
        if cond not in ("free", "contact"):
            raise UserError(f"{path}: data row {n}: condition must be 'free' or 'contact', got '{cond}'")
        try:
            modes.append(int(mode))
            freqs.append(float(freq))
            qs.append(float(cells[q_idx]) if q_idx is not None and cells[q_idx] else math.nan)
        except ValueError:
            raise UserError(f"{path}: data row {n}: mode must be an integer, frequency_hz and "
                            "quality_factor numbers") from None
        if modes[-1] < 1 or not (math.isfinite(freqs[-1]) and freqs[-1] > 0):
            raise UserError(f"{path}: data row {n}: mode >= 1 and a finite frequency_hz > 0 required")
        conds.append(cond)
    modes, conds, freqs, qs = np.array(modes), np.array(conds), np.array(freqs), np.array(qs)
    order = check_resonance_rows(str(path), modes, conds, freqs, MIN_RESONANCES)
    return ResonanceData(metadata, modes[order], conds[order], freqs[order],
                         quality_factor=qs[order] if q_idx is not None else None)


def check_resonance_rows(where, modes, conds, freqs, minimum) -> np.ndarray:
    """Row order sorting by (condition, mode); duplicates that disagree and too few rows are errors."""
    # Free modes alone still constrain the effects that change mode ratios (a tip mass).
    if len(freqs) < minimum:
        raise UserError(f"{where}: {len(freqs)} resonances; at least {minimum} are needed")
    order = np.lexsort((modes, conds == "contact"))
    seen, keep = {}, []
    for i in order:
        key = (str(conds[i]), int(modes[i]))
        if key in seen and seen[key] != freqs[i]:
            raise UserError(f"{where}: {key[0]} mode {key[1]} given twice with different frequencies")
        if key not in seen:
            keep.append(i)
        seen[key] = freqs[i]
    return np.array(keep, int)
