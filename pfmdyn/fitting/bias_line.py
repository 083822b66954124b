"""The straight line in DC bias at each frequency: ``R(f, V) = b(f) + c(f) V``.

The first-harmonic response is affine in the tip bias at every frequency (the electrostatic drives
are proportional to ``V - V_surf``), so a spectrum measured at several biases is a set of lines,
one per frequency.  :func:`bias_lines` fits them all at once, for points in any order; the
deconvolution (:mod:`pfmdyn.analysis.deconvolve`) reads ``G_elec``, ``d_eff`` and the nulling bias
from them, and the noise estimate (:mod:`pfmdyn.fitting.noise`) reads the noise from their
residual.  (A map's pixels share one bias grid, so :mod:`pfmdyn.maps.bias` factors that grid once
and fits the lines inside each band's model instead.)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BiasLines", "bias_lines", "rounding_spread", "BIAS_RESOLUTION"]

BIAS_RESOLUTION = 1e-6
"""Biases at one frequency whose RMS deviation from their mean is at most this fraction of the
data's largest ``|V|`` (of 1 V when all are smaller: biases all at 0 V but for rounding) are one
setpoint: no bias source sets a DC bias to a millionth of its range (a 16-bit converter: 1.5e-5),
while rounding leaves such differences (``-0.3 + 3 * 0.1`` is ``5.6e-17``, and the mean of three
biases of 0.1 V is not 0.1).  A line through one setpoint determines no slope."""


def rounding_spread(bias_v) -> float:
    """The largest ``sum (V - mean)**2`` per point of biases of one setpoint among ``bias_v``
    (:data:`BIAS_RESOLUTION`): a spread no larger is rounding, not a second bias.

    >>> v = np.array([0.0, -0.3 + 3 * 0.1, 5.0])               # 0 V, once as computed; and 5 V
    >>> round(rounding_spread(v) ** 0.5, 12)                    # 1e-6 of 5 V
    5e-06
    >>> bool(np.sum((v[:2] - v[:2].mean())**2) <= 2 * rounding_spread(v))
    True
    """
    return (BIAS_RESOLUTION * float(np.max(np.abs(bias_v), initial=1.0))) ** 2


@dataclass(frozen=True)
class BiasLines:
    """The lines of :func:`bias_lines`, per frequency in the order they first appear: ``frequency_hz``,
    ``count`` (points), ``mean_bias``, ``spread`` (``sum (V - mean)**2``; 0 at a frequency with one
    distinct bias, :data:`BIAS_RESOLUTION`), ``intercept`` ``b`` and ``slope`` ``c`` (both NaN there: the
    data determine no slope, nor the response at 0 V it extrapolates to); per point: ``group`` (its frequency's
    index) and ``residual``.  ``intercept``, ``slope`` and ``residual`` carry the leading axes of the
    response (spectra on one set of points)."""

    frequency_hz: np.ndarray
    count: np.ndarray
    mean_bias: np.ndarray
    spread: np.ndarray
    intercept: np.ndarray
    slope: np.ndarray
    group: np.ndarray
    residual: np.ndarray

    def squared_residual(self) -> np.ndarray:
        """``sum |residual|**2`` at each frequency (``(..., n_frequencies)``)."""
        return _sums(self.group, np.abs(self.residual) ** 2, len(self.count))


def _sums(group, values, n) -> np.ndarray:
    """Sums of ``values`` ``(..., points)`` over the points of each of ``n`` groups, ``(..., n)``: one
    ``bincount`` over all leading rows (each row its own ``n`` bins), so a row sums in the order it
    would alone."""
    values = np.asarray(values)
    if np.iscomplexobj(values):
        return _sums(group, values.real, n) + 1j * _sums(group, values.imag, n)
    rows = values.shape[:-1]
    bins = (group + n * np.arange(int(np.prod(rows)))[:, None]).ravel()
    return np.bincount(bins, values.ravel(), minlength=n * int(np.prod(rows))).reshape(*rows, n)


def bias_lines(frequency_hz, bias_v, response) -> BiasLines:
    """Fit ``b + c V`` to ``response`` at each frequency (least squares; sums centred on each
    frequency's mean bias, so a bias range far from zero keeps the fit conditioned).  ``response``
    ``(..., points)`` may hold many spectra at the same points: the grouping is found once.  A
    frequency whose biases are one setpoint (:data:`BIAS_RESOLUTION`) has no line: NaN, no warning.

    >>> f = np.array([2.0, 1.0, 2.0, 1.0, 2.0])
    >>> v = np.array([0.0, 1.0, 1.0, 3.0, 2.0])
    >>> lines = bias_lines(f, v, (1 + 2j) + (3 - 1j) * v)
    >>> lines.frequency_hz.tolist(), lines.count.tolist(), lines.slope.round(12).tolist()
    ([2.0, 1.0], [3, 2], [(3-1j), (3-1j)])
    >>> bias_lines(f, v, np.stack([v, 2 * v])).slope.round(12).tolist()       # two spectra at once
    [[1.0, 1.0], [2.0, 2.0]]
    >>> bias_lines([1.0] * 3, [0.1] * 3, [1.0, 2.0, 3.0]).slope.tolist()      # one bias: no slope (mean 0.1 + 1 ulp)
    [nan]
    """
    frequency_hz = np.asarray(frequency_hz, float)
    bias_v = np.asarray(bias_v, float)
    response = np.asarray(response)
    _, first, inverse = np.unique(frequency_hz, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    group = rank[inverse.reshape(-1)]
    n = len(order)
    count = np.bincount(group, minlength=n)
    mean_bias = _sums(group, bias_v, n) / count
    centred = bias_v - mean_bias[group]
    spread = _sums(group, centred**2, n)
    # rounding, not a second setpoint (the mean of equal biases may miss them by an ulp)
    spread[spread <= count * rounding_spread(bias_v)] = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(spread > 0, _sums(group, centred * response, n) / np.where(spread > 0, spread, 1.0), np.nan)
    intercept = _sums(group, response, n) / count - slope * mean_bias
    residual = response - (intercept[..., group] + slope[..., group] * bias_v)
    return BiasLines(frequency_hz[first[order]], count, mean_bias, spread, intercept, slope, group, residual)
