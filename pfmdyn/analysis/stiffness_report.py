"""Contact stiffness from contact resonances on the whole lever model: what ``pfmdyn stiffness`` reports.

What the resonances determine depends on what is stated (:func:`analyse`):

===========  ======================================  ====================================================
modes        stated                                  solved
===========  ======================================  ====================================================
one          (nothing more needed)                   ``k1``; ``k2`` by the policy of :meth:`Contact.tie`
two or more  a k2 policy (``k2``, ratio, Poisson)    ``k1``, least squares over the modes
two or more  a tip position, no k2 policy            ``k1`` and ``k2``
two or more  ``fit_tip_position``                    ``k1`` and ``tip_position``; ``k2`` by the policy,
                                                     else 0 (the L1/L method of Rabe et al., NIST)
two or more  neither                                 not unique: ``(k1, k2)`` and ``(k1, tip_position)``
                                                     explain them equally, both given
===========  ======================================  ====================================================

The numerics are :mod:`pfmdyn.analysis.contact_resonance`'s (set-back, heavy and tilted tips);
each answer carries the argument for its uniqueness, its propagated standard uncertainties
and, on request, the Hertz reduced modulus.  :class:`StiffnessReport` has ``to_dict()``
(names of :mod:`pfmdyn.names`: ``k1``, ``k2``, ``tip_position``, ``k1_stderr``, ...) and
``report()`` (the printed text).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..cantilever import Cantilever, Contact
from ..constants import TIP_HEIGHT_SPREAD
from ..errors import UserError
from ..generated import formulas
from . import contact_resonance as cr
from ..digits import rounded
from .stiffness import out_of_range_message, reduced_modulus, reduced_modulus_uncertainty
from .tip_position import tip_position_scan

__all__ = ["TIP_POSITION_LOW", "assumed_variations", "TIP_HEIGHT_TOLERANCE", "ASSUMED_POISSON", "assumed_tie_uncertainty", "tip_height_spread",
           "Solution", "StiffnessReport", "analyse"]

TIP_POSITION_LOW = 0.7
"""Lowest tip position (x_tip / L) searched when the tip position is fitted."""
TIP_HEIGHT_TOLERANCE = 0.1
"""Default standard uncertainty of a tip height, relative: no file records it, datasheets give it
nominally (a tip height is a datasheet's value or a guess, and k1 can depend on it steeply)."""
ASSUMED_POISSON = (0.2, 0.4)
"""Poisson's ratios a sample may have when none is stated: the assumed Mindlin tie's ``k2/k1`` is
uniform over what they give (its standard uncertainty: half the range over sqrt 3)."""


def assumed_tie_uncertainty() -> float:
    """Standard uncertainty of an assumed Mindlin tie's ``k2/k1``: uniform over what the Poisson's ratios
    of :data:`ASSUMED_POISSON` give.

    >>> round(assumed_tie_uncertainty(), 4)
    0.0401
    """
    ties = [formulas.mindlin_k2_over_k1(nu) for nu in ASSUMED_POISSON]
    return float(abs(ties[0] - ties[1]) / 2 / math.sqrt(3))
def tip_height_spread(tip_height: float, assumed: bool) -> float:
    """Standard uncertainty (m) every command takes for a tip height whose own is not given: the assumed one's
    spread (:data:`pfmdyn.constants.TIP_HEIGHT_SPREAD`), else :data:`TIP_HEIGHT_TOLERANCE` of a given one.

    >>> tip_height_spread(13e-6, True), round(tip_height_spread(20e-6, False), 12)
    (2.5e-06, 2e-06)
    """
    return TIP_HEIGHT_SPREAD if assumed else TIP_HEIGHT_TOLERANCE * tip_height


def assumed_variations(lever: Cantilever, stated: Contact, contact: Contact, assumed,
                       k1_uncertainty: float = 0.0) -> dict:
    """The inputs a command assumed, each moved down and up by its standard uncertainty (input ->
    ``((lever, contact), (lever, contact))``), for the spread of a result over them: the tip height (an assumed one's
    spread, else :data:`TIP_HEIGHT_TOLERANCE` of a given one, as ``stiffness`` takes it; ``assumed`` names what was
    assumed), a k2 tie that ``contact`` has and the ``stated`` contact had not (Mindlin over
    :data:`ASSUMED_POISSON`), and k1 by its ``k1_uncertainty`` when one is given (a tied k2 moves with it).

    >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=13e-6)
    >>> moved = assumed_variations(lever, Contact(k1=100.0), Contact(k1=100.0, poisson=0.3), ["tip_height"])
    >>> [round(l.tip_height * 1e6, 1) for l, _ in moved["tip_height_uncertainty"]], sorted(moved)
    ([10.5, 15.5], ['k2_policy_uncertainty', 'tip_height_uncertainty'])
    >>> [c.k1 for _, c in assumed_variations(lever, Contact(k1=100.0), Contact(k1=100.0), [], 4.0)["k1_uncertainty"]]
    [96.0, 104.0]
    >>> assumed_variations(lever, Contact(k1=100.0), Contact(k1=100.0), [], 100.0)
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: k1's uncertainty (100 N/m) must be below k1 (100 N/m): a spread that reaches k1 = 0 is no standard uncertainty
    """
    out = {}
    if lever.tip_height is not None:
        u = tip_height_spread(lever.tip_height, "tip_height" in assumed)
        out["tip_height_uncertainty"] = tuple((replace(lever, tip_height=lever.tip_height + s * u), contact)
                                              for s in (-1, 1))
    if stated.k2 is None and stated.ratio is None and contact.ratio is not None:
        u = assumed_tie_uncertainty()
        out["k2_policy_uncertainty"] = tuple((lever, Contact(k1=contact.k1, k2_over_k1=contact.ratio + s * u,
                                                             contact_loss=contact.contact_loss)) for s in (-1, 1))
    if k1_uncertainty:
        if not k1_uncertainty < contact.k1:
            raise UserError(f"k1's uncertainty ({k1_uncertainty:g} N/m) must be below k1 ({contact.k1:g} N/m): a spread "
                            "that reaches k1 = 0 is no standard uncertainty", quantity="k1_uncertainty")
        out["k1_uncertainty"] = tuple((lever, replace(contact, k1=contact.k1 + s * k1_uncertainty)) for s in (-1, 1))
    return out


_SAME = 1e-7           # relative difference below which two solutions are one


@dataclass(frozen=True)
class Solution:
    """One set of contact springs and tip position explaining the resonances.

    ``unknowns`` are the quantities solved for (their standard uncertainties in ``stderr``);
    ``k2`` is None when it cannot act (no tip height, no tilt); ``residual`` is the RMS shift
    in ``beta`` from the measured resonances to the model's.
    """

    k1: float
    k2: float | None
    tip_position: float
    unknowns: tuple[str, ...]
    stderr: dict
    residual: float = 0.0
    k1_by_mode: tuple[float, ...] = ()
    reduced_modulus: float | None = None
    reduced_modulus_stderr: float | None = None
    sources: dict = field(default_factory=dict)
    """Input (:data:`pfmdyn.analysis.contact_resonance.SOURCES`) -> unknown -> its standard uncertainty
    from that input alone."""

    def to_dict(self) -> dict:
        """Names -> values (SI), with ``<name>_stderr`` for each unknown.

        >>> Solution(300.0, 0.0, 0.93, ("k1", "tip_position"), {"k1": 1.0, "tip_position": 1e-4}).to_dict()["k1_stderr"]
        1.0
        """
        out = {"k1": self.k1, "k2": self.k2, "tip_position": self.tip_position, "unknowns": list(self.unknowns)}
        out.update({f"{name}_stderr": self.stderr[name] for name in self.unknowns})
        if self.sources:
            out["stderr_sources"] = {source: dict(parts) for source, parts in self.sources.items()}
        out["residual_beta"] = self.residual
        if self.k1_by_mode:
            out["k1_by_mode"] = list(self.k1_by_mode)
        if self.reduced_modulus is not None:
            out.update(reduced_modulus=self.reduced_modulus, reduced_modulus_stderr=self.reduced_modulus_stderr)
        return out

    def k1_over_k_stderr(self, spring_constant: float) -> float:
        """k1/k's standard uncertainty: k1's from every input but the spring constant, which k1 scales with.

        >>> Solution(300.0, 0.0, 1.0, ("k1",), {"k1": 5.0}, sources={"spring_constant_uncertainty": {"k1": 4.0},
        ...     "tip_height_uncertainty": {"k1": 3.0}}).k1_over_k_stderr(3.0)
        1.0
        """
        if not self.sources:
            return self.stderr.get("k1", 0.0) / spring_constant
        return math.hypot(*(parts.get("k1", 0.0) for source, parts in self.sources.items()
                            if source != "spring_constant_uncertainty")) / spring_constant

    def lines(self, spring_constant: float, assumed=()) -> list[str]:
        """The solution as printed lines, the inputs whose uncertainty was ``assumed`` marked so.

        >>> Solution(300.0, 0.0, 0.93, ("k1", "tip_position"), {"k1": 1.0, "tip_position": 1e-4}).lines(3.0)[0]
        'k1 = 300.0 +- 1 N/m  (k1/k = 100.00 +- 0.33)'
        """
        def pm(name):
            sigma = self.stderr.get(name, 0.0)
            return f" +- {sigma:.2g}" if sigma > 0 else ""

        def value(name, v):         # to the second significant digit of its uncertainty (k1's, relative), else six digits
            rel = self.stderr.get(name, 0.0) / abs(self.k1 if name == "k1" else v) if v else 0.0
            return rounded(v, rel * abs(v))
        ratio, ratio_stderr = self.k1 / spring_constant, self.k1_over_k_stderr(spring_constant)
        out = [f"k1 = {value('k1', self.k1)}{pm('k1')} N/m  (k1/k = {rounded(ratio, ratio_stderr)}"
               + (f" +- {ratio_stderr:.2g})" if ratio_stderr > 0 else ")")]
        shares = {source: parts["k1"] / self.k1 for source, parts in self.sources.items() if parts.get("k1", 0) > 0}
        if len(shares) > 1 or any(name in shares for name in ("tip_height_uncertainty", "k2_policy_uncertainty",
                                                              *assumed)):
            out.append("  k1's uncertainty, input by input: " + ", ".join(
                f"{_SOURCE_WORDS[name]}{' (assumed)' * (name in assumed)} {share:.1%}" for name, share in sorted(shares.items(), key=lambda kv: -kv[1])))
        if self.k2 is not None:
            out.append(f"k2 = {value('k2' if 'k2' in self.unknowns else 'k1', self.k2)}{pm('k2')} N/m" + ("" if "k2" in self.unknowns else "  (by the k2 policy)"))
        out.append(f"tip_position = {self.tip_position:.6g}{pm('tip_position')}"
                   + ("" if "tip_position" in self.unknowns else "  (held)"))
        if self.k1_by_mode:
            out.append("k1 from each mode alone: " + ", ".join(f"{v:.6g}" for v in self.k1_by_mode) + " N/m")
        if self.reduced_modulus is not None:
            out.append(f"E* = {self.reduced_modulus:.6g} +- {self.reduced_modulus_stderr:.2g} Pa  (Hertz)")
        return out


_SOURCE_WORDS = {"contact_uncertainty": "contact resonances", "free_resonance_uncertainty": "free resonance",
                 "spring_constant_uncertainty": "spring constant", "tip_height_uncertainty": "tip height",
                 "k2_policy_uncertainty": "k2 policy", "mode_disagreement": "the modes' disagreement"}


def _finite(value):
    return value if not isinstance(value, float) or math.isfinite(value) else None


@dataclass(frozen=True)
class StiffnessReport:
    """What the contact resonances say about the contact: the solution(s), why, and the inputs.

    ``unique`` is True when exactly one solution explains the resonances under what was
    stated; then :attr:`solution` is it.  Otherwise ``solutions`` holds every one found.
    """

    lever: Cantilever
    contact_hz: tuple[float, ...]
    modes: tuple[int, ...]
    k2_policy: str
    solutions: tuple[Solution, ...]
    unique: bool
    proof: tuple[str, ...]
    notes: tuple[str, ...] = ()
    uncertainties: dict = field(default_factory=dict)
    assumed: tuple[str, ...] = ()
    """The inputs (:data:`pfmdyn.analysis.contact_resonance.SOURCES`) whose uncertainty was assumed."""

    @property
    def solution(self) -> Solution | None:
        """The unique solution, or None."""
        return self.solutions[0] if self.unique else None

    def to_dict(self) -> dict:
        """The report as names -> values; ``k1`` and the rest are None unless the solution is unique.

        >>> d = analyse(Cantilever(2.0, 75e3, 2e-4), Contact(), [300e3]).to_dict()
        >>> round(d["k1"], 4), d["unique"], d["inputs"]["contact_hz"]
        (109.7483, True, [300000.0])
        """
        out = dict.fromkeys(("k1", "k1_stderr", "k2", "k2_stderr", "tip_position", "tip_position_stderr"))
        if self.unique:
            out.update(self.solution.to_dict())
            out["k1_over_k"] = self.solution.k1 / self.lever.spring_constant
            out["k1_over_k_stderr"] = self.solution.k1_over_k_stderr(self.lever.spring_constant)
        out.update(unique=self.unique, k2_policy=self.k2_policy, proof=list(self.proof), notes=list(self.notes),
                   solutions=[s.to_dict() for s in self.solutions])
        inputs = {k: _finite(v) for k, v in self.lever.to_dict().items()}
        inputs.update(contact_hz=list(self.contact_hz), modes=list(self.modes), **self.uncertainties)
        out["inputs"] = inputs
        return out

    def report(self) -> str:
        """The printed text: the solution (or each candidate), the k2 policy, the argument, notes.

        >>> print(analyse(Cantilever(2.0, 75e3, 2e-4), Contact(), [300e3]).report().splitlines()[0])
        k1 = 109.748 N/m  (k1/k = 54.8741)
        """
        k = self.lever.spring_constant
        if self.unique:
            lines = self.solution.lines(k, self.assumed)
        else:
            k1s = sorted(s.k1 for s in self.solutions)
            spread = f" (k1 from {k1s[0]:.6g} to {k1s[-1]:.6g} N/m)" if len(k1s) > 1 else ""
            lines = ["not unique: " + (f"{len(self.solutions)} solution(s) reproduce the resonances{spread}, see why"
                                       if self.solutions else "no solution found")]
            for i, s in enumerate(self.solutions, 1):
                lines += [f"solution {i}:"] + ["  " + line for line in s.lines(k, self.assumed)]
        if not any(s.stderr.get("k1", 0.0) > 0 for s in self.solutions):
            lines.append("(no uncertainty given: contact_uncertainty, free_resonance_uncertainty, "
                         "spring_constant_uncertainty)")
        lines.append(f"k2 policy: {self.k2_policy}")
        lines += [f"why: {text}" for text in self.proof]
        lines += [f"note: {text}" for text in self.notes]
        return "\n".join(lines)


def _check_inputs(contact_hz, modes, stderrs):
    fc = np.asarray(contact_hz, dtype=float)
    if fc.ndim != 1 or not len(fc):
        raise UserError("no contact resonance (Hz)", quantity="contact")
    if not (np.all(np.isfinite(fc)) and np.all(fc > 0)):
        raise UserError("contact resonances must be positive and finite (Hz)")
    modes = list(range(1, len(fc) + 1)) if modes is None else [int(m) for m in modes]
    if len(modes) != len(fc):
        raise UserError(f"{len(fc)} contact resonances but {len(modes)} mode numbers")
    if len(set(modes)) != len(modes) or min(modes) < 1:
        raise UserError(f"contact mode numbers must be distinct and >= 1, got {modes}")
    for name, value in stderrs.items():
        if np.ndim(value) and np.shape(value) != fc.shape:
            raise UserError(f"{len(fc)} contact resonances but {np.size(value)} values of {name}")
        if not (np.all(np.isfinite(value)) and np.all(np.asarray(value) >= 0)):
            raise UserError(f"{name} must be non-negative and finite, got {value}")
    return fc, modes


def _lateral(lever: Cantilever, contact: Contact, default: str) -> tuple[Contact, str]:
    """The k2 law and its words: stated, else ``default`` ("tie": :meth:`Contact.policy`, the commands'
    one; "zero": the L1/L method's k2 = 0)."""
    stated_nonzero = (contact.k2 or 0.0) > 0 or (contact.ratio or 0.0) > 0
    if stated_nonzero:
        cr.require_tip_height(lever, "a lateral contact stiffness k2")
    if default == "zero" and contact.k2 is None and contact.ratio is None and not (
            lever.tip_height is None and lever.tilt == 0.0):
        return Contact(), ("k2 = 0, the L1/L method's assumption (give k2, k2_over_k1 or poisson to "
                           "include it)")
    return Contact(k2=contact.k2, k2_over_k1=contact.k2_over_k1, poisson=contact.poisson).policy(lever)


def _same(a: dict, b: dict) -> bool:
    return all(abs(a[n] - b[n]) <= _SAME * max(abs(a[n]), abs(b[n]), 1e-300) for n in a)


def _keep(lever, lateral, fc, modes, candidates, check_modes: bool = True) -> list[tuple[dict, float]]:
    """Candidates polished on all modes, kept when their modes match, duplicates dropped."""
    out = []
    for start in candidates:
        values, rms = cr.fit(lever, lateral, fc, start)
        if not check_modes:
            out.append((values, rms))
            continue
        gamma = values.get("tip_position", lever.tip_position)
        k2 = values["k2"] if "k2" in values else lateral.k2_of(values["k1"])
        placed = replace(lever, tip_position=gamma)
        # The model's resonance nearest each measured one (they differ in a least-squares fit).
        nearest = cr.betas(placed, fc) + cr.beta_shifts(lever, lateral, fc, values)
        found = cr.mode_numbers(nearest, placed, values["k1"], k2, gamma)
        if np.array_equal(found, modes) and not any(_same(values, v) for v, _ in out):
            out.append((values, rms))
    return out


def _out_of_range(lever, lateral, words, fc, mode) -> UserError:
    b1 = lever.free_root()
    ratio_of = lambda b: formulas.frequency_from_beta(b, 1.0, b1)      # noqa: E731
    soft, stiff = cr.branch_limits(mode, lever, lateral, lever.tip_position)
    next_soft = cr.branch_limits(mode + 1, lever, lateral, lever.tip_position)[0]
    return UserError(out_of_range_message(fc / lever.free_resonance, mode, ratio_of(soft), ratio_of(stiff),
                                          ratio_of(next_soft), words))


def _k1_only(lever, lateral, words, fc, modes):
    b = cr.betas(lever, fc)
    k1s = [float(cr.k1_at(bi, m, lever, lateral, lever.tip_position)) for bi, m in zip(b, modes)]
    for f, m, k1 in zip(fc, modes, k1s):
        if not math.isfinite(k1):
            raise _out_of_range(lever, lateral, words, f, m)
    # Each mode's own k1 has its mode number checked; their least-squares compromise need not
    # reproduce any resonance exactly, so its modes are not counted again.
    found = _keep(lever, lateral, fc, modes, [{"k1": float(np.median(k1s))}], check_modes=False)
    degree = "2 (k2 tied to k1)" if lateral.ratio else "1 (k2 fixed)"
    proof = [f"mode {m}: at the measured frequency the characteristic is a polynomial of degree {degree} in k1; of "
             f"its positive roots exactly one puts the resonance at mode {m} (the roots below it counted): one k1"
             for m in modes]
    if len(fc) > 1:
        proof.append("k1 is the least-squares value over the modes (each mode's own k1 is shown)")
    return found, proof, tuple(k1s) if len(fc) > 1 else ()


def _decide(found, fc, noise_beta: float) -> tuple[list, list[str]]:
    """With more modes than unknowns, drop the solutions whose misfit is over 10 times the best."""
    if len(fc) <= 2 or len(found) <= 1:
        return found, []
    best = min(rms for _, rms in found)
    kept = [(v, rms) for v, rms in found if rms <= max(10 * best, 3 * noise_beta, 1e-10)]
    if len(kept) == len(found):
        return found, []
    return kept, [f"the other modes rule out {len(found) - len(kept)} of the {len(found)} solutions of the first two "
                  "(their misfit is over 10 times the best)"]


def _k1_k2(lever, fc, modes, noise_beta: float):
    cr.require_tip_height(lever, "k1 and k2 from two modes")
    b = cr.betas(lever, fc)
    candidates = cr.k1_k2_at(b[:2], modes[:2], lever, lever.tip_position)
    found = _keep(lever, Contact(), fc, modes, [{"k1": k1, "k2": k2} for k1, k2 in candidates])
    proof = [f"modes {modes[0]} and {modes[1]} with the tip at {lever.tip_position:g} L: the characteristic is "
             f"bilinear in (k1, k2); eliminating k2 leaves a quadratic in k1 with {len(candidates)} root(s) giving "
             f"k1 > 0, k2 >= 0, {len(found)} of them with the measured mode numbers"
             + (": unique" if len(found) == 1 else ": a third contact mode decides" if len(fc) == 2 else "")]
    found, decided = _decide(found, fc, noise_beta)
    return found, proof + decided


def _k1_tip(lever, lateral, fc, modes, noise_beta: float):
    crossings = tip_position_scan(lever, lateral, fc, modes, low=TIP_POSITION_LOW)
    found = _keep(lever, lateral, fc, modes,
                  [{"k1": k1, "tip_position": g} for g, k1 in zip(crossings.tip_positions, crossings.k1)
                   if math.isfinite(k1)])
    more = ["a third contact mode decides between them"] if len(found) > 1 and len(fc) == 2 else []
    found, decided = _decide(found, fc, noise_beta)
    return found, [crossings.text()] + more + decided, crossings.confirmed_points > 0


def _two_readings(lever, fc, modes, noise_beta: float):
    """Neither a k2 policy nor a tip position: (k1, k2) at the lever's tip position and (k1, tip position) at k2 = 0."""
    pairs, proof_pairs = [], ["(k1, k2) not computed: k2 acts through the tip height, not given"]
    if lever.tip_height is not None:
        pairs, proof_pairs = _k1_k2(lever, fc, modes, noise_beta)
    tips, proof_tips, _ = _k1_tip(lever, Contact(), fc, modes, noise_beta)
    both = ": both explain them equally" if pairs and tips else ""
    proof = ([f"{len(fc)} contact modes with neither a k2 policy nor a tip position: k1, k2 and the tip position are "
              "three unknowns, so no answer is unique; the two usual readings are (k1, k2) with the tip at "
              f"{lever.tip_position:g} L and (k1, tip position) with k2 = 0{both}; give k2, k2_over_k1 or "
              "poisson, or tip_position (a number, or fit)"] + proof_pairs + proof_tips)
    return pairs + tips, proof


def _solution(lever, lateral, fc, values, rms, stderrs, k1_by_mode=(), hertz=None) -> Solution:
    gamma = values.get("tip_position", lever.tip_position)
    placed = replace(lever, tip_position=gamma)
    parts = cr.covariance_by_source(placed, lateral, fc, values, stderrs)
    cov = sum(parts.values(), np.zeros((len(values), len(values))))
    sigma = {n: float(math.sqrt(max(cov[i, i], 0.0))) for i, n in enumerate(values)}
    sources = {source: {n: float(math.sqrt(max(c[i, i], 0.0))) for i, n in enumerate(values)}
               for source, c in parts.items()}
    k1 = values["k1"]
    acts = lever.tip_height is not None or lever.tilt != 0.0
    k2 = values["k2"] if "k2" in values else (float(lateral.k2_of(k1)) if acts else None)
    e_star = e_sigma = None
    if hertz is not None:
        radius, load = hertz
        e_star = float(reduced_modulus(k1, radius, load))
        e_sigma = float(reduced_modulus_uncertainty(k1, sigma["k1"], radius, load))
    return Solution(k1, k2, gamma, tuple(values), sigma, rms, tuple(k1_by_mode), e_star, e_sigma, sources)


def _with_mode_disagreement(solution: Solution) -> Solution:
    """``solution`` with the modes' disagreement, which no propagated input explains, in k1's uncertainty: the
    standard error of the mean of each mode's own k1 (``mode_disagreement`` in the budget).

    >>> s = _with_mode_disagreement(Solution(222.0, 0.0, 1.0, ("k1",), {"k1": 1.1}, k1_by_mode=(101.0, 227.0)))
    >>> round(s.stderr["k1"], 1), round(s.sources["mode_disagreement"]["k1"], 1)
    (63.0, 63.0)
    """
    k1s = np.asarray(solution.k1_by_mode, float)
    spread = float(np.std(k1s, ddof=1) / math.sqrt(len(k1s)))
    return replace(solution, stderr={**solution.stderr, "k1": math.hypot(solution.stderr.get("k1", 0.0), spread)},
                   sources={**solution.sources, "mode_disagreement": {"k1": spread}})


def analyse(lever: Cantilever, contact: Contact, contact_hz, modes=None, *, fit_tip_position: bool = False,
            tip_position_stated: bool = True, contact_uncertainty=0.0,
            free_resonance_uncertainty: float = 0.0, spring_constant_uncertainty: float = 0.0,
            tip_height_uncertainty: float | None = None, hertz: tuple[float, float] | None = None,
            notes: tuple[str, ...] = (), assumed: tuple[str, ...] = ()) -> StiffnessReport:
    """Contact stiffness (and ``k2`` or the tip position) from contact resonances (Hz) of ``lever``.

    Parameters
    ----------
    lever : the probe (its ``free_resonance`` is the measured one, with the tip)
    contact : the k2 policy (``k1`` is ignored: it is the answer)
    contact_hz, modes : contact resonances (Hz) and their mode numbers (default 1, 2, ...)
    fit_tip_position : solve the tip position with ``k1`` (two or more modes)
    tip_position_stated : False when ``lever.tip_position`` is only the default (then two
        modes without a k2 policy are reported as not unique)
    contact_uncertainty, free_resonance_uncertainty, spring_constant_uncertainty :
        standard uncertainties (Hz, Hz, N/m), propagated to first order; the contact resonances' one for all, or
        one per resonance
    assumed : the inputs of :data:`pfmdyn.analysis.contact_resonance.SOURCES` whose uncertainty was assumed
        (said so beside their share)
    tip_height_uncertainty : standard uncertainty of the tip height (m; default
        :data:`TIP_HEIGHT_TOLERANCE` of it), propagated likewise; so is an assumed k2 policy's
        (:data:`ASSUMED_POISSON`), each input's share stated
    hertz : ``(tip radius m, load N)`` to add the Hertz reduced modulus
    notes : sentences added to the report

    Examples
    --------
    >>> lever = Cantilever(2.0, 75e3, 2e-4)
    >>> r = analyse(lever, Contact(), [300e3], contact_uncertainty=100.0)
    >>> round(r.solution.k1, 4), round(r.solution.stderr["k1"], 4), r.unique
    (109.7483, 0.393, True)
    """
    per_resonance = np.asarray(contact_uncertainty, dtype=float)
    stderrs = {"contact_uncertainty": per_resonance.tolist() if per_resonance.ndim else float(per_resonance),
               "free_resonance_uncertainty": float(free_resonance_uncertainty),
               "spring_constant_uncertainty": float(spring_constant_uncertainty)}
    if lever.tip_height is not None:
        stderrs["tip_height_uncertainty"] = float(TIP_HEIGHT_TOLERANCE * lever.tip_height
                                                  if tip_height_uncertainty is None else tip_height_uncertainty)
    fc, modes = _check_inputs(contact_hz, modes, stderrs)
    if lever.tilt != 0.0:
        cr.require_tip_height(lever, "a tilt")
    policy = contact.k2 is not None or contact.ratio is not None
    notes = list(notes)
    k1_by_mode, settled = (), True
    # The beta shift that the frequency uncertainties alone would make (mode by mode, RMS).
    noise = float(np.sqrt(np.mean((0.5 * cr.betas(lever, fc) * np.hypot(
        per_resonance / fc, stderrs["free_resonance_uncertainty"] / lever.free_resonance)) ** 2)))
    if fit_tip_position:
        if len(fc) < 2:
            raise UserError("a fitted tip position needs two or more contact resonances, with their modes (or give "
                            "the tip position as a number)", quantity="contact")
        lateral, words = _lateral(lever, contact, "zero")
        found, proof, settled = _k1_tip(lever, lateral, fc, modes, noise)
    elif len(fc) == 1 or policy:
        lateral, words = _lateral(lever, contact, "tie")
        found, proof, k1_by_mode = _k1_only(lever, lateral, words, fc, modes)
        if not policy and lateral.ratio is not None:       # the tie is assumed: so is its ratio
            stderrs["k2_policy_uncertainty"] = assumed_tie_uncertainty()
    elif tip_position_stated:
        found, proof = _k1_k2(lever, fc, modes, noise)
        lateral, words = Contact(), "k2 solved with k1 from the modes"
    else:
        found, proof = _two_readings(lever, fc, modes, noise)
        lateral, words = Contact(), "none stated: k2 solved with k1, or k2 = 0 with the tip position solved"
        settled = False
    if k1_by_mode and found and found[0][1] > max(3 * noise, 1e-9):
        notes.append("the modes disagree beyond their uncertainties (k1 from each mode alone differs): the lever "
                     "(tip position, tip mass, tilt) or the k2 policy may be wrong; tip_position fit solves the tip "
                     "position with k1")
    if not found:
        raise UserError("no k1 > 0 of this lever model gives these contact resonances as modes "
                        f"{modes}: check the mode numbers, the free resonance and the lever (tip position, tip mass, "
                        "tilt)")
    solutions = tuple(_solution(lever, lateral, fc, v, rms, stderrs, k1_by_mode, hertz) for v, rms in found)
    if k1_by_mode and found[0][1] > max(3 * noise, 1e-9):
        solutions = tuple(_with_mode_disagreement(s) for s in solutions)
    unique = len(solutions) == 1 and settled
    return StiffnessReport(lever, tuple(map(float, fc)), tuple(modes), words, solutions, unique, tuple(proof),
                           tuple(notes), stderrs, tuple(assumed))
