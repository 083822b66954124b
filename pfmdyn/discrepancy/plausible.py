"""Whether a fitted effect is physically possible for the lever, and so a finding at all.

A greedy search can lower the misfit with values no cantilever has: a tip heavier than twice
the beam, a lateral contact stiffness five decades below the normal one, a parameter pressed
against its bound (the search wanted to go further than the library allows).  Such a fit
says that the misfit is real but that the effect did not explain it: the discrepancy loop
(:func:`pfmdyn.discrepancy.select.run`) drops the effect and reports the misfit as
``unexplained``.
"""
from __future__ import annotations

import numpy as np

from .effects import EFFECTS

__all__ = ["MAX_TIP_MASS_RATIO", "MIN_K2_OVER_K1", "implausible", "describe"]

MAX_TIP_MASS_RATIO = 2.0
"""Tip mass / beam mass above which a tip is not a tip (AFM tips weigh 0-50 % of the beam)."""
MIN_K2_OVER_K1 = 1e-5
"""``k2 / k1`` below which the lateral spring is absurd for a tip in contact (Mindlin: 0.7-0.9;
sliding or a soft layer lower it by a few decades at most)."""
AT_BOUND = 1e-3
"""A parameter within this fraction of its range from a bound is at the bound."""
MOVING = tuple(name for name, e in EFFECTS.items() if e.moves_resonances)
"""Effects that move the resonances: absurd springs blame these (the springs absorbed them)."""


def _at_bound(p, value: float, null: float | None) -> str | None:
    """'lower'/'upper' when ``value`` (internal) sits at a bound that is not the null value."""
    span = p.upper - p.lower
    for side, bound in (("lower", p.lower), ("upper", p.upper)):
        if abs(value - bound) <= AT_BOUND * span and (null is None or abs(null - bound) > AT_BOUND * span):
            return side
    return None


def implausible(fit) -> dict[str, str]:
    """Effect components of ``fit`` whose fitted values are absurd for the lever, with why.

    >>> from types import SimpleNamespace as S
    >>> from pfmdyn.discrepancy.model import Model
    >>> meta = S(spring_constant=0.5, length=1.6e-4, tip_height=1e-5, free_resonance=2e4)
    >>> model = Model(meta, ("tip_mass",))
    >>> implausible(S(model=model, internal=np.array([1.0, 0.0, 2.2]), fitted=None))["tip_mass"]
    'tip mass 2.2 times the beam mass (at most 2 is a tip)'
    >>> implausible(S(model=model, internal=np.array([1.0, 0.5, 0.3]), fitted=None))
    {}
    """
    params = fit.model.parameters
    fitted = fit.fitted if getattr(fit, "fitted", None) is not None else np.ones(len(params), bool)
    values = {p.name: (p, float(v)) for p, v, f in zip(params, fit.internal, fitted) if f}
    out: dict[str, str] = {}
    for component in fit.model.effects:
        effect = EFFECTS[component]
        for p, null in zip(effect.parameters, effect.null):
            if p.name not in values:
                continue
            side = _at_bound(p, values[p.name][1], null)
            if side:
                out[component] = (f"{p.key} = {p.value(values[p.name][1]):.3g} at the {side} bound of the "
                                  "library: the fit wanted a value beyond it")
        if component == "tip_mass" and "mu" in values and values["mu"][1] > MAX_TIP_MASS_RATIO:
            out[component] = (f"tip mass {values['mu'][1]:.2g} times the beam mass "
                              f"(at most {MAX_TIP_MASS_RATIO:g} is a tip)")
    springs = []
    if "k1" in values and "k2" in values:
        ratio = 10.0 ** (values["k2"][1] - values["k1"][1])
        if ratio < MIN_K2_OVER_K1:
            springs.append(f"k2 = {ratio:.2g} k1 (below {MIN_K2_OVER_K1:g} k1)")
    if springs:
        for component in fit.model.effects:
            if component in MOVING and component not in out:
                out[component] = "the springs it needs are absurd: " + "; ".join(springs)
    return out


def describe(reasons: dict[str, str]) -> str:
    """One sentence for the report.

    >>> describe({"tip_mass": "tip mass 2.2 times the beam mass"})
    'implausible for the lever, not a finding: tip_mass (tip mass 2.2 times the beam mass)'
    """
    return "implausible for the lever, not a finding: " + "; ".join(f"{c} ({why})" for c, why in reasons.items())

