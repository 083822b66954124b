"""``pfmdyn diagram``: draw a frequency-bias response diagram (Figs. 6-7) of a Table 1 or custom lever."""
from __future__ import annotations

import argparse
import contextlib
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..analysis.diagram import (PAPER_D_EFF, PAPER_K1, PAPER_TIP_HEIGHT, SILICON_DENSITY, TABLE1,
                                ResponseMap, cantilever_from_spring_constant, response_map,
                                table1_cantilever)
from ..errors import UserError, listed
from ..io.results import check_writable
from ..names import flag
from ..plots.diagram import KINDS, plot_diagram
from . import flags


def add_arguments(parser) -> None:
    """Options of ``pfmdyn diagram``."""
    parser.add_argument("--cantilever", default="A", metavar="A|B|C|custom",
                        help="Table 1 cantilever, or 'custom' with --spring-constant --length --width --thickness "
                             "(SI: N/m, m; default A)")
    flags.add_lever(parser, _CUSTOM)
    flags.add_lever(parser, ("spot_position",), medium=False)
    # The paper's values where the diagram needs a number (Figs. 6-7); the lossless lever as in the paper.
    flags.add_damping(parser, ("quality_factor",), defaults={"quality_factor": (None, "lossless, as in the paper")})
    flags.add_contact(parser, ("k1",), defaults={"k1": (PAPER_K1, f"{PAPER_K1:g}, the paper's")})
    flags.add_lever(parser, ("tip_height",), medium=False, defaults={"tip_height": (PAPER_TIP_HEIGHT, f"{PAPER_TIP_HEIGHT:g}, the paper's")})
    flags.add(parser, ("d_eff",), defaults={"d_eff": (PAPER_D_EFF, f"{PAPER_D_EFF:g}, the paper's")})
    flags.add(parser, ("local_force", "surface_potential"),
              defaults={"local_force": (0.0, "0"), "surface_potential": (0.0, "0")})
    parser.add_argument("--electrostatic-sign", type=int, choices=(-1, 1), default=-1,
                        help="-1: attractive capacitive force (default, the project's convention); "
                             "+1: the drives as the paper prints them")
    parser.add_argument("--kind", choices=KINDS,
                        default="amplitude", help="what to draw (default amplitude)")
    parser.add_argument("--fmin", type=float, default=1e3, help="lowest frequency, Hz (default 1e3)")
    parser.add_argument("--fmax", type=float, default=3e6, help="highest frequency, Hz (default 3e6)")
    parser.add_argument("--log-frequency", action="store_true", help="log-spaced frequency axis")
    parser.add_argument("--vmin", type=float, default=-10.0, help="lowest V_dc, V (-10)")
    parser.add_argument("--vmax", type=float, default=10.0, help="highest V_dc, V (10)")
    parser.add_argument("--frequency-points", type=int, default=1000, help="frequencies of the grid (default 1000)")
    parser.add_argument("--bias-points", type=int, default=401, help="DC biases of the grid (default 401)")
    parser.add_argument("--plot", type=Path, metavar="PATH", help="the figure to write (.png, .pdf, .svg); required")
    parser.add_argument("--out", dest="plot", type=Path, help=argparse.SUPPRESS)    # the old spelling, one release
    parser.add_argument("--csv", type=Path, help="also write the map as long-format CSV")
    flags.add_json(parser, "the response's parts per frequency (the map follows from them)")


MAX_POINTS = 2e7
"""Largest diagram (frequencies x biases): a few GB of complex responses and shares."""
_CUSTOM = ("spring_constant", "length", "width", "thickness", "density")
"""The custom lever's flags (:mod:`pfmdyn.names`, SI)."""


def _quality_factor(args) -> float:
    """``--quality-factor``, checked; lossless (inf) when not given."""
    return flags.given(args, ("quality_factor",)).get("quality_factor", math.inf)


def _cli_cantilever(args):
    """``(Cantilever, width in m)`` from the options; errors as :class:`UserError`."""
    custom = flags.given(args, _CUSTOM)
    if args.cantilever == "custom":
        missing = [flag(name) for name in _CUSTOM[:4] if name not in custom]
        if missing:
            raise UserError(f"--cantilever custom needs {listed(missing)}")
        with _one_line():
            lever = cantilever_from_spring_constant(
                spring_constant=custom["spring_constant"], length=custom["length"], width=custom["width"],
                thickness=custom["thickness"], density=custom.get("density", SILICON_DENSITY),
                quality_factor=_quality_factor(args))
        return _in_medium(args, lever, custom["width"]), custom["width"]
    if args.cantilever not in TABLE1:
        raise UserError(f"unknown cantilever {args.cantilever!r}: choose A, B, C or custom")
    given = [flag(name) for name in custom]
    if given:
        raise UserError(f"{listed(given)} appl{'ies' if len(given) == 1 else 'y'} only to --cantilever custom")
    with _one_line():
        lever = table1_cantilever(args.cantilever, quality_factor=_quality_factor(args))
    return _in_medium(args, lever, TABLE1[args.cantilever][0]), TABLE1[args.cantilever][0]


@contextlib.contextmanager
def _one_line():
    """A ValueError of the analysis (a lever its sizes do not allow, a grid it cannot compute) as the
    user's one line; a :class:`UserError` (a ValueError already one line) as it is."""
    try:
        yield
    except UserError:
        raise
    except ValueError as exc:
        raise UserError(str(exc)) from None


def _in_medium(args, lever, width):
    """The lever (resonance from its geometry: in vacuum) in ``--medium``, or as it is."""
    if not args.medium:
        return lever
    medium = flags.medium_from_args(args)
    print(flags.medium_line(medium, args))
    return lever.with_medium(medium, width)


def _write_csv(path, response: ResponseMap) -> None:
    f, v = np.meshgrid(response.frequency_hz, response.bias_v, indexing="ij")
    total = response.total
    columns = np.column_stack([f.ravel(), v.ravel(), np.abs(total).ravel(),
                               np.angle(total, deg=True).ravel(), response.shares().reshape(-1, 3)])
    np.savetxt(path, columns, delimiter=",", fmt="%.10g", comments="",
               header="frequency_hz,bias_v,amplitude_m_per_v,phase_deg,"
                      "local_share,nonlocal_share,piezo_share")


def run(args) -> int:
    """Compute the diagram, write the figure (and CSV)."""
    lever, width = _cli_cantilever(args)
    lever = replace(lever, **flags.given(args, ("spot_position",)))   # read at the laser spot (1: free end)
    contact = flags.given(args, ("k1", "tip_height"))                  # the paper's unless given
    drive = flags.given(args, ("d_eff", "local_force", "surface_potential"))
    if not contact["k1"] > 0:
        raise UserError(f"--k1 must be > 0 N/m: the diagram is of the lever in contact, got {contact['k1']:g}")
    if not args.fmin > 0 or not args.fmin < args.fmax or not np.isfinite(args.fmax):
        raise UserError(f"need 0 < --fmin < --fmax (finite), got {args.fmin:g} and {args.fmax:g} Hz")
    if not args.vmin < args.vmax or not np.isfinite(args.vmin + args.vmax):
        raise UserError(f"need --vmin < --vmax (finite), got {args.vmin:g} and {args.vmax:g} V")
    if args.frequency_points < 2 or args.bias_points < 2:
        raise UserError("--frequency-points and --bias-points must be at least 2")
    if args.frequency_points * args.bias_points > MAX_POINTS:
        raise UserError(f"--frequency-points x --bias-points must be at most {MAX_POINTS:g} (a diagram of "
                        f"{args.frequency_points * args.bias_points:g} points would not fit in memory)")
    if args.plot is None:
        raise UserError("give --plot PATH (the figure to write)")
    check_writable(args.plot, figure=True)
    check_writable(args.csv, args.json)
    spacing = np.geomspace if args.log_frequency else np.linspace
    frequency = spacing(args.fmin, args.fmax, args.frequency_points)
    bias = np.linspace(args.vmin, args.vmax, args.bias_points)
    with _one_line():
        response = response_map(lever, frequency, bias, width=width, k1=contact["k1"],
                                H=contact["tip_height"], d_eff=drive["d_eff"], local_force=drive["local_force"],
                                surface_potential_v=drive["surface_potential"],
                                electrostatic_sign=args.electrostatic_sign)
    name = args.cantilever if args.cantilever != "custom" else "custom"
    title = (f"cantilever {name}: k = {lever.spring_constant:.3g} N/m, "
             f"$f_1$ = {lever.free_resonance / 1e3:.1f} kHz, $k_1$ = {contact['k1']:g} N/m\n"
             f"H = {contact['tip_height'] * 1e6:g} µm, $d_{{eff}}$ = {drive['d_eff'] * 1e12:g} pm/V, "
             f"$F_{{loc}}$ = {drive['local_force'] * 1e9:g} nN/V, Q = {lever.quality_factor:g}"
             + (f", spot at {lever.spot_position:g} L" if lever.spot_position != 1.0 else ""))
    flags.save_figure(plot_diagram(response, args.kind, title=title, log_frequency=args.log_frequency), args.plot,
                      dpi=130)
    print(f"wrote {args.plot}")
    if args.csv is not None:
        _write_csv(args.csv, response)
        print(f"wrote {args.csv}")
    if args.json:
        flags.write_json(args.json, _document(args, lever, width, {**contact, **drive}, response))
    return 0


def _document(args, lever, width, values, response) -> dict:
    """The ``--json`` document: the lever and the drive as given, else Table 1's, the paper's or the defaults."""
    from ..io import documents

    values = {"spring_constant": lever.spring_constant, "free_resonance": lever.free_resonance,
              "length": lever.length, "width": width, "quality_factor": lever.quality_factor,
              "spot_position": lever.spot_position, **values}
    given = [name for name in values if isinstance(getattr(args, name, None), str)]    # a flag's text, not a default
    why = {name: f"Table 1, cantilever {args.cantilever}" for name in ("spring_constant", "length", "width")}
    why |= {"free_resonance": "from the geometry", "quality_factor": "lossless, as in the paper",
            "spot_position": "the free end, the default", "local_force": "the default",
            "surface_potential": "the default"} | {name: "the paper's" for name in ("k1", "tip_height", "d_eff")}
    notes = [f"electrostatic sign {args.electrostatic_sign:+d}"]
    if args.medium:
        notes.append(flags.medium_line(lever.medium, args))
    return documents.diagram(response, values, given=given,
                             assumed={name: text for name, text in why.items() if name not in given}, notes=notes)
