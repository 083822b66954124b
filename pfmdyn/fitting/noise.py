"""The noise of a spectrum and the gap: the noise-normalised RMS residual of a fit.

``sigma`` (the RMS of the complex noise) is estimated from the data alone, as the smaller of
two estimates that signal can only inflate: differences along frequency at each bias (orders
2-6) remove the smooth signal, and their median is robust to resonance peaks,
``sigma**2 = median |d|**2 / (C(2m, m) ln 2)`` for ``m``-th differences; with three or more
biases, the residual of a straight line in bias at each frequency (the response is affine in
the bias) does not see the peak shape at all, however coarsely a band samples it.  Neither
lowers the second-difference estimate below :data:`MAX_REFINEMENT` of it (data without noise).

The gap of a fit is ``sqrt(chi2 / n)``, ``chi2 = sum |r / sigma|**2`` over its ``n`` residuals
(:func:`gap`): 1 when the residual is noise.  ``pfmdyn discrepancy`` and ``pfmdyn map`` (each
pixel's spectra) report this one gap; a gap above :data:`GAP_LIMIT` is a misfit the noise does
not explain.

Every noise estimate of pfmdyn, and why those that differ do:

* bias spectra (``pfmdyn discrepancy`` on a CSV spectrum): :func:`noise_sigma`, as above;
* one spectrum with no bias axis (a drive sweep, with or without a reference, and a thermal
  tune's log ASD: :mod:`pfmdyn.discrepancy.sweep`, ``reference``, ``thermal``):
  :func:`spectrum_noise`, the same estimate without the line in bias it cannot have, floored at
  :data:`SPECTRUM_FLOOR` of the data's RMS.  Such data may be real (an amplitude-only sweep, a log
  ASD): a real difference's ``|d|**2`` is a chi-squared of one degree, whose median is
  ``2 gammaincinv(1/2, 1/2) = 0.455`` ``sigma**2``, not the exponential's ``ln 2``, so for real data that is the
  constant (with ``ln 2`` real noise would read at 0.81 of its standard deviation, and a residual
  of pure noise show a gap of 1.23);
* each pixel of a map (:mod:`pfmdyn.maps.fit`, :mod:`pfmdyn.maps.sho`): :func:`noise_sigmas`,
  floored at :data:`PIXEL_FLOOR` of the pixel's norm ``sqrt(sum |y|**2)`` (the maps' own floor for
  data without noise, far below the one-spectrum floor);
* choosing a map's model (:mod:`pfmdyn.maps.select`): the variance profiled from the fits, the
  smallest residual sum of squares per degree of freedom over the candidate models, floored at
  1e-12 of ``mean |y|**2``: the BIC compares models on the residuals of those fits, and there
  the few sample pixels' bands, a handful of points per peak width, would leave curvature in
  differences;
* finding resonances (:mod:`pfmdyn.discrepancy.peaks`): the noise of the bias-summed magnitude,
  real and before any fit, from the median absolute second difference (``/ 0.6745 sqrt 6``, the
  real normal's constants), floored at 1e-3 of the median magnitude: a threshold of prominence;
* deconvolving the bias lines (:mod:`pfmdyn.analysis.deconvolve`): the variance at each
  frequency from the residual of its line in bias (``RSS / 2 (n - 2)``), unbiased and per
  frequency, for the uncertainties of that frequency's coefficients; :func:`noise_sigma` takes
  the median of the same residuals over frequencies, for one robust level.
"""
from __future__ import annotations

import math

import numpy as np

from .bias_line import bias_lines

__all__ = ["noise_sigma", "noise_sigmas", "spectrum_noise", "gap", "misfit_band", "GAP_LIMIT", "MAX_REFINEMENT",
           "DIFFERENCE_ORDERS", "SPECTRUM_FLOOR", "PIXEL_FLOOR"]

GAP_LIMIT = 2.0
"""A gap above this is a misfit, not noise: ``pfmdyn discrepancy`` reports it ``unexplained``
(:data:`pfmdyn.discrepancy.select.UNEXPLAINED`), ``pfmdyn map`` marks the pixel unexplained
(the default gap threshold)."""


def gap(chi2, count):
    """``sqrt(chi2 / count)``: the noise-normalised RMS residual of ``count`` residuals whose
    squares divided by the noise variance sum to ``chi2`` (arrays: element by element).

    >>> float(gap(8.0, 2))
    2.0
    """
    return np.sqrt(np.asarray(chi2, float) / np.maximum(count, 1))


def misfit_band(frequency_hz, energy) -> list[float]:
    """The band (Hz) holding the central 80 % of a misfit: ``energy`` per frequency (sorted), e.g.
    ``|residual / sigma|**2``.

    >>> misfit_band(np.arange(10.0), np.r_[np.zeros(4), np.ones(2), np.zeros(4)])
    [4.0, 5.0]
    """
    cum = np.cumsum(energy) / np.sum(energy)
    last = len(frequency_hz) - 1
    return [float(frequency_hz[min(np.searchsorted(cum, 0.1), last)]),
            float(frequency_hz[min(np.searchsorted(cum, 0.9), last)])]


def noise_sigma(frequency_hz, bias_v, response) -> float:
    """RMS complex noise: the smallest of estimates that signal can only inflate (see module).

    >>> rng = np.random.default_rng(1)
    >>> f = np.repeat(np.arange(2000.0), 2); v = np.tile([0.0, 1.0], 2000)
    >>> y = np.sin(f / 300) + (rng.standard_normal(4000) + 1j * rng.standard_normal(4000)) / 2**0.5
    >>> round(noise_sigma(f, v, y), 1)
    1.0
    """
    return float(_noise(frequency_hz, bias_v, np.asarray(response)[None])[0])


def _noise(frequency_hz, bias_v, spectra) -> np.ndarray:
    """:func:`noise_sigma` of each row of ``spectra`` ``(n, points)``, all at the same points: the
    points' orderings and groupings are found once, the estimates are whole-array operations."""
    frequency_hz, bias_v = np.asarray(frequency_hz, float), np.asarray(bias_v, float)
    estimates = _difference_noise(frequency_hz, bias_v, spectra)
    across = _bias_noise(frequency_hz, bias_v, spectra)
    refined = np.min(estimates[1:] + ([across] if across is not None else []), axis=0)
    # Coarse sampling reads second differences at most about 1.3x high; a refined estimate far
    # below them means data without noise (a simulation), where the curvature is the floor.
    return np.minimum(estimates[0], np.maximum(refined, MAX_REFINEMENT * estimates[0]))


MAX_REFINEMENT = 0.7
"""The refined estimates lower the second-difference one by at most this factor."""


DIFFERENCE_ORDERS = (2, 3, 4, 5, 6)
"""Orders of the differences along frequency.  Second differences leave the curvature of a
peak sampled by few bins (band excitation: 64-256 bins over a few peak widths) and read the
noise up to 30 % high there; higher orders cancel more of a smooth signal and less of the
noise, and the smallest estimate is kept."""


def _difference_noise(frequency_hz, bias_v, spectra) -> list[np.ndarray]:
    """Noise from differences along frequency at each bias, one ``(n,)`` estimate per order of
    :data:`DIFFERENCE_ORDERS`: for white complex noise of RMS sigma, ``median |d|**2 = C(2 m, m)
    sigma**2 ln 2`` for ``m``-th differences.

    The points are ordered by bias, then frequency, and the differences taken along that order;
    those that straddle two biases are dropped.  An order no bias has enough frequencies for (a
    bias that changes with every row) takes its differences along frequency over all rows, an
    upper bound."""
    biases = [np.flatnonzero(bias_v == b) for b in np.unique(bias_v)]
    along_bias = np.concatenate([points[np.argsort(frequency_hz[points])] for points in biases])
    run = np.repeat(np.arange(len(biases)), [len(points) for points in biases])
    along_all = np.argsort(frequency_hz, kind="stable")
    in_order = np.array_equal(along_bias, np.arange(along_bias.size))    # a sorted grid: no copy
    within = dict(zip(DIFFERENCE_ORDERS, _differences(spectra if in_order else spectra[:, along_bias])))
    overall = None
    estimates = []
    for order in DIFFERENCE_ORDERS:
        one_bias = run[:-order] == run[order:]
        if one_bias.all():
            d = within[order]
        elif one_bias.any():
            d = within[order][:, one_bias]
        else:
            overall = overall or dict(zip(DIFFERENCE_ORDERS, _differences(spectra[:, along_all])))
            d = overall[order]
        scale = math.comb(2 * order, order) * math.log(2)
        estimates.append(np.sqrt(np.median(np.abs(d) ** 2, axis=1) / scale))
    return estimates


def _differences(rows):
    """The differences of :data:`DIFFERENCE_ORDERS` along the last axis, each the next's source
    (as ``np.diff`` iterates its first differences)."""
    d = rows
    for order in range(1, DIFFERENCE_ORDERS[-1] + 1):
        d = d[:, 1:] - d[:, :-1]
        if order in DIFFERENCE_ORDERS:
            yield d


def _bias_noise(frequency_hz, bias_v, spectra) -> np.ndarray | None:
    """Noise from the residual of a straight line in bias at each frequency, per spectrum (None
    with fewer than three biases per frequency).

    The response is affine in the bias at every frequency (the model's drives, d1, d2 and
    ``f0``, ``q0`` proportional to ``V - V_surf``) whatever the peak shape or sampling, so the
    residual of the line is noise plus whatever is not affine (which only raises this
    estimate); ``n`` biases leave ``n - 2`` complex degrees of freedom, and ``RSS / sigma**2``
    follows a Gamma(``n - 2``) law."""
    # the Gamma law's median, gammaincinv(a, 1/2) (scipy.stats would cost a second to import)
    from scipy.special import gammaincinv

    if np.sum(np.unique(frequency_hz, return_counts=True)[1] >= 3) < 10:      # too few biases: no lines to fit
        return None
    lines = bias_lines(frequency_hz, bias_v, spectra)
    ok = (lines.count >= 3) & (lines.spread > 0)      # two setpoints or more (bias_lines decides), a residual beside
    if ok.sum() < 10:
        return None
    dof = lines.count[ok] - 2
    return np.sqrt(np.median(lines.squared_residual()[:, ok] / gammaincinv(dof, 0.5), axis=1))


SPECTRUM_FLOOR = 1e-9
""":func:`spectrum_noise` is at least this fraction of the data's RMS (a simulated sweep without noise)."""


def spectrum_noise(frequency_hz, y) -> float:
    """RMS noise of one spectrum, ``y`` (complex or real) at ``frequency_hz``, with no bias axis:
    :func:`noise_sigma` (differences along frequency alone), floored at :data:`SPECTRUM_FLOOR` of the
    RMS of ``y`` (see the module for real data).

    >>> rng = np.random.default_rng(3)
    >>> f = np.linspace(1e4, 2e4, 4000)
    >>> round(spectrum_noise(f, np.sin(f / 500) + 0.01 * rng.standard_normal(4000)) / 0.01, 1)  # real noise
    1.0
    >>> spectrum_noise(f, np.full(4000, 2.0))          # no noise: the floor
    2e-09
    """
    sigma = noise_sigma(frequency_hz, np.zeros(len(y)), y)
    if np.isrealobj(y):     # the constant of real noise (see the module)
        from scipy.special import gammaincinv
        sigma *= math.sqrt(math.log(2) / (2 * gammaincinv(0.5, 0.5)))     # a chi-squared of one degree's median
    return max(sigma, SPECTRUM_FLOOR * float(np.sqrt(np.mean(np.abs(y)**2))), 1e-300)


PIXEL_FLOOR = 1e-15
""":func:`noise_sigmas` is at least this fraction of each pixel's norm ``sqrt(sum |y|**2)`` (1 when
the pixel is all zero): a map's data without noise."""


def noise_sigmas(frequency_hz, bias_v, spectra) -> np.ndarray:
    """:func:`noise_sigma` of each of ``spectra`` ``(n, n_bias, n_freq)`` (spectra on one grid:
    ``frequency_hz`` ``(n_freq,)``, ``bias_v`` ``(n_bias,)`` or None for one spectrum each), floored at
    :data:`PIXEL_FLOOR` of each one's norm; all spectra at once.

    >>> rng = np.random.default_rng(2)
    >>> y = (rng.standard_normal((2, 1, 4000)) + 1j * rng.standard_normal((2, 1, 4000))) * np.array([[[1.0]], [[3.0]]])
    >>> (noise_sigmas(np.arange(4000.0), None, y) / 2**0.5).round(0).tolist()
    [1.0, 3.0]
    """
    spectra = np.asarray(spectra)
    n_bias, n_freq = spectra.shape[-2:]
    f = np.tile(np.asarray(frequency_hz, float), n_bias)
    v = np.repeat(np.zeros(n_bias) if bias_v is None else np.asarray(bias_v, float), n_freq)
    flat = spectra.reshape(-1, n_bias * n_freq)
    norm = np.sqrt(np.sum(np.abs(flat) ** 2, axis=1))
    floor = PIXEL_FLOOR * np.where(norm == 0, 1.0, norm)
    return np.maximum(_noise(f, v, flat), floor)
