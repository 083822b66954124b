"""The input of ``pfmdyn discrepancy``, whatever file holds it.

A CSV spectrum or resonances table is read by :func:`pfmdyn.io.tables.read`; an instrument
file (.ibw, .nid, .h5/.hdf5, drive sweeps .txt/.dat) gives the resonance table its
instrument stored, or, for a thermal tune, the free modes fitted in it
(:func:`pfmdyn.analysis.thermal.instrument_resonances`); its short tables (one or two
resonances) are accepted.
"""
from __future__ import annotations

from ..analysis.thermal import instrument_resonances
from ..io import tables
from ..io.discrepancy_data import ResonanceData, SpectrumData

__all__ = ["read"]


def read(path, overrides: dict | None = None) -> SpectrumData | ResonanceData:
    """Read a discrepancy input (CSV table or instrument file); ``overrides``: metadata keys
    from the command line, applied over the file's values.

    >>> read("scan.xyz")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: scan.xyz: cannot read the file (No such file or directory)
    """
    if tables.is_instrument_file(path):
        return instrument_resonances(path, overrides)
    return tables.read(path, overrides)
