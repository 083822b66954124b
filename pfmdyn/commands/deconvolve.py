"""``pfmdyn deconvolve``: electrostatic and electromechanical parts of frequency-bias data (Eq. 41)."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..analysis.deconvolve import Deconvolution, deconvolve, summary
from ..errors import UserError
from ..io.spectra import read_spectra


def write_tables(result: Deconvolution, out_dir: Path) -> list[Path]:
    """Write the per-frequency results and the error map as CSV files.

    Parameters
    ----------
    result : Deconvolution
        From :func:`deconvolve`.
    out_dir : Path
        Existing output directory.

    Returns
    -------
    list of Path
        ``deconvolution.csv`` and ``error_map.csv``.

    Examples
    --------
    >>> import tempfile
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
    paths = [out_dir / "deconvolution.csv", out_dir / "error_map.csv"]
    for path, columns, comments in zip(paths, (per_frequency, error_map), (preamble, [])):
        with open(path, "w", newline="") as handle:
            handle.writelines(line + "\n" for line in comments)
            writer = csv.writer(handle)
            writer.writerow(columns)
            writer.writerows(zip(*(np.vectorize(lambda v: f"{v:.12g}", otypes=[str])(c) for c in columns.values())))
    return paths


def add_arguments(parser) -> None:
    """Define the command-line arguments of ``pfmdyn deconvolve``.

    Examples
    --------
    >>> import argparse
    >>> parser = argparse.ArgumentParser()
    >>> add_arguments(parser)
    >>> parser.parse_args(["d.csv", "--surface-potential", "0.5", "--out", "res"]).surface_potential
    0.5
    """
    # No lever model enters, so no probe flag (--spot-position ...) would change a number here.
    parser.epilog = ("No lever model enters: at each frequency the response is fitted as a straight line in the "
                     "bias (Eq. 41), and d_eff and G_elec are those of the signal as measured, the lever and "
                     "the laser spot's position included (there is no --spot-position; 'pfmdyn spot' gives "
                     "the calibration factor and d_eff error at a spot).")
    parser.add_argument("data", metavar="DATA.csv", help="frequency-bias CSV (see pfmdyn.io.spectra for the format)")
    parser.add_argument("--surface-potential", metavar="V", type=float, required=True,
                        help="surface potential V_surf in volts, used for d_eff = b + c V_surf")
    parser.add_argument("--out", metavar="DIR", type=Path, required=True,
                        help="directory for the CSV tables and PNG plots (created if missing)")


def run(args) -> int:
    """Read, fit, then write tables and plots; nothing is written if the input is bad."""
    if not np.isfinite(args.surface_potential):
        raise UserError("--surface-potential must be a finite number of volts")
    if args.out.exists() and not args.out.is_dir():
        raise UserError(f"{args.out}: exists and is not a directory")
    data = read_spectra(args.data)
    result = deconvolve(data.frequency_hz, data.bias_v, data.response, args.surface_potential)
    unit = data.metadata.get("response_unit", "a.u.")

    from ..plots import deconvolution as plotting  # matplotlib is imported only when plots are written

    args.out.mkdir(parents=True, exist_ok=True)
    written = write_tables(result, args.out)
    for name, figure in (("spectra", plotting.plot_spectra(result, unit)),
                         ("nulling_bias", plotting.plot_nulling_bias(result)),
                         ("error_map", plotting.plot_error_map(result, unit))):
        figure.savefig(args.out / f"{name}.png", dpi=120)
        written.append(args.out / f"{name}.png")
    print(f"{data.path}:")
    print(summary(result, unit))
    print("wrote " + ", ".join(str(path) for path in written))
    return 0
