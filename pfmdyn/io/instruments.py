"""Instrument files in, pfmdyn's cantilever description out (SI units), whatever wrote them.

Formats (each read with the maintained library of its field; they come with the
``pfmdyn[files]`` extra):

* Asylum Research ``.ibw`` (Igor binary wave, :mod:`igor2`): images with the instrument's
  ``key: value`` note (spring constant, thermal-tune fit, contact-tune fit, lever size);
* pycroscopy ``.h5`` / ``.hdf5`` (:mod:`h5py`): NSID images (the Asylum note kept in
  ``original_metadata``) and USID datasets (``Raw_Data`` with spectroscopic values);
* Nanosurf ``.nid`` (:mod:`NSFopen`): thermal tunes (amplitude spectral density and the
  instrument's fit), images and spectra;
* plain-text drive sweeps: Cytomass/pyIMD ``.txt`` and Nanonis oscillation-control ``.dat``.

:func:`read_instrument` returns an :class:`InstrumentRecord`: what the file is, its channels
with units, the cantilever fields found (SI) and the ones missing.  Prefixed units (``kHz``,
``nm``, ``pN/nm``, ``mV``) are converted to SI (:func:`pfmdyn.io.record.si_unit`): a channel
keeps the factor from its stored values, spectra and fields are converted; a unit that is
not SI is kept as written and said in the record's notes, never guessed.
:func:`resonance_table` turns a record into the resonance table of ``pfmdyn
discrepancy`` (:class:`pfmdyn.io.discrepancy_data.ResonanceData`): an image's metadata gives
free mode 1 and contact mode 1 with their Q; a thermal spectrum gives the free modes the
caller fitted in it (readers only read: :mod:`pfmdyn.analysis.thermal` fits).  A field that
neither the file nor the caller gives is a :class:`~pfmdyn.io.record.MissingFieldError`
naming it, never a silent default (the commands add the option that supplies it).
"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import UserError, listed
from ..names import canonical, checked
from .columns import column, read_table
from .kinds import CSV_KINDS, NANOSURF_KINDS, file_kind
from .record import FIELDS, Channel, InstrumentRecord, MissingFieldError, make_record

__all__ = ["FIELDS", "Channel", "InstrumentRecord", "MissingFieldError", "read_instrument", "resonance_table",
           "required_field"]


def _reader(path: Path):
    """The reader of the file's kind (:func:`pfmdyn.io.kinds.file_kind`); pfmdyn's table under a .txt or
    .dat name is read as a table, as discrepancy and stiffness read it."""
    if path.is_dir():
        raise UserError(f"{path}: a directory, not an instrument file (a Zarr map is read by pfmdyn map)")
    kind = file_kind(path)
    if kind == "asylum":
        from .ibw import read_ibw
        return read_ibw
    if kind in ("hdf5", "hdf5 contact map"):
        from .hdf5 import read_hdf5
        return read_hdf5
    if kind in NANOSURF_KINDS:
        from .nid import read_nid
        return read_nid
    if kind == "text sweep":
        from .sweeps import read_sweep
        return read_sweep
    if kind in CSV_KINDS | {"text table"}:
        return _read_csv
    raise UserError(f"{path}: unknown instrument file type '{path.suffix.lower()}'; pfmdyn reads .ibw (Asylum), "
                    ".h5/.hdf5 (pycroscopy NSID/USID), .nid (Nanosurf), .txt/.dat (drive sweeps), .csv")


# Unit suffixes of CSV column names (pfmdyn's own files and its decodings of instrument files).
_CSV_UNITS = {"_hz": "Hz", "_m_per_sqrthz": "m/sqrt(Hz)", "_n_per_m": "N/m", "_deg": "deg",
              "_v": "V", "_m": "m"}


def _table_rows(path: Path) -> dict:
    """The first free and contact resonance (and their Q) a resonance table's rows hold, as the fields an
    instrument's note would give them (discrepancy and stiffness read them there).

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "t.csv")
    ...     _ = open(name, "w").write("mode,condition,frequency_hz,q\\n1,contact,368990,213.5\\n1,free,72969,\\n")
    ...     _table_rows(Path(name))
    {'free_resonance': 72969.0, 'contact_resonance': 368990.0, 'contact_quality_factor': 213.5}
    """
    from .tables import read

    data, found = read(path, required=()), {}
    for condition, resonance in (("free", "free_resonance"), ("contact", "contact_resonance")):
        row = np.flatnonzero((data.condition == condition) & (data.mode == 1))
        if len(row):
            found[resonance] = float(data.frequency_hz[row[0]])
            q = np.nan if data.quality_factor is None else float(data.quality_factor[row[0]])
            if not np.isnan(q):
                found[f"{condition}_quality_factor"] = q
    return found


def _read_csv(path: Path) -> InstrumentRecord:
    """A CSV table (:func:`pfmdyn.io.columns.read_table`): columns with the units their names
    end in, ``# key: value`` metadata; every row as long as the header, a number under each unit."""
    table = read_table(path)
    if not table.header:
        raise UserError(f"{path}: no header line")
    units = [next((u for s, u in _CSV_UNITS.items() if c.lower().endswith(s)), "") for c in table.header]
    if not table.rows:
        raise UserError(f"{path}, line {table.header_line}: header but no data rows")
    for number, cells in table.rows:        # a truncated or damaged row is said, not counted as data
        cells = cells[:len(table.header)] if not any(cells[len(table.header):]) else cells
        if len(cells) != len(table.header):
            raise UserError(f"{path}, line {number}: {len(cells)} values for {len(table.header)} columns (truncated?)")
        for name, unit, cell in zip(table.header, units, cells):
            try:
                if unit:
                    float(cell)
            except ValueError:
                raise UserError(f"{path}, line {number}: column '{name}': '{cell}' is not a number") from None
    found = {}
    for key, value in table.metadata.items():     # any spelling of a field (``length_m`` is ``length``)
        if canonical(key) in FIELDS:
            try:
                found[canonical(key)] = float(value)
            except ValueError:
                pass
    kind = "resonance metadata" if {"mode", "condition"} <= set(table.header) else "spectrum"
    if kind == "resonance metadata":
        found.update(_table_rows(path))
    if not any(unit == "Hz" or (column(c) or ("",))[0] == "frequency_hz" for c, unit in zip(table.header, units)):
        raise UserError(f"{path}: not a table pfmdyn reads: no frequency column (frequency_hz; a drive sweep "
                        "has a 'Sweep data' or '[DATA]' line before its table)")
    channels = [Channel(c, u, (len(table.rows),)) for c, u in zip(table.header, units)]
    return make_record(path, kind, "CSV table", channels, found)


def read_instrument(path, data_only: bool = False) -> InstrumentRecord:
    """Read an instrument file (type from its extension) into an :class:`InstrumentRecord`; ``data_only``:
    for a caller that needs the fields and the spectrum, not the channels' names (a Nanosurf thermal tune
    is then read from its layout: :func:`pfmdyn.io.nid.read_nid`).

    Every problem with the file is one :class:`~pfmdyn.errors.UserError` line.

    >>> read_instrument("scan.xyz")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: scan.xyz: unknown instrument file type '.xyz'; pfmdyn reads .ibw (Asylum), .h5/.hdf5 (pycroscopy NSID/USID), .nid (Nanosurf), .txt/.dat (drive sweeps), .csv
    """
    path = Path(path)
    reader = _reader(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    if path.stat().st_size == 0:
        raise UserError(f"{path}: the file is empty")
    try:
        return reader(path, tune_from_layout=True) if data_only and file_kind(path) in NANOSURF_KINDS else reader(path)
    except UserError:
        raise
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, OSError, UnicodeError,
            RuntimeError, ArithmeticError, struct.error) as exc:
        # A file the library opened but whose layout this reader does not know, or a damaged one
        # (HDF5 raises RuntimeError on broken B-trees): one line, no traceback.
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise UserError(f"{path}: could not interpret the file ({type(exc).__name__}: {reason})") from None


def required_field(record: InstrumentRecord, name: str, overrides: dict | None = None) -> float:
    """A field from ``overrides`` (the caller's values) or else the file; missing ->
    :class:`~pfmdyn.io.record.MissingFieldError` naming the field.

    >>> r = make_record("a.ibw", "image", "test", (), {"spring_constant": 2.0})
    >>> required_field(r, "spring_constant"), required_field(r, "length", {"length": 2e-4})
    (2.0, 0.0002)
    >>> required_field(r, "tip_height")
    Traceback (most recent call last):
    ...
    pfmdyn.io.record.MissingFieldError: tip height not in a.ibw
    >>> required_field(r, "length", {"length": 223.0})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: length must be in (1e-06, 0.01] m, got 223.0
    """
    overrides = overrides or {}
    if overrides.get(name) is not None:
        return checked(name, overrides[name])
    if name in record.fields:
        return record.fields[name]
    left_out = record.left_out([name])
    raise MissingFieldError(f"{FIELDS[name][0]} not in {Path(record.path).name}"
                            + (f" ({left_out[0]})" if left_out else ""), name)


def resonance_table(record: InstrumentRecord, overrides: dict | None = None, peaks=None):
    """The resonance table of ``pfmdyn discrepancy`` that an instrument record implies.

    An image (or any record with resonance metadata): free mode 1 from the thermal fit and
    contact mode 1 from the tune fit, each with its Q, as the instrument stored them.  A
    thermal spectrum: ``peaks``, the free modes the caller fitted in it (objects with
    ``mode``, ``frequency_hz``, ``quality_factor``:
    :func:`pfmdyn.analysis.thermal.instrument_resonances` fits and calls this).
    ``overrides`` (names of :data:`FIELDS`, or their older spellings) win over the file.

    Returns
    -------
    pfmdyn.io.discrepancy_data.ResonanceData

    Examples
    --------
    >>> r = make_record("a.ibw", "image", "test", (), {"spring_constant": 2.0, "length": 2e-4,
    ...     "width": 3e-5, "free_resonance": 6e4, "contact_resonance": 3e5})
    >>> table = resonance_table(r, {"tip_height": 1e-5})
    >>> table.condition.tolist(), table.frequency_hz.tolist()
    (['free', 'contact'], [60000.0, 300000.0])
    >>> resonance_table(make_record("b.h5", "image", "test", (), {"free_resonance": 6e4}), {"length": 2e-4})
    Traceback (most recent call last):
    ...
    pfmdyn.io.record.MissingFieldError: spring constant and tip height not in b.h5
    """
    from .discrepancy_data import Metadata, ResonanceData

    overrides = {canonical(key) or key: value for key, value in (overrides or {}).items()}
    name = Path(record.path).name
    if record.kind == "thermal spectrum":
        if not peaks:
            raise UserError(f"{name}: no resonance peak found in the thermal spectrum")
        modes = np.array([p.mode for p in peaks])
        conditions = np.array(["free"] * len(peaks))
        freqs = np.array([p.frequency_hz for p in peaks])
        qs = np.array([p.quality_factor for p in peaks])
        overrides.setdefault("free_resonance", freqs[0])
    else:
        f_free = required_field(record, "free_resonance", overrides)
        q_free = record.fields.get("free_quality_factor", np.nan)
        if "contact_resonance" in record.fields:
            modes, conditions = np.array([1, 1]), np.array(["free", "contact"])
            freqs = np.array([f_free, record.fields["contact_resonance"]])
            qs = np.array([q_free, record.fields.get("contact_quality_factor", np.nan)])
        else:       # e.g. a drive sweep of the free lever: its fitted resonance alone
            modes, conditions = np.array([1]), np.array(["free"])
            freqs, qs = np.array([f_free]), np.array([q_free])
    needed = ("spring_constant", "length", "tip_height", "free_resonance")
    missing = tuple(key for key in needed if overrides.get(key) is None and key not in record.fields)
    if len(missing) > 1:        # all at once: the user gives them in one run
        left_out = record.left_out(missing)
        raise MissingFieldError(f"{listed(FIELDS[key][0] for key in missing)} not in {name}"
                                + (f" ({'; '.join(left_out)})" if left_out else ""), missing)
    lever = {key: required_field(record, key, overrides) for key in needed}
    # No resonance depends on the width: taken when known, never asked for.
    width = required_field(record, "width", overrides) if ("width" in record.fields or
                                                             overrides.get("width") is not None) else None
    metadata = Metadata(**lever, width=width, description=f"{record.instrument}: {name}")
    return ResonanceData(metadata, modes, conditions, freqs, quality_factor=qs)
