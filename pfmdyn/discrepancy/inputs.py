"""The input of ``pfmdyn discrepancy``, whatever file holds it.

A CSV spectrum or resonances table is read by :func:`pfmdyn.io.tables.read`; an instrument
file (.ibw, .nid, .h5/.hdf5, drive sweeps .txt/.dat) gives the resonance table its
instrument stored, or, for a thermal tune, the free modes fitted in it
(:func:`pfmdyn.analysis.thermal.instrument_resonances`); its short tables (one or two
resonances) are accepted.  A drive sweep (.txt/.dat) is fitted over its measured points instead
(:mod:`pfmdyn.discrepancy.sweep`).  Which is which is the file's kind
(:func:`pfmdyn.io.kinds.file_kind`).
"""
from __future__ import annotations

from ..analysis.thermal import instrument_resonances
from ..io import tables
from ..io.discrepancy_data import ResonanceData, SpectrumData
from ..errors import UserError
from ..io import nid, sweeps
from ..io.kinds import INSTRUMENT_KINDS, NANOSURF_KINDS, SWEEP_KINDS, file_kind

__all__ = ["read", "is_sweep", "read_sweep", "is_thermal_tune"]


def is_sweep(path) -> bool:
    """Whether ``path`` is a drive sweep (a .txt/.dat file with a sweep table, a Nanosurf .nid
    frequency sweep), fitted as a spectrum.

    >>> is_sweep("scan.ibw"), is_sweep("missing.txt"), is_sweep("missing.nid")
    (False, True, False)
    """
    return file_kind(path) in SWEEP_KINDS


def is_thermal_tune(path) -> bool:
    """Whether ``path`` holds a thermal tune (an instrument file's, or a CSV with an ASD column), fitted as
    a thermal spectrum; an unreadable file is not, so that the general reader reports it.

    >>> is_thermal_tune("missing.nid"), is_thermal_tune("table.csv")
    (False, False)
    """
    from ..io.instruments import read_instrument

    kind = file_kind(path)
    if kind == "thermal csv":
        return True
    if kind not in INSTRUMENT_KINDS - {"text sweep"}:
        return False
    try:
        return read_instrument(path).kind == "thermal spectrum"
    except UserError:
        return False


def read_sweep(path) -> sweeps.SweepTable:
    """The measured points of a drive sweep, whichever format holds them."""
    reader = nid.read_sweep_table if file_kind(path) in NANOSURF_KINDS else sweeps.read_sweep_table
    return reader(path)


def read(path, overrides: dict | None = None) -> SpectrumData | ResonanceData:
    """Read a discrepancy input (CSV table or instrument file); ``overrides``: metadata keys
    from the command line, applied over the file's values.

    >>> read("scan.xyz")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: scan.xyz: cannot read the file (No such file or directory)
    """
    if file_kind(path) in INSTRUMENT_KINDS:
        return instrument_resonances(path, overrides)
    return tables.read(path, overrides)
