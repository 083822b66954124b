"""``pfmdyn inspect FILE``: what pfmdyn understood from an instrument file.

Prints the kind of file, its channels with units, the cantilever fields found (SI) and the
ones missing; ``--json PATH`` writes the same as JSON (numbers as numbers).  Example:
``pfmdyn inspect scan.ibw --json scan.json``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from . import flags

if TYPE_CHECKING:       # the readers are imported when the command runs, not for --help
    from ..io.instruments import InstrumentRecord

__all__ = ["add_arguments", "run", "report"]


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn inspect``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["scan.ibw", "--json", "out.json"]).json
    'out.json'
    """
    parser.add_argument("file", metavar="INPUT", help="instrument file: .ibw, .h5/.hdf5, .nid, .txt/.dat sweep or .csv")
    flags.add_json(parser, "what was read")


def report(record: InstrumentRecord) -> str:
    """The human-readable report of a record.

    >>> from pfmdyn.io.instruments import Channel, make_record
    >>> r = make_record("a.ibw", "image", "Asylum", [Channel("HeightRetrace", "m", (2, 2))],
    ...                 {"spring_constant": 0.5})
    >>> print(report(r).splitlines()[0])
    a.ibw: image (Asylum)
    """
    from ..io.instruments import FIELDS

    lines = [f"{record.path}: {record.kind} ({record.instrument})", "channels:"]
    for c in record.channels:
        shape = " x ".join(str(n) for n in c.shape)
        stored = f"  (stored values x {c.scale:g})" if c.scale != 1 else ""
        lines.append(f"  {c.name:<40} [{c.unit or '?'}]  {shape}{stored}")
    lines.append("cantilever fields found (SI):" if record.fields else "cantilever fields found: none")
    for name, value in record.fields.items():
        what, unit = FIELDS[name]
        lines.append(f"  {what:<32} {value:.6g} {unit}".rstrip())
    if record.missing:
        lines.append("missing: " + ", ".join(FIELDS[name][0] for name in record.missing))
    lines.extend(f"note: {note}" for note in record.notes)
    return "\n".join(lines)


def run(args) -> int:
    """Read the file, print the report, write JSON if asked."""
    from ..io.instruments import read_instrument
    from ..io.results import check_writable

    check_writable(args.json)
    record = read_instrument(args.file)
    print(report(record))
    if args.json:
        from ..io import documents

        flags.write_json(args.json, documents.inspection(record.to_json()))
    return 0
