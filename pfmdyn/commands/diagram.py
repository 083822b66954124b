"""``pfmdyn diagram``: draw a frequency-bias response diagram (Figs. 6-7) of a Table 1 or custom lever."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..analysis.diagram import (PAPER_D_EFF, PAPER_K1, PAPER_TIP_HEIGHT, SILICON_DENSITY, TABLE1,
                                ResponseMap, cantilever_from_spring_constant, response_map,
                                table1_cantilever)
from ..errors import UserError
from ..plots.diagram import KINDS, plot_diagram


def add_arguments(parser) -> None:
    """Options of ``pfmdyn diagram``."""
    parser.add_argument("--cantilever", default="A", metavar="A|B|C|custom",
                        help="Table 1 cantilever, or 'custom' with --k --length --width --thickness")
    parser.add_argument("--k", type=float, help="custom: spring constant, N/m")
    parser.add_argument("--length", type=float, help="custom: length, um")
    parser.add_argument("--width", type=float, help="custom: width, um")
    parser.add_argument("--thickness", type=float, help="custom: thickness, um")
    parser.add_argument("--density", type=float, help="custom: density, kg/m^3 (silicon, 2330)")
    parser.add_argument("--quality-factor", type=float, default=math.inf,
                        help="Q of the loss factor 1/Q (default: lossless, as in the paper)")
    parser.add_argument("--k1", type=float, default=PAPER_K1, help="contact stiffness, N/m (1000)")
    parser.add_argument("--tip-height", type=float, default=PAPER_TIP_HEIGHT * 1e6, help="H, um (15)")
    parser.add_argument("--d-eff", type=float, default=PAPER_D_EFF * 1e12, help="d_eff, pm/V (5)")
    parser.add_argument("--local-force", type=float, default=0.0, metavar="NN_PER_V",
                        help="F_loc, nN/V (0 as in Fig. 6; 14 or 0.7 as in Fig. 7)")
    parser.add_argument("--surface-potential", type=float, default=0.0, help="V_surf, V")
    parser.add_argument("--electrostatic-sign", type=int, choices=(-1, 1), default=-1,
                        help="-1: attractive capacitive force (default, the project's convention); "
                             "+1: the drives as the paper prints them")
    parser.add_argument("--kind", choices=KINDS,
                        default="amplitude", help="what to draw (default amplitude)")
    parser.add_argument("--fmin", type=float, default=1e3, help="lowest frequency, Hz (1e3)")
    parser.add_argument("--fmax", type=float, default=3e6, help="highest frequency, Hz (3e6)")
    parser.add_argument("--log-frequency", action="store_true", help="log-spaced frequency axis")
    parser.add_argument("--vmin", type=float, default=-10.0, help="lowest V_dc, V (-10)")
    parser.add_argument("--vmax", type=float, default=10.0, help="highest V_dc, V (10)")
    parser.add_argument("--frequency-points", type=int, default=1000)
    parser.add_argument("--bias-points", type=int, default=401)
    parser.add_argument("--out", required=True, type=Path, help="PNG file to write")
    parser.add_argument("--csv", type=Path, help="also write the map as long-format CSV")


def _cli_cantilever(args):
    """``(Cantilever, width in m)`` from the options; errors as :class:`UserError`."""
    custom = {"k": args.k, "length": args.length, "width": args.width, "thickness": args.thickness,
              "density": args.density}
    if args.cantilever == "custom":
        missing = [f"--{name}" for name, value in custom.items() if value is None and name != "density"]
        if missing:
            raise UserError(f"--cantilever custom needs {' '.join(missing)}")
        for name, value in custom.items():   # checked here to report the user's units
            if value is not None and not (np.isfinite(value) and value > 0):
                raise UserError(f"--{name} must be positive and finite, got {value:g}")
        try:
            lever = cantilever_from_spring_constant(
                spring_constant=args.k, length=args.length * 1e-6, width=args.width * 1e-6,
                thickness=args.thickness * 1e-6,
                density=SILICON_DENSITY if args.density is None else args.density,
                quality_factor=args.quality_factor)
        except ValueError as exc:
            raise UserError(str(exc)) from None
        return lever, args.width * 1e-6
    if args.cantilever not in TABLE1:
        raise UserError(f"unknown cantilever {args.cantilever!r}: choose A, B, C or custom")
    given = [f"--{name}" for name, value in custom.items() if value is not None]
    if given:
        raise UserError(f"{' '.join(given)} apply only to --cantilever custom")
    try:
        lever = table1_cantilever(args.cantilever, quality_factor=args.quality_factor)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    return lever, TABLE1[args.cantilever][0]


def _write_csv(path, response: ResponseMap) -> None:
    f, v = np.meshgrid(response.frequency_hz, response.bias_v, indexing="ij")
    total = response.total
    columns = np.column_stack([f.ravel(), v.ravel(), np.abs(total).ravel(),
                               np.angle(total, deg=True).ravel(), response.shares().reshape(-1, 3)])
    np.savetxt(path, columns, delimiter=",", fmt="%.10g", comments="",
               header="frequency_hz,bias_v,amplitude_m_per_v,phase_deg,"
                      "local_share,nonlocal_share,piezo_share")


def run(args) -> int:
    """Compute the diagram, write the PNG (and CSV)."""
    lever, width = _cli_cantilever(args)
    if not args.fmin > 0 or not args.fmin < args.fmax or not np.isfinite(args.fmax):
        raise UserError(f"need 0 < --fmin < --fmax (finite), got {args.fmin:g} and {args.fmax:g} Hz")
    if not args.vmin < args.vmax or not np.isfinite(args.vmin + args.vmax):
        raise UserError(f"need --vmin < --vmax (finite), got {args.vmin:g} and {args.vmax:g} V")
    if args.frequency_points < 2 or args.bias_points < 2:
        raise UserError("--frequency-points and --bias-points must be at least 2")
    if args.out.suffix.lower() != ".png":
        raise UserError(f"--out must name a .png file, got {str(args.out)!r}")
    for path in (args.out, args.csv):
        if path is not None and not path.parent.is_dir():
            raise UserError(f"directory {str(path.parent)!r} does not exist")
    spacing = np.geomspace if args.log_frequency else np.linspace
    frequency = spacing(args.fmin, args.fmax, args.frequency_points)
    bias = np.linspace(args.vmin, args.vmax, args.bias_points)
    try:
        response = response_map(lever, frequency, bias, width=width, k1=args.k1,
                                H=args.tip_height * 1e-6, d_eff=args.d_eff * 1e-12,
                                local_force=args.local_force * 1e-9,
                                surface_potential_v=args.surface_potential,
                                electrostatic_sign=args.electrostatic_sign)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    name = args.cantilever if args.cantilever != "custom" else "custom"
    title = (f"cantilever {name}: k = {lever.spring_constant:.3g} N/m, "
             f"$f_1$ = {lever.resonance_frequency / 1e3:.1f} kHz, $k_1$ = {args.k1:g} N/m\n"
             f"H = {args.tip_height:g} µm, $d_{{eff}}$ = {args.d_eff:g} pm/V, "
             f"$F_{{loc}}$ = {args.local_force:g} nN/V, Q = {args.quality_factor:g}")
    plot_diagram(response, args.kind, title=title, log_frequency=args.log_frequency).savefig(args.out, dpi=130)
    print(f"wrote {args.out}")
    if args.csv is not None:
        _write_csv(args.csv, response)
        print(f"wrote {args.csv}")
    return 0
