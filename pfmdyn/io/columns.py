"""How researchers write the CSV tables pfmdyn reads: separators, comment lines, column names
with units, metadata values with units.

The readers (:mod:`pfmdyn.io.spectra`, :mod:`pfmdyn.io.tables`) keep one canonical vocabulary
(``frequency_hz``, ``bias_v``, ``x``, ``y``, ``amplitude``, ``phase_deg``; metadata in SI); this
module maps what a file says onto it, with the factor to the canonical unit:

* separators: comma, semicolon, tab or runs of spaces, decided by the header line (with a
  semicolon, tab or space separator a decimal comma is read as a point);
* comment and metadata lines start with ``#`` or ``%`` (``## key = value`` too);
* column names are compared case-insensitively, with the unit as a suffix (``frequency_khz``),
  in brackets (``Frequency (kHz)``, ``Bias [mV]``), after a slash (``Frequency / kHz``), on
  a line of its own under the header, or implied (``freq``: Hz, ``bias``: V);
  a phase needs its unit (``phase_deg``, ``Phase (rad)``): degrees and radians cannot be
  told apart safely from the numbers;
* metadata values may carry a unit of the key's dimension (``length: 223 um``).

:func:`read_table` is the one CSV reader: metadata lines, the header, the data rows as text
fields with their line numbers.  The readers of each kind of table interpret them.
"""
from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

from ..errors import UserError
from .. import names as vocabulary
from .record import si_unit

__all__ = ["Table", "read_table", "delimiter", "split", "comment_entry", "is_comment", "units_line", "column",
           "metadata_number"]

COMMENT_PREFIXES = ("#", "%")

_QUANTITIES = {
    "frequency_hz": (("frequency", "freq", "f", "drive_frequency"), {"hz": 1.0, "khz": 1e3, "mhz": 1e6}, "hz"),
    "bias_v": (("bias", "v", "vdc", "v_dc", "dc", "dc_bias", "bias_voltage", "voltage", "tip_bias", "v_bias",
                "vbias", "dc_voltage"), {"v": 1.0, "mv": 1e-3}, "v"),
    "x": (("x", "real", "re", "in_phase", "inphase"), None, None),
    "y": (("y", "imag", "im", "imaginary", "quadrature"), None, None),
    "amplitude": (("amplitude", "amp", "r", "mag", "magnitude"), None, None),
    "phase_deg": (("phase", "theta", "phi"), {"deg": 1.0, "degree": 1.0, "degrees": 1.0, "°": 1.0,
                                              "rad": 180 / math.pi, "radian": 180 / math.pi,
                                              "radians": 180 / math.pi}, None),
}
"""Canonical column -> (names, unit factors to the canonical unit, unit implied when none is
written; None: a unit must be written).  The response (x, y, amplitude) may carry any unit:
the analyses are invariant to its scale."""
_RESPONSE_UNITS = ("pm", "nm", "um", "m", "v", "mv", "uv", "au", "a.u.", "arb")

_METADATA_UNITS = (("_n_per_m", "N/m"), ("_m", "m"), ("_hz", "Hz"))
"""Unit of a metadata key that is no quantity of :mod:`pfmdyn.names` (``frequency_uncertainty_hz``),
from its suffix (the first that matches counts: ``_n_per_m`` before ``_m``); a value may be
written in any prefixed form of it (:func:`pfmdyn.io.record.si_unit`)."""


def delimiter(header: str) -> str | None:
    """The field separator of a table, from its header line (None: runs of whitespace).

    >>> delimiter("frequency_hz;bias_v;x;y"), delimiter("f\\tV\\tx\\ty"), delimiter("f V x y")
    (';', '\\t', None)
    """
    for candidate in ("\t", ";", ","):
        if candidate in header:
            return candidate
    return None if len(header.split()) > 1 else ","


def split(line: str, sep: str | None) -> list[str]:
    """Fields of one line, stripped of spaces and quotes; a decimal comma becomes a point when
    the separator is not a comma.

    >>> split('1,5; 2; "x"', ";")
    ['1.5', '2', 'x']
    """
    if sep is None:
        cells = line.split()
    else:       # the csv module only where a quote may hide a separator (a long table: 5x faster)
        cells = line.split(sep) if '"' not in line else next(csv.reader([line], delimiter=sep))
    cells = [cell.strip().strip('"').strip() for cell in cells]
    if sep != ",":
        cells = [c.replace(",", ".") if re.fullmatch(r"[-+]?\d*,\d+([eE][-+]?\d+)?", c) else c for c in cells]
    return cells


def comment_entry(line: str) -> tuple[str, str] | None:
    """``(key, value)`` of a metadata comment line (``# key: value``, ``% key = value``), key
    lower-cased with spaces as underscores; None for other lines.

    >>> comment_entry("## Spring constant = 2.4 N/m"), comment_entry("frequency_hz,x")
    (('spring_constant', '2.4 N/m'), None)
    """
    text = line.strip()
    if not text.startswith(COMMENT_PREFIXES):
        return None
    text = text.lstrip("#%").strip()
    match = re.match(r"([^:=]+?)\s*[:=]\s*(.*)$", text)
    if not match:
        return ("", "")
    return "_".join(match.group(1).lower().split()), match.group(2).strip()


@dataclass(frozen=True)
class Table:
    """A CSV file as written: metadata before the header, the header, the data rows (text)."""

    path: str
    metadata: dict[str, str]
    """``key: value`` lines before the header (:func:`comment_entry`), values as written."""
    header: list[str]
    """Fields of the header line (a trailing separator dropped)."""
    header_line: int
    """1-based line number of the header."""
    separator: str | None
    """Field separator (None: runs of whitespace), decided by the header (:func:`delimiter`)."""
    rows: list[tuple[int, list[str]]]
    """``(line number, fields)`` of every non-blank line after the header."""


TABLES_KEPT = 4
"""Tables :func:`read_table` keeps, each with the bytes it was parsed from: a command asks what kind a file
is, then reads it, and its parts read it again (``discrepancy`` on a tune: nine times, 100,000 rows ~1.5 s
each to parse, ~1 ms to read); a file whose bytes changed since is parsed afresh."""
_tables: dict = {}


def read_table(path) -> Table:
    """Read a CSV file into a :class:`Table` (shared, read-only, with every later reader of the same bytes:
    :data:`TABLES_KEPT`); every problem is one ``UserError`` line naming the file and the line.

    Comment lines are allowed only before the header; a metadata key given twice with
    different values is an error.

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     name = os.path.join(tmp, "t.csv")
    ...     _ = open(name, "w").write("% Length = 223 um\\n\\nmode;frequency_hz;\\n1;63,2\\n")
    ...     table = read_table(name)
    ...     again = read_table(name)
    ...     _ = open(name, "w").write("% Length = 223 um\\n\\nmode;frequency_hz;\\n1;63,3\\n")
    ...     changed = read_table(name)
    >>> table.metadata, table.header, table.header_line, table.rows
    ({'length': '223 um'}, ['mode', 'frequency_hz'], 3, [(4, ['1', '63.2'])])
    >>> again is table, changed.rows
    (True, [(4, ['1', '63.3'])])
    """
    path = Path(path)
    where = str(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise UserError(f"{where}: cannot read the file ({exc.strerror or exc})") from None
    kept = _tables.get(where)
    if kept is not None and kept[0] == data:
        return kept[1]
    try:
        lines = data.decode("utf-8-sig").splitlines()
    except UnicodeDecodeError:
        raise UserError(f"{where}: not a UTF-8 text file") from None
    table = _parse(where, lines)
    _tables.pop(where, None)
    while len(_tables) >= TABLES_KEPT:
        del _tables[next(iter(_tables))]         # the oldest first
    _tables[where] = (data, table)
    return table


def _parse(where: str, lines: list[str]) -> Table:
    """The :class:`Table` of a file's lines (:func:`read_table`)."""
    metadata: dict[str, str] = {}
    header_line = next((number for number, text in enumerate(lines, start=1)
                        if text.strip() and not is_comment(text)), None)
    preamble = lines if header_line is None else lines[:header_line - 1]
    for number, text in enumerate(preamble, start=1):
        entry = comment_entry(text) if text.strip() else None
        if entry and entry[0]:
            key, value = entry
            if metadata.get(key, value) != value:
                raise UserError(f"{where}, line {number}: metadata key '{key}' given twice")
            metadata[key] = value
    if not lines:
        raise UserError(f"{where}, line 1: the file is empty")
    if header_line is None:
        raise UserError(f"{where}, line {len(lines)}: no header line (only comments or blank lines)")
    sep = delimiter(lines[header_line - 1])
    header = split(lines[header_line - 1], sep)
    while header and not header[-1]:        # a trailing separator
        header.pop()
    rows = []
    for number in range(header_line + 1, len(lines) + 1):
        text = lines[number - 1]
        if not text.strip():
            continue
        if is_comment(text):
            raise UserError(f"{where}, line {number}: comment lines are only allowed before the header")
        rows.append((number, split(text, sep)))
    return Table(where, metadata, header, header_line, sep, rows)


def units_line(cells: list[str], count: int) -> list[str] | None:
    """The units of the columns when the first row after the header gives them (``Hz,V,pm,pm``,
    as spreadsheet exports write), else None.

    >>> units_line(["kHz", "mV", "", ""], 4), units_line(["1e4", "0", "1", "2"], 4)
    (['khz', 'mv', '', ''], None)
    """
    cells = cells[:count]
    if not any(cells) or any(_is_number(cell) for cell in cells):
        return None
    return [cell.strip("()[] ").lower() for cell in cells] + [""] * (count - len(cells))


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def is_comment(line: str) -> bool:
    """A comment (or metadata) line."""
    return line.lstrip().startswith(COMMENT_PREFIXES)


def column(name: str) -> tuple[str, float, str] | None:
    """``(canonical name, factor to its unit, unit written)`` of a column header, None when
    it is not a spectrum column.

    >>> column("Frequency (kHz)"), column("bias_mv"), column("X (pm)")[0], column("phase")
    (('frequency_hz', 1000.0, 'khz'), ('bias_v', 0.001, 'mv'), 'x', None)
    >>> column("Frequency / MHz"), column("Tip bias [V]"), column("Phase / rad")[1] == 180 / math.pi
    (('frequency_hz', 1000000.0, 'mhz'), ('bias_v', 1.0, 'v'), True)
    >>> column("amplitude_m_per_v"), column("x_pm_per_v")
    (('amplitude', 1.0, 'm/v'), ('x', 1.0, 'pm/v'))
    """
    text = name.strip().strip('"').strip().lower()
    unit = None
    # "Frequency (kHz)", "Frequency [kHz]" or "Frequency / kHz"
    bracket = (re.fullmatch(r"(.*?)\s*[(\[]\s*([^)\]]*?)\s*[)\]]", text)
               or re.fullmatch(r"(.*?)\s+/\s*(\S+)", text))
    if bracket:
        text, unit = bracket.group(1), bracket.group(2).replace(" ", "")
    key = "_".join(text.replace("-", " ").split())
    for canonical, (names, units, implied) in _QUANTITIES.items():
        if key == canonical and unit is None:
            return canonical, 1.0, canonical.rpartition("_")[2] if units else ""
        stem, _, suffix = key.rpartition("_")
        per_volt = units is None and key.endswith("_per_v")     # a response per volt of drive (pfmdyn diagram --csv)
        if per_volt:
            stem, _, suffix = key.removesuffix("_per_v").rpartition("_")
        if unit is None and key not in names and stem in names and suffix in (units or _RESPONSE_UNITS):
            key, unit = stem, suffix + "/v" * per_volt
        if key not in names:
            continue
        if units is None:
            return canonical, 1.0, unit or ""
        unit = unit if unit is not None else implied
        if unit in units:
            return canonical, units[unit], unit
    return None


def metadata_number(where: str, key: str, text: str) -> float:
    """A metadata value as a float in the key's SI unit (``223 um`` for ``length``).

    The unit is the quantity's (:mod:`pfmdyn.names`, any spelling) or the key's suffix.

    >>> metadata_number("f", "length", "223 um"), metadata_number("f", "free_resonance_hz", "63,2kHz")
    (0.000223, 63200.0)
    """
    text = re.sub(r"^(\s*[-+]?\d+),(\d)", r"\1.\2", text)     # a decimal comma
    match = re.fullmatch(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan)\s*(\S*)\s*", text,
                         re.IGNORECASE)
    if not match:
        raise UserError(f"{where}: metadata '{key}' is '{text}', not a number")
    number, unit = match.group(1), match.group(2)
    if not unit:
        return float(number)
    name = vocabulary.canonical(key)
    if name is not None:
        wanted = None if vocabulary.NAMES[name].unit == "1" else vocabulary.NAMES[name].unit
    else:
        wanted = next((si for suffix, si in _METADATA_UNITS if key.endswith(suffix)), None)
    converted = si_unit(unit)
    if wanted is None or converted is None or converted[0] != wanted:
        raise UserError(f"{where}: metadata '{key}' is '{text}': unit '{unit}' not understood "
                        f"({'a prefixed ' + wanted if wanted else 'no unit'} expected)")
    # In decimal: '10 um' reads exactly as '10e-6' would.
    return float(Decimal(number) * Decimal(repr(converted[1])))
