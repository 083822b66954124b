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
    """Cantilever description: k (N/m), L, width, H (m), first free resonance f1 (Hz).

    ``width`` is None when not given: no resonance depends on it.
    """

    k: float
    L: float
    width: float | None
    H: float
    f1: float
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
