"""``pfmdyn map --model auto``: choose the mechanisms on a few representative pixels.

The baseline is the elastic-contact beam with internal friction (``elastic``).  The candidates
add the mechanisms maps support (:data:`pfmdyn.maps.fit.MECHANISMS`: viscous drag, a contact
dashpot, the electrostatic load distributed along the lever).  Each model is fitted by :func:`pfmdyn.maps.fit.fit_block` at a grid of pixels spread
over the map (only their spectra are read), and the totals over those pixels are judged by the
discrepancy workflow's rule (:func:`pfmdyn.discrepancy.select.material`): a mechanism is added
when it lowers the BIC by more than 10 and shrinks the noise-normalised gap by 25 % (or brings
it near the noise).  Forward steps add the best material candidate until none is.

Every combination of mechanisms is fitted once (eight small fits); the noise variance of each
pixel is the smallest residual variance ``RSS / (n_freq - n_parameters / 2)`` any of them
reaches (the usual full-model estimate, robust to one combination stopping in a local
minimum), floored at 1 ppm of the signal.  Estimates from the spectrum alone (differences) fail here: a band-excitation
band samples a sharp resonance with a few points per width.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np

from ..discrepancy.select import material
from ..errors import UserError
from .fit import MECHANISMS, fit_block, fittable, model_name
from .readers import MapInput, read_block

__all__ = ["choose_model", "sample_pixels"]


def sample_pixels(source: MapInput, count: int = 16) -> np.ndarray:
    """Spectra ``(n, n_freq)`` (``(n, n_bias, n_freq)`` with a bias axis) at the centres of a
    ``sqrt(count)`` x ``sqrt(count)`` grid of cells (fewer on a map with fewer rows or columns);
    only those spectra are read.  Pixels the fit masks (NaN, inf, no response) are left out; if
    all are, a one-line error asks for ``--model``."""
    ny, nx = source.shape
    side = max(1, int(math.isqrt(count)))
    ys = np.unique(((np.arange(side) + 0.5) * ny / side).astype(int))
    xs = np.unique(((np.arange(side) + 0.5) * nx / side).astype(int))
    y = np.concatenate([read_block(source, slice(y, y + 1), slice(x, x + 1))[0] for y in ys for x in xs])
    usable = fittable(y)
    if not usable.any():
        raise UserError(f"{source.path}: the {len(y)} pixels sampled to choose the model hold NaN, inf or no "
                        "response; give --model (e.g. elastic)")
    return y[usable]


class _Score:
    """One model's fit at the sample pixels; totals over them once the noise is known."""

    def __init__(self, mechanisms, source, y, options):
        model = replace(source.model, mechanisms=mechanisms)
        self.name, self.mechanisms = model_name(mechanisms), mechanisms
        flat = y.reshape(len(y), -1)
        self.rss = fit_block(model, y, **options)["cost"] * np.sum(np.abs(flat) ** 2, axis=1)
        # complex amplitudes: one per band, two (intercept, slope) with a bias axis
        self.k_pixel = len(model.parameters) + 2 * len(model.bands) * (1 if model.bias_v is None else 2)

    def judge(self, sigma2, y):
        """chi2 (noise known), BIC = chi2 + k ln n and the noise-normalised gap."""
        self.chi2 = float(np.sum(self.rss / sigma2))
        n = 2 * y.size
        self.bic = self.chi2 + y.shape[0] * self.k_pixel * math.log(n)
        self.gap = math.sqrt(self.chi2 / y.size)

    def row(self, chosen: bool) -> dict:
        return {"model": self.name, "bic": round(self.bic, 3), "gap": round(self.gap, 4), "chosen": chosen}


def choose_model(source: MapInput, count: int = 16, **options) -> tuple[tuple[str, ...], list[dict]]:
    """The mechanisms chosen for ``source`` and one row per model.

    ``options`` go to :func:`pfmdyn.maps.fit.fit_block`.  Rows carry the model name, its BIC
    and gap totalled over the sample pixels, and whether it was chosen.

    Examples
    --------
    >>> import tempfile, h5py
    >>> from pfmdyn.maps.driver import open_map
    >>> from pfmdyn.maps.fit import BeamMapModel
    >>> f = np.linspace(2.2e5, 4.2e5, 64)
    >>> y = BeamMapModel(2.0, 225e-6, 75e3, 10e-6, f).shape_functions(np.full(16, 400.0), np.full(16, 60.0))
    >>> y = y + 1e-3 * np.abs(y).max() * np.random.default_rng(0).standard_normal(y.shape)
    >>> path = tempfile.mkdtemp() + "/be.h5"
    >>> with h5py.File(path, "w") as h:
    ...     h["response"], h["frequency_hz"] = y.reshape(4, 4, -1), f
    ...     h.attrs.update(spring_constant_n_per_m=2.0, length_m=225e-6, tip_height_m=10e-6, free_resonance_hz=75e3)
    >>> mechanisms, rows = choose_model(open_map(path))
    >>> mechanisms, len(rows), rows[-1]["model"]
    (('internal',), 8, 'elastic+viscous+contact+distributed')
    """
    y = sample_pixels(source, count)
    flat = y.reshape(len(y), -1)
    extras = MECHANISMS[1:]
    scores = {}
    for size in range(len(extras) + 1):
        for combo in itertools.combinations(extras, size):
            mechanisms = ("internal", *combo)
            scores[mechanisms] = _Score(mechanisms, source, y, options)
    sigma2 = np.min([s.rss / (flat.shape[1] - s.k_pixel / 2) for s in scores.values()], axis=0)
    # floor: 1 ppm of the signal, the model's own numerical precision (noise-free data choose nothing)
    sigma2 = np.maximum(sigma2, 1e-12 * np.mean(np.abs(flat) ** 2, axis=1))
    for s in scores.values():
        s.judge(sigma2, flat)
    current = scores[("internal",)]
    while True:
        trials = [scores[tuple(m for m in MECHANISMS if m in current.mechanisms or m == extra)]
                  for extra in extras if extra not in current.mechanisms]
        better = [t for t in trials if material(current, t)]
        if not better:
            break
        current = min(better, key=lambda t: t.bic)
    return current.mechanisms, [s.row(s is current) for s in scores.values()]
