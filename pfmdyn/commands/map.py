"""``pfmdyn map``: the elastic-contact beam model fitted at every pixel of a band-excitation map.

::

    pfmdyn map scan.h5 --out result/                       # Dask local scheduler, all cores
    pfmdyn map scan.h5 --out result/ --scheduler tcp://host:8786
    pfmdyn map be_usid.h5 --out result/ --spring-constant 2 --length 225e-6   # pycroscopy USID

The input holds ``response`` (ny, nx, n_freq, complex), ``frequency_hz`` and the cantilever
metadata as root attributes; ``result/maps.zarr`` gets one (ny, nx) array per quantity with its
units in the attributes.  A contact-resonance frequency map (``contact_frequency_hz``, (ny, nx))
becomes a k1 map through :func:`pfmdyn.analysis.stiffness.contact_stiffness`.  Rerunning an interrupted command resumes where it stopped.
"""
from __future__ import annotations

import math

from ..errors import UserError

__all__ = ["add_arguments", "run"]

_OVERRIDES = {"spring_constant": "spring_constant_n_per_m", "length": "length_m",
              "tip_height": "tip_height_m", "free_resonance": "free_resonance_hz"}


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn map``."""
    parser.add_argument("data", help="map file: HDF5 (.h5) or Zarr directory with response, frequency_hz; or USID BE HDF5")
    parser.add_argument("--out", required=True, help="output directory (gets maps.zarr)")
    parser.add_argument("--model", default="auto", choices=["auto", "elastic"],
                        help="per-pixel model: elastic contact, k1 + loss 1/Q + complex d_eff per band, "
                             "and k2 when the frequencies hold two or more contact-mode bands; "
                             "auto (default) picks that from the bands and reports it")
    parser.add_argument("--block", type=int, default=16, help="pixels per block side (default 16)")
    parser.add_argument("--scheduler", default=None,
                        help="'sync', or tcp://HOST:PORT of a dask.distributed scheduler (default: local, all cores)")
    parser.add_argument("--quality-factor", type=float, default=100.0, help="starting Q (default 100)")
    parser.add_argument("--gap-threshold", type=float, default=0.2,
                        help="relative residual above which a pixel is marked unexplained (default 0.2)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--png", action="store_true", help="also write OUT/NAME.png for each map")
    for flag, key in _OVERRIDES.items():
        parser.add_argument("--" + flag.replace("_", "-"), type=float, default=None,
                            help=f"override the file's {key}")


def run(args) -> int:
    """Fit the map and print a summary line."""
    from ..maps.driver import open_map, run_map
    for name in ("block", "quality_factor", "gap_threshold"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            raise UserError(f"--{name.replace('_', '-')} must be positive, got {value}")
    overrides = {key: getattr(args, flag) for flag, key in _OVERRIDES.items() if getattr(args, flag) is not None}
    from ..maps.contact import contact_map, is_contact_map
    if is_contact_map(args.data):
        s = contact_map(args.data, args.out, overrides)
        print(f"contact-frequency map: k1 at {100 * s['explained_fraction']:.1f} % of pixels, "
              f"median k1 {s['median_k1']:.4g} N/m; maps in {s['out']}")
        return 0
    source = open_map(args.data, overrides)
    n_bands = len(source.model.bands)
    print(f"model ({args.model}): elastic contact + loss 1/Q, "
          f"{'k1 and k2' if n_bands > 1 else 'k1 (k2 = 0: one contact mode cannot separate them)'}, "
          f"complex d_eff per band ({n_bands} band{'s' if n_bands > 1 else ''})")
    s = run_map(source, args.out, block=args.block, scheduler=args.scheduler, progress=not args.no_progress,
                q0=args.quality_factor, gap_threshold=args.gap_threshold)
    ny, nx = source.shape
    if args.png:
        from ..maps.driver import read_maps
        from ..plots.maps import plot_maps
        plot_maps(*read_maps(s["out"]), args.out)
    print(f"{ny}x{nx} pixels, {s['blocks_run']} blocks fitted ({s['pixels_per_s']:.0f} pixels/s); "
          f"explained {100 * s['explained_fraction']:.1f} %, median gap {s['median_gap']:.3g}; maps in {s['out']}")
    return 0
