"""``pfmdyn map`` with the model ``auto``: choose the mechanisms on a few representative pixels.

The baseline is the elastic-contact beam with internal friction (``elastic``).  The candidates
add the mechanisms maps support (:data:`pfmdyn.maps.spec.MECHANISMS`: viscous drag, a contact
dashpot, the electrostatic load distributed along the lever).  Each model is fitted by :func:`pfmdyn.maps.fit.fit_block` at a grid of pixels spread
over the map (only their spectra are read), and the totals over those pixels are judged by the
discrepancy workflow's rule (:func:`pfmdyn.discrepancy.select.material`): a mechanism is added
when it lowers the BIC by more than 10 and shrinks the noise-normalised gap by 25 % (or brings
it near the noise).  Forward steps add the best material candidate until none is.  Pixels where
the baseline fit sits at a parameter bound are not judged, a candidate that puts a judged pixel at
a bound is never chosen, and nothing is added when the baseline is at a bound at half the pixels
or more: a model that cannot reach the data is not mended by a mechanism.

Every combination of mechanisms is fitted once (eight small fits); the noise variance of each
pixel is the smallest residual variance ``RSS / (n_freq - n_parameters / 2)`` any of them
reaches (the usual full-model estimate, robust to one combination stopping in a local
minimum), floored at 1 ppm of the signal.  Estimates from the spectrum alone (differences) fail here: a band-excitation
band samples a sharp resonance with a few points per width (every estimate of the noise, and why
they differ: :mod:`pfmdyn.fitting.noise`).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np

from ..discrepancy.select import material
from ..errors import UserError
from .fit import fit_block, fittable
from .spec import MECHANISMS, model_name
from .readers import MapInput, read_block

__all__ = ["choose_model", "sample_pixels"]


def sample_pixels(source: MapInput, count: int = 16) -> np.ndarray:
    """Spectra ``(n, n_freq)`` (``(n, n_bias, n_freq)`` with a bias axis) at the centres of a
    ``sqrt(count)`` x ``sqrt(count)`` grid of cells (fewer on a map with fewer rows or columns);
    only those spectra are read.  Pixels the fit masks (NaN, inf, no response) are left out; if
    all are, a one-line error asks for the model."""
    ny, nx = source.shape
    side = max(1, int(math.isqrt(count)))
    ys = np.unique(((np.arange(side) + 0.5) * ny / side).astype(int))
    xs = np.unique(((np.arange(side) + 0.5) * nx / side).astype(int))
    y = np.concatenate([read_block(source, slice(y, y + 1), slice(x, x + 1))[0] for y in ys for x in xs])
    usable = fittable(y)
    if not usable.any():
        raise UserError(f"{source.path}: the {len(y)} pixels sampled to choose the model hold NaN, inf or no "
                        "response; choose the model (e.g. elastic)", quantity="model")
    return y[usable]


class _Score:
    """One model's fit at the sample pixels; totals over them once the noise is known."""

    def __init__(self, mechanisms, source, y, options):
        model = replace(source.model, mechanisms=mechanisms)
        self.name, self.mechanisms = model_name(mechanisms), mechanisms
        flat = y.reshape(len(y), -1)
        fitted = fit_block(model, y, **options)
        self.rss = fitted["cost"] * np.sum(np.abs(flat) ** 2, axis=1)
        self.at_bound = fitted["at_bound"].astype(bool)
        # complex amplitudes: one per band, two (intercept, slope) with a bias axis
        self.k_pixel = len(model.parameters) + 2 * len(model.bands) * (1 if model.bias_v is None else 2)

    def judge(self, sigma2, y, use):
        """chi2 (noise known), BIC = chi2 + k ln n and the noise-normalised gap over the pixels ``use``."""
        self.chi2 = float(np.sum(self.rss[use] / sigma2[use]))
        n = 2 * y[use].size
        self.bic = self.chi2 + int(use.sum()) * self.k_pixel * math.log(max(n, 2))
        self.gap = math.sqrt(self.chi2 / max(y[use].size, 1))

    def row(self, chosen: bool) -> dict:
        return {"model": self.name, "bic": round(self.bic, 3), "gap": round(self.gap, 4),
                "at_bound": int(self.at_bound.sum()), "chosen": chosen}


def choose_model(source: MapInput, count: int = 16, **options) -> tuple[tuple[str, ...], list[dict]]:
    """The mechanisms chosen for ``source`` and one row per model.

    ``options`` go to :func:`pfmdyn.maps.fit.fit_block`.  Rows carry the model name, its BIC
    and gap totalled over the sample pixels, and whether it was chosen.

    Examples
    --------
    >>> import tempfile, h5py
    >>> from pfmdyn.maps.driver import open_map
    >>> from pfmdyn.maps.beam import BeamMapModel
    >>> f = np.linspace(2.2e5, 4.2e5, 64)
    >>> from pfmdyn import Cantilever, Contact
    >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
    >>> y = BeamMapModel(lever, f, contact=Contact(k2=0.0)).shape_functions(np.full(16, 400.0), np.full(16, 60.0))
    >>> y = y + 1e-3 * np.abs(y).max() * np.random.default_rng(0).standard_normal(y.shape)
    >>> path = tempfile.mkdtemp() + "/be.h5"
    >>> with h5py.File(path, "w") as h:
    ...     h["response"], h["frequency_hz"] = y.reshape(4, 4, -1), f
    ...     h.attrs.update(spring_constant=2.0, length=225e-6, tip_height=10e-6, free_resonance=75e3, k2=0.0)
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
    # A fit stopped at a parameter bound is no measurement: such pixels are not judged, a model
    # that puts a judged pixel at a bound is not chosen, and when the baseline cannot reach most
    # pixels no mechanism is added to dress that up (the pixels are reported unexplained).
    baseline = scores[("internal",)]
    use = ~baseline.at_bound
    for s in scores.values():
        s.judge(sigma2, flat, use)
    current = baseline
    while use.mean() >= 0.5:
        trials = [scores[tuple(m for m in MECHANISMS if m in current.mechanisms or m == extra)]
                  for extra in extras if extra not in current.mechanisms]
        better = [t for t in trials if not t.at_bound[use].any() and material(current, t)]
        if not better:
            break
        current = min(better, key=lambda t: t.bic)
    return current.mechanisms, [s.row(s is current) for s in scores.values()]
