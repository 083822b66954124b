"""``pfmdyn spot``: where to put the laser spot (electrostatic blind spots, calibration, d_eff error)."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import UserError
from ..names import LEVER, checked
from . import flags

__all__ = ["add_arguments", "run", "report"]

ONE_LEVER = True
"""One lever at a few points: the NumPy forms of the lever (:func:`pfmdyn.commands.flags.lever_forms`)."""


def add_arguments(parser) -> None:
    """Options of ``pfmdyn spot``: the probe's flags (SI, :mod:`pfmdyn.names`) and the drive frequency
    (``--frequency``, its old spelling, hidden, still read).

    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> [p.parse_args([flag, "1e4", "--k1", "100"]).drive_frequency for flag in ("--drive-frequency", "--frequency")]
    ['1e4', '1e4']
    """
    parser.add_argument("file", nargs="?", metavar="INPUT", help="instrument file supplying what it holds of the lever "
                        "(.ibw, .h5, .nid, sweeps); flags override it")
    flags.add_lever(parser)
    flags.add_contact(parser, required=("k1",))
    flags.add(parser, ("drive_frequency",), defaults={"drive_frequency": (None, "the one INPUT records")})
    parser.add_argument("--frequency", dest="drive_frequency", default=None, help=argparse.SUPPRESS)
    flags.add_json(parser)
    parser.add_argument("--plot", metavar="PATH", help="write the figure (ratio along the lever and over frequency)")


def report(result) -> str:
    """The lines ``pfmdyn spot`` prints."""
    d = result.to_dict()
    lines = [f"drive frequency {d['drive_frequency']:.6g} Hz (beta = {d['beta']:.6g})"]
    if not d["certified"]:
        lines.append(f"blind spot: not certified ({d['reason']})")
    elif d["blind_spot"]:
        lines.append("blind spot x_s/L: " + ", ".join(f"{p:.6f}" for p in d["blind_spot"])
                     + " (certified: complete on (0, 1])")
    else:
        lines.append("blind spot x_s/L: none in (0, 1] (certified)")
    lines.append(f"at x_s/L = {d['spot_position']:g}: static sensitivity u_tip/(L theta) "
                 f"free {d['free_sensitivity']:.6g}, in contact {d['contact_sensitivity']:.6g} (paper: 2/3)")
    c, p = d["calibration_factor"], d["paper_calibration_factor"]
    lines.append(f"  measured/true d_eff: {_signed(c)} (InvOLS from a static force curve "
                 f"on this contact), {_signed(p)} (A = 2 theta L/3)")
    e = d["d_eff_error_per_volt"]
    lines.append("  d_eff error from the distributed load: "
                 + (f"{e['re'] * 1e12:+.4g} pm/V per volt of V_dc - V_surf" if e else "undetermined (needs --width)"))
    return "\n".join(lines)


def _signed(z: dict) -> str:
    """A complex ratio ``{re, im}`` signed, real when it is (a lossless lever's): ``+3.729``, ``-1.2+0.03j``.

    >>> _signed({"re": 3.72892, "im": 0.0}), _signed({"re": -1.2, "im": 0.0312})
    ('+3.72892', '-1.2+0.0312j')
    """
    return f"{z['re']:+.6g}" + (f"{z['im']:+.3g}j" if z["im"] else "")


def _read(args) -> dict:
    """What the instrument file (when given) records (names -> SI), its notes of what it left out printed."""
    if not args.file:
        return {}
    from ..io.instruments import read_instrument
    record = read_instrument(args.file)
    for note in record.left_out():
        print(f"note: {note}")
    return record.fields


def _frequency(args, fields: dict) -> float:
    """The drive frequency: ``--drive-frequency``, else the one the file records."""
    if args.drive_frequency is not None:
        return checked("drive_frequency", args.drive_frequency, "--drive-frequency")
    if fields.get("drive_frequency") is None:
        where = f" in {Path(args.file).name}" if args.file else ""
        raise UserError(f"no drive frequency{where}: give --drive-frequency")
    return checked("drive_frequency", fields["drive_frequency"], args.file)


def _lever(args, found: dict, assumed: dict):
    """The lever from the file's values ``found`` with the flags over them; the defaults it took into
    ``assumed`` (name -> why)."""
    given = {**found, **flags.given(args, LEVER)}
    flags.require(given, ("spring_constant", "free_resonance", "length"), args.file)
    return flags.cantilever(args, found, assumed)


def run(args) -> int:
    """Analyse, print, write what was asked."""
    from ..analysis.spot import spot_analysis
    from ..io.results import check_writable
    check_writable(args.json)
    check_writable(args.plot, figure=True)
    if args.drive_frequency is not None:
        _frequency(args, {})                    # a bad flag before the file
    fields = _read(args)
    frequency = _frequency(args, fields)
    found = {key: value for key, value in fields.items() if key in LEVER}
    assumed = {}
    lever = _lever(args, found, assumed)
    contact, policy = flags.contact(args).policy(lever)
    result = spot_analysis(lever, contact, frequency)
    if lever.medium is not None:
        print(flags.medium_line(lever.medium, args))
    if assumed:
        print(flags.assumed_line(assumed, lever))
    if args.file:
        print(flags.taken_line({**found, **({} if args.drive_frequency else {"drive_frequency": frequency})},
                               flags.given_names(args, LEVER)))
    print(report(result))
    print(f"k2 policy: {policy}")
    if args.json:
        from ..io import documents

        flags.write_json(args.json, documents.spot({**result.to_dict(), "k2_policy": policy,
                                                    "frequency_from_file": args.drive_frequency is None},
                                                   flags.given_names(args, (*flags.NAMES,)), list(found), args.file))
    if args.plot:
        import numpy as np

        from ..analysis.spot import ratio_map
        from ..plots.spot import plot_spot
        fmax = max(2.0 * frequency, 8.0 * lever.free_resonance)
        frequencies = np.linspace(fmax / 400, fmax, 400)
        flags.save_figure(plot_spot(result, frequencies, ratio_map(lever, contact, frequencies, result.positions)),
                          args.plot)
    return 0
