"""``pfmdyn discrepancy`` on a spectrum: where the paper's model and a measurement disagree, and why.

The loop is :func:`pfmdyn.discrepancy.select.run` (shared with resonance tables); this
module supplies the spectrum's :class:`SpectrumProblem`: the baseline fit, the candidate
effects and their fits, and where the residual concentrates.

The misfit ``gap`` is the noise-normalised RMS residual ``sqrt(mean |r|**2) / sigma``, with
``sigma`` (the RMS of the complex noise) estimated from the data alone
(:func:`pfmdyn.fitting.noise.noise_sigma`, shared with ``pfmdyn map``).  A model that explains
the data reaches ``gap ~ 1``.

Damping is one effect with three mechanisms (:mod:`pfmdyn.derivations.damping`); what
tells them apart is how the half-power width of the peaks scales with their frequency
(constant in Hz: viscous; proportional to ``f``: internal; growing with ``f`` and with the
contact stiffness: contact).  :func:`peaks.peak_widths` measures the widths (complex poles),
which seed the fits and are reported; the mechanism named is the one whose fit is best (BIC).
"""
from __future__ import annotations

import dataclasses
import math
from itertools import islice

import numpy as np

from ..fitting.noise import misfit_band, noise_sigma
from ..fitting.projection import bias_nodes, project
from ..fitting.workers import Forked, cores
from ..io.tables import SpectrumData
from . import select
from .effects import DAMPING, EFFECTS, spring_grid
from .model import FitResult, Model, bounds, fit, solve
from .peaks import Matches, match_starts, peak_widths
from .report import DiscrepancyReport, report, summary  # noqa: F401  (summary: public here too)

__all__ = ["noise_sigma", "signature", "peak_widths", "SpectrumProblem", "analyse", "summary", "thin", "MAX_ROWS"]



def signature(data: SpectrumData, result: FitResult, sigma: float) -> dict:
    """Where the residual concentrates: band, share near resonances, and its shape.

    Resonances are the peaks of the fitted |response| summed over biases; the shape is
    ``peak width`` when the residual is even about the nearest resonance, ``peak shift``
    when odd, ``smooth trend`` when most residual lies away from every resonance.
    """
    freq_u, inverse = np.unique(data.frequency_hz, return_inverse=True)
    energy = np.bincount(inverse, np.abs(result.residual) ** 2) / sigma**2
    size = np.bincount(inverse, np.abs(result.prediction))
    peaks = [i for i in range(1, len(size) - 1) if size[i] >= size[i - 1] and size[i] >= size[i + 1]
             and size[i] > 3 * np.median(size)]
    band = misfit_band(freq_u, energy)
    near = np.zeros(len(freq_u), bool)
    for p in peaks:
        near |= np.abs(freq_u - freq_u[p]) < 0.05 * freq_u[p]
    share = float(energy[near].sum() / energy.sum()) if peaks else 0.0
    shape = "smooth trend"
    if share > 0.5:
        p = max(peaks, key=lambda i: energy[near & (np.abs(freq_u - freq_u[i]) < 0.05 * freq_u[i])].sum())
        win = np.abs(freq_u - freq_u[p]) < 0.05 * freq_u[p]
        offset = freq_u[win] - freq_u[p]
        w = energy[win]
        odd = abs(np.sum(w * np.sign(offset))) / w.sum()
        shape = "peak shift" if odd > 0.3 else "peak width"
    return {"band_hz": band, "resonances_hz": [float(freq_u[p]) for p in peaks],
            "share_near_resonances": share, "signature": shape}


MAX_ROWS = 12000
"""Rows ``pfmdyn discrepancy`` analyses at most (1000 frequencies x 12 biases): the fits' cost
grows with the rows, and a longer spectrum (e.g. 20 000 frequencies x 9 biases: 107 s,
stopped by the time budget with an effect missed) is analysed at every k-th frequency
(:func:`thin`)."""


def thin(data: SpectrumData, max_rows: int | None = None) -> tuple[SpectrumData, int]:
    """Every k-th frequency (all its biases) with the smallest k that leaves at most
    ``max_rows`` rows (default :data:`MAX_ROWS`); returns the data and k.

    >>> from pfmdyn.io.tables import Metadata
    >>> m = Metadata(spring_constant=2.4, length=2.2e-4, width=3e-5, tip_height=1e-5, free_resonance=6e4)
    >>> f = np.repeat(np.arange(1.0, 11.0), 2); v = np.tile([0.0, 1.0], 10)
    >>> small, k = thin(SpectrumData(m, f, v, f + 0j), max_rows=8)
    >>> k, small.frequency_hz.tolist()
    (3, [1.0, 1.0, 4.0, 4.0, 7.0, 7.0, 10.0, 10.0])
    """
    stride = math.ceil(len(data.frequency_hz) / (max_rows or MAX_ROWS))
    if stride <= 1:
        return data, 1
    _, index = np.unique(data.frequency_hz, return_inverse=True)
    keep = index % stride == 0
    return dataclasses.replace(data, frequency_hz=data.frequency_hz[keep], bias_v=data.bias_v[keep],
                               response=data.response[keep]), stride


SPOT_COARSE = (0.95, 0.85, 0.75, 0.6)
"""Spot positions at which :meth:`SpectrumProblem.spot_trial` ranks its starts."""

PEAK_WIDTHS = 3.0
BACKGROUND_AWAY = 0.5
"""A background is named only when at least this share of the misfit it removes lies more than
:data:`PEAK_WIDTHS` half-power widths from every resonance (:meth:`SpectrumProblem.not_a_background`)."""

TRIAL_NFEV = 30
"""Evaluations per start of a candidate's fit: enough to rank candidates; the one added is
then converged (:meth:`SpectrumProblem.polish`)."""


class SpectrumProblem:
    """What :func:`pfmdyn.discrepancy.select.run` needs for a spectrum (see there)."""

    alone = ("spot_position",)
    """Effects named only on their own merit, never as half of a pair: the spot reweights the
    modes, as a damping law outside the library does (air damping, width ~ sqrt f), and paired
    with a set-back it absorbed such a misfit (band-limited air damping then also took a tilt
    and a tip mass, five effects where one was hidden)."""

    def __init__(self, data: SpectrumData, vertical_only: bool = False, workers: int = 1):
        self.data, self.vertical_only = data, vertical_only
        self._sent = None       # the caches' sizes when the workers were last sent what they lack
        self._took = {}         # (method, names among its arguments) -> the seconds such a call last took
        self.sigma = noise_sigma(data.frequency_hz, data.bias_v, data.response)
        if not (math.isfinite(self.sigma) and self.sigma > 0):
            # Noise-free data: a floor far below the signal keeps the gap finite.
            self.sigma = 1e-12 * float(np.max(np.abs(data.response))) or 1e-300
        self.widths = peak_widths(data)
        self.peaks = self.widths[0]         # data_peaks(data): the same poles, found once
        # Peaks narrower than half a frequency step: a misfit landscape of needles (undamped).
        step = float(np.median(np.diff(np.unique(data.frequency_hz))))
        self.sharp = bool(np.any(self.widths[1] < 0.5 * step))
        # Library order breaks ties between candidates the data do not tell apart.
        self.library = (["lateral_stiffness"] if vertical_only else []) + [
            "damping", "tip_mass", "tilt", "tip_setback", "background", "spot_position"]
        # forked at the baseline's fits (they see its caches); no more than a step's candidates can use, not
        # every core of a large machine
        self.pool = Forked(min(workers, len(self.library)), self, _take, _before_fork)
        m = data.metadata
        self.band = (float(data.frequency_hz.min()), float(data.frequency_hz.max()))
        self.k1_grid, self.k2_grid = spring_grid(m, 23, 9)
        self.matches = Matches()
        self._nodes = bias_nodes(data.frequency_hz, data.bias_v, data.response)   # the rows the costs fold
        self._costs = {}      # (model, parameters) -> misfit: start grids and rankings ask again

    def each(self, method: str | None, calls) -> list:
        """``method`` of this problem on each of ``calls`` (argument tuples; with ``method`` None, pairs of a
        method and its arguments), in order, in the worker
        processes of :attr:`pool` (:class:`~pfmdyn.fitting.workers.Forked`, ``workers`` of them): independent
        fits, each computing what it would here.  The start grids' misfits and the peak matches found are
        shared: a call returns what it added to the caches, kept here, and each worker takes what was added
        here since the last calls, once (a worker would otherwise find again what another one found).  The calls
        the last step found dearest go first (those not timed yet before them, in order): one long trial sent
        last kept the other worker waiting, up to 0.6 s."""
        caches = self._caches()
        sizes = [len(cache) for cache in caches]
        news = [list(islice(cache.items(), n, None)) for cache, n in zip(caches, self._sent or sizes)]
        self._sent = sizes
        pairs = [(method, args) for args in calls] if method else list(calls)
        kinds = [(name, *(a for a in args if isinstance(a, str))) for name, args in pairs]
        found = self.pool.map(_caching, [(name, *args) for name, args in pairs], shared=news,
                              costs=[self._took.get(kind, math.inf) for kind in kinds])
        self._took.update(zip(kinds, self.pool.took))
        for _, added in found:
            for cache, items in zip(caches, added):
                cache.update(items)
        return [out for out, _ in found]

    @property
    def worker_seconds(self) -> float:
        """CPU seconds the worker processes spent on this problem's calls."""
        return self.pool.seconds

    def _caches(self) -> tuple[dict, ...]:
        return (self._costs, *self.matches.caches())

    # -- starts --------------------------------------------------------------------------
    def resonance_starts(self, model: Model, extra: list[np.ndarray], count: int = 2) -> list[np.ndarray]:
        """Starts whose resonances match the data's peaks (:func:`peaks.match_starts`)."""
        # Damped peaks leave a smooth misfit: one match per profile value is enough there.
        return match_starts(model, extra, self.peaks, self.band, (self.k1_grid, self.k2_grid),
                            lambda x: self.cost(model, x), count, per_value=3 if self.sharp else 1,
                            joint=6 if self.sharp else 4, sharp=self.sharp, matches=self.matches)

    def spot_trial(self, current: FitResult, count: int = 3) -> FitResult:
        """Best fit of the current model plus the laser spot (``spot_position``).

        The spot moves no resonance but reweights the modes, so what was fitted without it
        may have bent to mimic it: the springs (and missed a peak the spot weakened), the
        damping values and even the mechanism.  Starts: the nested one (spot at the free
        end), and the ``count`` best sets of springs among the current ones and those matched
        to the peaks 3x above the median (not 5x; also leaving modes where no peak is: the
        spot can hide a mode), each with the current damping or the value the peak widths
        give, in the current mechanism or (one mechanism) each other one, ranked by the
        misfit at the spot positions :data:`SPOT_COARSE`, then with the spot seed of least
        misfit.
        """
        effects, meta, vertical = current.model.effects, current.model.meta, current.model.vertical_only
        spot = EFFECTS["spot_position"]
        models = [current.model.with_effect("spot_position")]
        present = [c for c in effects if c.startswith("damping_")]
        if len(present) == 1:
            models += [Model(meta, tuple(c if e == present[0] else e for e in effects) + ("spot_position",), vertical)
                       for c in DAMPING.values() if c != present[0]]
        springs = 1 if vertical else 2
        values = dict(zip((p.name for p in current.model.parameters), current.internal))
        widths = {EFFECTS[DAMPING[m]].parameters[0].name: v for m, v in self.damping_seeds().items()}
        # Undamped resonances: the springs matched once serve every damping variant.
        others = np.append(current.internal[springs:], spot.null)
        matched = {tuple(np.round(x[:springs], 3)): x[:springs] for unseen in (False, True) for x in match_starts(
            models[0], [others], self.widths[0], self.band, (self.k1_grid, self.k2_grid),
            lambda x: self.cost(models[0], x), 3, per_value=4 if unseen else (3 if self.sharp else 1), joint=6,
            sharp=self.sharp, unseen=unseen, matches=self.matches)}
        # The best model and damping per set of springs, at a few spot positions (so that the
        # current springs do not crowd out the re-matched ones), then its best spot seed.
        coarse = {}
        for model in models:
            rest = model.parameters[springs:-1]
            variants = {tuple(np.array([source.get(p.name, backup.get(p.name)) for p in rest]))
                        for source, backup in ((values, widths), (widths, values))}
            for k in [current.internal[:springs]] + list(matched.values()):
                for o in variants:
                    base = np.concatenate([k, o])
                    misfit = min(self.cost(model, np.append(base, v)) for v in SPOT_COARSE)
                    key = tuple(np.round(k, 3))
                    if key not in coarse or misfit < coarse[key][0]:
                        coarse[key] = (misfit, model, base)
        best = []
        for _, model, base in sorted(coarse.values(), key=lambda t: t[0])[:count]:
            rows = [np.append(base, v) for v in spot.seeds]
            best += [(model, rows[i]) for i in _lowest_valleys([self.cost(model, x) for x in rows], 2)]
        fits = [fit(models[0], self.data, [np.append(current.internal, spot.null)], self.sigma, max_nfev=TRIAL_NFEV)]
        fits += [fit(model, self.data, [x], self.sigma, max_nfev=TRIAL_NFEV) for model, x in best]
        return min(fits, key=lambda f: f.bic)

    def damping_seeds(self) -> dict[str, float]:
        """Start values of each damping mechanism's parameter from the measured peak widths."""
        m = self.data.metadata
        peaks, widths = self.widths
        ok = np.isfinite(widths) & (widths > 0)
        if not ok.any():
            return {"internal": 0.01, "viscous": 0.02, "fluid": 0.02, "contact": 0.01}
        q = peaks[ok] / widths[ok]
        r = peaks[ok] / m.free_resonance
        return {"internal": float(np.clip(np.median(1 / q), 1e-4, 0.4)),
                "viscous": float(np.clip(np.median(widths[ok]) / m.free_resonance, 1e-4, 0.9)),
                "fluid": float(np.clip(np.median(widths[ok] / np.sqrt(r)) / m.free_resonance, 1e-4, 0.9)),
                "contact": float(np.clip(np.median(1 / (q * r)), 1e-4, 4.0))}

    # -- the problem interface -----------------------------------------------------------
    def baseline(self) -> FitResult:
        """Global start for the springs, then a local fit.

        Undamped resonances make the misfit landscape in (k1, k2) needle-sharp, so starts
        come from matching the model's resonances to the peaks of the data, and from a
        damped fit (1/Q = 0.05, continuation).
        """
        model = Model(self.data.metadata, (), self.vertical_only)
        smooth, rows = _damped_grid(self.data.metadata, self.vertical_only)
        # the starts matched to the peaks and the damped grid's misfits, side by side in the workers
        starts, costs = self.each(None, [("resonance_starts", (model, [np.array([])], 3)), ("costs", (smooth, rows))])
        quick = sorted((c, i) for i, c in enumerate(costs))
        damped = fit(smooth, self.data, [rows[i] for _, i in quick[:2]], self.sigma, max_nfev=40,
                     solve_each=self._solve_each)
        starts.append(damped.internal[:-1])
        return fit(model, self.data, starts, self.sigma, max_nfev=80, solve_each=self._solve_each)

    def solve(self, model: Model, start: np.ndarray, max_nfev: int):
        """One start's solution of a fit of ``model`` (:func:`pfmdyn.discrepancy.model.solve`)."""
        return solve(model, self.data, start, self.sigma, max_nfev)

    def _solve_each(self, model: Model, starts, max_nfev: int) -> list:
        return self.each("solve", [(model, start, max_nfev) for start in starts])

    def cost(self, model, internal) -> float:
        """RSS/sigma**2 at fixed nonlinear parameters (for start grids); on the rows folded per frequency
        (:func:`pfmdyn.fitting.projection.bias_nodes`), plus the misfit they do not carry."""
        internal = np.asarray(internal)
        key = (model, internal.dtype.str, internal.tobytes())
        if key not in self._costs:
            n = self._nodes
            A = model.design(n.frequency_hz, n.inverse, n.bias_v, internal) * n.weight[:, None]
            pred = project(A[None], n.response[None, :, None]).prediction[0, :, 0]
            r = np.abs(n.response - pred) ** 2
            rss = np.sum(r[np.isfinite(r)]) + n.constant
            self._costs[key] = float(rss / self.sigma**2) if np.isfinite(r).any() else math.inf
        return self._costs[key]

    def costs(self, model, rows) -> list[float]:
        """:meth:`cost` of each of ``rows``."""
        return [self.cost(model, x) for x in rows]

    def candidates(self, current: FitResult) -> list[str]:
        """Effects not yet in the model (damping while a mechanism is left; the laser spot
        with two peaks or more: it sets the relative heights of the modes, and the scale of
        a lone peak is a linear coefficient's)."""
        present = current.model.effects
        out = []
        for name in self.library:
            if name == "damping":
                if len(current.model.damping_mechanisms) < 2 and any(c not in present for c in DAMPING.values()):
                    out.append(name)
            elif name == "spot_position" and len(self.widths[0]) < 2:
                continue
            elif name not in present:
                out.append(name)
        return out

    def trial(self, current: FitResult, name: str) -> FitResult:
        """Best fit of the current model plus ``name`` (for damping: best mechanism by BIC)."""
        if name == "damping":
            # Each mechanism from the current springs; the best one also from springs
            # re-matched to the peaks (the undamped fit may sit in another basin).
            seeds = self.damping_seeds()
            fits = {mech: self._fit_with(current, DAMPING[mech], [seeds[mech]])
                    for mech in DAMPING if DAMPING[mech] not in current.model.effects}
            best = min(fits, key=lambda m: fits[m].bic)
            rematched = self._fit_with(current, DAMPING[best], [seeds[best]], rematch=True)
            return min([rematched] + list(fits.values()), key=lambda f: f.bic)
        if name == "spot_position":
            return self.spot_trial(current)
        trial = self._fit_with(current, name, None)
        if name == "background":
            why = self.not_a_background(current, trial)
            if why:
                trial.extra["refused"] = why
        return trial

    def not_a_background(self, current: FitResult, trial: FitResult) -> str | None:
        """Why ``trial`` (``current`` plus the background) does not lower the misfit as a
        background does, or None.

        The background must change the fitted response by more than the noise (RMS): a cross-talk
        below the noise at every point, named because it lowers a gap already near the noise by
        a few per cent (air damping: 1.22 -> 1.10 with a background at 0.4 % of the median
        response), is the smooth remainder of another misfit as much as a background.  And a
        cross-talk background is smooth in frequency and small beside a resonance, so most of
        the misfit it removes lies away from the peaks (more than :data:`PEAK_WIDTHS` half-power
        widths from each).  When most lies within them, the two columns only reshape the peaks:
        a damping law or a per-sweep gain outside the library (air damping, width ~ sqrt f; a
        gain drifting between bias sweeps) leaves a misfit there that a background absorbs in
        part.  Band-limited data (bands of a few widths around each resonance) cannot tell a
        background from that at all.
        """
        change = (float(np.sqrt(np.mean(np.abs(trial.prediction - current.prediction) ** 2)))
                  if trial.prediction is not None and current.prediction is not None else math.inf)
        if change < self.sigma:
            return (f"it changes the fitted response by {change / self.sigma:.2g} x the noise (RMS): a cross-talk "
                    "below the noise at every point cannot be told from the smooth remainder of another misfit "
                    "(a damping law outside the library)")
        peaks, widths = self.widths
        near = np.zeros(len(self.data.frequency_hz), bool)
        for p, w in zip(peaks, widths):
            if np.isfinite(w):
                near |= np.abs(self.data.frequency_hz - p) < PEAK_WIDTHS * w
        removed = np.abs(current.residual) ** 2 - np.abs(trial.residual) ** 2
        total = float(removed.sum())
        away = min(max(float(removed[~near].sum()), 0.0) / total, 1.0) if total > 0 else 1.0
        if away >= BACKGROUND_AWAY:
            return None
        return (f"only {away:.0%} of the misfit it removes lies more than {PEAK_WIDTHS:g} half-power widths "
                "from the resonances: it reshapes the peaks, which a smooth cross-talk does not (a damping "
                "law or gain outside the library)")

    def _fit_with(self, current: FitResult, component: str, seeds, rematch: bool = False) -> FitResult:
        model = current.model.with_effect(component)
        effect = EFFECTS[component]
        if component == "lateral_stiffness":
            # Parameters: k1, k2, then the current effects'; k2 at its lower bound is the
            # current model (the nested start: never worse).
            extra = [np.insert(current.internal[1:], 0, v) for v in self.k2_grid]
            nested = np.insert(current.internal, 1, bounds(model)[0][1])
            starts = [nested] + self.resonance_starts(model, extra, count=3)
            return fit(model, self.data, starts, self.sigma, max_nfev=TRIAL_NFEV)
        # The nested start (effect switched off) guarantees the fit is never worse.
        starts = [np.append(current.internal, effect.null)] if effect.parameters else [current.internal]
        if effect.moves_resonances:
            springs = 1 if model.vertical_only else 2
            others = [current.internal[springs:]]
            # Damping fitted while this effect was missing may sit anywhere (even on a
            # bound): also start from the peak widths' values.
            seed = {EFFECTS[DAMPING[m]].parameters[0].name: v for m, v in self.damping_seeds().items()}
            reseeded = np.array([seed.get(p.name, v)
                                 for p, v in zip(current.model.parameters[springs:], others[0])])
            if not np.allclose(reseeded, others[0]):
                others.append(reseeded)
            extra = [np.concatenate([o, [v]]) for o in others for v in effect.seeds]
            starts += self.resonance_starts(model, extra, count=2)
        elif seeds:
            starts = [np.append(current.internal, v) for v in seeds]
            if rematch:
                springs = 1 if model.vertical_only else 2
                # No peak in the data to match: the nested starts remain.
                starts = self.resonance_starts(
                    model, [np.append(current.internal[springs:], seeds[0])], count=1) or starts
        return fit(model, self.data, starts, self.sigma, max_nfev=TRIAL_NFEV)

    def without(self, current: FitResult, component: str) -> FitResult:
        """Refit with one component removed, from the current values of the others."""
        keep = [i for i, p in enumerate(current.model.parameters)
                if p not in EFFECTS[component].parameters or p.name in ("k1", "k2")]
        if component == "lateral_stiffness":
            keep = [i for i, p in enumerate(current.model.parameters) if p.name != "k2"]
        effects = list(current.model.effects)
        effects.remove(component)
        return self.refit(Model(current.model.meta, tuple(effects), current.model.vertical_only), [current.internal[keep]])

    def alternatives(self, current: FitResult) -> list[FitResult]:
        """The final model with its damping mechanism(s) replaced by each single other one."""
        refits = self._moved_alternatives(current) if current.gap > select.NEAR_NOISE else []
        present = [c for c in current.model.effects if c.startswith("damping_")]
        others = [c for c in current.model.effects if c not in present]
        keep = [i for i, p in enumerate(current.model.parameters)
                if not any(p in EFFECTS[c].parameters for c in present)]
        seeds = self.damping_seeds()
        for mech, component in DAMPING.items():
            if not present or present == [component]:
                continue
            model = Model(current.model.meta, tuple(others) + (component,), current.model.vertical_only)
            refits.append((model, [np.append(current.internal[keep], seeds[mech])]))
        return self.each("refit", refits)

    def _moved_alternatives(self, current: FitResult) -> list[tuple[Model, list[np.ndarray]]]:
        """When the gap stays far above the noise: each effect that moves resonances swapped
        for another one (a set-back and a tip mass shift the same two peaks alike, and the
        greedy path may have taken the wrong one), from peak-matched starts (model and starts)."""
        moving = ("tip_mass", "tip_setback", "tilt")
        out = []
        for old in [e for e in current.model.effects if e in moving]:
            for new in [e for e in moving if e not in current.model.effects]:
                effects = tuple(new if e == old else e for e in current.model.effects)
                model = Model(current.model.meta, effects, current.model.vertical_only)
                springs = 1 if model.vertical_only else 2
                values = dict(zip([p.name for p in current.model.parameters], current.internal))
                extra = []
                for seed in EFFECTS[new].seeds:
                    row = [seed if p in EFFECTS[new].parameters else values[p.name]
                           for p in model.parameters[springs:]]
                    extra.append(np.array(row, float))
                starts = self.resonance_starts(model, extra, count=2)
                if starts:
                    out.append((model, starts))
        return out

    def refit(self, model: Model, starts: list[np.ndarray]) -> FitResult:
        """``model``'s fit from ``starts`` with a refit's budget (100 evaluations): the backward pass's."""
        return fit(model, self.data, starts, self.sigma, max_nfev=100)

    def polish(self, trial: FitResult) -> FitResult:
        """Converge an accepted trial fully (trials stop early: they only rank candidates)."""
        return fit(trial.model, self.data, [trial.internal], self.sigma, max_nfev=200)

    def locate(self, current: FitResult) -> dict:
        """Where the residual concentrates, and the measured peak widths."""
        where = signature(self.data, current, self.sigma)
        peaks, widths = self.widths
        ok = np.isfinite(widths) & (widths > 0)
        where["peak_widths_hz"] = {f"{p:.6g}": float(w) for p, w in zip(peaks[ok], widths[ok])}
        if ok.sum() >= 2:
            # Width ~ f**s: s ~ 0 for viscous damping, ~ 1 for internal friction.
            where["width_exponent"] = float(np.polyfit(np.log(peaks[ok]), np.log(widths[ok]), 1)[0])
        return where


def analyse(data: SpectrumData, vertical_only: bool = False, progress: bool = False,
            time_budget_s: float | None = None, workers: int | None = None) -> DiscrepancyReport:
    """Run the discrepancy loop on a spectrum; return its report (:class:`~pfmdyn.discrepancy.report.DiscrepancyReport`).

    The baseline's starts, a step's candidate fits and the refits of the backward pass run in ``workers``
    processes (default one per core, :func:`~pfmdyn.fitting.workers.cores`); the report is the same with any
    number.

    Examples
    --------
    See ``tests/test_discrepancy.py`` (finite-element data with hidden effects).
    """
    problem = SpectrumProblem(data, vertical_only, workers or cores())
    with problem.pool:
        result = select.run(problem, progress, time_budget_s)
    return report(result, problem.data.frequency_hz, list(zip(*problem.widths)),
                  gap_definition="sqrt(mean |residual|^2) / sigma, sigma = RMS complex noise "
                  "estimated from the data (pfmdyn.fitting.noise)", noise_sigma=problem.sigma)


def _take(problem: SpectrumProblem, news: list) -> None:
    """Add ``news`` (items of each cache, :meth:`SpectrumProblem.each`) to ``problem``'s caches (dicts that only grow)."""
    for cache, items in zip(problem._caches(), news):
        cache.update(items)


def _damped_grid(meta, vertical_only: bool) -> tuple[Model, list[np.ndarray]]:
    """The baseline with internal friction, and the grid of springs at ``1/Q = 0.05`` its damped start search
    ranks (:meth:`SpectrumProblem.baseline`)."""
    smooth = Model(meta, ("damping_internal",), vertical_only)
    a, b = spring_grid(meta, 15, 6)
    grid = [np.array([x]) for x in a] if vertical_only else [np.array([x, y]) for x in a for y in b]
    return smooth, [np.append(g, 0.05) for g in grid]


def _before_fork(problem: SpectrumProblem) -> None:
    """What each worker would load on its first fit, loaded once here before they fork (they inherit it): the
    compiled kernels of a fit's residual and Jacobian (:mod:`pfmdyn.discrepancy.fit_kernel`) and of its steps
    (:mod:`pfmdyn.fitting.trust_region_kernel`), by an iteration of the damped baseline from its grid's first
    point (the composed lever's kernels with them); nothing is kept."""
    smooth, rows = _damped_grid(problem.data.metadata, problem.vertical_only)
    solve(smooth, problem.data, np.clip(rows[0], *bounds(smooth)), problem.sigma, 2)


def _caching(problem: SpectrumProblem, method: str, *args):
    """``problem``'s ``method`` on ``args``, and what the call added to its caches."""
    caches = problem._caches()
    sizes = [len(cache) for cache in caches]
    out = getattr(problem, method)(*args)
    return out, [list(islice(cache.items(), n, None)) for cache, n in zip(caches, sizes)]


def _lowest_valleys(values, count: int) -> list[int]:
    """Indices of the ``count`` lowest local minima of ``values`` along its grid (the misfit over
    the spot's seeds: at damping not yet refitted, the true spot's valley need not be the lowest).

    >>> _lowest_valleys([3.0, 1.0, 2.0, 0.5, 0.7, 4.0, 0.9], 2)
    [3, 6]
    """
    v = np.asarray(values, float)
    padded = np.concatenate([[np.inf], v, [np.inf]])
    valleys = np.flatnonzero((v <= padded[:-2]) & (v <= padded[2:]))
    return [int(i) for i in valleys[np.argsort(v[valleys])][:count]]
