"""Resonances in a thermal-noise spectrum: peaks found and fitted with a damped oscillator.

Near an isolated flexural mode the thermal amplitude spectral density of a cantilever is
that of a damped harmonic oscillator over a white floor,

    ASD(f)**2 = w**2 + A**2 f0**4 / ((f0**2 - f**2)**2 + (f f0 / Q)**2),

(the beam's modal response, one mode at a time: pfmdyn's transfer functions with loss
``1/Q`` reduce to it near each root; derived in ``derivations/formulas.py``, evaluated by
the generated ``formulas.oscillator_asd``).  Peaks are located on the logarithm of the median-
smoothed spectrum, then each is fitted on a window of a few linewidths, in log space, so
that the floor and the peak weigh alike.  A spectrum estimate (Welch, FFT) holds in each bin the
power in it: a peak narrower than a few bins is fitted bin-averaged too (:func:`oscillator_bin_power`)
and the better kept (:func:`fit_oscillator`).

Which peaks are flexural modes: the most prominent peak is mode 1 (in a displacement spectrum the
fundamental dominates) unless a lower peak makes it a higher mode (mode 2 of a much higher Q than
mode 1's, mode 1 on a 1/f rise); a peak is mode ``n`` when its ratio to mode 1 lies within
25 % of the free beam's ``(z_n/z_1)**2`` (certified free roots, :mod:`pfmdyn.roots.core`);
other peaks (electrical pick-up, torsion, the stage) are left out.

:func:`instrument_resonances` is the resonance table of any instrument file: the readers
(:mod:`pfmdyn.io.instruments`) only read, the thermal tune's peaks are fitted here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import UserError
from ..generated import formulas
from ..io.discrepancy_data import ResonanceData
from ..io.instruments import read_instrument, resonance_table
from ..io.tables import check_resonance_rows

__all__ = ["ThermalPeak", "oscillator_asd", "oscillator_bin_power", "fit_oscillator", "tallest_peak", "half_power_run", "broad_mode",
           "fit_thermal_peaks", "first_mode_index", "instrument_resonances"]


@dataclass(frozen=True)
class ThermalPeak:
    """One fitted flexural mode (1-based): f0 (Hz), Q, peak amplitude A and white floor w (units of the ASD).

    ``covariance`` of (f0, Q, A, w) from the fit's scatter; ``shape`` the same parameters' change when the
    spectrum is weighted in power instead of in log (:func:`fit_oscillator`): a peak that is an oscillator
    over a white floor gives the same parameters either way, one that is not (a fluid-loaded mode, a
    drifting resonance, leakage of the FFT's window) does not, and that spread is part of each uncertainty.
    A floor that the window does not reach is undetermined and carries no variance into the others.
    ``bin_width`` (Hz): the oscillator was fitted bin-averaged (:func:`oscillator_bin_power`), else None
    (point-sampled); ``sampling`` which of the two a peak narrower than :data:`NARROW` bins took (by BIC),
    "" for a wider one (the two agree); ``area_profile``: the relative standard error of its mean square
    from the fit's profile over Q (:func:`fit_oscillator`), 0 for a wide peak (the covariance holds it);
    ``drift`` the resonance's relative standard deviation over the averages, 0 where none was fitted."""

    mode: int
    frequency_hz: float
    quality_factor: float
    amplitude: float
    white: float
    covariance: tuple
    shape: tuple = (0.0, 0.0, 0.0, 0.0)
    bin_width: float | None = None
    sampling: str = ""
    area_profile: float = 0.0
    drift: float = 0.0

    def stderr(self, gradient, part: str = "total") -> float:
        """Standard error of a quantity whose partials w.r.t. (f0, Q, A, w) are ``gradient``: from the
        ``"fit"``'s scatter, the peak's ``"shape"``, or their ``"total"`` (in quadrature).

        >>> p = ThermalPeak(1, 1e5, 100.0, 1.0, 0.0, ((4.0, 0, 0, 0), (0, 1.0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0)), (3.0, 0, 0, 0))
        >>> p.stderr((1, 0, 0, 0)), p.stderr((1, 0, 0, 0), "fit"), p.frequency_uncertainty_hz
        (3.605551275463989, 2.0, 3.605551275463989)
        """
        g = np.asarray(gradient, dtype=float)
        used = g != 0           # an undetermined (infinite) variance elsewhere does not reach this quantity
        scatter = float(g[used] @ np.asarray(self.covariance)[np.ix_(used, used)] @ g[used]) if part != "shape" else 0.0
        shape = float(g @ np.asarray(self.shape)) ** 2 if part != "fit" else 0.0
        return math.sqrt(max(scatter, 0.0) + shape)

    @property
    def frequency_uncertainty_hz(self) -> float:
        """Standard error of the resonance (Hz), scatter and shape."""
        return self.stderr((1, 0, 0, 0))

    @property
    def quality_factor_uncertainty(self) -> float:
        """Standard error of Q, scatter and shape."""
        return self.stderr((0, 1, 0, 0))


def oscillator_asd(f, f0, q, amplitude, white):
    """Amplitude spectral density of a damped oscillator over a white floor (module formula).

    >>> round(float(oscillator_asd(1e5, 1e5, 100.0, 1.0, 0.0)), 6)   # A Q at resonance
    100.0
    """
    return formulas.oscillator_asd(np.asarray(f, dtype=float), f0, q, amplitude, white)


def oscillator_bin_power(f, bin_width: float, f0, q, amplitude, white):
    """Each bin's mean of :func:`oscillator_asd` squared over ``[f - bin_width/2, f + bin_width/2]``: what a
    Welch/FFT estimate holds (the power in the bin, whatever the linewidth), where a peak narrower than a
    bin or two is no point sample.  Exact, for ``Q > 1/2``: ``(f0**2 - f**2)**2 + (f f0/Q)**2`` is
    ``(f**2 - p)(f**2 - conj p)``, ``p = f0**2 (1 - 1/(2Q**2) + i sqrt(1 - 1/(4Q**2)) / Q)``, so the
    oscillator's PSD is ``A**2 f0**4 Im(1/(f**2 - p)) / Im p`` and ``1/(f**2 - s**2)``, ``s = sqrt p``,
    integrates to ``(log(f - s) - log(f + s)) / (2 s)`` (continuous on the real line: ``Im s > 0``).

    >>> f = np.array([1e5 - 40.0, 1e5, 1e5 + 55.0])
    >>> fine = [np.mean(oscillator_asd(np.linspace(x - 50, x + 50, 200001), 1e5, 3000.0, 1.0, 0.1) ** 2) for x in f]
    >>> np.allclose(oscillator_bin_power(f, 100.0, 1e5, 3000.0, 1.0, 0.1), fine, rtol=1e-4)
    True
    """
    f = np.asarray(f, dtype=float)
    p = f0**2 * (1 - 1 / (2 * q**2) + 1j * np.sqrt(1 - 1 / (4 * q**2)) / q)
    s = np.sqrt(p)

    def antiderivative(x):
        return ((np.log(x - s) - np.log(x + s)) / (2 * s)).imag

    area = antiderivative(f + bin_width / 2) - antiderivative(f - bin_width / 2)
    return amplitude**2 * f0**4 * area / (p.imag * bin_width) + white**2


SMOOTH_ELEMENTS = 2**24
"""The most window values :func:`_smooth` holds at once (128 MB): beyond, a wide window runs over block medians."""


def _smooth(y, width):
    """Running median of ``y`` over ``width`` points (its ends held).  A wide window over a long spectrum (a window
    array of more than :data:`SMOOTH_ELEMENTS` values: 1.6 GB for 100,000 points at a 2 % window) runs over the
    medians of blocks of ``width/101`` points, interpolated back: a floor that needs no finer grain.

    >>> y = np.random.default_rng(0).normal(size=400_000) + np.linspace(0, 10, 400_000)
    >>> floor = _smooth(y, 8001)                # 3.2e9 window values: by blocks, the exact medians within 0.02
    >>> floor.shape, all(abs(floor[i] - np.median(y[i - 4000:i + 4001])) < 0.02 for i in (50_000, 200_000, 350_000))
    ((400000,), True)
    """
    pad = width // 2
    step = (2 * pad + 1) // 101
    if y.size * (2 * pad + 1) > SMOOTH_ELEMENTS and step > 1:
        blocks = y[:y.size // step * step].reshape(-1, step)
        centres = np.arange(len(blocks)) * step + (step - 1) / 2
        return np.interp(np.arange(y.size), centres, _smooth(np.median(blocks, axis=1), 101))
    padded = np.pad(y, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * pad + 1)
    return np.median(windows, axis=-1)


DRIFT_NODES = 15
"""Gauss-Hermite nodes over a drifting resonance's normal spread (:func:`_oscillator_power`)."""


def _oscillator_power(f, parameters, bin_width: float | None):
    """The oscillator's power spectral density, point-sampled (``bin_width`` None) or bin-averaged;
    ``parameters`` (f0, Q, A, w), or with a fifth, the resonance's relative standard deviation over the
    averages: the mean of oscillators at ``f0 (1 + spread x)``, ``x`` normal, each of the same mean square
    (``A**2 f0 Q``: equipartition does not care where the resonance is), over the floor.

    >>> f = np.linspace(9.9e4, 10.1e4, 2001)
    >>> drifted = _oscillator_power(f, (1e5, 1000.0, 1.0, 0.0, 2e-3), None)
    >>> plain = _oscillator_power(f, (1e5, 1000.0, 1.0, 0.0), None)
    >>> round(float(drifted.max() / plain.max()), 2), round(float(drifted.sum() / plain.sum()), 3)   # lower, the same area
    (0.36, 0.998)
    """
    if len(parameters) == 5:
        f0, q, amplitude, white, spread = parameters
        x, weight = np.polynomial.hermite_e.hermegauss(DRIFT_NODES)
        return sum(w_n / weight.sum() * _oscillator_power(f, (f0 * (1 + spread * x_n), q,
                                                               amplitude / np.sqrt(1 + spread * x_n), 0.0), bin_width)
                   for x_n, w_n in zip(x, weight)) + white**2
    if bin_width is None:
        return oscillator_asd(f, *parameters) ** 2
    return oscillator_bin_power(f, bin_width, *parameters)


def _log_fit(f, y, start, weight_in_power: bool, bin_width: float | None = None, fixed_quality=None):
    """Least squares of one oscillator over a white floor in log parameters (all positive, no sign
    folding), residuals in log ASD or, ``weight_in_power``, in power relative to the data's peak power;
    point-sampled or bin-averaged (``bin_width``), drifting with a fifth parameter (:func:`_oscillator_power`);
    ``fixed_quality``: Q held there (start without it)."""
    from scipy.optimize import least_squares

    log_y, top = np.log(y), float(np.max(y)) ** 2

    def residual(p):
        parameters = np.exp(p if fixed_quality is None else np.insert(p, 1, math.log(fixed_quality)))
        with np.errstate(all="ignore"):      # a trial step far out: a large residual, not a warning
            power = _oscillator_power(f, parameters, bin_width)
            r = (power - y**2) / top if weight_in_power else 0.5 * np.log(power) - log_y
        return np.where(np.isfinite(r), r, 1e30)

    return least_squares(residual, np.log(start), method="trf", x_scale=1.0, max_nfev=2000)


DRIFT_START = 0.5
"""The drifting oscillator's start: its resonance spread over half a linewidth."""
DRIFT_BINS = 2.0
"""Bins a peak must span for its drift to be told from its damping: a narrower one's shape is the bins'."""

NARROW = 5.0
"""Bins per linewidth below which the bin-averaged oscillator is fitted beside the point-sampled one."""
POSITIVE = 2.0
"""The BIC difference (chi2 in noise units: both have four parameters) by which the point-sampled oscillator
must fit a narrow peak better to be taken: a spectrum estimate holds each bin's power (Welch, FFT), so the
bin-averaged one is the default; over a sub-bin peak the two differ in a handful of bins, where noise alone
can favour either (a Q-1,900 peak fitted point-sampled at Q 5,300, its area off 70 %)."""


def _area_profile(f, y, values, bin_width: float | None, variance: float) -> float:
    """The relative standard error of the oscillator's mean square (``A**2 f0 Q``) from the profile of the
    fit over Q (f0, A and the floor refitted at each Q, stepping out from the fitted one by ``2**(1/4)`` up
    to 16 times, each way until chi2 is more than one scaled unit above its least): half the spread of the
    log mean square within that unit.  Where the linewidth is under a bin or two, a point-sampled
    oscillator's area is set by where the bins fall, not by the data (chi2 flat over Q 2,500-8,000 while the
    area moves 27-49 %): the local covariance does not see it."""
    best = 2 * _log_fit(f, y, values, False, bin_width).cost
    area = [math.log(values[2] ** 2 * values[0] * values[1])]
    for direction in (1, -1):
        start = np.delete(values, 1)
        for step in range(1, 17):
            q = values[1] * 2 ** (direction * step / 4)
            fit = _log_fit(f, y, start, False, bin_width, fixed_quality=q)
            if 2 * fit.cost - best > variance:
                break
            start = np.exp(fit.x)
            area.append(math.log(start[1] ** 2 * start[0] * q))
    return (max(area) - min(area)) / 2


def fit_oscillator(f, y, guess, mode: int = 1, drifting: bool = True) -> ThermalPeak | None:
    """One mode of a thermal spectrum: :func:`oscillator_asd` fitted to ``y`` (ASD, positive) on ``f`` from
    ``guess`` (f0, Q, A, w), in log ASD (an averaged spectrum's scatter is relative); None when the fit
    leaves the window.

    The covariance comes from the Jacobian, scaled by the residual's variance; a parameter the window
    does not constrain (the floor, when the window stays above it) is held, its variance zero.  The fit
    is repeated weighted in power, from the first one; the change is :attr:`ThermalPeak.shape`.  A peak
    narrower than :data:`NARROW` bins is fitted bin-averaged too, the default unless the point-sampled
    one fits better by :data:`POSITIVE`; its area's error is also read from the profile over Q
    (:func:`_area_profile`), where the bins, not the data, may set it.  ``drifting``: the oscillator whose
    resonance drifted over the averages (:func:`_oscillator_power`) is fitted too and kept where it fits
    better by BIC (``ln n`` in chi2 units, one parameter more), on a peak :data:`DRIFT_BINS` bins wide or
    more: a plain one fits such a peak's core and
    flanks with one Q and misses its mean square by up to 10 % (``benchmarks/thermal_regimes.py``,
    ``drifting``); its Q is then the lever's own, the spread the peak's extra width.

    >>> f = np.linspace(9e4, 11e4, 400)
    >>> p = fit_oscillator(f, oscillator_asd(f, 1e5, 200.0, 1e-12, 1e-13), (1.001e5, 150.0, 1.5e-12, 2e-13))
    >>> round(p.frequency_hz, 3), round(p.quality_factor, 6), p.frequency_uncertainty_hz < 1e-6
    (100000.0, 200.0, True)
    >>> p = fit_oscillator(f[180:220], oscillator_asd(f[180:220], 1e5, 200.0, 1e-12, 1e-18), (1e5, 150.0, 1e-12, 1e-13))
    >>> math.isfinite(p.quality_factor_uncertainty), p.covariance[3][3]   # the floor is far below the window
    (True, 0.0)
    """
    f, y = np.asarray(f, dtype=float), np.asarray(y, dtype=float)
    keep = np.isfinite(y) & (y > 0)
    f, y = f[keep], y[keep]
    if f.size < 6:
        return None
    start = np.maximum(np.abs(np.asarray(guess, dtype=float)), np.finfo(float).tiny)
    first, bin_width = _log_fit(f, y, start, False), None
    step = float(np.median(np.diff(f)))
    if np.exp(first.x[0] - first.x[1]) < NARROW * step:     # a narrow peak: bin-averaged too, the better kept
        binned = min((_log_fit(f, y, x, False, step) for x in (start, np.exp(first.x))), key=lambda b: b.cost)
        noise = 2 * min(binned.cost, first.cost) / max(f.size - 4, 1)
        if 2 * (binned.cost - first.cost) < POSITIVE * noise:
            first, bin_width = binned, step
    if drifting and np.exp(first.x[0] - first.x[1]) >= DRIFT_BINS * step:
        drifted = _log_fit(f, y, np.r_[np.exp(first.x), DRIFT_START / np.exp(first.x[1])], False, bin_width)
        if 2 * (first.cost - drifted.cost) > math.log(f.size) * 2 * drifted.cost / max(f.size - 5, 1):
            first = drifted
    values = np.exp(first.x)
    if not (f[0] < values[0] < f[-1]):
        return None
    J = first.jac
    norms = np.linalg.norm(J, axis=0)
    held = norms <= 1e-6 * norms.max()
    dof = max(f.size - int(np.sum(~held)), 1)
    variance = float(np.sum(first.fun**2)) / dof
    covariance = np.zeros((values.size, values.size))
    free = np.flatnonzero(~held)
    covariance[np.ix_(free, free)] = np.linalg.pinv(J[:, free].T @ J[:, free]) * variance
    covariance = (covariance * np.outer(values, values))[:4, :4]         # d x = x d log x; the drift's share held
    second = _log_fit(f, y, values, True, bin_width)
    shape = np.where(held, 0.0, np.exp(second.x) - values)[:4]
    if not np.all(np.isfinite(shape)):
        shape = np.zeros(4)
    narrow = values[0] / values[1] < NARROW * step
    return ThermalPeak(mode, *map(float, values[:4]), tuple(map(tuple, covariance.tolist())), tuple(map(float, shape)),
                       bin_width, ("bin-averaged" if bin_width else "point-sampled") if narrow else "",
                       _area_profile(f, y, values, bin_width, variance) if narrow else 0.0,
                       float(values[4]) if values.size == 5 else 0.0)


def _low_bins(size: int) -> int:
    """The lowest bins of a spectrum from (near) 0 hold the offset and 1/f noise, never a flexural mode."""
    return max(3, size // 100)


def tallest_peak(y) -> int:
    """Index of the tallest peak of a spectrum ``y`` (positive, equally spaced from near 0): the maximum of
    its logarithm median-smoothed over 5 bins (no single-bin spike), above :func:`_low_bins`, at its highest
    bin; where that is the low edge (a 1/f rise above a low peak), the most prominent peak.  Every thermal fit (the oscillator's, the whole lever's) starts from it.

    >>> f = np.linspace(0, 4e4, 2000); y = oscillator_asd(f, 1.2e4, 20.0, 1e-11, 1e-13)
    >>> spiked = y.copy(); spiked[900] = 1.0
    >>> int(tallest_peak(spiked)), int(np.argmax(y))
    (599, 599)
    >>> abs(tallest_peak(y + 2e-9 * f[20] / f.clip(1.0)) - 599) < 5      # on a 1/f rise taller than the peak
    True
    """
    y = np.asarray(y, dtype=float)
    start = _low_bins(y.size)
    smooth = _smooth(np.log(np.maximum(y, np.finfo(float).tiny)), 5)[start:]
    j = start + int(np.argmax(smooth))
    if j <= start + 2:          # still falling at the low edge: a 1/f rise, the peak the most prominent
        tops, prominence = _peaks(smooth - smooth.min(), 0.0)
        j = start + int(tops[np.argmax(prominence)]) if tops.size else j
    near = slice(max(j - 2, start), j + 3)        # the median's plateau: its highest bin
    return near.start + int(np.argmax(y[near]))


def half_power_run(y, i: int) -> tuple[int, int]:
    """First and last index of the contiguous run around the peak ``i`` where ``y`` (an ASD) stays above
    ``y[i] / sqrt(2)``: the half-power width is ``(last - first + 1)`` bins.

    >>> half_power_run(np.array([0.1, 0.8, 0.9, 1.0, 0.75, 0.2, 0.9]), 3)
    (1, 4)
    """
    below = np.asarray(y) <= y[i] / np.sqrt(2)
    left, right = np.flatnonzero(below[:i]), np.flatnonzero(below[i + 1:])
    return (int(left[-1]) + 1 if left.size else 0), (i + int(right[0]) if right.size else len(below) - 1)


def _quality_start(f, y, i: int, floor: float = 0.0) -> float:
    """A starting Q from the half-power run (at least two bins wide); of the power above ``floor`` (an ASD)
    for a peak not twice its floor, which never falls to half its power otherwise."""
    lo, hi = half_power_run(np.sqrt(np.maximum(y**2 - floor**2, 0.0)) if y[i] < 2 * floor else y, i)
    step = f[1] - f[0]
    return f[i] / max((hi - lo + 1) * step, 2 * step)


def broad_mode(f, y) -> ThermalPeak | None:
    """The tallest peak as one oscillator over the whole band (first mode): a low-Q mode (in liquid) is
    wider than the windows :func:`fit_thermal_peaks` searches and fits in.

    >>> f = np.linspace(0, 4e4, 2000)
    >>> p = broad_mode(f, oscillator_asd(f, 1.2e4, 2.0, 1e-11, 1e-13))
    >>> round(p.frequency_hz, 3), round(p.quality_factor, 6)
    (12000.0, 2.0)
    """
    f, y = np.asarray(f, dtype=float), np.asarray(y, dtype=float)
    i = tallest_peak(y)
    q0 = max(_quality_start(f, y, i), 0.5)
    band = (f > f[_low_bins(f.size)]) & (y > 0)
    return fit_oscillator(f[band], y[band], (f[i], q0, y[i] / max(q0, 1.0), np.min(y[band])), drifting=False)


def _peaks(x, minimum: float):
    """Peaks of ``x`` rising at least ``minimum`` above zero and above their surroundings (prominence),
    and their prominences: ``scipy.signal.find_peaks(x, height=minimum, prominence=minimum)``
    written out (importing ``scipy.signal`` costs a command a third of a second).

    A peak is the middle of a run of equal values with lower neighbours on both sides; its
    prominence, its height above the higher of the lowest points between it and the nearest
    higher value on either side (or the end).

    >>> peaks, prominence = _peaks(np.array([0, 2, 1, 1, 3, 3, 3, 0, 1, 0.5]), 0.4)
    >>> peaks.tolist(), prominence.tolist()
    ([1, 5, 8], [1.0, 3.0, 0.5])
    """
    edges = np.flatnonzero(np.diff(x)) + 1                 # starts of runs of equal values
    starts, ends = np.r_[0, edges], np.r_[edges - 1, x.size - 1]
    inner = (starts > 0) & (ends < x.size - 1)
    starts, ends = starts[inner], ends[inner]
    rising = (x[starts - 1] < x[starts]) & (x[ends + 1] < x[ends])
    peaks = (starts[rising] + ends[rising]) // 2
    peaks = peaks[x[peaks] >= minimum]
    prominence = np.empty(peaks.size)
    for n, i in enumerate(peaks):
        higher = np.flatnonzero(x > x[i])
        left, right = higher[higher < i], higher[higher > i]
        lo = left[-1] + 1 if left.size else 0
        hi = right[0] if right.size else x.size
        prominence[n] = x[i] - max(x[lo:i + 1].min(), x[i:hi].min())
    keep = prominence >= minimum
    return peaks[keep], prominence[keep]


def _flexural_modes(candidates, max_modes):
    """Mode number of each candidate peak (most prominent first), 0 for a peak that is no flexural mode.

    Mode 1 is the most prominent peak unless a lower candidate has it as a higher mode (its frequency
    ratio within 25 % of the free beam's ``(z_n/z_1)**2``, the fluid's load shifting it): then the most
    prominent such lower one.  Mode 2 can stand out more than mode 1 (a Q 8-10 times mode 1's, mode 1 on
    a 1/f rise) and was taken for it, k then read 2-3 times too high.

    >>> _flexural_modes([6.3e5, 1.0e5, 5e4], 5)      # the tallest is mode 2 of the second
    [2, 1, 0]
    """
    from ..roots.core import family_roots

    if len(candidates) == 0:
        return []
    z = np.array([float(r) for r in family_roots("free", max_modes, 17).roots])
    ratios = formulas.frequency_from_beta(z, 1.0, z[0])

    def mode_of(f, first):
        r = f / first
        n = int(np.argmin(np.abs(r / ratios - 1))) + 1
        return n if abs(r / ratios[n - 1] - 1) < 0.25 else 0

    first = next((c for c in candidates[1:] if c < candidates[0] and mode_of(candidates[0], c) > 1), candidates[0])
    out, taken = [], set()
    for f in candidates:
        n = mode_of(f, first)
        n = n if n not in taken else 0
        out.append(n)
        taken.add(n)
    return out


def _candidates(f, y, min_prominence: float, max_peaks: int) -> list[tuple[int, int, float]]:
    """``(mode, index, floor)`` of the flexural modes among a spectrum's peaks (:func:`_flexural_modes`),
    lowest mode first: peaks of the log ASD above a median-smoothed floor by at least ``min_prominence``
    (the floor's ASD there the third)."""
    start = _low_bins(f.size)
    logy = np.log10(np.maximum(y, np.finfo(float).tiny))
    # A floor smoothed over 2 % of the span misses a peak wider than that (low Q, fine bins): wider
    # smoothing until a peak stands out.  The spectrum's own median over 5 bins hides a single-bin spike,
    # and with it a peak narrower than a bin (near vacuum, Q in the thousands): unsmoothed, last.
    for share, smoothing in ((50, 5), (10, 5), (4, 5), (50, 1)):
        floor = _smooth(logy, max(11, f.size // share))
        peaks, prominence = _peaks(_smooth(logy, smoothing)[start:] - floor[start:], np.log10(min_prominence))
        if peaks.size:
            break
    order = np.argsort(prominence)[::-1]
    modes = _flexural_modes(f[peaks[order] + start], max_peaks)
    return sorted((m, int(peaks[j] + start), float(10 ** floor[peaks[j] + start])) for m, j in zip(modes, order) if m)


def first_mode_index(f, y) -> int:
    """Index of the first flexural mode's peak in a thermal spectrum (equally spaced from near 0): the
    lowest mode among its peaks (:func:`_candidates`), else :func:`tallest_peak`.

    >>> f = np.linspace(0, 8e5, 8000)
    >>> y = np.hypot(oscillator_asd(f, 1e5, 30.0, 1e-12, 1e-13), oscillator_asd(f, 6.3e5, 300.0, 2e-13, 0.0))
    >>> round(float(f[first_mode_index(f, y)]), -3), round(float(f[tallest_peak(y)]), -3)
    (100000.0, 630000.0)
    """
    f, y = np.asarray(f, dtype=float), np.asarray(y, dtype=float)
    found = _candidates(f, y, 1.5, 5)
    return found[0][1] if found and found[0][0] == 1 else tallest_peak(y)


def fit_thermal_peaks(frequency_hz, asd, *, min_prominence: float = 1.5, max_peaks: int = 5) -> list[ThermalPeak]:
    """Resonances of a thermal spectrum, lowest first, each fitted with :func:`oscillator_asd`.

    Parameters
    ----------
    frequency_hz, asd : 1-D arrays, equally spaced frequencies from (near) 0
    min_prominence : a peak must rise this factor above the smoothed floor around it
    max_peaks : at most this many (the most prominent), returned in frequency order

    Examples
    --------
    >>> f = np.linspace(0, 4e5, 8001)
    >>> rng = np.random.default_rng(0)
    >>> asd = oscillator_asd(f, 1.8e5, 400.0, 2e-15, 5e-14) * rng.gamma(100, 0.01, f.size)
    >>> asd[(f > 2e4) & (f < 2.1e4)] *= 4          # a bump that is no flexural mode
    >>> [p] = fit_thermal_peaks(f, asd)
    >>> p.mode, round(p.frequency_hz, -2), abs(p.quality_factor - 400) < 3 * p.quality_factor_uncertainty
    (1, 180000.0, True)
    """

    f, y = np.asarray(frequency_hz, dtype=float), np.asarray(asd, dtype=float)
    if f.ndim != 1 or f.shape != y.shape or f.size < 50:
        raise UserError(f"{y.size} ASD values at {f.size} frequencies; a thermal spectrum needs equal 1-D frequency "
                        "and ASD arrays of at least 50 points")
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(y)) and np.all(np.diff(f) > 0)):
        raise UserError("a thermal spectrum needs finite values and increasing frequencies")
    step = f[1] - f[0]
    out = []
    for mode, i, base in _candidates(f, y, min_prominence, max_peaks):
        f0, top = f[i], y[i]
        q0 = _quality_start(f, y, i, base)
        half = max(6 * f0 / q0, 20 * step)
        window = (f > f0 - half) & (f < f0 + half)
        peak = fit_oscillator(f[window], y[window], (f0, q0, top / q0, base), mode)
        if peak is not None:
            out.append(peak)
    return out


def instrument_resonances(path, overrides: dict | None = None):
    """The resonance table of ``pfmdyn discrepancy`` that an instrument file implies, rows
    sorted by (condition, mode).

    A thermal tune's free modes are fitted (:func:`fit_thermal_peaks`); any other file gives
    the resonances its instrument stored (:func:`pfmdyn.io.instruments.resonance_table`).
    ``overrides`` (field names, e.g. ``tip_height``) win over the file.

    >>> instrument_resonances("scan.xyz")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: scan.xyz: unknown instrument file type '.xyz'; pfmdyn reads .ibw (Asylum), .h5/.hdf5 (pycroscopy NSID/USID), .nid (Nanosurf), .txt/.dat (drive sweeps), .csv
    """
    record = read_instrument(path)
    peaks = None
    if record.kind == "thermal spectrum":
        freq, asd, _ = record.spectrum
        peaks = fit_thermal_peaks(freq, asd)
    data = resonance_table(record, {k: v for k, v in (overrides or {}).items() if v is not None}, peaks)
    order = check_resonance_rows(str(path), data.mode, data.condition, data.frequency_hz, 1, data.quality_factor)
    qs = None if data.quality_factor is None else data.quality_factor[order]
    return ResonanceData(data.metadata, data.mode[order], data.condition[order], data.frequency_hz[order],
                         quality_factor=qs)
