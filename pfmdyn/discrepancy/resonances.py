"""The discrepancy loop for a resonance table (free and contact modes): which effects it can
test, and the report.

The fit of each model is :func:`pfmdyn.discrepancy.resonance_fit.fit_resonances`.  With the
frequency uncertainty known, the criterion is ``BIC = chi2 + k ln n``; the loop and its stopping
rule are :func:`pfmdyn.discrepancy.select.run`'s.

Damping.  Undamped resonances do not move with damping, so ``damping`` is a candidate only
when the table gives Q values (a ``quality_factor`` column, or an instrument's thermal and
tune fits).  The mechanisms differ in how the half-power width
``f/Q`` scales with the mode and the contact: internal friction keeps 1/Q of free modes
equal, viscous drag keeps the width in Hz equal, a contact dashpot damps contact modes only,
more the larger ``k1``'s share of the mode.  The mechanism (or two) with the lowest BIC is
reported as ``damping`` with ``damping_mechanisms``, as for spectra.


Candidates (:func:`candidate_rule`): ``damping`` with Q values; ``tip_mass``;
``tip_setback``, ``tilt`` and (with a vertical-only baseline: the baseline has ``k2`` otherwise)
``lateral_stiffness`` change contact modes only (the set-back when the tip carries no mass),
so they are tried only when there are more contact modes than contact parameters already
fitted, or when those parameters leave a contact misfit (frequencies, and with damping Q
values) above the noise; the effect's parameter may then be undetermined, and tied
candidates are listed (set-back before tilt).  The others are listed in the report's
``untestable_effects``.  ``background`` and ``spot_position`` never (they change spectra, not
resonances).  Every candidate needs a degree of freedom left once its parameters are fitted
(data values reproduced by construction, free mode 1, do not count), a second damping
mechanism a Q value left over.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..constants import Q_RELATIVE_UNCERTAINTY, RESONANCE_RELATIVE_UNCERTAINTY
from ..io.tables import ResonanceData
from . import select
from .report import degrees, report
from .effects import DAMPING, EFFECTS
from .model import FitResult, Model
from .resonance_fit import (K2_OVER_K1, SPRINGS, _jacobian, _residual, contact_modes, damping_seeds, fit_resonances,
                            frequency_sigma, held_springs, rows_with_q)

__all__ = ["CANDIDATES", "ResonanceProblem", "analyse_resonances", "candidate_rule"]

CANDIDATES = ("tip_setback", "tip_mass", "tilt")
"""Effects a resonance table can show, in the order ties are broken.  Set-back and tilt both
change contact modes only and often tie (two contact modes); the set-back comes first:
every real tip sits some microns from the free end, while a tilt of the spring tensor is
largely absorbed by the fitted k1 and k2 (in ``benchmarks/discrepancy_tables.py`` a hidden
tilt is invisible in most tables, a hidden set-back almost never)."""
CONTACT_ONLY = ("tilt", "lateral_stiffness")
"""Effects that change only contact modes; so does ``tip_setback`` without a tip mass
(:func:`_contact_only`).  Each parameter needs a contact mode of its own."""


def _contact_only(effect: str, effects) -> bool:
    """Whether ``effect`` changes only contact modes on top of ``effects`` (a set-back tip
    moves free modes only when it carries a mass)."""
    return effect in CONTACT_ONLY or (effect == "tip_setback" and "tip_mass" not in effects)


def _locate(data: ResonanceData, result: FitResult) -> dict:
    r = result.residual / result.sigma
    n = len(data.frequency_hz)
    rf, rq = r[:n], r[n:]
    free = data.condition == "free"
    share = float(np.sum(rf[free] ** 2) / max(np.sum(rf**2), 1e-300))
    q_share = float(np.sum(rq**2) / max(np.sum(r**2), 1e-300))
    if q_share > 0.5:
        rows = np.flatnonzero(rows_with_q(data))
        worst = int(rows[np.argmax(np.abs(rq))])
        return {"worst": f"Q of {data.condition[worst]} mode {data.mode[worst]}", "share_free_modes": share,
                "share_quality_factors": q_share, "signature": _q_signature(data)}
    worst = int(np.argmax(np.abs(rf)))
    return {"worst": f"{data.condition[worst]} mode {data.mode[worst]}",
            "share_free_modes": share, "share_quality_factors": q_share,
            "signature": "mode-ratio error" if share > 0.5 else "peak shift"}


def _q_signature(data: ResonanceData) -> str:
    """How the measured half-power width ``f/Q`` scales: with frequency, and from free to contact."""
    has_q = rows_with_q(data) & np.isfinite(data.quality_factor if data.quality_factor is not None else 0.0)
    f, q = data.frequency_hz[has_q], data.quality_factor[has_q]
    parts = []
    if len(np.unique(f)) >= 2:
        # Width ~ f**s: s ~ 0 for viscous damping, ~ 1 for internal friction.
        s = float(np.polyfit(np.log(f), np.log(f / q), 1)[0])
        parts.append(f"half-power width ~ f^{s:.2f}")
    contact = data.condition[has_q] == "contact"
    if contact.any() and (~contact).any():
        parts.append(f"contact/free median 1/Q ratio {np.median(1 / q[contact]) / np.median(1 / q[~contact]):.2g}")
    return "damping: " + (", ".join(parts) or "one Q value")


class ResonanceProblem:
    """What :func:`pfmdyn.discrepancy.select.run` needs for a resonance table.

    The library (see :func:`candidate_rule`): ``damping`` when the table gives Q values;
    tip mass and set-back; tilt (and ``lateral_stiffness`` with a vertical-only baseline: the
    baseline has ``k2`` otherwise) when there is a contact mode for each contact parameter.
    """

    def __init__(self, data: ResonanceData, vertical_only: bool = False):
        self.data, self.vertical_only = data, vertical_only
        self.library = candidate_rule(data, vertical_only)
        self.seeds = damping_seeds(data)

    def baseline(self) -> FitResult:
        return fit_resonances(Model(self.data.metadata, (), self.vertical_only), self.data)

    def _contact_room(self, current: FitResult) -> int:
        """Contact modes not yet used by fitted contact parameters (springs, tilt, set-back, k2);
        when the fitted springs cannot reach the contact modes (their residual, frequencies
        and, with damping, Q values, is above the noise), there is a misfit to explain
        whatever the count: 1."""
        held = current.extra.get("held", {})
        springs = sum(1 for p in current.model.parameters if p.name in SPRINGS and p.name not in held)
        effects = current.model.effects
        free = contact_modes(self.data) - springs - sum(_contact_only(e, effects) for e in effects)
        contact = self.data.condition == "contact"
        r = current.residual / current.sigma
        rows = np.zeros(len(r), bool)
        rows[:len(contact)] = contact
        if current.model.damping_mechanisms:
            # With damping, the contact modes' Q values also depend on the contact parameters.
            rows[len(contact):] = contact[rows_with_q(self.data)]
        r = r[rows]
        misfit = bool(len(r)) and float(np.sqrt(np.mean(r**2))) > select.NEAR_NOISE
        return max(free, int(misfit and springs > 0))

    def candidates(self, current: FitResult) -> list[str]:
        # An effect needs a degree of freedom left to test it once its parameters are fitted;
        # contact-only effects a contact mode each.
        return [e for e in self.library if self._testable(current, e) is None]

    def _testable(self, current: FitResult, e: str) -> str | None:
        """None when ``e`` can be tried on top of ``current``; else why these data cannot test it."""
        dof = degrees(current)["dof"]
        if e == "damping":
            mechanisms = len(current.model.damping_mechanisms)
            if mechanisms >= 2 or not self._mechanisms(current):
                return "every mechanism the table can show is in the model"
            n_q = int(rows_with_q(self.data).sum())
            # The first mechanism is tested by the undamped baseline's 1/Q = 0; a second one
            # needs a Q value left over once both are fitted.
            if mechanisms and n_q <= mechanisms + 1:
                return (f"a second damping mechanism: {n_q} Q value(s) and {mechanisms + 1} mechanism "
                        "parameters would leave none to test it")
            if dof < 1 or (mechanisms and dof <= 1):
                return f"{dof} degree(s) of freedom left, and a mechanism parameter would use it"
            return None
        if e in current.model.effects:
            return "in the model"
        p = max(len(EFFECTS[e].parameters), 1)
        if dof <= p:
            return (f"{degrees(current)['data_values']} data values and {current.k} fitted parameters leave "
                    f"{dof} degree(s) of freedom; its {p} parameter(s) would leave none to test it")
        if _contact_only(e, current.model.effects) and self._contact_room(current) <= 0:
            n = contact_modes(self.data)
            reason = (f"the fitted contact parameters already reproduce the {n} contact mode(s)" if n
                      else "the table has no contact mode")
            return f"changes contact modes only{' (without a tip mass)' if e == 'tip_setback' else ''}, and {reason}"
        return None

    def untestable(self, current: FitResult) -> dict[str, str]:
        """Effects of the library this table cannot test on top of ``current``: "not testable
        with these data", and why (a damping mechanism already in the model is not listed)."""
        out = {}
        for e in self.library:
            why = self._testable(current, e)
            if why is None or why in ("in the model", "every mechanism the table can show is in the model"):
                continue
            out[e] = f"not testable with these data: {why}"
        fitted = self._fitted_damping(current)
        if fitted:
            out["damping"] = fitted
        return out

    def _fitted_damping(self, current: FitResult) -> str | None:
        """Why the damping in ``current`` is fitted rather than tested, when its mechanism
        parameters use up every Q value (one Q, as a thermal tune gives): the undamped baseline
        (Q infinite) is rejected, but the fitted Q reproduces the measured ones by construction,
        so neither the mechanism nor how the width scales with the mode is tested."""
        mechanisms = current.model.damping_mechanisms
        n_q = int(rows_with_q(self.data).sum())
        if not mechanisms or n_q > len(mechanisms):
            return None
        left = degrees(current)["dof"]
        return (f"not testable with these data: {n_q} Q value(s) and {len(mechanisms)} damping parameter(s) "
                f"({left} degree(s) of freedom left): the undamped model is rejected, but the fitted Q "
                "reproduces the measured one by construction, so the mechanism and the law of the width "
                "with frequency are not tested (another Q value, e.g. of a second mode, would test them)")

    def _mechanisms(self, current: FitResult | None = None) -> list[str]:
        """Damping components not yet in the model (the dashpot only with a contact Q)."""
        contact_q = np.any(rows_with_q(self.data) & (self.data.condition == "contact"))
        present = current.model.effects if current is not None else ()
        return [c for m, c in DAMPING.items() if c not in present and (m != "contact" or contact_q)]

    def _fit_with(self, current: FitResult, component: str) -> FitResult:
        model = current.model.with_effect(component)
        effect = EFFECTS[component]
        if component.startswith("damping_"):
            # Damping leaves the resonances alone: its parameter alone from the current fit
            # (null and the data's seed values); polish() converges the one accepted.
            name = effect.parameters[0].name
            return fit_resonances(model, self.data, local=[np.append(current.internal, v) for v in
                                                           (effect.null[0],) + self.seeds[name]], vary=(name,))
        start = None if component == "lateral_stiffness" else np.concatenate([current.internal, effect.null])
        return fit_resonances(model, self.data, start)

    def trial(self, current: FitResult, name: str) -> FitResult:
        """Best fit with ``name`` added (for damping: the mechanism with the lowest BIC)."""
        if name != "damping":
            return self._fit_with(current, name)
        fits = [self._fit_with(current, c) for c in self._mechanisms(current)]
        return min(fits, key=lambda f: f.bic)

    def without(self, current: FitResult, component: str) -> FitResult:
        effects = list(current.model.effects)
        effects.remove(component)
        model = Model(self.data.metadata, tuple(effects), self.vertical_only)
        if not component.startswith("damping_"):
            return fit_resonances(model, self.data)
        keep = [i for i, p in enumerate(current.model.parameters) if p not in EFFECTS[component].parameters]
        return fit_resonances(model, self.data, local=[current.internal[keep]])

    def alternatives(self, current: FitResult) -> list[FitResult]:
        """The final model with its damping mechanism(s) replaced by each single other one."""
        present = [c for c in current.model.effects if c.startswith("damping_")]
        if not present:
            return []
        others = tuple(c for c in current.model.effects if c not in present)
        out = []
        keep = [i for i, p in enumerate(current.model.parameters)
                if not any(p in EFFECTS[c].parameters for c in present)]
        for component in self._mechanisms():
            if present != [component]:
                name = EFFECTS[component].parameters[0].name
                out.append(fit_resonances(Model(self.data.metadata, others + (component,), self.vertical_only),
                                          self.data, local=[np.append(current.internal[keep], v)
                                                            for v in self.seeds[name]], vary=(name,)))
        return out

    def polish(self, trial: FitResult) -> FitResult:
        """Every parameter of an accepted trial converged (trials may move one only)."""
        return fit_resonances(trial.model, self.data, local=[trial.internal])

    def locate(self, current: FitResult) -> dict:
        return _locate(self.data, current)


def _tied_mechanisms(problem: ResonanceProblem, final: FitResult) -> list[str]:
    """Damping mechanisms that explain the Q values as well as the reported ones (BIC within
    the threshold), e.g. every mechanism when the table holds one Q."""
    if not final.model.damping_mechanisms:
        return []
    fits = [f for f in problem.alternatives(final) if f.bic - final.bic <= select.BIC_THRESHOLD]
    return sorted({m for f in fits for m in f.model.damping_mechanisms} - set(final.model.damping_mechanisms))


def candidate_rule(data: ResonanceData, vertical_only: bool) -> list[str]:
    """The effect library of a resonance table, in the order ties are broken.

    * ``damping`` only when the table gives Q values (undamped resonances do not move);
    * ``background`` and ``spot_position`` never (they change a spectrum, not its resonances);
    * ``tilt`` and ``lateral_stiffness`` only with contact modes (they act through the
      springs); ``lateral_stiffness`` only with a vertical-only baseline, since any other
      already fits ``k2``.  Whether the data have room for each is decided per step
      (:meth:`ResonanceProblem.candidates`: one contact mode per contact parameter).

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.4, length=223e-6, width=24e-6, tip_height=10e-6, free_resonance=54.55e3)
    >>> free = ResonanceData(meta, np.array([1, 2, 3]), np.array(["free"] * 3), np.array([54.55, 346.73, 980.55]) * 1e3)
    >>> candidate_rule(free, vertical_only=True)
    ['tip_setback', 'tip_mass']
    """
    library = (["damping"] if rows_with_q(data).any() else []) + \
        (["lateral_stiffness"] if vertical_only else []) + list(CANDIDATES)
    if not contact_modes(data):
        library = [e for e in library if e not in CONTACT_ONLY]
    return library


def uncertainty_budget(final: FitResult, data: ResonanceData, tip_height_uncertainty: float = 0.0) -> dict:
    """Each fitted parameter's standard uncertainty, input by input: the table's resonance frequencies and
    its Q values (their shares of the fit's covariance, by the rows of each: ``(J^T J)^-1 = A A^T`` with
    ``A = pinv(J)``), and the tip height, which no file records (first order: ``-A dr/dH u(H)``, the residual's
    change with the metadata's tip height at the fitted parameters).  Name -> source -> stderr (the
    parameter's unit); the sources' squares add up to the total.

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=2.0, length=240e-6, width=3e-5, tip_height=13e-6, free_resonance=7e4)
    >>> data = ResonanceData(meta, np.array([1, 1]), np.array(["free", "contact"]), np.array([7e4, 3.5e5]))
    >>> fit = fit_resonances(Model(meta), data)
    >>> parts = uncertainty_budget(fit, data, 2.5e-6)["k1"]
    >>> sorted(parts), parts["tip_height"] > parts["resonance_frequencies"]
    (['k2_policy', 'resonance_frequencies', 'tip_height'], True)
    """
    model, x = final.model, np.asarray(final.internal, float)
    params = model.parameters
    fitted = final.fitted if final.fitted is not None else np.ones(len(params), bool)
    names = [p.name for p in params]
    jac = _jacobian(model, x, data)
    held = held_springs(model, data)
    tied = "k2" in held and "k1" not in held
    lateral = jac[:, names.index("k2")].copy() if tied else None
    if tied:        # one contact mode: k2 follows k1 (fit_resonances' tie)
        jac[:, names.index("k1")] += lateral
    inverse = np.linalg.pinv(jac[:, fitted])
    n = len(data.frequency_hz)
    rows = {"resonance_frequencies": slice(0, n), "quality_factors": slice(n, None)}
    parts = {source: np.sqrt(np.sum(inverse[:, span] ** 2, axis=1)) for source, span in rows.items()
             if inverse[:, span].size}
    scale = np.sqrt(np.maximum(np.diag(final.covariance), 0.0)) / np.sqrt(sum(v**2 for v in parts.values()))
    parts = {source: v * np.where(np.isfinite(scale), scale, 1.0) for source, v in parts.items()}
    if tip_height_uncertainty:
        height = data.metadata.tip_height
        step = 1e-6 * height
        meta = replace(data.metadata, tip_height=height + step)
        moved = _residual(replace(model, meta=meta), x, replace(data, metadata=meta)) - _residual(model, x, data)
        parts["tip_height"] = np.abs(inverse @ (moved / step)) * tip_height_uncertainty
    if tied:        # the tie's ratio assumed (Mindlin at an assumed Poisson's ratio): d log10 k2 = d ratio / (ratio ln 10)
        from ..analysis.stiffness_report import assumed_tie_uncertainty

        parts["k2_policy"] = np.abs(inverse @ lateral) * assumed_tie_uncertainty() / (K2_OVER_K1 * math.log(10))
    out = {}
    for j, i in enumerate(np.flatnonzero(fitted)):
        p = params[i]
        out[p.key] = {source: float(p.stderr(x[i], float(v[j]))) for source, v in parts.items() if v[j] > 0}
    return out


def analyse_resonances(data: ResonanceData, vertical_only: bool = False, progress: bool = False,
                       time_budget_s: float | None = None, tip_height_uncertainty: float | None = None) -> dict:
    """Discrepancy loop on a resonances table; same report keys as the spectrum loop.

    Each fitted parameter's uncertainty is given input by input (:func:`uncertainty_budget`): the
    resonance frequencies (:data:`pfmdyn.constants.RESONANCE_RELATIVE_UNCERTAINTY` each unless the table says,
    assumed), the Q values (:data:`pfmdyn.constants.Q_RELATIVE_UNCERTAINTY`, assumed) and,
    with ``tip_height_uncertainty`` (m), the tip height, added to the fit's.

    Examples
    --------
    See ``tests/test_discrepancy.py`` (FE resonances, and the paper's tips 1 and 2).
    """
    problem = ResonanceProblem(data, vertical_only)
    result = select.run(problem, progress, time_budget_s)
    sigma = frequency_sigma(data)
    n = len(data.frequency_hz)
    base, final = result["baseline"], result["final"]
    extra = {"damping_mechanisms_indistinguishable_from": _tied_mechanisms(problem, final)}
    gap_definition = "RMS of (f_model - f_measured) / frequency uncertainty"
    if rows_with_q(data).any():
        rows = rows_with_q(data)
        measured = data.quality_factor[rows]
        extra.update(measured_quality_factor=measured.tolist(),
                     predicted_quality_factor=[1 / v if v > 0 else None for v in 1 / measured + final.residual[n:]],
                     quality_factor_relative_uncertainty=float(final.sigma[n] / max(1 / measured[0], 1e-4)))
        gap_definition += " and of (1/Q_model - 1/Q_measured) / its uncertainty"
    budget = uncertainty_budget(final, data, tip_height_uncertainty or 0.0)
    parameters = _with_budget(result, budget)
    assumed = {"resonance_frequencies": data.metadata.frequency_uncertainty_hz is None,
               "quality_factors": data.metadata.quality_factor_uncertainty is None}
    return report(result, gap_definition=gap_definition, parameters=parameters,
                  uncertainty_inputs={source: {"assumed": assumed.get(source, True), "words": _INPUT_WORDS[source](data)}
                                      for source in {s for parts in budget.values() for s in parts}},
                  measured_hz=data.frequency_hz.tolist(),
                  baseline_hz=(data.frequency_hz + base.residual[:n]).tolist(),
                  predicted_hz=(data.frequency_hz + final.residual[:n]).tolist(),
                  frequency_uncertainty_hz=sigma.tolist(), spring_rule=held_springs(final.model, data),
                  untestable_effects=problem.untestable(final),
                  **extra)


_INPUT_WORDS = {
    "resonance_frequencies": lambda data: "resonance frequencies" + (
        f" ({data.metadata.frequency_uncertainty_hz:g} Hz)" if data.metadata.frequency_uncertainty_hz is not None
        else f" ({RESONANCE_RELATIVE_UNCERTAINTY:.1%} each, assumed: the table gives none)"),
    "quality_factors": lambda data: "Q values" + (
        f" ({data.metadata.quality_factor_uncertainty:.3g} relative)" if data.metadata.quality_factor_uncertainty
        is not None else f" ({Q_RELATIVE_UNCERTAINTY:.0%} each, assumed: the table gives none)"),
    "tip_height": lambda data: f"tip height ({data.metadata.tip_height * 1e6:.3g} um)",
    "k2_policy": lambda data: "k2 policy (Mindlin, Poisson's ratio 0.2-0.4 assumed)",
}
"""How the report names each input of :func:`uncertainty_budget`, with the uncertainty it took."""


def _with_budget(result: dict, budget: dict) -> dict:
    """The final fit's parameters (:func:`pfmdyn.discrepancy.report.parameters`), each stderr the sum in
    quadrature of its ``budget`` (the fit's and the tip height's), the budget kept beside it."""
    from .report import parameters

    out = parameters(result["final"])
    for name, parts in budget.items():
        if name in out and out[name].get("value") is not None and parts:
            total = math.sqrt(sum(v**2 for v in parts.values()))
            out[name] = dict(out[name], stderr=total, budget=parts)
    return out
