"""``pfmdyn roots``: certified resonance roots of one family, as a table and as JSON.

Example: ``pfmdyn roots elastic --n 5 --digits 30 --k1-over-k 10 --k2-ratio 0.1 --json r.json``.
Parameter values are read as exact decimals (``1e6``, ``0.1``); see :mod:`pfmdyn.roots`.
"""
from __future__ import annotations

import argparse

from fractions import Fraction
from typing import TYPE_CHECKING

from ..errors import UserError, listed
from ..generated import characteristic, families
from . import flags

if TYPE_CHECKING:       # the certified root finder is imported when the command runs, not for --help
    from ..roots.core import RootResult

__all__ = ["OPTIONS", "add_arguments", "parse_parameters", "positive_int", "run", "table"]

OPTIONS = {"k1_over_k": "--k1-over-k", "k2_ratio": "--k2-ratio", "k2t_HL": "--k2t-hl"}
"""Dimensionless parameter -> command-line option."""


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn roots``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["free", "--modes", "2"]).modes
    '2'
    """
    parser.add_argument("family", help=f"one of: {', '.join(characteristic.FAMILIES)}")
    # Numbers are parsed in run() so that every bad value is reported as one line.
    parser.add_argument("--modes", default="5", help="number of roots, counted from the lowest (default 5)")
    parser.add_argument("--n", dest="modes", help=argparse.SUPPRESS)        # the old spelling, one release
    parser.add_argument("--digits", default="15", help="significant digits (default 15)")
    for name, option in OPTIONS.items():
        parser.add_argument(option, dest=name, default=None, help=families.PARAMETER_HELP[name])
    flags.add_json(parser, "the roots")


MAX_ROOTS, MAX_DIGITS = 1000, 4000
"""Largest ``--n`` and ``--digits``: beyond them a proof runs for hours (and Python prints no
integer of more than 4300 digits)."""


def positive_int(text: str, what: str, most: int | None = None) -> int:
    """``text`` as an integer > 0 (and at most ``most``), else a :class:`UserError`.

    >>> positive_int("12", "--n")
    12
    >>> positive_int("5000", "--digits", MAX_DIGITS)
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: --digits must be at most 4000, got 5000
    """
    try:
        value = int(text)
    except ValueError:
        raise UserError(f"{what} must be an integer, got {text!r}") from None
    if value <= 0:
        raise UserError(f"{what} must be positive, got {value}")
    if most is not None and value > most:
        raise UserError(f"{what} must be at most {most}, got {value}")
    return value


def parse_parameters(family: str, given: dict) -> dict:
    """The family's parameters from ``{name: text or None}``, checked, as decimal strings.

    >>> parse_parameters("frictionless", {"k1_over_k": "1e6", "k2_ratio": None, "k2t_HL": None})
    {'k1_over_k': '1e6'}
    >>> parse_parameters("elastic", {"k1_over_k": None, "k2_ratio": None})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: family 'elastic' needs --k1-over-k (k1/k: vertical contact stiffness over the cantilever spring constant) and --k2-ratio (k2 H^2/(k L^2): longitudinal contact stiffness seen through the lever arm H)
    """
    if family not in characteristic.FAMILIES:
        raise UserError(f"unknown family {family!r}; choose from {', '.join(characteristic.FAMILIES)}")
    wanted = characteristic.PARAMETERS[family]
    extra = [OPTIONS[n] for n, v in given.items() if v is not None and n not in wanted]
    if extra:
        raise UserError(f"family {family!r} takes no {', '.join(extra)}")
    missing = [name for name in wanted if given.get(name) is None]
    if missing:         # every one at once: the user gives them in one run
        raise UserError(f"family {family!r} needs " + listed(
            f"{OPTIONS[name]} ({families.PARAMETER_HELP[name]})" for name in missing))
    out = {}
    for name in wanted:
        text = given[name]
        try:
            value = Fraction(text)
        except (ValueError, ZeroDivisionError):
            raise UserError(f"{OPTIONS[name]} must be a finite decimal number, got {text!r}") from None
        if value < 0:
            raise UserError(f"{OPTIONS[name]} must be non-negative (a stiffness), got {text}")
        out[name] = text
    return out


def table(result: RootResult) -> str:
    """A readable table of a :class:`~pfmdyn.roots.core.RootResult`.

    >>> from pfmdyn.roots.core import family_roots
    >>> print(table(family_roots("pinned", 1, 6)))
    pinned: first 1 roots of the characteristic equation in beta, 6 significant digits
    certified: the list is complete on (0, 4.67699] and each interval holds exactly one simple root
      n  root     interval
      1  3.92660  [3.92660231, 3.92660232]
    """
    var = "xi L" if result.family.startswith("torsion") else "beta"
    params = ", ".join(f"{k} = {v}" for k, v in result.parameters.items())
    head = (f"{result.family}{f' ({params})' if params else ''}: first {len(result.roots) or 'n'} roots of the "
            f"characteristic equation in {var}, {result.digits} significant digits")
    if not result.certified:
        return f"{head}\nnot certified: {result.reason}"
    width = max(len(r) for r in result.roots)
    rows = [f"{i:>3}  {r:<{width}}  [{lo}, {hi}]" for i, (r, (lo, hi)) in enumerate(zip(result.roots, result.intervals), 1)]
    return "\n".join([head, f"certified: the list is complete on (0, {result.z_max}] and each interval holds "
                      "exactly one simple root", f"  n  {'root':<{width}}  interval", *rows])


def run(args) -> int:
    """Compute, print and optionally write the roots; exit status 1 when not certified.

    >>> import argparse
    >>> run(argparse.Namespace(family="torsion-force", modes="1", digits="5", k1_over_k=None,
    ...                        k2_ratio=None, k2t_HL=None, json=None))
    torsion-force: first 1 roots of the characteristic equation in xi L, 5 significant digits
    certified: the list is complete on (0, 2.32079] and each interval holds exactly one simple root
      n  root    interval
      1  1.5708  [1.5707963, 1.5707964]
    0
    """
    from ..io.results import check_writable
    from ..roots.core import family_roots

    check_writable(args.json)
    params = parse_parameters(args.family, {name: getattr(args, name) for name in OPTIONS})
    n, digits = positive_int(args.modes, "--modes", MAX_ROOTS), positive_int(args.digits, "--digits", MAX_DIGITS)
    result = family_roots(args.family, n, digits, **params)
    print(table(result))
    if args.json:
        from ..io import documents

        flags.write_json(args.json, documents.roots(result.to_json()))
    return 0 if result.certified else 1
