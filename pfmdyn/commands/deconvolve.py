"""``pfmdyn deconvolve``: electrostatic and electromechanical parts of frequency-bias data (Eq. 41)."""
from __future__ import annotations

import csv
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..names import CONTACT, LEVER, NAMES
from . import flags

if TYPE_CHECKING:       # the analysis is imported when the command runs, not for --help
    from ..analysis.deconvolve import Deconvolution, SurfaceDisplacement


def write_tables(result: Deconvolution, out_dir: Path, surface: SurfaceDisplacement | None = None,
                 unit: str = "a.u.") -> list[Path]:
    """Write the per-frequency results and the error map as CSV files.

    Parameters
    ----------
    result : Deconvolution
        From :func:`deconvolve`.
    out_dir : Path
        Existing output directory.
    surface : SurfaceDisplacement, optional
        With a lever given: the true surface displacement columns (``calibration_factor``,
        ``d_eff_surface_*``, ``g_elec_surface_*``, ``d_eff_error_per_volt_*`` with the width),
        their units and the undetermined ranges in the preamble.  Without it the tables are
        those of the model-free fit alone.
    unit : str
        Unit of the response (for the preamble of the surface columns).

    Returns
    -------
    list of Path
        ``deconvolution.csv`` and ``error_map.csv``.

    Examples
    --------
    >>> import tempfile
    >>> from pfmdyn.analysis.deconvolve import deconvolve
    >>> fit = deconvolve([1e5] * 3, [-1.0, 0.0, 1.0], [1, 2, 3], surface_potential_v=0.0)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     [p.name for p in write_tables(fit, Path(tmp))]
    ['deconvolution.csv', 'error_map.csv']
    """
    per_frequency = {
        "frequency_hz": result.frequency_hz,
        "n_bias": result.n_bias,
        "g_elec_x": result.g_elec.real,
        "g_elec_y": result.g_elec.imag,
        "g_elec_abs": np.abs(result.g_elec),
        "g_elec_se": result.g_elec_se,
        "intercept_x": result.intercept.real,
        "intercept_y": result.intercept.imag,
        "d_eff_x": result.d_eff.real,
        "d_eff_y": result.d_eff.imag,
        "d_eff_abs": np.abs(result.d_eff),
        "d_eff_se": result.d_eff_se,
        "v_null_v": result.v_null,
        "v_null_se_v": result.v_null_se,
    }
    error_map = {
        "frequency_hz": result.point_frequency_hz,
        "bias_v": result.point_bias_v,
        "residual_x": result.residual.real,
        "residual_y": result.residual.imag,
        "residual_abs": np.abs(result.residual),
    }
    preamble = [f"# surface_potential_v: {result.surface_potential_v:.12g}"]
    if surface is not None:
        per_frequency.update(_surface_columns(surface))
        preamble += _surface_preamble(surface, unit)
    paths = [out_dir / "deconvolution.csv", out_dir / "error_map.csv"]
    for path, columns, comments in zip(paths, (per_frequency, error_map), (preamble, [])):
        with open(path, "w", newline="") as handle:
            handle.writelines(line + "\n" for line in comments)
            writer = csv.writer(handle)
            writer.writerow(columns)
            writer.writerows(zip(*(np.vectorize(lambda v: f"{v:.12g}", otypes=[str])(c) for c in columns.values())))
    return paths


def _surface_columns(surface: SurfaceDisplacement) -> dict:
    """The columns a lever adds to ``deconvolution.csv``."""
    out = {"calibration_factor": surface.calibration_factor}
    for name, values in (("d_eff_surface", surface.d_eff), ("g_elec_surface", surface.g_elec)):
        out.update({f"{name}_x": values.real, f"{name}_y": values.imag, f"{name}_abs": np.abs(values)})
    out["d_eff_surface_se"] = surface.d_eff_se
    if surface.d_eff_error_per_volt is not None:
        out["d_eff_error_per_volt"] = surface.d_eff_error_per_volt
    return out


def _surface_preamble(surface: SurfaceDisplacement, unit: str) -> list[str]:
    """Comment lines stating the spot, the units of the surface columns and where they are NaN."""
    from ..analysis.deconvolve import CONDITION_LIMIT

    lines = [f"# spot_position: {surface.spot_position:.12g}",
             "# calibration_factor: measured over true surface displacement, InvOLS from a static force curve "
             "in this contact read at the same spot (1)",
             f"# d_eff_surface: true surface displacement d_eff / calibration_factor ({unit}, as the data);"
             f" g_elec_surface: G_elec / calibration_factor ({unit}/V)"]
    if surface.d_eff_error_per_volt is not None:
        lines.append("# d_eff_error_per_volt: amplitude the distributed capacitive load adds at the spot, as "
                     "measured (m per volt of ac drive per volt of V_dc - V_surf; parallel plate over the tip height)")
    lines += [f"# undetermined {low:.6g}-{high:.6g} Hz (|d ln C/d ln f| > {CONDITION_LIMIT:g}): {why}"
              for low, high, why in surface.undetermined]
    return lines


def add_arguments(parser) -> None:
    """Define the command-line arguments of ``pfmdyn deconvolve``.

    Examples
    --------
    >>> import argparse
    >>> parser = argparse.ArgumentParser()
    >>> add_arguments(parser)
    >>> parser.parse_args(["d.csv", "--surface-potential", "0.5", "--out", "res"]).surface_potential
    '0.5'
    """
    parser.epilog = (
        "At each frequency the response is fitted as a straight line b + c V in the bias (Eq. 41), d_eff = "
        "b + c V_surf at --surface-potential and G_elec = c; they "
        "are those of the signal as measured, in its units, and without lever flags no lever model enters. "
        "With the lever and contact (--spring-constant --free-resonance --length --k1, optionally "
        "--tip-height (default: a typical PFM probe's), --k2/--k2-over-k1/--poisson, --tip-position, "
        "--tip-mass-ratio, --tilt, --width) deconvolution.csv "
        "gains, per frequency, the true surface displacement at the laser spot (--spot-position, default 1: "
        "the free end): d_eff_surface = d_eff / C with C the calibration factor of 'pfmdyn spot' (data "
        "calibrated with an InvOLS from a static force curve in the same contact, at the same spot), "
        "g_elec_surface likewise, and with --width the d_eff error the distributed electrostatic load adds at "
        "the spot. Where C changes too fast with frequency (|d ln C/d ln f| above the limit the preamble states: "
        "around a contact resonance or a zero of the spot's response) those columns are NaN and the preamble "
        "says why.")
    parser.add_argument("data", metavar="INPUT", help="frequency-bias CSV (see pfmdyn.io.spectra for the format)")
    flags.add(parser, ("surface_potential",))
    parser.add_argument("--out", metavar="DIR", type=Path, required=True,
                        help="directory for the CSV tables and PNG plots (created if missing)")
    flags.add_lever(parser)
    flags.add_contact(parser)
    flags.add_json(parser, "the fitted lines per frequency (and the surface displacement)")


def run(args) -> int:
    """Read, fit, then write tables and plots; nothing is written if the input is bad."""
    from ..analysis.deconvolve import deconvolve, summary, surface_displacement, tip_quality
    from ..io.results import check_directory, check_writable
    from ..io.spectra import read_spectra

    surface_potential = flags.given(args, ("surface_potential",)).get("surface_potential")
    potential_assumed = surface_potential is None
    if potential_assumed:
        surface_potential = NAMES["surface_potential"].default
    check_directory(args.out)
    check_writable(args.json)
    assumed = {}
    probe = _probe(args, assumed)
    data = read_spectra(args.data)
    result = deconvolve(data.frequency_hz, data.bias_v, data.response, surface_potential)
    unit = data.response_unit or "a.u."
    surface = None if probe is None else surface_displacement(result, *probe)

    from ..plots import deconvolution as plotting  # matplotlib is imported only when plots are written

    args.out.mkdir(parents=True, exist_ok=True)
    written = write_tables(result, args.out, surface, unit)
    for name, figure in (("spectra", plotting.plot_spectra(result, unit, surface)),
                         ("nulling_bias", plotting.plot_nulling_bias(result)),
                         ("error_map", plotting.plot_error_map(result, unit))):
        figure.savefig(args.out / f"{name}.png", dpi=120)
        written.append(args.out / f"{name}.png")
    if probe is not None and probe[0].medium is not None:
        print(flags.medium_line(probe[0].medium, args))
    if assumed:
        print(flags.assumed_line(assumed, probe[0]))
    if potential_assumed:
        print(f"assumed: surface potential {surface_potential:g} V ({NAMES['surface_potential'].default_why}; give "
              "--surface-potential)")
    print(f"{data.path}:")
    print(summary(result, unit))
    if surface is not None:
        print(_surface_summary(surface, unit))
    print("wrote " + ", ".join(str(path) for path in written))
    if args.json:
        from ..io import documents

        values = flags.given(args, LEVER + CONTACT)
        quality = tip_quality(result.v_null, result.v_null_se)
        taken = {**values, **{name: getattr(probe[0], name) for name in assumed}}     # the assumed: their default
        given = [*values, *([] if potential_assumed else ["surface_potential"])]
        flags.write_json(args.json, documents.deconvolution(result, quality, data.path, surface, unit, taken,
                                                            given, args.out))
    return 0


def _probe(args, assumed: dict):
    """``(lever, contact)`` when any probe flag is given (all of the lever's essentials then; a tip height not
    given, the default of every command, into ``assumed``), else None."""
    values = flags.given(args, LEVER + CONTACT)
    if not values:
        return None
    flags.require(values, ("spring_constant", "free_resonance", "length", "k1"))
    return flags.cantilever(args, assumed=assumed), flags.contact(args)


def _surface_summary(surface: SurfaceDisplacement, unit: str) -> str:
    """Lines on the true surface displacement: its median, the spot, where it is undetermined."""
    finite = np.isfinite(surface.d_eff)
    head = (f"true surface displacement at x_s/L = {surface.spot_position:g}: median |d_eff| "
            f"{np.median(np.abs(surface.d_eff[finite])):.4g} {unit} at {finite.sum()} of {finite.size} frequencies"
            if finite.any() else f"true surface displacement at x_s/L = {surface.spot_position:g}: undetermined everywhere")
    lines = [head] + [f"  undetermined {low / 1e3:.5g}-{high / 1e3:.5g} kHz: {why}"
                      for low, high, why in surface.undetermined]
    if surface.d_eff_error_per_volt is not None:
        lines.append(f"  d_eff error of the distributed load at the spot (parallel plate): "
                     f"{surface.d_eff_error_per_volt[0] * 1e12:+.4g} pm/V per volt of V_dc - V_surf at "
                     "the lowest frequency (d_eff_error_per_volt in the table)")
    return "\n".join(lines)
