"""The probe's command-line flags, the same in every command (names: :mod:`pfmdyn.names`).

A command adds the groups it uses (:func:`add_lever`, :func:`add_contact`, :func:`add_damping`)
and builds the one description from them, values found in a file first and flags over them
(:func:`cantilever`, :func:`contact`).  Every value is checked against what a real probe can
have, and a bad one is a one-line error naming the flag.
"""
from __future__ import annotations

import argparse
import contextlib
import math
import sys
from pathlib import Path

from ..cantilever import Cantilever, Contact
from ..errors import UserError, listed
from ..medium import Medium
from ..names import CONTACT, DAMPING, LEVER, NAMES, checked, fill_defaults

__all__ = ["add", "taken_line", "assume_length", "assumed_tip_height_uncertainty", "add_lever", "add_contact", "add_damping", "add_medium_arguments", "medium_from_args", "check_medium",
           "temperature", "medium_line", "add_json", "write_json", "save_figure", "given", "require", "fill_defaults",
           "assumed_line", "cantilever", "contact", "progress_shown",
           "option_hint"]


@contextlib.contextmanager
def lever_forms(one_lever: bool):
    """While a command runs: for one that evaluates one lever at a few points (``ONE_LEVER`` in its
    module: ``resonances``, ``stiffness``, ``spot``) the composed lever's NumPy forms
    (:data:`pfmdyn.composed.KERNELS` off), restored after.  The compiled kernels pay off in fits over
    many spectra; there a fresh install would first compile them (14-19 s) for an answer the NumPy
    forms give in under a second (the same numbers: the tests hold the kernels to them).

    >>> from pfmdyn import composed
    >>> with lever_forms(True):
    ...     composed.KERNELS
    False
    >>> composed.KERNELS
    True
    """
    from .. import composed
    kept = composed.KERNELS
    composed.KERNELS = kept and not one_lever
    try:
        yield
    finally:
        composed.KERNELS = kept


def add(parser, names, required=(), defaults=None) -> None:
    """Flags of any quantities of :mod:`pfmdyn.names` (``defaults`` as in :func:`add_lever`).

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add(p, ("tip_radius",))
    >>> p.parse_args(["--tip-radius", "2e-8"]).tip_radius
    '2e-8'
    """
    defaults = defaults or {}
    for name in names:
        q = NAMES[name]
        unit = "" if q.unit == "1" else f", {q.unit}"
        assumed = f"{q.default:g} {q.unit}, assumed" + (f": {q.default_why}" if q.default_why else "") \
            if q.default is not None else \
            "none: the lever in vacuum" if name == "medium" else ""
        value, why = defaults.get(name, (None, assumed))
        text = f"{q.meaning} ({q.symbol}{unit}" + (f"; default {why})" if why else ")")
        # argparse %-formats help (``%(default)s``): a "%" of a meaning is literal
        parser.add_argument(q.flag, dest=name, default=value, metavar=q.symbol.upper() if q.unit == "1" else q.unit,
                            required=name in required, help=text.replace("%", "%%"))


def add_lever(parser, names=LEVER, required=(), defaults=None, medium: bool = True) -> None:
    """Flags of the lever, its tip and the spot (``--spring-constant ... --spot-position``), and with
    ``medium`` the fluid around it (``--medium --temperature``, and ``--width`` it acts across).

    ``defaults`` maps a name to ``(value, words)``: the value taken when the flag is not given
    (checked like a given one by :func:`given`) and how ``--help`` states it.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_lever(p, defaults={"tip_height": (1e-5, "1e-05, the paper's")})
    >>> p.parse_args(["--tip-position", "0.93", "--tilt", "12"]).tip_position, p.parse_args([]).tip_height
    ('0.93', 1e-05)
    """
    add(parser, names, required, defaults)
    if medium:
        add(parser, [n for n in ("medium", "width", "temperature") if n not in names])


def add_contact(parser, names=CONTACT, required=(), defaults=None) -> None:
    """Flags of the contact (``--k1 --k2 --k2-over-k1 --poisson``); ``defaults`` as in :func:`add_lever`."""
    add(parser, names, required, defaults)


def add_damping(parser, names=DAMPING, defaults=None) -> None:
    """Flags of the three damping mechanisms (``--quality-factor --viscous-loss --contact-loss``);
    ``defaults`` as in :func:`add_lever`."""
    add(parser, names, defaults=defaults)


def add_medium_arguments(parser, width_required: bool = False, medium: str = "") -> None:
    """``--medium --width --temperature``: the fluid around the lever and the width it acts on; ``medium``:
    how ``--help`` states its default (none: the lever in vacuum).

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_medium_arguments(p)
    >>> p.parse_args(["--medium", "water", "--temperature", "298.15"]).medium
    'water'
    """
    add(parser, ("medium", "width", "temperature"), required=("width",) if width_required else (),
        defaults={"medium": (None, medium)} if medium else None)


def medium_from_args(args, found: dict | None = None, default: str = "air") -> Medium:
    """The :class:`~pfmdyn.medium.Medium` of ``--medium`` at ``--temperature`` (K); ``found`` (values a
    file holds: ``medium``, ``temperature``) fills what the flags leave out, then ``default`` at the
    assumed temperature (:func:`temperature`).  Air and water only where they are that phase.

    >>> import argparse
    >>> medium_from_args(argparse.Namespace(medium=None, temperature="313.15")).name
    'air at 40 C'
    >>> medium_from_args(argparse.Namespace(medium="1000,1e-3", temperature=None)).viscosity
    0.001
    >>> medium_from_args(argparse.Namespace(medium="water", temperature="20"))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --temperature: water is liquid at temperatures from 273.15 to 373.15 K (one atmosphere), got 20 K: did you mean 293.15 K (20 C)?
    """
    found = found or {}
    given_medium = getattr(args, "medium", None)
    text = given_medium if given_medium is not None else found.get("medium") or default
    flagged = getattr(args, "temperature", None)
    try:        # a flag's text as it is: air's and water's check hints at Celsius (0 included)
        return Medium.parse(text, flagged if flagged is not None else temperature(args, found)[0])
    except UserError as exc:
        blamed = "temperature" if exc.quantity == "temperature" and flagged is not None else "medium"
        raise UserError(f"{NAMES[blamed].flag}: {exc}") from None


def temperature(args, found: dict | None = None) -> tuple[float, str]:
    """The temperature (K) a command uses and where it came from: ``given`` (the flag), ``from the file``
    (``found``) or ``assumed`` (the default of :mod:`pfmdyn.names`).

    >>> import argparse
    >>> temperature(argparse.Namespace(temperature="300")), temperature(argparse.Namespace(), {"temperature": 313.15})
    ((300.0, 'given'), (313.15, 'from the file'))
    >>> temperature(argparse.Namespace(temperature=None))
    (293.15, 'assumed: give --temperature')
    """
    q = NAMES["temperature"]
    if getattr(args, "temperature", None) is not None:
        return checked("temperature", args.temperature, q.flag), "given"
    if (found or {}).get("temperature") is not None:
        return checked("temperature", found["temperature"]), "from the file"
    return q.default, f"assumed: give {q.flag}"


def medium_line(medium: Medium, args, found: dict | None = None, thermal: bool = False) -> str:
    """What a command prints of the fluid it used: its name and the temperature that sets its
    properties (air, water) or the thermal noise (``thermal``), with where that came from.

    >>> import argparse
    >>> medium_line(Medium.air(300.0), argparse.Namespace(temperature="300"))
    'medium: air at 26.85 C; temperature 300 K (given)'
    >>> medium_line(Medium(1000.0, 1e-3, "oil"), argparse.Namespace(temperature=None))
    'medium: oil'
    """
    if medium.temperature is None and not thermal:
        return f"medium: {medium.name}"
    kelvin, source = temperature(args, found)
    return f"medium: {medium.name}; temperature {kelvin:g} K ({source})"


def progress_shown(args) -> bool:
    """Whether a command draws a progress bar: on a terminal only (a log or a pipe gets the report alone),
    and not with ``--quiet`` or ``--no-progress``.

    >>> progress_shown(argparse.Namespace(quiet=True))
    False
    """
    return not (getattr(args, "quiet", False) or getattr(args, "no_progress", False)) and sys.stderr.isatty()


def add_json(parser, what: str = "the result") -> None:
    """``--json PATH``: ``what`` as a JSON document in PATH, or with ``-`` alone on standard output, the
    lines the command prints going to standard error (:func:`write_json`).

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_json(p)
    >>> p.parse_args(["--json", "-"]).json
    '-'
    """
    parser.add_argument("--json", metavar="PATH", help=f"write {what} as JSON to PATH ('-': the document alone "
                        "on standard output, the report on standard error)")


def write_json(path, document) -> None:
    """``document`` as JSON to ``path`` (:func:`pfmdyn.io.results.write_json`), to standard output when
    ``path`` is ``-``, nowhere when None.

    >>> write_json("-", {"k1": 300.0})
    {
      "k1": 300.0
    }
    """
    from ..io import results

    if path == "-":
        print(results.dumps(document), file=DOCUMENTS[-1] if DOCUMENTS else sys.stdout)
    elif path:
        results.write_json(path, document)


def save_figure(figure, path, dpi: int = 120) -> None:
    """Save ``figure`` to ``path`` (checked before the analysis); what matplotlib then cannot save is one
    line.

    >>> from matplotlib.figure import Figure
    >>> save_figure(Figure(), "/nonexistent/folder/f.png")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /nonexistent/folder/f.png: No such file or directory
    """
    try:
        figure.savefig(path, dpi=dpi)
    except (OSError, ValueError) as exc:     # no such folder; a format matplotlib lacks
        raise UserError(f"cannot write {path}: {getattr(exc, 'strerror', None) or exc}") from None


DOCUMENTS: list = []
"""Where ``--json -`` prints when the command's other output is silenced (``--quiet``; set by the CLI)."""


def given(args, names) -> dict[str, float]:
    """The values of the flags among ``names`` that were given, checked (name -> SI float).

    >>> import argparse
    >>> given(argparse.Namespace(length="2e-4", width=None), ("length", "width"))
    {'length': 0.0002}
    >>> given(argparse.Namespace(length="-2"), ("length",))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --length: length must be in (1e-06, 0.01] m, got -2
    """
    out = {}
    for name in names:
        value = getattr(args, name, None)
        if value is not None:
            out[name] = checked(name, value, NAMES[name].flag)
    return out


def given_names(args, names) -> list[str]:
    """The names among ``names`` whose flag was given (their records' status ``given``).

    >>> import argparse
    >>> given_names(argparse.Namespace(medium="water", length=None), ("medium", "length", "width"))
    ['medium']
    """
    return [name for name in names if getattr(args, name, None) is not None]


def require(values: dict, names, file=None) -> None:
    """A one-line error naming every one of ``names`` with no value: what is missing, where, which
    flags (all at once: a user gives them in one run, not one per run).

    >>> require({"length": 2e-4}, ("length", "tip_height"), "scan.ibw")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: no tip height in scan.ibw: give --tip-height
    >>> require({}, ("spring_constant", "length"))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: no spring constant or lever length: give --spring-constant and --length
    """
    missing = [name for name in names if values.get(name) is None]
    if missing:
        where = f" in {Path(file).name}" if file else ""
        raise UserError(f"no {listed((NAMES[name].label for name in missing), 'or')}{where}: "
                        f"give {listed(NAMES[name].flag for name in missing)}")


PATHS = (("file", "INPUT"), ("data", "INPUT"), ("reference", "--reference"), ("json", "--json"), ("plot", "--plot"),
         ("csv", "--csv"), ("errata", "--errata"))
"""The files a command reads (the first three) and writes, and how its command line names them."""


def check_distinct_paths(args) -> None:
    """Refuse an output that names an input or another output: the one written last would be all that is left
    (a data file overwritten by its own report).

    >>> check_distinct_paths(argparse.Namespace(file="t.csv", json="-", plot="t.png"))
    >>> check_distinct_paths(argparse.Namespace(data="t.csv", json="./t.csv"))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --json would overwrite INPUT ./t.csv: give it a path of its own
    >>> check_distinct_paths(argparse.Namespace(json="out.png", plot="out.png"))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --json and --plot name the same file out.png: give each its own
    """
    seen = {}
    for dest, flag in PATHS:
        value = getattr(args, dest, None)
        if value is None or str(value) == "-":
            continue
        path = Path(value).expanduser().resolve()
        if path in seen and dest in ("json", "plot", "csv", "errata"):
            other, inputs = seen[path], ("INPUT", "--reference")
            raise UserError(f"{flag} would overwrite {other} {value}: give it a path of its own" if other in inputs
                            else f"{other} and {flag} name the same file {value}: give each its own")
        seen.setdefault(path, flag)


def check_medium(args) -> None:
    """Refuse a bad ``--medium`` or ``--temperature`` even where the command would not use it (a
    lever in vacuum): a value given is a value meant.

    >>> import argparse
    >>> check_medium(argparse.Namespace(medium=None, temperature="abc"))
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --temperature: air is a gas at temperatures from 150 to 2000 K (one atmosphere), got 'abc'
    """
    if getattr(args, "medium", None) is not None or getattr(args, "temperature", None) is not None:
        medium_from_args(args)
        temperature(args)       # also where the medium's own numbers do not depend on it


def assume_length(values: dict, assumed: dict) -> None:
    """Put a typical PFM lever's length (:data:`pfmdyn.constants.LEVER_LENGTH`) into ``values`` and why into
    ``assumed``: for a file without the length whose tip height is assumed too, only their ratio acts.

    >>> values, why = {}, {}; assume_length(values, why); values["length"], why["length"].split(":")[0]
    (0.000225, "a typical PFM lever's, 225 um +/- 10%")
    """
    from ..constants import LEVER_LENGTH, LEVER_LENGTH_SPREAD
    values["length"] = LEVER_LENGTH
    assumed["length"] = (f"a typical PFM lever's, {LEVER_LENGTH * 1e6:g} um +/- {LEVER_LENGTH_SPREAD:.0%}: only the "
                         "assumed tip height over it acts")


def assumed_tip_height_uncertainty(tip_height: float, assumed) -> float:
    """The standard uncertainty (m) of a tip height whose own is not given: an assumed one's spread (with an
    assumed length's, relative, when only their ratio acts: :func:`assume_length`), else 10 % of a given one.

    >>> assumed_tip_height_uncertainty(13e-6, ["tip_height"]), round(assumed_tip_height_uncertainty(13e-6, ["tip_height", "length"]), 8)
    (2.5e-06, 2.82e-06)
    """
    from ..analysis.stiffness_report import tip_height_spread
    from ..constants import LEVER_LENGTH_SPREAD
    spread = tip_height_spread(tip_height, "tip_height" in assumed)
    return math.hypot(spread / tip_height, LEVER_LENGTH_SPREAD) * tip_height if "length" in assumed else spread


def taken_line(found: dict, given, first=()) -> str:
    """The line a command prints of the values it took from the input file (``found``, names -> SI) that no flag
    (``given``) replaced, after the parts ``first`` (already worded).

    >>> taken_line({"spring_constant": 0.46538, "length": 2.4e-4, "drive_frequency": 380740.0}, ["length"])
    'from the file: drive_frequency 380740 Hz, spring_constant 0.46538 N/m'
    """
    parts = [*first, *(f"{name} {value:.6g}" + (f" {NAMES[name].unit}" if NAMES[name].unit != "1" else "")
                       for name, value in sorted(found.items()) if name not in given)]
    return "from the file: " + (", ".join(parts) or "nothing the flags did not replace")


def assumed_line(assumed: dict, lever: Cantilever) -> str:
    """The line a command prints of the values of ``lever`` it assumed (name -> why: :func:`fill_defaults`),
    "" for none.

    >>> assumed_line({"tip_height": "a typical PFM probe's"}, Cantilever(2.0, 7e4, 2e-4, tip_height=13e-6))
    "assumed: tip height 1.3e-05 m (a typical PFM probe's; give --tip-height)"
    """
    return "; ".join(f"assumed: {NAMES[name].label} {getattr(lever, name):g} {NAMES[name].unit} ({why}; give "
                     f"{NAMES[name].flag})" for name, why in assumed.items() if name in LEVER)


def cantilever(args, found: dict | None = None, assumed: dict | None = None, defaults: bool = True) -> Cantilever:
    """The lever from values ``found`` in a file (names -> SI) with the flags over them, and (``defaults``)
    those of :func:`fill_defaults` for what neither gives (into ``assumed``, when a dict, name -> why).

    >>> import argparse
    >>> ns = argparse.Namespace(spring_constant="2", free_resonance="7e4", length=None, tilt="12")
    >>> lever = cantilever(ns, {"length": 2e-4, "spring_constant": 1.0}, assumed := {})
    >>> lever.spring_constant, lever.length, lever.tilt, lever.tip_height, list(assumed)
    (2.0, 0.0002, 12.0, 1.3e-05, ['tip_height'])
    """
    values = {k: v for k, v in (found or {}).items() if k in LEVER or k in ("quality_factor", "viscous_loss")}
    values.update(given(args, LEVER + ("quality_factor", "viscous_loss")))
    filled = fill_defaults(values) if defaults else {}
    if assumed is not None:
        assumed.update(filled)
    if values.get("quality_factor") is None:
        values["quality_factor"] = math.inf
    if getattr(args, "medium", None) or (found or {}).get("medium"):      # else vacuum, the paper's case
        values["medium"] = medium_from_args(args, found)
        require(values, ("width",))
    return Cantilever.from_values(values)


def contact(args) -> Contact:
    """The contact from its flags (and ``--contact-loss``).

    >>> import argparse
    >>> contact(argparse.Namespace(k1="300", poisson="0.3")).describe_k2()
    'k2 tied to k1 (Mindlin, Poisson ratio 0.3: k2 = 0.824 k1)'
    """
    values = given(args, CONTACT + ("contact_loss",))
    return Contact(**values)


def option_hint(error: Exception, parser=None) -> str:
    """``": give --flag"`` when ``error`` concerns a quantity that a flag supplies.

    The library names the quantity (:attr:`pfmdyn.errors.UserError.quantity`; a field missing
    from a file: :class:`pfmdyn.io.record.MissingFieldError`); only the commands know flags.  The
    flag is the option of ``parser`` (the command's) that sets the quantity, else the name's own
    (:mod:`pfmdyn.names`); a quantity no flag sets gives no hint; several quantities (a tuple), each its flag.

    >>> from pfmdyn.io.record import MissingFieldError
    >>> option_hint(MissingFieldError("tip height not in a.ibw", "tip_height"))
    ': give --tip-height'
    >>> import argparse
    >>> p = argparse.ArgumentParser(); _ = p.add_argument("--out", dest="out")
    >>> option_hint(UserError("maps.zarr holds another map", quantity="out"), p)
    ': give --out'
    >>> option_hint(MissingFieldError("no contact resonance in a.ibw", "contact_resonance")), option_hint(ValueError("x"))
    ('', '')
    >>> option_hint(MissingFieldError("lever length and tip height not in a.h5", ("length", "tip_height")))
    ': give --length and --tip-height'
    """
    quantity = getattr(error, "quantity", None)
    hints = [hint for hint in (_flag_of(name, parser) for name in
                               (quantity if isinstance(quantity, tuple) else (quantity,)) if name) if hint]
    return f": give {listed(hints)}" if hints else ""


def _flag_of(name: str, parser) -> str | None:
    """The option of ``parser`` that sets ``name``, else the name's own flag, else None."""
    options = [option for action in getattr(parser, "_actions", ()) if action.dest == name
               and action.help != argparse.SUPPRESS for option in action.option_strings if option.startswith("--")]
    if options:
        return options[0]
    return NAMES[name].flag if name in NAMES and NAMES[name].option else None
