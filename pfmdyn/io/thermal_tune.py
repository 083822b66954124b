"""A thermal tune as ``pfmdyn calibrate`` needs it: the amplitude spectral density with its unit, what
the instrument concluded from it, and the conditions it was taken in.

Read from any instrument file :func:`pfmdyn.io.instruments.read_instrument` calls a thermal spectrum
(Nanosurf ``.nid``), or from a CSV table of a frequency column (Hz) and an ASD column whose name ends
in its unit, ``_m_per_sqrthz`` or ``_v_per_sqrthz`` (the first such column; ``thermal_asd.csv``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import UserError
from .kinds import ASD_UNITS, CSV_KINDS, NANOSURF_KINDS, file_kind

__all__ = ["ThermalTune", "read_thermal_tune"]


@dataclass(frozen=True)
class ThermalTune:
    """``asd`` in ``unit`` per sqrt(Hz) (``unit`` ``"m"`` or ``"V"``) at ``frequency_hz``; ``instrument``:
    the instrument's own results (names of :mod:`pfmdyn.names`, SI); ``conditions``: ``temperature`` (K)
    and ``environment`` when the file says."""

    path: str
    frequency_hz: np.ndarray = field(repr=False)
    asd: np.ndarray = field(repr=False)
    unit: str
    instrument: dict
    conditions: dict


def _from_csv(path: Path) -> ThermalTune:
    from .columns import read_table

    table = read_table(path)
    names = [c.lower() for c in table.header]
    freq = next((i for i, c in enumerate(names) if c.endswith("_hz") and "freq" in c), None)
    asd = next(((i, u) for i, c in enumerate(names) for s, u in ASD_UNITS.items() if c.endswith(s)), None)
    if freq is None or asd is None:
        raise UserError(f"{path}: a thermal tune CSV needs a frequency column ending in _hz and an ASD column "
                        "ending in _m_per_sqrthz or _v_per_sqrthz")
    rows = []
    for number, cells in table.rows:
        try:
            rows.append((float(cells[freq]), float(cells[asd[0]])))
        except (ValueError, IndexError):
            raise UserError(f"{path}, line {number}: not a number in the frequency or ASD column") from None
    values = np.array(rows, dtype=float).reshape(-1, 2)
    lines = np.array([number for number, _ in table.rows])
    return ThermalTune(str(path), *_checked_rows(str(path), values, lines), asd[1], {}, {})


def _checked_rows(where: str, values: np.ndarray, lines: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Frequency and ASD of a tune's rows, sorted by frequency (rows may come in any order); a value
    that is not finite or is negative, or a frequency given twice with two ASDs, names its line.

    >>> f, a = _checked_rows("t.csv", np.array([[2.0, 1.0], [1.0, 3.0], [2.0, 1.0]]), np.array([2, 3, 4]))
    >>> f.tolist(), a.tolist()
    ([1.0, 2.0], [3.0, 1.0])
    >>> _checked_rows("t.csv", np.array([[1.0, -3.0]]), np.array([2]))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: t.csv, line 2: a negative frequency or ASD (-3); an amplitude spectral density is >= 0
    """
    finite = np.isfinite(values).all(axis=1)
    if not finite.all():
        raise UserError(f"{where}, line {lines[~finite][0]}: a frequency or ASD that is not a finite number")
    negative = (values < 0).any(axis=1)
    if negative.any():
        row = np.flatnonzero(negative)[0]
        raise UserError(f"{where}, line {lines[row]}: a negative frequency or ASD ({values[row].min():.6g}); "
                        "an amplitude spectral density is >= 0")
    order = np.argsort(values[:, 0], kind="stable")
    values, lines = values[order], lines[order]
    repeated = np.diff(values[:, 0]) == 0
    clash = np.flatnonzero(repeated & (np.diff(values[:, 1]) != 0))
    if clash.size:
        row = clash[0] + 1
        raise UserError(f"{where}, line {lines[row]}: frequency {values[row, 0]:.12g} Hz given twice (first at line "
                        f"{lines[row - 1]}) with a different ASD")
    values = values[np.concatenate(([True], ~repeated))]
    return values[:, 0], values[:, 1]


def read_thermal_tune(path) -> ThermalTune:
    """Read a thermal tune; anything else is a one-line :class:`~pfmdyn.errors.UserError`.

    >>> read_thermal_tune("tune.xyz")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: tune.xyz: unknown instrument file type '.xyz'; pfmdyn reads .ibw (Asylum), .h5/.hdf5 (pycroscopy NSID/USID), .nid (Nanosurf), .txt/.dat (drive sweeps), .csv
    """
    from .instruments import read_instrument

    path = Path(path)
    record = read_instrument(path, data_only=True)   # checks the type, the file's existence and emptiness
    kind = file_kind(path)
    if kind in CSV_KINDS:
        return _from_csv(path)
    if record.kind != "thermal spectrum" or record.spectrum is None:
        raise UserError(f"{path}: not a thermal tune ({record.instrument}: {record.kind})")
    frequency, asd, unit = record.spectrum
    base = str(unit).replace("/sqrt(Hz)", "")
    if base not in ("m", "V"):
        raise UserError(f"{path}: the spectrum is in {unit}; pfmdyn calibrates spectra in m/sqrt(Hz) or V/sqrt(Hz)")
    conditions = {}
    if kind in NANOSURF_KINDS:
        from .nid import thermal_conditions
        conditions = thermal_conditions(path)
    instrument = {k: v for k, v in record.fields.items()
                  if k in ("spring_constant", "free_resonance", "free_quality_factor")}
    return ThermalTune(str(path), np.asarray(frequency, float), np.asarray(asd, float), base, instrument, conditions)
