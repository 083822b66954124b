"""Where on the lever the tip sits, from two contact resonances: fact 4 of
:mod:`pfmdyn.analysis.contact_resonance`.

At each tip position ``gamma`` each mode alone gives ``k1(gamma)`` exactly
(:func:`pfmdyn.analysis.contact_resonance.k1_at`); two modes are explained where their curves
cross.  Scanning ``gamma`` over a box and counting the crossings at two resolutions
(:func:`tip_position_scan`) shows whether the solution is unique there (the L1/L method of
Rabe et al., NIST).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..cantilever import Cantilever, Contact
from .contact_resonance import betas, branch_limits, k1_at

__all__ = ["Crossings", "tip_position_scan"]


@dataclass(frozen=True)
class Crossings:
    """Where the ``k1(gamma)`` curves of two modes cross on a tip-position grid (fact 4)."""

    tip_positions: tuple[float, ...]
    k1: tuple[float, ...]
    low: float
    points: int
    confirmed_points: int
    modes: tuple[int, int]

    def text(self) -> str:
        """The uniqueness argument in words.

        >>> Crossings((0.93,), (300.0,), 0.7, 101, 201, (1, 2)).text().split("positions: ")[-1]
        'one solution in the box: unique there (a search at two resolutions, not an interval proof)'
        """
        n = len(self.tip_positions)
        verdict = ("one solution in the box: unique there" if n == 1 else
                   "no solution in the box" if n == 0 else f"{n} solutions in the box: not unique")
        if self.confirmed_points < 0:
            again = f"but a different number of times at {2 * self.points - 1} positions: the count is not settled"
        else:
            again = f"the same at {self.confirmed_points} positions: {verdict}"
        return (f"k1 from mode {self.modes[0]} alone and from mode {self.modes[1]} alone at {self.points} "
                f"tip positions in [{self.low:g}, 1] (exact at each: a polynomial in k1, the mode fixed by counting "
                f"the roots below it); their curves cross {n} time(s), {again} (a search at two resolutions, not an "
                "interval proof)")


def _k1_curves(lever, contact, contact_hz, modes, gammas):
    """``k1`` of each mode alone at each tip position, and the same compactified to
    ``s = k1 / (k1 + k)``, continued past the branch: ``-(soft - beta) / soft`` below its soft
    limit (no ``k1`` is small enough), ``1 + (beta - stiff) / stiff`` above its stiff limit
    (none is large enough).  So ``s`` is continuous in ``gamma`` and its curves of two modes
    change order exactly where they cross, even where both run off to ``k1 -> oo``."""
    b = np.stack([betas(lever, f, gammas) for f in contact_hz])
    k1 = np.stack([k1_at(b[i], m, lever, contact, gammas) for i, m in enumerate(modes)])
    s = k1 / (k1 + lever.spring_constant)
    for i, m in enumerate(modes):
        for j in np.flatnonzero(np.isnan(k1[i])):
            soft, stiff = branch_limits(m, lever, contact, float(gammas[j]))
            beta = b[i][j]
            s[i][j] = -(soft - beta) / soft if beta <= soft else 1.0 + (beta - stiff) / stiff
    return k1, s


def _crossings(lever, contact, contact_hz, modes, gammas):
    _, s = _k1_curves(lever, contact, contact_hz[:2], modes[:2], gammas)
    d = s[1] - s[0]
    brackets = [i for i in range(len(gammas) - 1) if d[i] * d[i + 1] < 0]
    brackets += [i - 0.5 for i in range(len(gammas)) if d[i] == 0.0]
    return sorted(brackets)


def tip_position_scan(lever: Cantilever, contact: Contact, contact_hz, modes, low: float = 0.5,
                      points: int = 101) -> Crossings:
    """``(tip_position, k1)`` explaining the first two resonances, by crossing their ``k1(gamma)`` curves.

    The curves, compactified to ``k1 / (k1 + k)`` and continued past their branches (so that
    a branch running off to ``k1 -> oo`` near the solution stays continuous), are evaluated at
    ``points`` tip positions in ``[low, 1]``; each sign change of their difference is refined
    by Brent's method and kept where both modes have a ``k1``, and the count is confirmed on a
    grid of ``2 points - 1`` positions (module, fact 4).

    >>> from pfmdyn.analysis.contact_resonance import characteristic
    >>> from pfmdyn.roots.bracket import grid_roots
    >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5)   # tip at 0.9 L, k1 = 100 N/m, k2 = 0
    >>> b = grid_roots(lambda x: characteristic(x, lever, 100.0, 0.0, 0.9), np.arange(1, 9, 0.01))[:2]
    >>> c = tip_position_scan(lever, Contact(), 7e4 * (b / lever.free_root()) ** 2, (1, 2), low=0.8)
    >>> [round(g, 9) for g in c.tip_positions], [round(k, 6) for k in c.k1]
    ([0.9], [100.0])
    """
    from scipy.optimize import brentq

    def curves(g):
        return _k1_curves(lever, contact, contact_hz[:2], modes[:2], np.array([g]))

    def crossings(count):
        gammas = np.linspace(low, 1.0, count)
        found = []
        for i in _crossings(lever, contact, contact_hz, modes, gammas):
            if i != int(i):                                # a grid point on the crossing
                g = float(gammas[int(i + 0.5)])
            else:
                g = brentq(lambda x: float(np.diff(curves(x)[1][:, 0])[0]), gammas[i], gammas[i + 1],
                           xtol=1e-15, rtol=1e-15)
            # Where the continued curves cross beyond a branch, no k1 explains either mode.
            if np.all(np.isfinite(curves(g)[0])):
                found.append(g)
        return found

    found = crossings(points)
    finer = crossings(2 * points - 1)
    k1 = [float(curves(g)[0][0, 0]) for g in found]
    return Crossings(tuple(found), tuple(k1), low, points, 2 * points - 1 if len(finer) == len(found) else -1,
                     (int(modes[0]), int(modes[1])))
