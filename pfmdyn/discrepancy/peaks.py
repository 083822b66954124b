"""The peaks of a measured spectrum, and fit starts whose resonances match them.

A resonance seen in a response ``y(f)`` is a complex pole: near it, at every bias,
``y = a / (f - p) + b + c f`` with one ``p`` shared by all biases.  ``Re p`` is the
resonance frequency and ``2 |Im p|`` the half-power width (for a Lorentzian peak ``|y|**2``
falls to half at ``|f - Re p| = |Im p|``).  :func:`poles` fits that form on a window
around each peak of the bias-summed magnitude: the pole is located to a small fraction of
the frequency step, which an undamped spectrum (needle peaks, where a shift of one step
changes the misfit by orders of magnitude) needs, and a damped one gives its width.

:func:`match_starts` turns the peaks into starts for a model's nonlinear parameters.  Peak
positions rarely fix the parameters alone: two peaks and three parameters (``k1``, ``k2``
and an effect) leave a curve of exact matches, and three peaks may be matched by several
isolated points.  So the springs are matched at each value of the remaining parameters
(a profile), every match is then refined jointly, and all are ranked by the full misfit
of the spectrum, which the residues (mode shapes) decide.
"""
from __future__ import annotations

import hashlib
import math

import numpy as np
from scipy.optimize import least_squares, minimize_scalar

from .. import composed
from ..fitting import trust_region
from ..generated import formulas
from .model import bounds, free_root_and_jacobian
from .undamped_modes import (_beta_grid, _characteristic_args_many, _resonances_of, parameter_changes,
                             resonance_sensitivity, resonances)

__all__ = ["bands", "data_peaks", "prominences", "poles", "peak_widths", "peak_match", "peak_scores", "Matches",
           "match_starts"]


def _summed(data):
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    return freq_u, np.bincount(inverse, np.abs(data.response))


def bands(freq_u) -> np.ndarray:
    """Index of the band each frequency belongs to: a new band starts after a step five
    times longer than the steps on either side (band excitation records a few narrow bands
    around the resonances; a sweep is one band).

    >>> bands(np.array([1.0, 2, 3, 4, 50, 51, 52])).tolist()
    [0, 0, 0, 0, 1, 1, 1]
    """
    step = np.diff(freq_u)
    if len(step) < 3:
        return np.zeros(len(freq_u), int)
    before = np.concatenate([[step[0]], step[:-1]])
    after = np.concatenate([step[1:], [step[-1]]])
    gap = step > 5 * np.maximum(before, after)
    return np.concatenate([[0], np.cumsum(gap)])


PROMINENCE = 20.0
"""A local maximum of the bias-summed magnitude is a resonance when it rises this many noise
levels above the higher of its two bases (noise maxima rise 2-5 noise levels)."""

RISE_RATIO = 2.0
"""... and to at least this many times that base: a broad hump (the shoulder beyond an
antiresonance, carrying noise) can rise a hundred noise levels on a quiet spectrum yet only
a quarter above its base, while resonances, even weakly coupled ones, rise three times and more."""


def _maxima(size, freq_u=None):
    """Resonances among the local maxima of ``size``: those that rise :data:`PROMINENCE` noise
    levels above their bases and to :data:`RISE_RATIO` times the higher base; with several bands
    (:func:`bands` of ``freq_u``), also each band's highest interior sample when it stands twice
    above the band's lowest (a band holding only the top of a peak has no base on either side).

    Height alone (a maximum five times above the median) is no test: a weakly coupled mode (a
    set-back tip near a node of its slope) stands only 2-3 times above the median, beside its
    antiresonance, yet rises hundreds of noise levels (missed, the spring starts matched the
    other peaks with that mode elsewhere: a false tip mass and tilt), while a noise wiggle on
    the skirt of a strong peak stands high and rises three noise levels (taken, a false peak).

    >>> f = np.linspace(0.0, 10.0, 1001)
    >>> size = 1 + 100 * np.exp(-((f - 3) / 0.05) ** 2) + 2 * np.exp(-((f - 7) / 0.05) ** 2)
    >>> f[_maxima(size)].round(2).tolist()
    [3.0, 7.0]
    """
    inner = np.arange(1, len(size) - 1)
    local = inner[(size[inner] >= size[inner - 1]) & (size[inner] > size[inner + 1])]
    # Noise of ``size`` from its second differences (their median ignores the peaks), with a
    # floor for data without noise: a thousandth of the median (why not the fits' estimate:
    # pfmdyn.fitting.noise).
    noise = max(np.median(np.abs(np.diff(size, 2))) / (0.6745 * math.sqrt(6)), 1e-3 * np.median(size))
    rise, left, right = prominences(size, local)
    which = bands(freq_u) if freq_u is not None else np.zeros(len(size), int)
    found = set(local[(rise > PROMINENCE * noise)
                      & (size[local] >= RISE_RATIO * np.maximum(size[left], size[right]))].tolist())
    if which.max() > 0:
        for b in range(which.max() + 1):
            idx = np.flatnonzero(which == b)
            top = idx[np.argmax(size[idx])]
            if idx[0] < top < idx[-1] and size[top] >= 2 * size[idx].min():
                found.add(int(top))
    return np.array(sorted(found), int)


def prominences(x, peaks):
    """How far each of ``peaks`` (indices into ``x``) rises above the higher of its two bases, and those bases:
    a base is the lowest sample between the peak and the nearest higher sample on its side (the array's end
    if none; of equal lows, the one nearest the peak).  ``scipy.signal.peak_prominences`` without a window,
    which ``tests/test_discrepancy_peaks.py`` holds it to; written here because importing ``scipy.signal``
    (and ``scipy.stats`` with it) took a third of a second of every ``discrepancy`` command.

    >>> prominences(np.array([0.0, 3.0, 1.0, 5.0, 2.0, 2.0, 4.0, 0.5]), np.array([1, 3, 6]))
    (array([2. , 4.5, 2. ]), array([0, 0, 5]), array([2, 7, 7]))
    """
    x, peaks = np.asarray(x, float), np.asarray(peaks, int)
    n = len(x)
    # the nearest sample on each side that rises above (or is not comparable: NaN)
    bound = np.where(np.isnan(x), np.inf, x).tolist()
    higher_left = _nearest_higher(bound)
    higher_right = [n - 1 - i for i in reversed(_nearest_higher(bound[::-1]))]
    rise, left, right = np.zeros(len(peaks)), np.empty(len(peaks), int), np.empty(len(peaks), int)
    for j, p in enumerate(peaks.tolist()):
        span = x[higher_left[p] + 1:p + 1]
        left[j] = p - int(np.argmin(span[::-1]))            # of equal lows, the nearest
        span = x[p:higher_right[p]]
        right[j] = p + int(np.argmin(span))
        rise[j] = x[p] - max(x[left[j]], x[right[j]])
    return rise, left, right


def _nearest_higher(values: list) -> list[int]:
    """For each value, the index of the nearest earlier one above it (-1: none), by one pass with a stack.

    >>> _nearest_higher([3.0, 1.0, 2.0, 5.0, 2.0])
    [-1, 0, 0, -1, 3]
    """
    out, stack = [], []
    for i, v in enumerate(values):
        while stack and values[stack[-1]] <= v:
            stack.pop()
        out.append(stack[-1] if stack else -1)
        stack.append(i)
    return out


def _half_power_span(size, i) -> tuple[int, int]:
    """Indices around maximum ``i`` where the summed magnitude first drops below 1/sqrt(2)."""
    level = size[i] / math.sqrt(2)
    lo, hi = i, i
    while lo > 0 and size[lo] > level and size[lo - 1] <= size[lo]:
        lo -= 1
    while hi < len(size) - 1 and size[hi] > level and size[hi + 1] <= size[hi]:
        hi += 1
    return lo, hi


def poles(data, guesses_hz, half_width: int | None = None) -> np.ndarray:
    """Complex poles ``p`` (Hz) of the response near each guess (see module).

    The window spans ``half_width`` samples each side (default: twice the half-power span,
    6 to 40 samples); ``a, b, c`` per bias come by linear least squares at each ``p``.

    >>> from types import SimpleNamespace
    >>> f = np.repeat(np.linspace(90, 110, 41), 2); v = np.tile([0.0, 1.0], 41)
    >>> y = (1 + v) / (f - (100.13 + 0.02j)) + 0.3
    >>> p = poles(SimpleNamespace(frequency_hz=f, bias_v=v, response=y), [100.0])
    >>> round(float(p[0].real), 4), round(float(abs(p[0].imag)), 4)
    (100.13, 0.02)
    """
    freq_u, size = _summed(data)
    biases, which_all = np.unique(data.bias_v, return_inverse=True)
    out = []
    for guess in np.atleast_1d(guesses_hz):
        i = int(np.clip(np.searchsorted(freq_u, guess), 1, len(freq_u) - 2))
        i = max((i - 1, i, i + 1), key=lambda j: size[j])
        if half_width is None:
            lo, hi = _half_power_span(size, i)
            half = int(np.clip(2 * max(hi - lo, 1), 6, 40))
        else:
            half = half_width
        lo, hi = max(i - half, 0), min(i + half, len(freq_u) - 1)
        sel = (data.frequency_hz >= freq_u[lo]) & (data.frequency_hz <= freq_u[hi])
        scale = (freq_u[hi] - freq_u[lo]) / 2
        x = (data.frequency_hz[sel] - freq_u[i]) / scale
        y = data.response[sel] / np.max(np.abs(data.response[sel]))
        which, rows = which_all[sel], np.arange(sel.sum())

        def design(p):
            A = np.zeros((len(x), 3 * len(biases)), complex)
            A[rows, 3 * which] = 1 / (x - p)
            A[rows, 3 * which + 1] = 1
            A[rows, 3 * which + 2] = x
            return A

        def residual(v):
            A = design(v[0] + 1j * v[1])
            coef = np.linalg.lstsq(A, y, rcond=None)[0]
            r = y - A @ coef
            return np.concatenate([r.real, r.imag])

        step = (freq_u[i + 1] - freq_u[i - 1]) / 2 / scale
        # The sign of Im p depends on the time convention of the data: try both.
        fits = [least_squares(residual, [0.0, sign * step / 2], method="lm", max_nfev=200) for sign in (1, -1)]
        best = min(fits, key=lambda r: r.cost)
        p = best.x[0] + 1j * best.x[1]
        inside = abs(p.real) < 1 and np.isfinite(p)
        out.append(freq_u[i] + scale * p if inside else complex(guess, math.nan))
    return np.array(out, complex)


def data_peaks(data) -> np.ndarray:
    """Resonance frequencies (Hz): the prominent maxima of the bias-summed |response|
    (:func:`_maxima`), each located by its complex pole (:func:`poles`).

    >>> from types import SimpleNamespace
    >>> f = np.repeat(np.linspace(1, 10, 91), 2); y = 1 / (f - 4.03) + 0j   # pole off the grid
    >>> data_peaks(SimpleNamespace(frequency_hz=f, bias_v=np.tile([0, 1], 91), response=y)).round(6).tolist()
    [4.03]
    """
    return peak_widths(data)[0]


def peak_widths(data) -> tuple[np.ndarray, np.ndarray]:
    """Peaks (as :func:`data_peaks` finds them) and their half-power widths
    (Hz), ``2 |Im p|`` of each pole; NaN where no pole was found near the peak.

    >>> from types import SimpleNamespace
    >>> f = np.linspace(50, 150, 2001); y = 1 / (100**2 - f**2 + 1j * f * 2.0)
    >>> p, w = peak_widths(SimpleNamespace(frequency_hz=f, bias_v=np.zeros_like(f), response=y))
    >>> p.round(1).tolist(), w.round(2).tolist()
    ([100.0], [2.0])
    """
    freq_u, size = _summed(data)
    found = freq_u[_maxima(size, freq_u)]
    if not len(found):
        return found, found
    p = poles(data, found)      # (Re p is a number: where no pole is found, the guess)
    return np.where(np.isfinite(p.real), p.real, found), formulas.half_power_width_from_root(np.abs(p.imag))


def peak_match(roots, peaks, band, d_roots=None, unseen: bool = False):
    """Log-frequency distance of each peak to the nearest of the resonances ``roots`` (Hz),
    then one entry for the resonances in the band that no peak explains (fixed length, for
    least squares; zero with ``unseen``: a laser spot near a mode's node hides that mode).
    With ``d_roots`` (roots x parameters) also its Jacobian, where each minimum is attained.

    >>> peak_match(np.array([100.0, 300.0]), np.array([100.0]), (50.0, 400.0)).round(3).tolist()
    [0.0, 1.099]
    """
    p = 0 if d_roots is None else d_roots.shape[1]
    if not len(roots):
        out = np.full(len(peaks) + 1, 10.0)
        return out if d_roots is None else (out, np.zeros((len(out), p)))
    inside = (roots > band[0]) & (roots < band[1]) & (not unseen)
    lp, lr = np.log(peaks), np.log(roots)
    near = np.argmin(np.abs(lr[None, :] - lp[:, None]), axis=1)          # nearest root of each peak
    there = np.abs(lr[near] - lp)
    li = lr[inside]
    partner = np.argmin(np.abs(lp[None, :] - li[:, None]), axis=1)       # nearest peak of each root
    gaps = li - lp[partner]
    back = math.sqrt(float(np.sum(gaps**2)))
    out = np.append(there, back)
    if d_roots is None:
        return out
    d_log = d_roots / roots[:, None]
    jac = np.zeros((len(out), p))
    jac[:-1] = np.sign(lr[near] - lp)[:, None] * d_log[near]
    if back > 0:
        jac[-1] = gaps @ d_log[inside] / back
    return out, jac


def peak_scores(roots, peaks, band, unseen: bool = False) -> np.ndarray:
    """``sum(peak_match(r, peaks, band, unseen=unseen) ** 2)`` for each resonance set ``r`` of ``roots``
    at once (a start grid's: one set per grid point), the same numbers.

    >>> roots = [np.array([100.0, 300.0]), np.array([]), np.array([90.0])]
    >>> peaks, band = np.array([100.0]), (50.0, 400.0)
    >>> want = [float(np.sum(peak_match(r, peaks, band) ** 2)) for r in roots]
    >>> peak_scores(roots, peaks, band).tolist() == want
    True
    """
    count = np.array([len(r) for r in roots], int)
    out = np.full(len(roots), 10.0**2 * (len(peaks) + 1))
    has = count > 0
    if not has.any():
        return out
    # the sets side by side, padded with NaN (each set's place: its row, then its order)
    R = np.full((int(has.sum()), int(count.max())), np.nan)
    filled = count[has]
    row = np.repeat(np.arange(len(filled)), filled)
    R[row, np.arange(len(row)) - np.repeat(np.cumsum(filled) - filled, filled)] = np.concatenate(
        [r for r in roots if len(r)])
    lp = np.log(peaks)
    with np.errstate(invalid="ignore"):
        lr = np.log(R)
        there = np.min(np.where(np.isnan(R)[:, None, :], np.inf, np.abs(lr[:, None, :] - lp[None, :, None])), axis=2)
        inside = (R > band[0]) & (R < band[1]) & (not unseen)
        partner = np.argmin(np.abs(lp[None, None, :] - lr[:, :, None]), axis=2)
        gaps = np.where(inside, lr - lp[partner], 0.0)
    # summed in peak_match's order (the roots inside first, one after another; NumPy's pairwise
    # sum from eight terms on), for the same bits
    gaps = np.take_along_axis(gaps, np.argsort(~inside, axis=1, kind="stable"), 1) ** 2
    total = np.zeros(len(gaps))
    for column in gaps.T:
        total = total + column
    for row in np.flatnonzero(inside.sum(1) >= 8):
        total[row] = np.sum(gaps[row, :inside[row].sum()])
    back = np.sqrt(total)
    out[has] = np.sum(np.concatenate([there, back[:, None]], axis=1) ** 2, axis=1)
    return out


COMPILED_PEAK_FITS = True
"""Whether a peak fit evaluates its steps compiled (:mod:`pfmdyn.discrepancy.peak_kernel`, with
:data:`pfmdyn.composed.KERNELS`); NumPy's path is the reference, equal but for the last bits of the
tip's jump and of a few sums (the reports within 1e-6: ``benchmarks/discrepancy_speed.py``)."""


def _peak_fit(model, start, moving, peaks, band, lower, upper, max_nfev, unseen=False):
    """Least-squares match of the model's resonances to the peaks from ``start``, moving the
    parameters where ``moving`` is True; the Jacobian comes from the resonances'
    sensitivities (no root search per parameter).  Returns (parameters, sum of squares)."""
    last = {}

    def full(v):
        x = start.copy()
        x[moving] = v
        return x

    if COMPILED_PEAK_FITS and composed.KERNELS:
        match = _compiled_match(model, moving, peaks, band, band[1] * 1.3, unseen)

        def evaluated(v):
            key = tuple(v)
            if key not in last:
                last.clear()
                last[key] = match(full(v))
            return last[key]

        res = trust_region.least_squares(lambda v: evaluated(v)[0], lambda v: evaluated(v)[1], start[moving],
                                         (lower[moving], upper[moving]), max_nfev)
        return full(res.x), 2 * res.cost

    def roots_at(v):
        key = tuple(v)
        if key not in last:
            last.clear()
            last[key] = resonances(model, full(v), True, band[1] * 1.3, refine_roots=True)
        return last[key]

    def jac(v):
        roots = roots_at(v)
        d_roots = (resonance_sensitivity(model, full(v), True, roots) if len(roots)
                   else np.zeros((0, len(start))))
        return peak_match(roots, peaks, band, d_roots[:, moving], unseen)[1]

    res = least_squares(lambda v: peak_match(roots_at(v), peaks, band, unseen=unseen), start[moving], jac=jac,
                        bounds=(lower[moving], upper[moving]), max_nfev=max_nfev)
    return full(res.x), 2 * res.cost


def _compiled_match(model, moving, peaks, band, f_max, unseen):
    """:func:`peak_match` of the model's contact resonances below ``f_max`` and its Jacobian w.r.t. the
    parameters where ``moving``, as a function of the parameters: one compiled call
    (:func:`pfmdyn.discrepancy.peak_kernel.match_and_jacobian`), the free root once per lever and tip
    (:func:`pfmdyn.discrepancy.model.free_root_and_jacobian`, which keeps them: an analysis's hundred
    peak fits ask a few tips again and again), the grid in ``beta`` once per fit and tip, the characteristic's parameters
    differentiated by the moving parameters alone (one that moves none of them there adds zeros to the
    sensitivities).

    >>> from types import SimpleNamespace
    >>> from .model import Model
    >>> model = Model(SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4))
    >>> x, peaks, band = np.array([2.0, 2.0]), np.array([1.1e4, 6e4]), (5e3, 7e4)
    >>> out, jac = _compiled_match(model, np.array([True, False]), peaks, band, 9.1e4, False)(x)
    >>> roots = resonances(model, x, True, 9.1e4)
    >>> want = peak_match(roots, peaks, band, resonance_sensitivity(model, x, True, roots)[:, :1])
    >>> bool(np.allclose(out, want[0], rtol=1e-12, atol=0) and np.allclose(jac, want[1], rtol=1e-12, atol=0))
    True
    """
    from .peak_kernel import match_and_jacobian

    m, tips = model.meta, {}
    peaks, band = np.array(peaks, float), np.array(band, float)
    # the partials by complex steps where the tip may leave the end (resonance_sensitivity's gamma moves)
    setback = any(p.name == "gamma" for p in model.parameters)

    def match(x):
        c = model.coords(x)
        tip = (c["mu"], c["gamma"])
        if tip not in tips:
            b1, d_b1_dp = free_root_and_jacobian(m.spring_constant, m.tip_height, m.length, *tip)
            tips[tip] = b1, d_b1_dp, _beta_grid(m.free_resonance, b1, f_max)
        b1, d_b1_dp, grid = tips[tip]
        lever, moved, per_unit, d_b1 = parameter_changes(model, x, True, d_b1_dp, moving)
        out, jac = np.empty(len(peaks) + 1), np.empty((len(peaks) + 1, len(d_b1)))
        match_and_jacobian(grid, lever[None, :], b1, d_b1, float(m.free_resonance), moved,
                           np.ascontiguousarray(per_unit), lever[7] == 1.0 and not setback, peaks, band, unseen,
                           out, jac)
        return out, jac

    return match


class _RootSets(list):
    """Resonance sets (arrays), pickled as one array and their lengths: hundreds of small arrays pickle
    slowly, and a start grid's sets go to worker processes (:meth:`Matches.caches`).

    >>> import pickle
    >>> sets = pickle.loads(pickle.dumps(_RootSets([np.array([1.0, 2.0]), np.empty(0), np.array([3.0])])))
    >>> type(sets).__name__, [r.tolist() for r in sets]
    ('_RootSets', [[1.0, 2.0], [], [3.0]])
    """

    def __reduce__(self):
        lengths = [len(r) for r in self]
        return _unpacked_roots, (np.concatenate(self) if self else np.empty(0), lengths)


def _unpacked_roots(values: np.ndarray, lengths: list[int]) -> _RootSets:
    return _RootSets(np.split(values, np.cumsum(lengths)[:-1]) if lengths else [])


class Matches:
    """What :func:`match_starts` found, kept for one analysis: a start grid's undamped resonances, and
    the springs matched to the peaks from a grid point, by what decides them (the characteristic's
    arguments; the springs, the tilt and the tip's mass and position).  A spectrum's steps try the
    same effects from the same grids and seeds in models that differ in damping, background and
    spot, which move no undamped resonance: the same numbers, found once (a third of an analysis).

    >>> from types import SimpleNamespace
    >>> from .model import Model
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> plain, damped = Model(meta), Model(meta, ("damping_internal",))
    >>> matches = Matches()
    >>> a = matches.roots(plain, [[2.0, 2.0]], 7e4)
    >>> a is matches.roots(damped, [[2.0, 2.0, 0.01]], 7e4), a is matches.roots(plain, [[2.1, 2.0]], 7e4)
    (True, False)
    """

    def __init__(self):
        self._roots, self._springs = {}, {}

    def caches(self) -> tuple[dict, dict]:
        """The two tables (they only grow): a worker's additions are kept by the process that forked it."""
        return self._roots, self._springs

    def roots(self, model, grid, f_max: float) -> list[np.ndarray]:
        """:func:`pfmdyn.discrepancy.undamped_modes.resonances_many` of the grid's rows (contact modes)."""
        levers = _characteristic_args_many(model, np.asarray(grid, float), True)
        # a digest of the grid's arguments (kilobytes each), not the arguments: the table goes to worker processes
        key = (hashlib.blake2b(levers.tobytes(), digest_size=20).digest(), levers.shape, f_max)
        if key not in self._roots:
            self._roots[key] = _RootSets(_resonances_of(model.meta, levers, f_max))
        return self._roots[key]

    def peak_fit(self, model, start, moving, peaks, band, lower, upper, max_nfev, unseen=False):
        """:func:`_peak_fit`; a match of the springs alone once per what decides it."""
        n = len(model.springs)
        if not (moving[:n].all() and not moving[n:].any()):
            return _peak_fit(model, start, moving, peaks, band, lower, upper, max_nfev, unseen)
        c = model.coords(start)
        key = (tuple(p.name for p in model.springs), start[:n].tobytes(), lower[:n].tobytes(), upper[:n].tobytes(),
               c["alpha"], c["mu"], c["gamma"], np.asarray(peaks).tobytes(), tuple(band), max_nfev, unseen)
        if key not in self._springs:
            x, ss = _peak_fit(model, start, moving, peaks, band, lower, upper, max_nfev, unseen)
            self._springs[key] = (x[:n].copy(), ss)
        springs, ss = self._springs[key]
        x = start.copy()
        x[:n] = springs
        return x, ss


def match_starts(model, extra, peaks, band, spring_grids, cost, count: int = 2,
                 per_value: int = 3, joint: int = 6, sharp: bool = False, unseen: bool = False,
                 matches: Matches | None = None) -> list[np.ndarray]:
    """Starts whose resonances match ``peaks``, best first by ``cost`` (the full misfit).

    ``extra``: values of the parameters after the springs (one vector per profile point).
    At each, the spring grid is ranked by :func:`peak_match` and its best ``per_value``
    distinct ``k1`` rows are matched by least squares over the springs alone; the best
    ``joint`` of all those are refined over every parameter; the ``count`` best by ``cost``
    are returned; with ``sharp`` (peaks narrower than half a frequency step: an undamped
    spectrum) each is first moved along its curve of matches to the least misfit.  With
    ``unseen`` a resonance may lie where no peak is (:func:`peak_match`).  ``matches``: what earlier
    calls of the analysis found (:class:`Matches`).
    """
    if not len(peaks):
        return []
    matches = matches or Matches()
    lower, upper = bounds(model)
    n_springs = 1 if model.vertical_only else 2
    k1_grid, k2_grid = spring_grids
    springs = (np.asarray(k1_grid, float)[:, None] if n_springs == 1 else
               np.stack(np.meshgrid(k1_grid, k2_grid, indexing="ij"), -1).reshape(-1, 2))
    # the k1 rounded as ranking tells rows apart (a grid point's k1 is one of the grid's values)
    k1_key = np.array([round(float(a), 6) for a in np.clip(springs[:, 0], lower[0], upper[0])])

    springs_only = np.arange(len(lower)) < n_springs
    matched = []
    for e in extra:
        others = np.broadcast_to(np.asarray(e, float), (len(springs), len(e)))
        grid = np.clip(np.concatenate([springs, others], axis=1), lower, upper)
        roots = matches.roots(model, grid, band[1] * 1.3)
        score = peak_scores(roots, peaks, band, unseen)
        # the best row of each distinct k1, in the order of their scores
        order = np.argsort(score)
        _, first = np.unique(k1_key[order], return_index=True)
        for i in order[np.sort(first)][:per_value]:
            x, ss = matches.peak_fit(model, grid[i], springs_only, peaks, band, lower, upper, 15, unseen)
            matched.append((ss, x))
    # Matches within 0.1 % of every peak tie on the peaks: the misfit ranks them.
    exact = sorted((x for r, x in matched if r < 1e-6), key=cost)
    rest = [x for _, x in sorted((t for t in matched if t[0] >= 1e-6), key=lambda t: t[0])]
    starts = []
    every = np.ones(len(lower), bool)
    for x in (exact + rest)[:joint]:
        if len(x) > n_springs:
            x = _peak_fit(model, x, every, peaks, band, lower, upper, 20, unseen)[0]
        if not any(np.allclose(x, s, atol=1e-3) for s in starts):
            starts.append(x)
    best = sorted(starts, key=cost)[:count]
    if sharp and len(lower) > n_springs:
        best = sorted((_along_matches(model, x, peaks, band, cost, n_springs, lower, upper, matches) for x in best),
                      key=cost)
    return best


def _along_matches(model, x, peaks, band, cost, n_springs, lower, upper, matches) -> np.ndarray:
    """Minimise ``cost`` over the last parameter with the springs re-matched to the peaks at
    every value: along the curve of matches the misfit is smooth, while across it (a peak
    moved by a fraction of its width) an undamped spectrum's misfit is a needle.
    """
    j = len(x) - 1
    seen = {float(x[j]): x[:n_springs]}       # springs matched so far, by parameter value

    def matched(v):
        y = x.copy()
        y[j] = v
        y[:n_springs] = seen[min(seen, key=lambda u: abs(u - v))]
        y = matches.peak_fit(model, y, np.arange(len(y)) < n_springs, peaks, band, lower, upper, 20)[0]
        seen[float(v)] = y[:n_springs]
        return y

    def along(v):
        return cost(matched(v))

    # A scan outward from the start (each match continues from its neighbour), then Brent
    # between the best point's neighbours.
    reach = 0.3 * (upper[j] - lower[j])
    grid = np.linspace(max(lower[j], x[j] - reach), min(upper[j], x[j] + reach), 17)
    order = sorted(range(len(grid)), key=lambda i: abs(grid[i] - x[j]))
    values = {i: along(grid[i]) for i in order}
    i = min(values, key=values.get)
    span = (grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)])
    res = minimize_scalar(along, bounds=span, method="bounded", options={"xatol": 1e-5 * (upper[j] - lower[j])})
    y = min((matched(res.x), matched(grid[i])), key=cost)
    return y if cost(y) < cost(x) else x
