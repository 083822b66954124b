"""Contact-resonance frequency maps (DART, CR-AFM tracking) to contact-stiffness maps.

The input holds ``contact_frequency_hz`` (ny, nx) and the root attributes
``spring_constant_n_per_m`` and ``free_resonance_hz`` (optionally ``contact_mode``, default 1,
and ``contact_uncertainty_hz``).  The inversion is :func:`pfmdyn.analysis.stiffness.contact_stiffness`,
vectorised over the whole map; pixels whose frequency no k1 explains become NaN.
"""
from __future__ import annotations

import os

import numpy as np

from ..analysis.stiffness import contact_stiffness
from ..errors import UserError
from .readers import open_root
from .store import open_group, write_array

__all__ = ["contact_map", "describe", "is_contact_map"]


def is_contact_map(path: str) -> bool:
    """True when ``path`` holds a contact-frequency map rather than spectra."""
    if not os.path.exists(path):
        raise UserError(f"{path}: no such file or directory")
    with open_root(path) as root:
        return "contact_frequency_hz" in root and "response" not in root


def contact_map(path: str, out_dir: str, overrides: dict | None = None) -> dict:
    """Write ``out_dir/maps.zarr`` with ``k1`` and ``k1_stderr`` (N/m); returns a summary.

    >>> import tempfile, h5py
    >>> d = tempfile.mkdtemp()
    >>> with h5py.File(d + "/cr.h5", "w") as h:
    ...     h["contact_frequency_hz"] = np.full((2, 3), 300e3)
    ...     h.attrs.update(spring_constant_n_per_m=2.0, free_resonance_hz=75e3)
    >>> round(contact_map(d + "/cr.h5", d)["median_k1"], 3)
    109.748
    """
    with open_root(path) as root:
        fc = np.asarray(root["contact_frequency_hz"][...], float)
        attrs = dict(root.attrs)
    attrs.update(overrides or {})
    missing = [key for key in ("spring_constant_n_per_m", "free_resonance_hz") if key not in attrs]
    if missing:
        raise UserError(f"{path}: missing metadata {', '.join(missing)} (root attributes or command-line options)")
    if fc.ndim != 2:
        raise UserError(f"{path}: contact_frequency_hz must have shape (ny, nx), got {fc.shape}")
    result = contact_stiffness(fc, float(attrs["free_resonance_hz"]), float(attrs["spring_constant_n_per_m"]),
                               mode=int(attrs.get("contact_mode", 1)),
                               contact_uncertainty_hz=float(attrs.get("contact_uncertainty_hz", 0.0)),
                               out_of_range="nan")
    out = os.path.join(out_dir, "maps.zarr")
    group = open_group(out, "w")
    for name, value in (("k1", result.k1_n_per_m), ("k1_stderr", result.k1_uncertainty_n_per_m)):
        write_array(group, name, np.broadcast_to(value, fc.shape).astype(float), units="N/m",
                    description=f"{name} from the contact resonance", dims=["y", "x"])
    k1 = np.asarray(result.k1_n_per_m)
    return {"explained_fraction": float(np.mean(np.isfinite(k1))), "median_k1": float(np.nanmedian(k1)), "out": out}


def describe(summary: dict) -> str:
    """One line on a :func:`contact_map` summary.

    >>> describe({"explained_fraction": 1.0, "median_k1": 109.75, "out": "o/maps.zarr"})
    'contact-frequency map: k1 at 100.0 % of pixels, median k1 109.8 N/m; maps in o/maps.zarr'
    """
    return (f"contact-frequency map: k1 at {100 * summary['explained_fraction']:.1f} % of pixels, "
            f"median k1 {summary['median_k1']:.4g} N/m; maps in {summary['out']}")
