"""The data classes of ``pfmdyn discrepancy``'s input: cantilever metadata, a spectrum, a
resonances table.

They live apart from their readers so that :mod:`pfmdyn.io.tables` (CSV files, and the one
entry point :func:`pfmdyn.io.tables.read`) and :mod:`pfmdyn.io.instruments` (instrument
files) both build them without importing each other.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Metadata", "SpectrumData", "ResonanceData"]


@dataclass(frozen=True)
class Metadata:
    """Cantilever description in the names of :mod:`pfmdyn.names` (SI units).

    ``width`` is None when not given: no resonance depends on it.  ``frequency_uncertainty_hz``
    applies to every resonance of a table, free and contact alike (``contact_uncertainty`` of
    :mod:`pfmdyn.names` covers contact resonances only).
    """

    spring_constant: float
    length: float
    width: float | None
    tip_height: float
    free_resonance: float
    description: str = ""
    frequency_uncertainty_hz: float | None = None
    quality_factor_uncertainty: float | None = None


@dataclass(frozen=True)
class SpectrumData:
    """Complex response at (frequency, bias) rows, plus metadata."""

    metadata: Metadata
    frequency_hz: np.ndarray
    bias_v: np.ndarray
    response: np.ndarray
    kind: str = "spectrum"
    ignored_columns: tuple = ()
    """Header columns that are none of a spectrum's (a note, a fit of the instrument's): not read."""


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
    ignored_columns: tuple = ()
    """Header columns that are none of a table's: not read."""
