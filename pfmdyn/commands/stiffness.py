"""``pfmdyn stiffness``: contact stiffness k1 (with k2 or the tip position) from contact resonances.

Numbers on the command line (the probe's flags are those of every command)::

    pfmdyn stiffness --free-resonance 75e3 --contact 300e3 --spring-constant 2 --contact-uncertainty 100

or an instrument file (free and contact resonance and spring constant from its metadata;
command-line values win) or a pfmdyn resonance table (CSV, ``mode,condition,frequency_hz``)::

    pfmdyn stiffness scan.ibw --k2-over-k1 0.8 --length 225e-6 --tip-height 15e-6 --json k1.json

The lever may have its tip set back (``--tip-position``), a heavy tip (``--tip-mass-ratio``) and
a tilt (``--tilt``, degrees, positive when the free end is nearer the sample than the clamp).
With two or more ``--contact`` values (and their ``--mode`` numbers), ``--tip-position fit``
solves k1 and the tip position together (the L1/L method).  What is solved with what is
:mod:`pfmdyn.analysis.stiffness_report`'s table.  A contact-resonance frequency map
(``contact_frequency_hz`` (ny, nx) in an HDF5 file or Zarr group, :mod:`pfmdyn.maps.contact`)
becomes a k1 map::

    pfmdyn stiffness dart.h5 --out result/      # result/maps.zarr: k1, k1_stderr

Resonances given without an uncertainty (no flag, no ``frequency_uncertainty_hz`` in the table) take
:data:`pfmdyn.constants.RESONANCE_RELATIVE_UNCERTAINTY` of each frequency, as ``discrepancy`` does, said as assumed
beside its share of k1's.  ``--reduced-modulus`` converts k1 to E* with the Hertz relation (``--tip-radius``,
``--normal-load``).
``--free``, ``--free-uncertainty`` and ``--load`` are the old spellings of ``--free-resonance``,
``--free-resonance-uncertainty`` and ``--normal-load`` (hidden, still read).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..constants import LEVER_LENGTH, RESONANCE_RELATIVE_UNCERTAINTY
from ..errors import UserError, listed
from ..io.kinds import CONTACT_MAP_KINDS, CSV_KINDS, file_kind
from ..names import LEVER, NAMES, checked
from . import flags

__all__ = ["add_arguments", "run"]

ONE_LEVER = True
"""One lever at a few points: the NumPy forms of the lever (:func:`pfmdyn.commands.flags.lever_forms`)."""

_LEVER = tuple(n for n in LEVER if n not in ("tip_position", "spot_position"))
_UNCERTAINTIES = ("contact_uncertainty", "free_resonance_uncertainty", "spring_constant_uncertainty",
                  "tip_height_uncertainty")
_RESONANCE_UNCERTAINTIES = _UNCERTAINTIES[:2]
_NOMINAL_LENGTH = 1e-4
"""Length used when none is given and none is needed (no lateral spring, no tilt: the resonance ratios do
not depend on it); reported as not given."""
_MAX_MODE = 1000
"""No instrument resolves a higher flexural mode (and the root counts would run for hours)."""


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn stiffness``.

    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> a = p.parse_args(["--contact", "3e5", "--contact", "9e5", "--mode", "1", "--mode", "2", "--free", "7e4"])
    >>> a.contact, a.free_resonance
    (['3e5', '9e5'], '7e4')
    """
    parser.add_argument("file", nargs="?", default=None, metavar="INPUT",
                        help="instrument file (.ibw, .h5, .nid) or resonance table (.csv); optional")
    parser.add_argument("--contact", action="append", default=None, metavar="HZ",
                        help="contact resonance (Hz); repeat for several modes")
    parser.add_argument("--mode", action="append", default=None, metavar="N",
                        help="mode number of each --contact (default 1, 2, ...)")
    flags.add_lever(parser, _LEVER)
    parser.add_argument("--tip-position", dest="tip_position", default=None, metavar="X|fit",
                        help=f"{NAMES['tip_position'].meaning} (x_tip/L); 'fit': solve it with k1 from two or "
                        "more contact modes (the L1/L method)")
    parser.add_argument("--free", dest="free_resonance", default=None, help=argparse.SUPPRESS)
    flags.add_contact(parser, ("k2", "k2_over_k1", "poisson"))
    flags.add(parser, _UNCERTAINTIES)
    parser.add_argument("--free-uncertainty", dest="free_resonance_uncertainty", default=None,
                        help=argparse.SUPPRESS)
    parser.add_argument("--reduced-modulus", action="store_true", help="also give E* from k1 (Hertz contact)")
    flags.add(parser, ("tip_radius", "normal_load"))
    parser.add_argument("--load", dest="normal_load", default=None, help=argparse.SUPPRESS)
    flags.add_json(parser)
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="for a contact-frequency map (contact_frequency_hz): write DIR/maps.zarr with k1")


def _from_file(path: str) -> tuple[dict, list, list]:
    """Lever values (names -> SI), contact resonances and their modes from an instrument file or table."""
    from ..io.instruments import read_instrument

    # pfmdyn's table under a .txt or .dat name too, as discrepancy reads it
    if file_kind(path) in CSV_KINDS | {"text table"}:
        from ..io.tables import ResonanceData, ignored_note, read
        data = read(path, required=())          # the lever's flags and defaults fill what the table lacks
        if not isinstance(data, ResonanceData):
            raise UserError(f"{path}: a resonance table (mode, condition, frequency_hz) is needed, not a spectrum")
        if ignored_note(data):
            print(f"note: {path}: {ignored_note(data)}")
        contact = data.condition == "contact"
        if not contact.any():
            raise UserError(f"{path}: no contact resonance in the table")
        free = [f for m, c, f in zip(data.mode, data.condition, data.frequency_hz) if c == "free" and m == 1]
        found = {name: value for name, value in vars(data.metadata).items() if name in LEVER and value is not None}
        if data.metadata.frequency_uncertainty_hz is not None:        # the table's, for every frequency
            found.update(dict.fromkeys(_RESONANCE_UNCERTAINTIES, data.metadata.frequency_uncertainty_hz))
        if free:
            found["free_resonance"] = free[0]
        return found, data.frequency_hz[contact].tolist(), data.mode[contact].tolist()
    record = read_instrument(path)
    for note in record.left_out():
        print(f"note: {note}")
    found = {key: value for key, value in record.fields.items() if key in LEVER}
    contact = record.fields.get("contact_resonance")
    return found, [contact] if contact else [], [1] if contact else []


def _lever(args, found: dict):
    """The lever from the file's values and the flags, the defaults of :func:`pfmdyn.commands.flags.fill_defaults`
    for the rest; the notes and what was assumed (name -> why).  Without a length, only the ratio of the tip height
    to it acts: an assumed tip height is then taken on a typical PFM lever (:data:`pfmdyn.constants.LEVER_LENGTH`)."""
    values = {**found, **flags.given(args, _LEVER)}
    flags.require(values, ("free_resonance", "spring_constant"), args.file)
    contact = flags.contact(args)
    lateral = values.get("tilt") or (contact.k2 if contact.k2 is not None else contact.ratio) != 0.0
    assumed = flags.fill_defaults(values, _LEVER) if lateral else {}
    notes = []
    if values.get("length") is None and not (lateral or values.get("tip_height") is not None):
        values["length"] = _NOMINAL_LENGTH
        notes.append("length not given and not needed (no lateral spring, no tilt)")
    elif values.get("length") is None:
        if "tip_height" not in assumed or values.get("tilt"):
            raise UserError("the tip height and the tilt act through the lever length: give --length")
        flags.assume_length(values, assumed)
        notes.append(f"length not given: the assumed tip height acts as a ratio to a typical PFM lever's length "
                     f"({values['tip_height'] / LEVER_LENGTH:.3g}), its uncertainty with the length's")
    if args.tip_position is not None:
        values["tip_position"] = checked("tip_position", args.tip_position, "--tip-position")
    medium = argparse.Namespace(medium=args.medium, temperature=args.temperature)
    return flags.cantilever(medium, values, defaults=False), notes, assumed


def _tip_height_uncertainty(args, lever, assumed: dict) -> dict:
    """``tip_height_uncertainty`` for :func:`pfmdyn.analysis.stiffness_report.analyse`: given, else the spread of an
    assumed tip height (with an assumed length's, relative, when only their ratio acts), else its own default (10 %
    of a given tip height)."""
    if args.tip_height_uncertainty is not None or "tip_height" not in assumed:
        return {}
    return {"tip_height_uncertainty": flags.assumed_tip_height_uncertainty(lever.tip_height, assumed)}


def _assumed_resonance_uncertainties(contacts, free_resonance: float, assumed: dict) -> dict:
    """The resonances' standard uncertainties (Hz) when none is given: :data:`RESONANCE_RELATIVE_UNCERTAINTY` of
    each frequency, their why added to ``assumed`` (the caller drops what a flag or the file gives).

    >>> _assumed_resonance_uncertainties([3e5, 8e5], 7e4, why := {})
    {'contact_uncertainty': [300.0, 800.0], 'free_resonance_uncertainty': 70.0}
    >>> sorted(why)
    ['contact_uncertainty', 'free_resonance_uncertainty']
    """
    why = (f"{RESONANCE_RELATIVE_UNCERTAINTY:.1%} of each frequency, assumed: neither a flag nor the input gives it "
           "(pfmdyn.constants.RESONANCE_RELATIVE_UNCERTAINTY)")
    assumed.update(dict.fromkeys(_RESONANCE_UNCERTAINTIES, why))
    return {"contact_uncertainty": [RESONANCE_RELATIVE_UNCERTAINTY * f for f in contacts],
            "free_resonance_uncertainty": RESONANCE_RELATIVE_UNCERTAINTY * free_resonance}


def _contact_map(args) -> int:
    """k1 at every pixel of a contact-frequency map (command-line values win over the file's)."""
    from ..maps.contact import contact_map, describe
    if not args.out:
        raise UserError(f"{args.file}: a contact-frequency map needs --out DIR (gets maps.zarr with k1)")
    others = [NAMES[n].flag for n in _LEVER + ("tip_position", "k2", "k2_over_k1", "poisson")
              if n not in ("spring_constant", "free_resonance") and getattr(args, n, None) is not None]
    others = ["--contact"] * bool(args.contact) + ["--reduced-modulus"] * bool(args.reduced_modulus) + others
    if others:
        raise UserError(f"{args.file}: a contact-frequency map is read on the paper's lever with k2 = 0 (the tip at "
                        f"the free end), its frequencies from the file, which {listed(others)} would not enter: "
                        "drop " + ("it" if len(others) == 1 else "them"))
    overrides = flags.given(args, ("free_resonance", "spring_constant"))
    overrides.update(flags.given(args, _RESONANCE_UNCERTAINTIES))
    if args.mode:
        if len(args.mode) != 1:
            raise UserError("a contact-frequency map has one mode: give --mode once")
        overrides["contact_mode"] = _mode(args.mode[0])
    summary = contact_map(args.file, args.out, overrides)
    print(describe(summary))
    from .map import write_summary
    write_summary(args.json, args.out, args.file, summary, overrides)       # the document map writes (it was lost)
    return 0


def _taken_line(found: dict, given: list, contacts) -> str:
    """What the file gave and no flag replaced (:func:`pfmdyn.commands.flags.taken_line`), the contact resonances
    (and their modes) first when they came from it.

    >>> print(_taken_line({"spring_constant": 0.46538, "length": 2.4e-4}, ["length"], ([368990.0], [1])))
    from the file: contact_resonance 368990 Hz (mode 1), spring_constant 0.46538 N/m
    """
    parts = [f"contact_resonance {f:.6g} Hz (mode {m})" for f, m in zip(*contacts)] if contacts else []
    return flags.taken_line(found, given, parts)


def _resonances_command(args, lever, solution, modes, assumed: dict) -> str:
    """The ``pfmdyn resonances`` command that puts the contact resonances back (the round trip): this lever with
    what the file gave, the flags given, k1 unrounded (the printed one is rounded to its uncertainty) and k2 by the
    same policy (its value when solved, or tied by the tip-position fit's k2 = 0, which no flag of resonances says).

    >>> import argparse
    >>> from pfmdyn.analysis.stiffness_report import Solution
    >>> from pfmdyn.cantilever import Cantilever
    >>> args = argparse.Namespace(k2=None, k2_over_k1=None, poisson="0.25", medium=None, temperature=None, tip_height=None)
    >>> lever = Cantilever(0.46538, 72969.0, 2.4e-4, tip_height=13e-6)
    >>> _resonances_command(args, lever, Solution(258.48086225838, 213.0, 1.0, ("k1",), {}), [1], {"tip_height": ""})
    'pfmdyn resonances --spring-constant 0.46538 --free-resonance 72969 --length 0.00024 --k1 258.4808623 --poisson 0.25'
    """
    import dataclasses
    import shlex

    def number(x):
        return f"{x:.10g}"
    defaults = {f.name: f.default for f in dataclasses.fields(lever)}
    argv = ["pfmdyn", "resonances"]
    for name in ("spring_constant", "free_resonance", "length", "width", "tip_height", "tip_position",
                 "tip_mass_ratio", "tip_gyration_radius", "tilt"):
        value = solution.tip_position if name == "tip_position" else getattr(lever, name)
        if name == "length" or (value is not None and value != defaults[name] and name not in assumed):
            argv += [NAMES[name].flag, number(value)]
    argv += [flag for name in ("medium", "temperature") if getattr(args, name) is not None
             for flag in (NAMES[name].flag, str(getattr(args, name)))]
    argv += ["--k1", number(solution.k1)]
    policy = [(NAMES[n].flag, str(getattr(args, n))) for n in ("k2", "k2_over_k1", "poisson") if getattr(args, n)
              is not None]
    if "k2" in solution.unknowns or ("tip_position" in solution.unknowns and not policy):
        policy = [("--k2", number(solution.k2 or 0.0))]
    argv += [word for pair in policy for word in pair]
    if max(modes or [1]) > 3:
        argv += ["--modes", str(max(modes))]
    return shlex.join(argv)


def _mode(text) -> int:
    """A flexural mode number, 1 to :data:`_MAX_MODE` (a count, not a quantity of :mod:`pfmdyn.names`).

    >>> _mode("2"), _mode("3.0")
    (2, 3)
    >>> _mode("0")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --mode must be a whole number from 1 to 1000, got 0
    """
    try:
        value = float(text)
    except ValueError:
        raise UserError(f"--mode must be a number, got {text!r}") from None
    if not (math.isfinite(value) and 1 <= value <= _MAX_MODE and value == int(value)):
        raise UserError(f"--mode must be a whole number from 1 to {_MAX_MODE}, got {text}")
    return int(value)


def run(args) -> int:
    """Parse, analyse (:func:`pfmdyn.analysis.stiffness_report.analyse`), print, write JSON if asked."""
    from ..analysis.stiffness_report import analyse
    from ..io.results import check_writable

    check_writable(args.json)
    if args.file and file_kind(args.file) in CONTACT_MAP_KINDS:
        return _contact_map(args)
    if args.out:
        raise UserError("--out is for a contact-frequency map (a file holding contact_frequency_hz)")
    fit = args.tip_position is not None and str(args.tip_position).strip().lower() == "fit"
    if fit:
        args = argparse.Namespace(**{**vars(args), "tip_position": None})
    found, contacts, modes = _from_file(args.file) if args.file else ({}, [], [])
    if args.contact:
        contacts = [checked("contact_resonance", c, "--contact") for c in args.contact]
        modes = []
    modes = [_mode(m) for m in args.mode] if args.mode else modes or None
    if not contacts:
        where = f" in {Path(args.file).name}" if args.file else ""
        raise UserError(f"no contact resonance{where}: give --contact HZ")
    lever, notes, assumed = _lever(args, found)
    hertz = flags.given(args, ("tip_radius", "normal_load"))     # checked even when not used
    if args.reduced_modulus and len(hertz) < 2:
        raise UserError("--reduced-modulus needs --tip-radius (m) and --normal-load (N)")
    hertz = (hertz["tip_radius"], hertz["normal_load"]) if args.reduced_modulus else None
    uncertainties = ({"spring_constant_uncertainty": 0.0}
                     | _assumed_resonance_uncertainties(contacts, lever.free_resonance, assumed)
                     | {name: found[name] for name in _RESONANCE_UNCERTAINTIES if name in found}
                     | flags.given(args, _UNCERTAINTIES) | _tip_height_uncertainty(args, lever, assumed))
    for name in _RESONANCE_UNCERTAINTIES:
        if name in found or getattr(args, name) is not None:
            assumed.pop(name)
    try:
        report = analyse(
            lever, flags.contact(args), contacts, modes, fit_tip_position=fit,
            tip_position_stated=args.tip_position is not None or "tip_position" in found,
            hertz=hertz, notes=tuple(notes), assumed=tuple(n for n in _UNCERTAINTIES if n in assumed), **uncertainties)
    except UserError as exc:
        if not args.file or str(exc).startswith(str(args.file)):
            raise
        # some of the numbers came from the file: the line names it
        raise UserError(f"{args.file}: {exc}", quantity=exc.quantity) from None
    if lever.medium is not None:
        print(flags.medium_line(lever.medium, args))
    if any(name in LEVER for name in assumed):
        print(flags.assumed_line(assumed, lever))
    if any(name in assumed for name in _RESONANCE_UNCERTAINTIES):
        which = {"contact_uncertainty": "the contact resonances", "free_resonance_uncertainty": "the free resonance"}
        print(f"assumed: standard uncertainty {RESONANCE_RELATIVE_UNCERTAINTY:.1%} of "
              f"{listed(which[n] for n in _RESONANCE_UNCERTAINTIES if n in assumed)} (none given; give "
              f"{listed((NAMES[n].flag for n in _RESONANCE_UNCERTAINTIES if n in assumed), 'or')})")
    given = flags.given_names(args, (*_LEVER, "tip_position", "medium", "temperature", *_UNCERTAINTIES))
    if args.file:
        print(_taken_line(found, given, None if args.contact else (contacts, modes)))
    print(report.report())
    if report.unique:
        print("the same lever in resonances (k1 unrounded): "
              + _resonances_command(args, lever, report.solution, modes, assumed))
    if args.json:
        from ..io import documents

        taken = [*found, *(["contact_resonance"] if args.file and not args.contact else [])]
        if "tip_height" in assumed and "tip_height_uncertainty" not in given:
            assumed["tip_height_uncertainty"] = NAMES["tip_height_uncertainty"].default_why + (
                " and of PFM levers' lengths" if "length" in assumed else "")
        document = report.to_dict()
        if "length" not in (*found, *assumed, *given):         # the nominal one: not given, not needed
            document["inputs"]["length"] = None
        flags.write_json(args.json, documents.stiffness(document, args.file, given, taken, assumed))
    return 0
