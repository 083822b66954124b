"""The one selection loop of ``pfmdyn discrepancy`` (spectra and resonance tables alike).

Greedy forward selection over the effect library with an honest stopping rule.  At each
step every candidate effect is fitted on top of the current model (by the data kind's
*problem*: :class:`pfmdyn.discrepancy.spectrum.SpectrumProblem` or
:class:`pfmdyn.discrepancy.resonances.ResonanceProblem`).  A candidate is *material* when

* it lowers the BIC by more than :data:`BIC_THRESHOLD` (10, "very strong" evidence), and
* it shrinks the gap by at least :data:`MIN_REDUCTION` (25 %), or brings it within
  :data:`NEAR_NOISE` (1.5) times the noise while shrinking it by at least 5 %.

A candidate the problem refuses (:func:`refusal`: it lowers the misfit but not the way the
effect would, e.g. a background that only reshapes the peaks) is not material.

With a misfit far above the noise any extra parameter wins the BIC, so the criterion
alone would name effects that explain 1 % of the misfit; the gap rule prevents that.  A
misfit already below :data:`WITHIN_NOISE` (0.5) times the noise estimate needs nothing
more: there the estimate measures the curvature of noise-free data (a simulation), and the
BIC, with the noise profiled, would name effects of negligible size.  The
material candidate with the largest BIC gain is added (candidates within
:data:`BIC_THRESHOLD` of it are indistinguishable: the first in the library's order is
taken and the others are listed in the step).  When none is material, pairs of
the three best candidates are tried (two effects can be needed together before either
helps on its own), and the loop stops when no pair is material either.  A backward pass
then removes every component that is no longer material in the final model (an effect
that only helped a fit out of a local minimum, a damping mechanism replaced by another).  An effect whose
fitted values no lever has (:func:`pfmdyn.discrepancy.plausible.implausible`) is then removed: it is not a
finding.

Every named effect's *share* is reported (:func:`shares`): the part of the baseline's misfit above the
noise (``gap**2 - 1``) that the final model loses without the effect, and its part of the misfit the
other effects leave (``share_of_rest``).  Without it means the best fit known of the other effects or
of fewer: a refit can land in a worse minimum than the baseline, and a drop measured from there makes
any effect look needed.  Near the noise every kept effect is material and the data are explained.
Far from it that is not enough (a report named five effects that together took 16 % of a misfit:
gap 188 -> 172).
While the final gap stays above :data:`UNEXPLAINED` (2), an effect must also explain at least as much
as stays unexplained (``share_of_rest`` >= :data:`MIN_SHARE`, a half); the one of least share is
removed, the best fit of the rest taken (the refit or a known fit of fewer effects, by BIC), until all
do: the named set explains most with fewest parameters.  A final gap above :data:`UNEXPLAINED`, or any
removal, is reported as ``unexplained``: how large (the gap and the share of the misfit left), where
the misfit concentrates, and what was removed and why.
"""
from __future__ import annotations

from tqdm import tqdm

from ..fitting.workers import count_compiling, cpu_seconds
from .effects import public_name
from .plausible import describe, implausible

__all__ = ["BIC_THRESHOLD", "MIN_REDUCTION", "NEAR_NOISE", "WITHIN_NOISE", "UNEXPLAINED", "MIN_SHARE", "material",
           "refusal", "share", "shares", "run"]

BIC_THRESHOLD = 10.0
MIN_REDUCTION = 0.25
NEAR_NOISE = 1.5
WITHIN_NOISE = 0.5
UNEXPLAINED = 2.0
MIN_SHARE = 0.5
"""Part of the misfit the other named effects leave that an effect must take while the final gap
stays above :data:`UNEXPLAINED`: a half, i.e. it explains at least as much as stays unexplained
(a material step, the gap lowered by 25 %, takes 44 %: far from the noise that is not enough)."""
TIME_BUDGET_S = 35.0
"""``pfmdyn discrepancy``'s budget: forward steps start only within this many seconds of the
start (then prune and report), so that a hard file still ends in a report within about a
minute.  The seconds are CPU time (the process's and its workers'), not the wall clock: on a
loaded machine the same file gets the same report (a wall-clock budget stopped a large set-back
spectrum after its first step when other jobs shared the cores).  numba's compiling is left out:
a fresh install's first run compiles the kernels (35 CPU s and more, which stopped it after the
baseline) and gets the report of the next.  Library calls have no budget unless given one."""

CRITERION = (f"add the effect with the largest BIC gain among those with gain > {BIC_THRESHOLD:g} that shrink "
             f"the gap by >= {MIN_REDUCTION:.0%} (or to <= {NEAR_NOISE:g} x noise, by >= 5 %); while the final gap "
             f"stays above {UNEXPLAINED:g} x noise, keep only effects that take >= {MIN_SHARE:.0%} of the misfit "
             "the others leave")


def material(old, new) -> bool:
    """Whether ``new`` (a fit with one more effect) explains a material part of ``old``'s misfit.

    >>> from types import SimpleNamespace as S
    >>> material(S(bic=0.0, gap=123.3), S(bic=-1108.0, gap=122.0))      # 1 % of the misfit
    False
    >>> material(S(bic=0.0, gap=40.0), S(bic=-900.0, gap=1.1))
    True
    >>> material(S(bic=0.0, gap=0.19), S(bic=-9e4, gap=0.01))          # noise-free data
    False
    """
    gain = old.bic - new.bic
    if not gain > BIC_THRESHOLD or old.gap <= WITHIN_NOISE or refusal(new):
        return False
    return new.gap <= (1 - MIN_REDUCTION) * old.gap or (new.gap <= NEAR_NOISE and new.gap <= 0.95 * old.gap)


def refusal(fit) -> str | None:
    """Why the problem refused ``fit``'s new effect although it lowers the misfit (it does not
    act as that effect does, e.g. a background reshaping the peaks), or None.

    >>> from types import SimpleNamespace as S
    >>> refusal(S(extra={"refused": "reshapes the peaks"})), refusal(S(bic=0.0, gap=1.0))
    ('reshapes the peaks', None)
    """
    extra = getattr(fit, "extra", None)
    return extra.get("refused") if extra else None


def _row(name, old, new) -> dict:
    row = {"effect": name, "bic": new.bic, "delta_bic": old.bic - new.bic, "gap": new.gap}
    if refusal(new):
        row["refused"] = refusal(new)
    return row


def run(problem, progress: bool = False, time_budget_s: float | None = None) -> dict:
    """Run the loop on ``problem``; return baseline, final fit and the steps.

    ``problem`` provides ``baseline()``, ``candidates(fit) -> names``, ``trial(fit, name)
    -> fit`` (the best fit with that effect added), ``without(fit, component) -> fit``
    (refit with one component removed), ``locate(fit) -> dict`` and optionally
    ``polish(fit) -> fit`` (converge a trial that is accepted), ``each(method, calls) -> list``
    (the method on each argument tuple, e.g. in worker processes; the same results as in turn) and
    ``worker_seconds`` (the CPU seconds of those workers, which the budget counts).
    """
    if time_budget_s is not None:
        count_compiling()       # a first run's compiling is left out: it gets the report of the next
    started = cpu_seconds()
    problem = _Record(problem)
    current = problem.baseline()
    baseline, steps = current, []
    with tqdm(desc="discrepancy", unit="fit", disable=not progress) as bar:
        while True:
            where = problem.locate(current)
            spent = cpu_seconds() - started + getattr(problem, "worker_seconds", 0.0)
            if time_budget_s is not None and spent > time_budget_s:
                steps.append({"effect": None, "located": where, "candidates": [],
                              "decision": f"stop: time budget of {time_budget_s:g} s used"})
                break
            names = problem.candidates(current)
            if not names:
                break
            trials = dict(zip(names, problem.each("trial", [(current, name) for name in names])))
            bar.update(len(names))
            table = [_row(n, current, t) for n, t in trials.items()]
            good = [n for n in names if material(current, trials[n])]
            if good:
                top = min(trials[n].bic for n in good)
                # Candidates within the BIC threshold of the best are not told apart by the
                # data: take the first in the library's order and say which were equivalent.
                tied = [n for n in good if trials[n].bic - top <= BIC_THRESHOLD]
                best = tied[0]
                steps.append({"effect": best, "located": where, "candidates": table,
                              "indistinguishable_from": tied[1:],
                              "gap_before": current.gap, "gap_after": trials[best].gap,
                              "criterion_gain": current.bic - trials[best].bic,
                              "parameters": trials[best].parameters()})
                current = _polish(problem, trials[best])
                steps[-1].update(gap_after=current.gap, parameters=current.parameters())
                continue
            pair = _best_pair(problem, current, trials, bar) if current.gap > NEAR_NOISE else None
            if pair is None:
                gains = {n: current.bic - t.bic for n, t in trials.items()}
                best = max(gains, key=gains.get)
                steps.append({"effect": None, "located": where, "candidates": table,
                              "decision": f"stop: no material candidate (best {best}: BIC gain "
                              f"{gains[best]:.1f}, gap {current.gap:.3g} -> {trials[best].gap:.3g})"})
                break
            (first, second), fit = pair
            for name, before, after in ((first, current, trials[first]), (second, trials[first], fit)):
                steps.append({"effect": name, "located": where, "candidates": table if name == first else [],
                              "gap_before": before.gap, "gap_after": after.gap,
                              "criterion_gain": before.bic - after.bic, "parameters": after.parameters(),
                              "note": f"added together with {second if name == first else first}"})
            current = _polish(problem, fit)
            steps[-1].update(gap_after=current.gap, parameters=current.parameters())
    current = _prune(problem, current, steps)
    current, dropped = _drop_implausible(problem, current, steps)
    current, small, found = _drop_small(problem, baseline, current, steps)
    unexplained = None
    if current.gap > UNEXPLAINED or dropped or small:
        loc = problem.locate(current)
        unexplained = {"gap": current.gap, "share": share(baseline.gap, current.gap, 1.0),
                       "where": loc.get("band_hz", loc.get("worst"))}
        if dropped:
            unexplained["implausible"] = dropped
        if small:
            unexplained["small_share"] = small
    return {"baseline": baseline, "final": current, "steps": steps, "unexplained": unexplained,
            "shares": {name: {k: v for k, v in s.items() if k != "fit"} for name, s in found.items()}}


def share(baseline_gap: float, without_gap: float, gap: float) -> float:
    """Share of the baseline's misfit above the noise (``gap**2 - 1``, gaps in noise levels) that
    going from ``without_gap`` to ``gap`` removes, within [0, 1].

    >>> round(share(188.0, 188.0, 172.0), 3), share(300.0, 300.0, 1.0)
    (0.163, 1.0)
    """
    excess = max(baseline_gap**2 - 1.0, 1e-300)
    return float(min(max((without_gap**2 - gap**2) / excess, 0.0), 1.0))


def shares(problem, baseline, current, known=None) -> dict[str, dict]:
    """Each named effect's share of the misfit in ``current``: the gap without it (all its
    components: damping may hold two mechanisms), the least of the ``known`` fits (effect set ->
    fit) of the other effects or fewer, and of the refit when none is known of the others exactly;
    ``share`` of ``baseline``'s misfit and ``share_of_rest`` of what the others leave
    (:func:`share`); ``fit``, the best by BIC of those.

    >>> from types import SimpleNamespace as S
    >>> problem = S(without=lambda fit, c: S(gap=40.0, bic=9.0, model=S(effects=())))
    >>> out = shares(problem, S(gap=300.0), S(gap=20.0, model=S(effects=("damping_viscous",))))
    >>> round(out["damping"]["share"], 4), out["damping"]["gap_without"], round(out["damping"]["share_of_rest"], 3)
    (0.0133, 40.0, 0.75)
    """
    out = {}
    for name in dict.fromkeys(public_name(c) for c in current.model.effects):
        rest = frozenset(c for c in current.model.effects if public_name(c) != name)
        fits = [f for effects, f in (known or {}).items() if effects <= rest]
        if rest not in (known or {}):
            fit = current
            for component in [c for c in current.model.effects if c not in rest]:
                fit = problem.without(fit, component)
            fits.append(fit)
        gap = min(f.gap for f in fits)
        out[name] = {"share": share(baseline.gap, gap, current.gap), "gap_without": gap,
                     "share_of_rest": share(gap, gap, current.gap), "fit": min(fits, key=lambda f: f.bic)}
    return out


def _drop_small(problem, baseline, current, steps):
    """While the gap stays above :data:`UNEXPLAINED`, remove the effect of least ``share_of_rest``
    below :data:`MIN_SHARE` (and any the best fit of the rest leaves out).  Returns the fit, the
    removed effects' shares of the rest and the final shares."""
    small = {}
    while True:
        known = {effects: f for effects, f in problem.best.items() if not implausible(f)}
        found = shares(problem, baseline, current, known)
        below = {n: s for n, s in found.items() if s["share_of_rest"] < MIN_SHARE}
        if current.gap <= UNEXPLAINED or not below:
            return current, small, found
        name = min(below, key=lambda n: below[n]["share_of_rest"])
        fit = below[name]["fit"]
        gone = [n for n in found if n not in {public_name(c) for c in fit.model.effects}]
        who = "it" if gone == [name] else name
        steps.append({"effect": None, "removed": ", ".join(gone), "gap_before": current.gap, "gap_after": fit.gap,
                      "decision": f"removed {', '.join(gone)}: {who} takes {below[name]['share_of_rest']:.0%} of the "
                      f"misfit the others leave (at least {MIN_SHARE:.0%} while the gap stays "
                      f"{current.gap:.3g} x noise)"})
        small.update({n: found[n]["share_of_rest"] for n in gone})
        current = fit


class _Record:
    """``problem`` keeping ``best``, the fit of least gap of every set of effects it returned."""

    FITTING = ("baseline", "trial", "without", "polish", "alternatives")

    def __init__(self, problem):
        self.problem, self.best = problem, {}

    def __getattr__(self, name):
        attr = getattr(self.problem, name)
        if name not in self.FITTING:
            return attr

        def recorded(*args):
            return self._keep(attr(*args))
        return recorded

    def each(self, method: str, calls) -> list:
        """The problem's ``method`` on each of ``calls``, by its ``each`` when it has one (worker processes),
        recorded in order."""
        calls = list(calls)
        run = getattr(self.problem, "each", None)
        outs = run(method, calls) if run else [getattr(self.problem, method)(*args) for args in calls]
        for out in outs:
            self._keep(out)
        return outs

    def _keep(self, out):
        for fit in out if isinstance(out, list) else [out]:
            key = frozenset(fit.model.effects)
            if key not in self.best or fit.gap < self.best[key].gap:
                self.best[key] = fit
        return out


def _drop_implausible(problem, current, steps):
    """Remove the effects whose fitted values no lever has (:mod:`.plausible`): the misfit
    they lowered stays, reported as unexplained.  Returns the fit and what was dropped."""
    dropped = {}
    while True:
        bad = implausible(current)
        if not bad:
            return current, dropped
        component, why = next(iter(bad.items()))
        fit = problem.without(current, component)
        steps.append({"effect": None, "removed": component, "gap_before": current.gap, "gap_after": fit.gap,
                      "decision": f"removed {component}: {describe({component: why})}"})
        dropped[component] = why
        current = fit


def _prune(problem, current, steps):
    """Backward pass: drop every effect component that the final model does not need.

    Greedy steps can add an effect that only helped the fit out of a local minimum (its
    parameter ends at its null value) or a damping mechanism that a later one replaced.
    A component goes when it is no longer material, i.e. when the model without it would
    not be extended by it again.
    """
    for _ in range(2):      # two rounds: e.g. a swapped effect, then a swapped mechanism
        options = getattr(problem, "alternatives", lambda fit: [])(current)
        best = min(options, key=lambda f: f.bic, default=None)
        if best is None or best.bic >= current.bic:
            break
        # e.g. one damping mechanism in place of another, or of two that mimic it together.
        steps.append({"effect": None, "removed": ", ".join(current.model.effects),
                      "gap_before": current.gap, "gap_after": best.gap,
                      "decision": f"replaced {', '.join(current.model.effects)} by "
                      f"{', '.join(best.model.effects)} (BIC lower by {current.bic - best.bic:.1f})"})
        current = best
    while len(current.model.effects) > 0:
        effects = current.model.effects
        trials = dict(zip(effects, problem.each("without", [(current, c) for c in effects])))
        spare = [c for c, t in trials.items() if t is not None and not material(t, current)]
        if not spare:
            return current
        drop = min(spare, key=lambda c: trials[c].bic)
        steps.append({"effect": None, "removed": drop, "gap_before": current.gap, "gap_after": trials[drop].gap,
                      "decision": f"removed {drop}: not material in the final model (BIC gain "
                      f"{trials[drop].bic - current.bic:.1f}, gap {trials[drop].gap:.3g} -> {current.gap:.3g})"})
        current = trials[drop]
    return current


def _polish(problem, trial):
    """The trial fit converged fully, when the problem stops trials early (never worse)."""
    if not hasattr(problem, "polish"):
        return trial
    polished = problem.polish(trial)
    return polished if polished.bic <= trial.bic else trial


def _best_pair(problem, current, trials, bar):
    """The material pair of effects (among the three best single ones, none of the problem's
    ``alone``) with the largest gain."""
    alone = getattr(problem, "alone", ())
    ranked = sorted((n for n in trials if not refusal(trials[n]) and n not in alone),
                    key=lambda n: current.bic - trials[n].bic, reverse=True)[:3]
    pairs = [(a, b) for i, a in enumerate(ranked) for b in ranked[i + 1:] if b in problem.candidates(trials[a])]
    found = None
    for pair, fit in zip(pairs, problem.each("trial", [(trials[a], b) for a, b in pairs])):
        bar.update()
        if material(current, fit) and (found is None or fit.bic < found[1].bic):
            found = (pair, fit)
    return found
