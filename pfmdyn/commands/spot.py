"""``pfmdyn spot``: where to put the laser spot (electrostatic blind spots, calibration, d_eff error)."""
from __future__ import annotations

from ..analysis.spot import Lever, ratio_map, spot_analysis
from ..errors import UserError

__all__ = ["add_arguments", "run", "report"]


def add_arguments(parser) -> None:
    """Options of ``pfmdyn spot`` (SI units, names as in the probe description)."""
    parser.add_argument("--spring-constant", type=float, required=True, help="lever spring constant k, N/m")
    parser.add_argument("--free-resonance", type=float, required=True, help="first free resonance f1, Hz")
    parser.add_argument("--length", type=float, required=True, help="lever length L, m")
    parser.add_argument("--tip-height", type=float, required=True, help="tip height H, m")
    parser.add_argument("--k1", type=float, required=True, help="vertical contact stiffness, N/m")
    parser.add_argument("--k2", type=float, default=0.0, help="lateral contact stiffness, N/m (default 0: frictionless)")
    parser.add_argument("--frequency", type=float, required=True, help="drive frequency, Hz")
    parser.add_argument("--tip-position", type=float, default=1.0, help="tip position x_tip/L (default 1)")
    parser.add_argument("--tip-mass-ratio", type=float, default=0.0, help="tip mass over lever mass (default 0)")
    parser.add_argument("--tilt", type=float, default=0.0,
                        help="tilt, degrees, positive when the free end is nearer the sample (default 0)")
    parser.add_argument("--spot-position", type=float,
                        help="detection spot x_s/L: report the calibration factor and d_eff error there")
    parser.add_argument("--width", type=float, help="lever width w, m (sizes the capacitive load for the d_eff error)")
    parser.add_argument("--json", metavar="PATH", help="write the result as JSON")
    parser.add_argument("--plot", metavar="PNG", help="write the figure (ratio along the lever and over frequency)")


def report(result) -> str:
    """The lines ``pfmdyn spot`` prints."""
    d = result.to_dict()
    lines = [f"frequency {d['frequency']:.6g} Hz (beta = {d['beta']:.6g})"]
    if not d["certified"]:
        lines.append(f"blind spot: not certified ({d['reason']})")
    elif d["blind_spot"]:
        lines.append("blind spot x_s/L: " + ", ".join(f"{p:.6f}" for p in d["blind_spot"])
                     + " (certified: complete on (0, 1])")
    else:
        lines.append("blind spot x_s/L: none in (0, 1] (certified)")
    if d["spot_position"] is not None:
        lines.append(f"at x_s/L = {d['spot_position']:g}: static sensitivity u_tip/(L theta) "
                     f"free {d['free_sensitivity']:.6g}, in contact {d['contact_sensitivity']:.6g} (paper: 2/3)")
        c, p = d["calibration_factor"], d["paper_calibration_factor"]
        lines.append(f"  measured/true d_eff: {c['re']:+.6g}{c['im']:+.3g}j (InvOLS from a static force curve "
                     f"on this contact), {p['re']:+.6g}{p['im']:+.3g}j (A = 2 theta L/3)")
        e = d["d_eff_error_per_volt"]
        lines.append("  d_eff error from the distributed load: "
                     + (f"{e['re'] * 1e12:+.4g} pm/V per volt of V_dc - V_surf" if e else "undetermined (needs --width)"))
    return "\n".join(lines)


def run(args) -> int:
    """Analyse, print, write what was asked."""
    lever = Lever(args.spring_constant, args.free_resonance, args.length, args.tip_height, args.k1, args.k2,
                  args.tip_position, args.tip_mass_ratio, args.tilt)
    if args.width is not None and not args.width > 0:
        raise UserError(f"--width must be positive, got {args.width!r}")
    result = spot_analysis(lever, args.frequency, args.spot_position, width=args.width)
    print(report(result))
    if args.json:
        from .inspect import write_json
        write_json(args.json, result.to_dict())
    if args.plot:
        import numpy as np

        from ..plots.spot import plot_spot
        fmax = max(2.0 * args.frequency, 8.0 * args.free_resonance)
        frequencies = np.linspace(fmax / 400, fmax, 400)
        fig = plot_spot(result, frequencies, ratio_map(lever, frequencies, result.positions))
        try:
            fig.savefig(args.plot, dpi=120)
        except OSError as exc:
            raise UserError(f"cannot write {args.plot}: {exc.strerror or exc}") from None
    return 0
