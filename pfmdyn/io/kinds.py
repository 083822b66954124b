"""What kind of file a path is: the one table every reader and command consults.

The suffix names the format; for the suffixes that more than one kind shares, the content
decides (each test reads no more than it needs, and never raises):

* ``.ibw``: ``asylum``;
* ``.h5``, ``.hdf5``: ``hdf5 contact map`` with ``contact_frequency_hz`` and no ``response`` at
  the root (:mod:`pfmdyn.maps.contact`), else ``hdf5`` (pycroscopy NSID/USID, a spectra map);
* a directory: ``zarr contact map`` likewise, else ``zarr`` (a Zarr group of spectra);
* ``.nid``: ``nanosurf sweep`` when the header lists a ``Frame=Frequency sweep`` data set, else
  ``nanosurf`` (thermal tune, image, spectroscopy);
* ``.txt``, ``.dat``: ``text sweep`` with a ``Sweep data`` or ``[DATA]`` line (Cytomass,
  Nanonis: :mod:`pfmdyn.io.sweeps`), else ``text table`` (pfmdyn's CSV format under a text name);
* ``.csv``: ``thermal csv`` when a column name ends in ``_m_per_sqrthz`` or ``_v_per_sqrthz``
  (:mod:`pfmdyn.io.thermal_tune`), else ``table`` (a spectrum or resonances table);
* anything else: ``unknown``.

A file its test cannot read gets the kind whose reader reports the problem best: an unreadable
``.txt``/``.dat`` is a ``text sweep`` (the sweep reader names it), an unreadable ``.nid`` is
``nanosurf``, an unreadable ``.csv`` a ``table``, an unreadable ``.h5`` ``hdf5``.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from ..errors import UserError

__all__ = ["KINDS", "INSTRUMENT_KINDS", "CONTACT_MAP_KINDS", "SWEEP_KINDS", "CSV_KINDS", "NANOSURF_KINDS",
           "SWEEP_TABLE_STARTS", "ASD_UNITS", "file_kind"]

_BY_SUFFIX = {".ibw": "asylum", ".h5": "hdf5", ".hdf5": "hdf5", ".nid": "nanosurf", ".txt": "text table",
              ".dat": "text table", ".csv": "table"}

KINDS = ("asylum", "hdf5", "hdf5 contact map", "zarr", "zarr contact map", "nanosurf", "nanosurf sweep",
         "text sweep", "text table", "thermal csv", "table", "unknown")
"""Every kind :func:`file_kind` returns."""
INSTRUMENT_KINDS = frozenset({"asylum", "hdf5", "hdf5 contact map", "nanosurf", "nanosurf sweep", "text sweep"})
"""Files an instrument wrote (:func:`pfmdyn.io.instruments.read_instrument` reads them for their resonances)."""
CONTACT_MAP_KINDS = frozenset({"hdf5 contact map", "zarr contact map"})
"""Contact-resonance frequency maps (:mod:`pfmdyn.maps.contact`), in either store."""
SWEEP_KINDS = frozenset({"nanosurf sweep", "text sweep"})
"""Drive sweeps: the lever's response against the drive frequency, fitted point by point."""
CSV_KINDS = frozenset({"thermal csv", "table"})
"""CSV files (pfmdyn's table format, :mod:`pfmdyn.io.columns`)."""
NANOSURF_KINDS = frozenset({"nanosurf", "nanosurf sweep"})
"""Nanosurf ``.nid`` files, whatever they hold."""

SWEEP_TABLE_STARTS = ("Sweep data", "[DATA]")
"""The line before a text drive sweep's table: Cytomass, Nanonis (:mod:`pfmdyn.io.sweeps`)."""
ASD_UNITS = {"_m_per_sqrthz": "m", "_v_per_sqrthz": "V"}
"""Column-name endings of an amplitude spectral density and its unit per sqrt(Hz)
(:mod:`pfmdyn.io.thermal_tune`)."""


def file_kind(path) -> str:
    """The kind of the file at ``path`` (one of :data:`KINDS`), by the module's table.

    >>> file_kind("scan.ibw"), file_kind("missing.nid"), file_kind("missing.txt"), file_kind("scan.xyz")
    ('asylum', 'nanosurf', 'text sweep', 'unknown')
    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "tune.csv")
    ...     _ = open(name, "w").write("frequency_hz,asd_m_per_sqrthz\\n1e3,2e-12\\n")
    ...     file_kind(name), file_kind(tmp)
    ('thermal csv', 'zarr')
    """
    if os.path.isdir(path):
        return "zarr contact map" if _holds_contact_map(path) else "zarr"
    kind = _BY_SUFFIX.get(Path(path).suffix.lower(), "unknown")
    if kind == "hdf5":
        return "hdf5 contact map" if _holds_contact_map(path) else kind
    if kind == "nanosurf" and _lists_frequency_sweep(path):
        return "nanosurf sweep"
    if kind == "text table" and _holds_sweep_table(path):
        return "text sweep"
    if kind == "table" and _names_asd_column(path):
        return "thermal csv"
    return kind


def _holds_contact_map(path) -> bool:
    """An HDF5 file or Zarr group with ``contact_frequency_hz`` and no ``response`` at its root
    (:mod:`pfmdyn.maps.contact`); what its library cannot open (or is not installed) is not one."""
    try:
        if os.path.isdir(path):
            import zarr
            root = zarr.open_group(str(path), mode="r")
            return "contact_frequency_hz" in root and "response" not in root
        import h5py
        with h5py.File(path, "r") as root:
            return "contact_frequency_hz" in root and "response" not in root
    except Exception:       # h5py, zarr: not their format, damaged, absent (ImportError)
        return False


def _lists_frequency_sweep(path) -> bool:
    """Whether a ``.nid`` file's header (up to ``#!``) lists a "Frequency sweep" data set."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(1 << 16)
    except OSError:
        return False
    return re.search(rb"^Frame=Frequency sweep", head.split(b"#!")[0], re.MULTILINE | re.IGNORECASE) is not None


def _holds_sweep_table(path) -> bool:
    """Whether a text file has the line a drive sweep's table follows; an unreadable file counts
    as one, so that the sweep reader reports the problem."""
    try:
        text = Path(path).read_text(encoding="latin-1")
    except OSError:
        return True
    return any(line.strip() in SWEEP_TABLE_STARTS for line in re.split(r"\r\n|\r|\n", text))


def _names_asd_column(path) -> bool:
    """Whether a CSV file's header names an amplitude-spectral-density column; an unreadable file
    does not (the table reader reports it)."""
    from .columns import read_table

    try:
        header = read_table(path).header
    except (UserError, OSError):
        return False
    return any(str(c).lower().endswith(tuple(ASD_UNITS)) for c in header)
