"""Nonlinear fit parameters: public name, unit, internal transform, bounds, null value, seeds.

A fit moves an *internal* coordinate; reports give the *value* under the public name
(:mod:`pfmdyn.names`).  Three transforms cover pfmdyn's parameters:

* ``log10``: springs and quality factors (decades apart between levers; one log base
  everywhere), value ``10**internal``;
* ``inverse``: a loss factor ``1/Q``, so that 0 (no loss, ``Q`` infinite) is an ordinary point;
* ``linear``: value ``scale * internal`` (the tilt: the derivations' angle in rad is minus the
  public tilt in degrees, ``scale = -180/pi``).

``null`` is the internal value at which the parameter switches its effect off (no loss, no
tip mass, tip at the free end): a bound equal to the null is not a bound the data push against.
``seeds`` are internal values to start fresh fits from.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..names import NAMES

__all__ = ["Parameter", "VISCOUS_LOSS", "FLUID_LOSS", "CONTACT_LOSS", "INTERNAL_LOSS", "bounds"]

LN10 = math.log(10.0)


@dataclass(frozen=True)
class Parameter:
    """A nonlinear parameter (see module docstring); ``lower``, ``upper``, ``null`` and ``seeds``
    are internal coordinates.

    >>> p = Parameter("k1", "N/m", 0.0, 6.0, transform="log10")
    >>> p.value(2.0), float(p.internal(1e3)), p.key
    (100.0, 3.0, 'k1')
    """

    name: str
    unit: str
    lower: float
    upper: float
    transform: str = "linear"
    description: str = ""
    """What it is; by default the meaning :mod:`pfmdyn.names` gives its :attr:`key`."""
    public: str = ""
    scale: float = 1.0
    null: float | None = None
    seeds: tuple[float, ...] = ()

    def __post_init__(self):
        if self.transform not in ("linear", "log10", "inverse"):
            raise ValueError(f"unknown transform {self.transform!r}")
        if not self.description and self.key in NAMES:
            object.__setattr__(self, "description", NAMES[self.key].meaning)

    @property
    def key(self) -> str:
        """The name reports use (:mod:`pfmdyn.names`; the internal name when none is given).

        >>> Parameter("gamma", "", 0.5, 1.0, public="tip_position").key
        'tip_position'
        """
        return self.public or self.name

    @property
    def log(self) -> bool:
        """Whether the internal coordinate is ``log10`` of the value."""
        return self.transform == "log10"

    @property
    def inverse(self) -> bool:
        """Whether the internal coordinate is the inverse of the value (a loss factor)."""
        return self.transform == "inverse"

    def value(self, internal: float) -> float:
        """Physical value of an internal coordinate.

        >>> INTERNAL_LOSS.value(0.01), INTERNAL_LOSS.value(0.0)
        (100.0, inf)
        """
        if self.inverse:
            return math.inf if internal <= 0 else 1.0 / internal
        return 10.0**internal if self.log else self.scale * float(internal)

    def values(self, internal):
        """:meth:`value` of an array of internal coordinates.

        >>> Parameter("q", "", 0.0, 5.0, transform="log10").values(np.array([1.0, 2.0])).tolist()
        [10.0, 100.0]
        """
        internal = np.asarray(internal, float)
        if self.inverse:
            with np.errstate(divide="ignore"):
                return np.where(internal > 0, 1.0 / internal, np.inf)
        return 10.0**internal if self.log else self.scale * internal

    def internal(self, value):
        """Internal coordinate of a physical value (inverse of :meth:`values`).

        >>> TILT = Parameter("alpha", "deg", -0.8, 0.8, scale=-180.0 / math.pi)
        >>> round(float(TILT.internal(TILT.value(0.3))), 12)
        0.3
        """
        value = np.asarray(value, float)
        if self.inverse:
            with np.errstate(divide="ignore"):
                return np.where(np.isfinite(value), 1.0 / value, 0.0)
        return np.log10(value) if self.log else value / self.scale

    def stderr(self, internal: float, sd: float) -> float:
        """Uncertainty of the value from that ``sd`` of the internal coordinate (delta method).

        >>> round(Parameter("k1", "N/m", 0.0, 6.0, transform="log10").stderr(2.0, 0.001), 6)
        0.230259
        """
        if self.inverse:
            return math.inf if internal <= 0 else sd / internal**2
        return self.value(internal) * LN10 * sd if self.log else abs(self.scale) * sd

    def spread(self, internal, sd):
        """Half the width of the image of ``internal +- sd`` (arrays): for ``log10``,
        ``value sinh(ln 10 sd)``, the delta method's ``value ln 10 sd`` when ``sd`` is small and
        huge, not small, when the data leave the value undetermined; else :meth:`stderr`.

        >>> p = Parameter("k1", "N/m", 0.0, 6.0, transform="log10")
        >>> p.spread(np.array([2.0]), np.array([1.0])).round(3).tolist()
        [495.0]
        """
        sd = np.asarray(sd, float)
        if self.inverse:
            internal = np.asarray(internal, float)
            with np.errstate(divide="ignore", invalid="ignore"):
                return np.where(internal > 0, sd / internal**2, np.inf)
        if not self.log:
            return np.abs(self.scale) * sd
        with np.errstate(over="ignore"):
            return self.values(internal) * np.sinh(LN10 * sd)

    def at_bound(self, internal, tolerance: float = 1e-6):
        """Where ``internal`` (arrays) sits at a bound that is not the null (within ``tolerance``,
        relative for ``log10``): where the fit was stopped, not where an effect switched off.

        >>> p = Parameter("k2", "N/m", -1.0, 4.0, transform="log10", null=-1.0)
        >>> p.at_bound(np.array([-1.0, 4.0, 2.0])).tolist()
        [False, True, False]
        """
        tol = tolerance / LN10 if self.log else tolerance
        p = np.asarray(internal, float)
        low = (np.abs(p - self.lower) < tol) & (self.null != self.lower)
        return low | ((np.abs(p - self.upper) < tol) & (self.null != self.upper))


def bounds(parameters) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper internal bounds of ``parameters`` as arrays.

    >>> bounds([VISCOUS_LOSS, CONTACT_LOSS])
    (array([0., 0.]), array([1., 5.]))
    """
    return np.array([p.lower for p in parameters], float), np.array([p.upper for p in parameters], float)


INTERNAL_LOSS = Parameter("inv_q", "", 0.0, 0.5, transform="inverse", public="quality_factor", null=0.0,
                          seeds=(0.003, 0.01, 0.03))
"""Internal friction as the loss factor ``1/Q`` (0: none)."""

VISCOUS_LOSS = Parameter("g", "", 0.0, 1.0, public="viscous_loss", null=0.0, seeds=(0.01, 0.03, 0.1))
"""Viscous drag ``g = c / (rho S omega1)`` (:mod:`pfmdyn.derivations.damping`)."""

FLUID_LOSS = Parameter("fluid", "", 0.0, 1.0, public="fluid_loss", null=0.0, seeds=(0.003, 0.01, 0.03))
"""A fluid's Stokes-layer loss, Sader's hydrodynamic function at high Reynolds number: the drag
``fluid sqrt(r)`` (:func:`pfmdyn.discrepancy.effects.fluid_law`)."""

CONTACT_LOSS = Parameter("x", "", 0.0, 5.0, public="contact_loss", null=0.0, seeds=(0.003, 0.02, 0.1))
"""Contact dashpot ``x = omega1 eta / k1`` (:mod:`pfmdyn.derivations.damping`)."""
