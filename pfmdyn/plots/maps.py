"""PNG maps of the per-pixel fit: one image per quantity, with a colour bar in SI units.

Uses ``matplotlib.figure.Figure`` directly, so no GUI backend is selected.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_maps"]

_SHOWN = ("k1", "k1_stderr", "k2", "quality_factor", "viscous_loss", "contact_loss", "amplitude", "phase",
          "electrostatic", "electrostatic_phase", "nulling_bias", "gap")


def plot_maps(maps: dict[str, np.ndarray], units: dict[str, str], out_dir: Path) -> list[Path]:
    """Write ``out_dir/NAME.png`` for each shown quantity present in ``maps``; return the paths.

    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> [p.name for p in plot_maps({"k1": np.ones((4, 4))}, {"k1": "N/m"}, d)]
    ['k1.png']
    """
    paths = []
    for name in _SHOWN:
        if name not in maps or not np.isfinite(maps[name]).any():    # e.g. k2 with one band
            continue
        fig = Figure(figsize=(4.2, 3.6))
        ax = fig.add_subplot()
        image = ax.imshow(maps[name], origin="lower", cmap="twilight" if name.endswith("phase") else "viridis")
        fig.colorbar(image, ax=ax, label=f"{name} ({units.get(name, '')})")
        ax.set_xlabel("x (pixel)")
        ax.set_ylabel("y (pixel)")
        fig.tight_layout()
        path = Path(out_dir) / f"{name}.png"
        fig.savefig(path, dpi=100)
        paths.append(path)
    return paths
