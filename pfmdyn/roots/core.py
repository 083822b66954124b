"""Certified resonance roots of every family, to any number of digits (ball arithmetic).

The resonances of a family are the real zeros ``z > 0`` of its characteristic function in
:mod:`pfmdyn.generated.characteristic` (``z = beta`` for flexure, ``z = xi L`` for
torsion).  The scaled forms vanish at ``z = 0`` as well (the beam at rest, not a mode),
so **a root is a zero with z > 0**; the zero at the origin is never reported.

How a list of roots is certified: :mod:`pfmdyn.derivations.certify` (exact series near the origin,
complete isolation with ``arb_series.find_roots``, interval Newton refinement).

When any proof fails (a double root, an undecidable sign, fewer roots than asked below the
search limit) the result says ``certified = False`` with the reason and carries no numbers.

Parameters (dimensionless, non-negative): ``k1_over_k`` = k1/k (vertical contact stiffness
over the cantilever spring constant), ``k2_ratio`` = k2 H**2/(k L**2) (longitudinal contact
stiffness through the lever arm H), ``k2t_HL`` = H**2 k2 L / c_T (lateral contact stiffness
over the torsional stiffness).

References: Jesse, Baddorf, Kalinin (2006), Eqs. 5, 20-22, 28, 33, 35.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import flint

from ..derivations.certify import CertificationError, certify, floor_string, interval_strings, rounded
from ..generated import characteristic, families

__all__ = ["FAMILIES", "PARAMETER_HELP", "CertificationError", "RootResult", "characteristic_function",
           "certify", "family_roots", "interval_strings"]

PARAMETER_HELP = {name: families.PARAMETER_HELP[name]
                  for name in sorted({p for ps in characteristic.PARAMETERS.values() for p in ps})}
"""Dimensionless parameter name -> definition."""


FAMILIES = dict(characteristic.FAMILIES)
"""Family name -> characteristic function ``f(z, m, **params)``."""


@dataclass(frozen=True)
class RootResult:
    """Roots of one characteristic equation, each with an interval proven to hold exactly it.

    ``roots`` are decimal strings with ``digits`` significant digits, ``intervals`` pairs of
    decimal strings rounded outward; both are empty when ``certified`` is false.  ``z_max``
    is the end of the range on which the list is proven complete; ``balls`` keeps the
    certified ``arb`` enclosures for callers that go on computing with them.
    """

    family: str
    parameters: dict
    digits: int
    roots: tuple = ()
    intervals: tuple = ()
    certified: bool = False
    reason: str = ""
    z_max: str = ""
    balls: tuple = field(default=(), repr=False, compare=False)

    def to_json(self) -> dict:
        """The JSON document ``pfmdyn roots`` writes.

        >>> family_roots("free", 1, 5).to_json()["roots"]
        ['1.8751']
        """
        out = {"family": self.family, "parameters": dict(self.parameters), "roots": list(self.roots),
               "intervals": [list(i) for i in self.intervals], "certified": self.certified}
        if not self.certified:
            out["reason"] = self.reason
        return out


def characteristic_function(family: str, **params):
    """The family's characteristic function of ``(z, m)`` with its parameters bound.

    Parameters are given as decimal strings or numbers and kept exact (``fmpq``), so the
    same function serves exact series at 0, ``arb`` balls and ``arb_series`` (pass
    ``m = characteristic.FLINT``).

    >>> f = characteristic_function("torsion-elastic", k2t_HL="0.5")
    >>> f(flint.fmpq_series([0, 1], prec=4), characteristic.FLINT)
    3/2*x + (-7/12)*x^3 + O(x^4)
    """
    if family not in FAMILIES:
        raise KeyError(f"unknown family {family!r}; choose from {', '.join(FAMILIES)}")
    names = characteristic.PARAMETERS[family]
    missing = [n for n in names if params.get(n) is None]
    if missing:
        raise KeyError(f"family {family!r} needs {', '.join(missing)}")
    exact = {n: _fmpq(params[n]) for n in names}
    base = FAMILIES[family]
    return lambda z, m: base(z, m, **exact)


def _fmpq(value) -> flint.fmpq:
    q = Fraction(str(value))
    return flint.fmpq(q.numerator, q.denominator)


def _on_series(f):
    # find_roots and interval Newton call f(series) alone: bind the python-flint namespace.
    return lambda s: f(s, characteristic.FLINT)


def family_roots(family: str, n: int, digits: int, **params) -> RootResult:
    """The first ``n`` resonance roots of a family, certified, to ``digits`` significant digits.

    Parameters
    ----------
    family : one of :data:`FAMILIES`
    n : number of roots (z > 0, counted from the lowest)
    digits : significant digits of each decimal string (correctly rounded)
    **params : the family's dimensionless parameters (see :data:`PARAMETER_HELP`),
        as numbers or decimal strings; they are used exactly.

    Returns
    -------
    RootResult
        with ``certified = False`` and a ``reason`` (and no numbers) when a proof fails.

    Examples
    --------
    >>> family_roots("free", 3, 12).roots
    ('1.87510406871', '4.69409113297', '7.85475743824')
    >>> family_roots("torsion-elastic", 1, 8, k2t_HL=1).roots
    ('2.0287578',)
    """
    f_exact = characteristic_function(family, **params)
    used = {name: str(params[name]) for name in characteristic.PARAMETERS[family]}
    f = _on_series(f_exact)
    old = flint.ctx.prec
    try:
        balls, z_max = certify(f, n, digits, f_exact=lambda s: f_exact(s, characteristic.FLINT))
        texts = []
        for i, ball in enumerate(balls):
            balls[i], text = rounded(f, ball, digits)
            texts.append(text)
    except CertificationError as exc:
        return RootResult(family, used, digits, reason=str(exc))
    finally:
        flint.ctx.prec = old
    return RootResult(family, used, digits, tuple(texts), tuple(interval_strings(b, digits + 3) for b in balls),
                      True, "", floor_string(z_max, 6), tuple(balls))
