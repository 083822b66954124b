"""``pfmdyn spot``: where to put the laser spot (electrostatic blind spots, calibration, d_eff error)."""
from __future__ import annotations

import argparse
import math
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
    flags.add(parser, ("k1_uncertainty",))
    flags.add(parser, ("drive_frequency",), defaults={"drive_frequency": (None, "the one INPUT records")})
    parser.add_argument("--frequency", dest="drive_frequency", default=None, help=argparse.SUPPRESS)
    flags.add_json(parser)
    parser.add_argument("--plot", metavar="PATH", help="write the figure (ratio along the lever and over frequency)")


def report(result, stderr: dict | None = None, shares: dict | None = None) -> str:
    """The lines ``pfmdyn spot`` prints: each result with its standard uncertainty over the assumed inputs
    (``stderr``, ``shares``: :func:`pfmdyn.analysis.spot.spread`), to the digits it leaves."""
    d = result.to_dict()
    stderr = stderr or {}
    lines = [f"drive frequency {d['drive_frequency']:.6g} Hz (beta = {d['beta']:.6g})"]
    if not d["certified"]:
        lines.append(f"blind spot: not certified ({d['reason']})")
    elif d["blind_spot"]:
        lines.append("blind spot x_s/L: " + ", ".join(
            _pm(p, u) for p, u in zip(d["blind_spot"], stderr.get("blind_spot", [0.0] * len(d["blind_spot"]))))
            + " (certified: complete on (0, 1] for these inputs)")
    else:
        lines.append("blind spot x_s/L: none in (0, 1] (certified)")
    lines.append(f"at x_s/L = {d['spot_position']:g}: static sensitivity u_tip/(L theta) "
                 f"free {d['free_sensitivity']:.6g} (exact: the free lever's), in contact "
                 f"{_pm(d['contact_sensitivity'], stderr.get('contact_sensitivity', 0.0))} (paper: 2/3)")
    c, p = d["calibration_factor"], d["paper_calibration_factor"]
    lines.append(f"  measured/true d_eff: {_signed(c, stderr.get('calibration_factor'))} (InvOLS from a static force "
                 f"curve on this contact), {_signed(p, stderr.get('paper_calibration_factor'))} (A = 2 theta L/3)")
    e = d["d_eff_error_per_volt"]
    lines.append("  d_eff error from the distributed load: "
                 + (f"{_pm(e['re'] * 1e12, stderr.get('d_eff_error_per_volt', 0.0) * 1e12, '+')} pm/V per volt of "
                    "V_dc - V_surf" if e else "undetermined (needs --width)"))
    words = {"tip_height_uncertainty": "tip height", "k2_policy_uncertainty": "k2 policy", "k1_uncertainty": "k1"}
    moved = [name for name in (shares or {}) if any(
        v > 0 for part in shares[name].values() for v in (part if isinstance(part, list) else [part]))]
    if moved:
        lines.append("  uncertainties from the assumed inputs, each moved by its own: " + ", ".join(
            words[name] for name in moved) + ("" if "k1_uncertainty" in moved
                                              else "; k1 as given, without an uncertainty of its own"))
    return "\n".join(lines)


def _pm(value: float, sigma: float | None, sign: str = "") -> str:
    """``value`` to the digits its standard uncertainty leaves, with it; 'undetermined' when a blind spot
    appears or goes within it.

    >>> _pm(0.5563036, 0.0055), _pm(31.2311, 812.0, "+"), _pm(0.673401, 0.0), _pm(0.55, float("nan"))
    ('0.5563 +- 0.0055', '+31 +- 8.1e+02', '0.673401', '0.55 (undetermined uncertainty: a blind spot appears or goes within the assumed inputs)')
    >>> _pm(0.0012, 0.05)                      # an uncertainty above the value: the value to two digits
    '0.0012 +- 0.05'
    """
    from ..digits import rounded
    if sigma is not None and math.isnan(sigma):
        return f"{value:{sign}.2g} (undetermined uncertainty: a blind spot appears or goes within the assumed inputs)"
    text = rounded(value, sigma or 0.0) if not sigma or sigma < abs(value) else f"{value:.2g}"
    text = ("+" + text if sign and not text.startswith("-") else text)
    return text + (f" +- {sigma:.2g}" if sigma else "")


def _signed(z: dict, sigma: float | None = None) -> str:
    """A complex ratio ``{re, im}`` signed, real when it is (a lossless lever's): ``+3.729``, ``-1.2+0.03j``.

    >>> _signed({"re": 3.72892, "im": 0.0}), _signed({"re": -1.2, "im": 0.0312}), _signed({"re": 3.72892, "im": 0.0}, 0.2)
    ('+3.72892', '-1.2+0.0312j', '+3.73 +- 0.2')
    """
    return _pm(z["re"], sigma, "+") + (f"{z['im']:+.3g}j" if z["im"] else "")


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
    from ..analysis.spot import spot_analysis, spread
    from ..analysis.stiffness_report import assumed_variations
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
    stated = flags.contact(args)
    contact, policy = stated.policy(lever)
    result = spot_analysis(lever, contact, frequency)
    k1_uncertainty = flags.given(args, ("k1_uncertainty",)).get("k1_uncertainty", 0.0)
    stderr, shares = spread(lever, contact, frequency, assumed_variations(lever, stated, contact, assumed,
                                                                          k1_uncertainty))
    if lever.medium is not None:
        print(flags.medium_line(lever.medium, args))
    if assumed:
        print(flags.assumed_line(assumed, lever))
    if args.file:
        print(flags.taken_line({**found, **({} if args.drive_frequency else {"drive_frequency": frequency})},
                               flags.given_names(args, LEVER)))
    print(report(result, stderr, shares))
    print(f"k2 policy: {policy}")
    if args.json:
        from ..io import documents

        flags.write_json(args.json, documents.spot({**result.to_dict(), "k2_policy": policy, "stderr": stderr,
                                                    "frequency_from_file": args.drive_frequency is None,
                                                    "k1_uncertainty": k1_uncertainty},
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
