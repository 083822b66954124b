"""Contact-resonance frequency maps (DART, CR-AFM tracking) to contact-stiffness maps.

The input (:data:`pfmdyn.io.kinds.CONTACT_MAP_KINDS`) holds ``contact_frequency_hz`` (ny, nx) and no
``response``, and the root attributes
``spring_constant`` and ``free_resonance`` (:mod:`pfmdyn.names`; older spellings are read too; optionally ``contact_mode``, default 1,
and ``contact_uncertainty`` in Hz, ``contact_uncertainty_hz`` read too).  The inversion is :func:`pfmdyn.analysis.stiffness.contact_stiffness`,
vectorised over the whole map; pixels whose frequency no k1 explains become NaN.
"""
from __future__ import annotations

import math
import os

import numpy as np

from ..analysis.stiffness import contact_stiffness
from ..errors import UserError, listed
from ..names import NAMES, canonical, checked
from .readers import open_root, scalar
from .store import write_maps

__all__ = ["contact_map", "describe"]


def contact_map(path: str, out_dir: str, overrides: dict | None = None) -> dict:
    """Write ``out_dir/maps.zarr`` with ``k1`` and ``k1_stderr`` (N/m); returns a summary.

    >>> import tempfile, h5py
    >>> d = tempfile.mkdtemp()
    >>> with h5py.File(d + "/cr.h5", "w") as h:
    ...     h["contact_frequency_hz"] = np.full((2, 3), 300e3)
    ...     h.attrs.update(spring_constant=2.0, free_resonance=75e3)
    >>> round(contact_map(d + "/cr.h5", d)["median_k1"], 3)
    109.748
    """
    with open_root(path) as root:
        fc = np.asarray(root["contact_frequency_hz"][...])
        attrs = {canonical(key) or key: value for key, value in root.attrs.items()}
    given = {canonical(key) or key: value for key, value in (overrides or {}).items()}     # any spelling
    attrs.update(given)
    missing = [key for key in ("spring_constant", "free_resonance") if key not in attrs]
    if missing:
        raise UserError(f"{path}: no {listed((NAMES[key].label for key in missing), 'or')} in its root attributes",
                        quantity=tuple(missing))
    if fc.ndim != 2 or not np.issubdtype(fc.dtype, np.number) or np.iscomplexobj(fc):
        raise UserError(f"{path}: contact_frequency_hz must be a (ny, nx) array of real numbers, got shape "
                        f"{fc.shape} of {fc.dtype}")
    if fc.size == 0:
        raise UserError(f"{path}: the map holds no pixels (shape {fc.shape})")
    k, f1 = (checked(key, scalar(attrs[key]), f"{path} (command line)" if key in given
                     else str(path)) for key in ("spring_constant", "free_resonance"))
    try:
        mode, sigma = (float(scalar(attrs.get(key, default))) for key, default in
                       (("contact_mode", 1), ("contact_uncertainty", 0.0)))
    except (TypeError, ValueError):
        mode = sigma = math.nan
    if not (math.isfinite(mode) and mode == int(mode) and mode >= 1 and math.isfinite(sigma) and sigma >= 0):
        raise UserError(f"{path}: contact_mode must be a whole number from 1 and contact_uncertainty a number "
                        f"from 0, got {attrs.get('contact_mode', 1)!r} and {attrs.get('contact_uncertainty', 0.0)!r}")
    result = contact_stiffness(fc.astype(float), f1, k, mode=int(mode), contact_uncertainty=sigma,
                               out_of_range="nan")
    out = os.path.join(out_dir, "maps.zarr")
    # a new map each time (nothing to resume): whatever was at out is replaced
    write_maps(out, {name: (np.broadcast_to(value, fc.shape).astype(float), "N/m", f"{name} from the contact resonance")
                     for name, value in (("k1", result.k1), ("k1_stderr", result.k1_stderr))})
    k1 = np.broadcast_to(np.asarray(result.k1), fc.shape)
    summary = {"explained_fraction": float(np.mean(np.isfinite(k1))), "out": out}
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = fc / f1
    unexplained = ratio[~np.isfinite(k1) & np.isfinite(ratio)]
    seen = f"{unexplained.min():.4g} to {unexplained.max():.4g}" if unexplained.size else "none finite"
    limits = (f"mode {int(mode)}'s limits {result.proof.soft_ratio:.4g} (k1 = 0) and "
              f"{result.proof.stiff_ratio:.4g} (k1 -> inf) of the paper's lever (tip at the free end, no k2)")
    if np.isfinite(k1).any():
        left = int(np.sum(~np.isfinite(k1)))
        return summary | {"median_k1": float(np.nanmedian(k1))} | ({"left_out": (
            f"k1 undetermined at {left} of {k1.size} pixels: their contact/free ratio ({seen}) lies outside {limits}"
            if unexplained.size else f"k1 undetermined at {left} of {k1.size} pixels: no finite frequency")} if left else {})
    return summary | {"median_k1": None, "why": f"no pixel's contact/free ratio ({seen}) lies between {limits}"}


def describe(summary: dict) -> str:
    """One line on a :func:`contact_map` summary.

    >>> describe({"explained_fraction": 1.0, "median_k1": 109.75, "out": "o/maps.zarr"})
    'contact-frequency map: k1 at 100.0 % of pixels, median k1 109.8 N/m; maps in o/maps.zarr'
    >>> describe({"explained_fraction": 0.0, "median_k1": None, "why": "no ratio fits", "out": "o/maps.zarr"})
    'contact-frequency map: k1 undetermined at every pixel: no ratio fits; maps in o/maps.zarr'
    """
    if summary["median_k1"] is None:
        return f"contact-frequency map: k1 undetermined at every pixel: {summary['why']}; maps in {summary['out']}"
    return (f"contact-frequency map: k1 at {100 * summary['explained_fraction']:.1f} % of pixels, "
            f"median k1 {summary['median_k1']:.4g} N/m; maps in {summary['out']}"
            + (f"\n{summary['left_out']}" if summary.get("left_out") else ""))
