"""Reading and validating frequency-bias spectroscopy CSV files.

The format, shared by every command that reads measured spectra::

    # spring_constant: 4.5              <- optional metadata, "# key: value", before the header
    # response_unit: pm                 <- else the response columns' unit (X (pm), amplitude_m_per_v); other comment lines too
    frequency_hz,bias_v,x,y             <- or amplitude,phase_deg instead of x,y
    10000,-5,1.2,-0.3
    10000,-4,1.1,-0.2
    ...

* ``x, y`` are the lock-in in-phase and quadrature signals; ``amplitude, phase_deg`` the
  same response in polar form (phase in degrees).  Either pair gives the complex response
  :math:`x + i y = A e^{i\\varphi}`; a file with both pairs is read from ``x, y``, the
  polar pair checked to agree (0.1 %).  Other columns are ignored.
* Spellings researchers use are read too (:mod:`pfmdyn.io.columns`): other separators
  (semicolon, tab, spaces), ``%`` comments, names with units (``Frequency (kHz)``,
  ``bias_mv``, ``Phase (rad)``) and aliases (``freq``, ``V_dc``, ``real, imag``, ``R``);
  values are converted to Hz, V and degrees.  Sweeps whose frequencies differ only by
  rounding (less than 1/1000 of a step) share their setpoints.
* A table is a set of rows: any row order is accepted (a sweep at each bias written one
  after another, as instruments do, or frequency-grouped, or shuffled).  After reading, the
  rows are sorted by frequency, then bias.  A (frequency, bias) pair given twice with the
  same response is kept once; with different responses it is an error.  Unless the caller
  says otherwise, every frequency needs at least two distinct biases so that a line can be
  fitted.
* Blank lines are skipped.  Every problem is reported as one :class:`~pfmdyn.errors.UserError`
  naming the file and the line.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import UserError
from . import columns
from .kinds import INSTRUMENT_KINDS, file_kind

COORDINATE_COLUMNS = ("frequency_hz", "bias_v")
RESPONSE_VARIANTS = (("x", "y"), ("amplitude", "phase_deg"))
EXPECTED_COLUMNS = COORDINATE_COLUMNS + tuple(name for pair in RESPONSE_VARIANTS for name in pair)
_EXPECTED_TEXT = "frequency_hz, bias_v and either x, y or amplitude, phase_deg"


@dataclass(frozen=True)
class Spectra:
    """A validated frequency-bias data set, one entry per CSV data row.

    Attributes
    ----------
    path : str
        The file it was read from (for messages).
    frequency_hz, bias_v : ndarray
        Drive frequency (Hz, positive; rows sorted by frequency, then bias) and tip dc bias (V).
    response : ndarray of complex
        :math:`x + i y` (or :math:`A e^{i\\varphi}`), in the file's units.
    response_columns : tuple of str
        ``("x", "y")`` or ``("amplitude", "phase_deg")``: which pair the file used.
    metadata : dict of str to str
        The ``# key: value`` lines before the header, values as written (stripped).
    response_unit : str or None
        The response's unit: the metadata's ``response_unit``, else what the response columns' names
        say (``amplitude_m_per_v``: m/V), else None (arbitrary units).
    """

    path: str
    frequency_hz: np.ndarray
    bias_v: np.ndarray
    response: np.ndarray
    response_columns: tuple[str, str]
    metadata: dict[str, str] = field(default_factory=dict)
    response_unit: str | None = None


def frequency_group_starts(frequency_hz):
    """Index of the first row of each frequency in frequency-grouped data.

    Parameters
    ----------
    frequency_hz : array_like
        Frequencies, grouped (equal values adjacent).

    Returns
    -------
    ndarray of int
        Start index of every group, suitable for :func:`numpy.add.reduceat`.

    Examples
    --------
    >>> frequency_group_starts([1.0, 1.0, 2.0, 2.0, 2.0, 5.0]).tolist()
    [0, 2, 5]
    """
    frequency_hz = np.asarray(frequency_hz)
    return np.concatenate(([0], np.flatnonzero(np.diff(frequency_hz)) + 1))


def read_spectra(path, biases_per_frequency: int = 2) -> Spectra:
    """Read and validate a frequency-bias CSV file (format in the module docstring).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    biases_per_frequency : int
        Least number of distinct biases required at every frequency (2 for a line fit per
        frequency; 1 when the caller fits all rows together).

    Returns
    -------
    Spectra
        The validated data.

    Raises
    ------
    pfmdyn.errors.UserError
        One line naming the file, the line number and the problem.

    Examples
    --------
    >>> import tempfile, os
    >>> text = "# response_unit: pm\\nfrequency_hz,bias_v,x,y\\n1e4,-1,1,0\\n1e4,1,3,0\\n"
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "d.csv")
    ...     _ = open(name, "w").write(text)
    ...     data = read_spectra(name)
    >>> data.response.tolist(), data.metadata
    ([(1+0j), (3+0j)], {'response_unit': 'pm'})
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "scan.ibw")
    ...     _ = open(name, "wb").write(bytes(8))
    ...     read_spectra(name)                    # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: .../scan.ibw: an instrument file (asylum), not a frequency-bias table: a CSV of frequency_hz, bias_v and the response is read here (pfmdyn inspect shows what the file holds)
    """
    kind = file_kind(path) if Path(path).is_file() else None
    # a text drive sweep is a table too: its columns decide
    if kind in INSTRUMENT_KINDS - {"text sweep"}:
        raise UserError(f"{path}: an instrument file ({kind}), not a frequency-bias table: a CSV of frequency_hz, "
                        "bias_v and the response is read here (pfmdyn inspect shows what the file holds)")
    source = columns.read_table(path)
    where, header_line = source.path, source.header_line
    written = list(source.header)
    data_rows = source.rows
    units = columns.units_line(data_rows[0][1], len(written)) if data_rows else None
    if units is not None:
        written = [f"{name} ({unit})" if unit else name for name, unit in zip(written, units)]
        data_rows = data_rows[1:]
    found = [columns.column(name) for name in written]
    names = [match[0] if match else name for match, name in zip(found, written)]
    response_columns = _check_header(where, header_line, names)
    # Both pairs (lock-ins export X, Y, R, theta): x, y are read, the polar pair checked.
    polar = RESPONSE_VARIANTS[1] if len(response_columns) == 4 else ()
    response_columns = response_columns[:2]
    wanted = COORDINATE_COLUMNS + response_columns + polar
    indices = [names.index(name) for name in wanted]
    factors = np.array([found[i][1] for i in indices])
    rows, line_numbers = [], []
    for number, fields in data_rows:
        if len(fields) > len(names) and not any(fields[len(names):]):
            fields = fields[:len(names)]
        if len(fields) != len(names):
            raise UserError(f"{where}, line {number}: expected {len(names)} fields as in the header, found {len(fields)}")
        rows.append([_number(where, number, name, fields[i]) for name, i in zip(wanted, indices)])
        line_numbers.append(number)
    if not rows:
        raise UserError(f"{where}, line {header_line}: header but no data rows")
    table = np.array(rows, dtype=float) * factors
    if polar:
        _check_same_response(where, table, line_numbers)
        table = table[:, :4]
    table[:, 0] = _common_setpoints(table[:, 0], table[:, 1])
    table[:, 1] = _common_biases(table[:, 0], table[:, 1])
    table = _check_rows(where, table, np.array(line_numbers), response_columns, biases_per_frequency)
    first, second = table[:, 2], table[:, 3]
    if response_columns == ("x", "y"):
        response = first + 1j * second
    else:
        response = first * np.exp(1j * np.deg2rad(second))
    written = {found[i][2] for i in indices[2:4 if response_columns == ("x", "y") else 3]}
    return Spectra(where, table[:, 0], table[:, 1], response, response_columns, source.metadata,
                   _response_unit(source.metadata, written))


def _response_unit(metadata: dict, written: set) -> str | None:
    """The response's unit: the metadata's ``response_unit``, else the one the response columns' names agree on
    (``amplitude_m_per_v``: m/V; ``X (pm)``: pm), else None.

    >>> _response_unit({}, {"m/v"}), _response_unit({}, {"pm", ""}), _response_unit({"response_unit": "nm"}, {"v"})
    ('m/V', None, 'nm')
    """
    if "response_unit" in metadata:
        return metadata["response_unit"]
    return next(iter(written)).replace("v", "V") if len(written) == 1 and next(iter(written)) else None


def _check_header(where: str, number: int, names: list[str]) -> tuple[str, str]:
    """Check the header and return the response column pair it uses."""
    for position, name in enumerate(names):
        if not name:
            raise UserError(f"{where}, line {number}: column {position + 1} of the header has no name")
        if names.count(name) > 1:
            raise UserError(f"{where}, line {number}: column '{name}' appears more than once")
    present = [pair for pair in RESPONSE_VARIANTS if set(pair) <= set(names)]
    if len(present) == 2:
        return present[0] + present[1]
    unknown = [name for name in names if name not in EXPECTED_COLUMNS]
    # Without a complete pair, report against the pair the header most resembles.
    pair = present[0] if present else max(
        RESPONSE_VARIANTS,
        key=lambda candidate: sum(name in names or bool(_closest(name, unknown)) for name in candidate),
    )
    for name in COORDINATE_COLUMNS + pair:
        if name not in names:
            hint = _closest(name, unknown)
            found = f" (found '{hint}': did you mean '{name}'?)" if hint else ""
            raise UserError(f"{where}, line {number}: missing column '{name}'{found}; expected {_EXPECTED_TEXT}")
    return pair


def _closest(expected: str, candidates: list[str]) -> str | None:
    """The header name most similar to an expected column name, compared case-insensitively."""
    lowered = {candidate.lower(): candidate for candidate in candidates}
    match = difflib.get_close_matches(expected, list(lowered), n=1, cutoff=0.6)
    return lowered[match[0]] if match else None


def _number(where: str, number: int, name: str, cell: str) -> float:
    """Parse one cell as a finite float."""
    if not cell:
        raise UserError(f"{where}, line {number}: column '{name}' is empty")
    try:
        value = float(cell)
    except ValueError:
        raise UserError(f"{where}, line {number}: column '{name}': '{cell}' is not a number") from None
    if not math.isfinite(value):
        raise UserError(f"{where}, line {number}: column '{name}' is '{cell}'; a finite number is required")
    return value


def _check_same_response(where: str, table: np.ndarray, line_numbers: list[int]) -> None:
    """Columns x, y, amplitude, phase_deg (2-5) must give one response, to 0.1 %."""
    xy = table[:, 2] + 1j * table[:, 3]
    polar = table[:, 4] * np.exp(1j * np.deg2rad(table[:, 5]))
    bad = np.flatnonzero(np.abs(xy - polar) > 1e-3 * np.abs(xy) + 1e-9 * np.abs(xy).max())
    if bad.size:
        raise UserError(f"{where}, line {line_numbers[bad[0]]}: x, y and amplitude, phase_deg give different "
                        "responses; keep one pair")


def _common_setpoints(frequency_hz: np.ndarray, bias_v: np.ndarray) -> np.ndarray:
    """Frequencies of different sweeps closer than 1/1000 of the finest step of one sweep are the
    same setpoint written with rounding noise (e.g. ``f0 + i df`` computed two ways): each such
    cluster takes its mean, so that every frequency has its biases together.

    >>> _common_setpoints(np.array([1.0, 2.0, 1.0 + 1e-9, 2.0]), np.array([0, 0, 1, 1])).round(6).tolist()
    [1.0, 2.0, 1.0, 2.0]
    """
    steps = [np.diff(np.unique(frequency_hz[bias_v == b])) for b in np.unique(bias_v)]
    steps = np.concatenate(steps)
    unique = np.unique(frequency_hz)
    if not steps.size or len(unique) < 2:
        return frequency_hz
    cluster = np.concatenate(([0], np.cumsum(np.diff(unique) > 1e-3 * steps.min())))
    if cluster[-1] == len(unique) - 1:
        return frequency_hz
    means = np.bincount(cluster, unique) / np.bincount(cluster)
    return means[cluster[np.searchsorted(unique, frequency_hz)]]


def _common_biases(frequency_hz: np.ndarray, bias_v: np.ndarray) -> np.ndarray:
    """Biases read back with jitter (every row its own value) but in sweeps: when every
    frequency has the same number of rows and the i-th lowest bias at each frequency stays
    below the (i+1)-th everywhere, the i-th sweep takes its mean bias.

    >>> _common_biases(np.array([1.0, 1.0, 2.0, 2.0]), np.array([-1.001, 0.999, -0.999, 1.001])).tolist()
    [-1.0, 1.0, -1.0, 1.0]
    """
    order = np.lexsort((bias_v, frequency_hz))
    starts = frequency_group_starts(frequency_hz[order])
    counts = np.diff(np.append(starts, len(order)))
    if counts.min() != counts.max() or len(np.unique(bias_v)) <= counts[0] or counts[0] < 2:
        return bias_v
    sweeps = bias_v[order].reshape(-1, counts[0])           # row: one frequency, biases ascending
    if np.any(sweeps.max(axis=0)[:-1] >= sweeps.min(axis=0)[1:]):
        return bias_v
    out = np.empty_like(bias_v)
    out[order] = np.broadcast_to(sweeps.mean(axis=0), sweeps.shape).ravel()
    return out


def _check_rows(where: str, table: np.ndarray, line_numbers: np.ndarray, response_columns: tuple[str, str],
                biases_per_frequency: int = 2) -> np.ndarray:
    """Check value ranges, duplicates and biases per frequency; return the rows sorted by
    (frequency, bias), identical repeated rows kept once."""
    frequency = table[:, 0]
    bad = np.flatnonzero(frequency <= 0)
    if bad.size:
        row = bad[0]
        raise UserError(f"{where}, line {line_numbers[row]}: frequency_hz must be positive, got {frequency[row]:.12g}")
    if response_columns == ("amplitude", "phase_deg") and (table[:, 2] < 0).any():
        row = np.flatnonzero(table[:, 2] < 0)[0]
        raise UserError(f"{where}, line {line_numbers[row]}: amplitude must be non-negative, got {table[row, 2]:.12g}")
    order = np.lexsort((line_numbers, table[:, 1], table[:, 0]))     # stable: file order among equals
    table, line_numbers = table[order], line_numbers[order]
    same = (np.diff(table[:, 0]) == 0) & (np.diff(table[:, 1]) == 0)
    clash = np.flatnonzero(same & np.any(np.diff(table[:, 2:], axis=0) != 0, axis=1))
    if clash.size:
        row = clash[0] + 1
        raise UserError(
            f"{where}, line {line_numbers[row]}: duplicate row for frequency {table[row, 0]:.12g} Hz"
            f" and bias {table[row, 1]:.12g} V (first at line {line_numbers[row - 1]}) with a different response"
        )
    keep = np.concatenate(([True], ~same))
    table, line_numbers = table[keep], line_numbers[keep]
    starts = frequency_group_starts(table[:, 0])
    counts = np.diff(np.append(starts, len(table)))
    few = np.flatnonzero(counts < biases_per_frequency)
    if few.size:
        start = starts[few[0]]
        raise UserError(
            f"{where}, line {line_numbers[start]}: only one bias value at frequency {table[start, 0]:.12g} Hz;"
            " the linear fit needs at least two distinct biases"
        )
    return table
