"""The effect library of ``pfmdyn discrepancy``: one :class:`Effect` component per effect.

An effect (in the spirit of lmfit's ``Parameter``/``Model``) states everything the fitting
loop needs: its nonlinear parameters (unit, internal coordinate, bounds), the internal
values that switch it off exactly (``null``: the model without it is nested, so a fit
started there is never worse), seed values for fresh starts (for an effect that moves the
resonances, the profile along which the springs are matched to the peaks, dense enough that
one lies near each exact match: :func:`pfmdyn.discrepancy.peaks.match_starts`), how many
linear design columns it adds, whether it moves the undamped resonances, whether only a
spectrum can show it (``spectrum_only``: background, the laser spot; damping shows in a
table's Q values), and the derivation it comes from.  ``damping`` is one effect name with
three mechanisms (components ``damping_internal``, ``damping_viscous``, ``damping_contact``,
:mod:`pfmdyn.derivations.damping`).

Bounds of the springs depend on the cantilever: :func:`spring_parameters` centres them on
``k`` (for ``k1``) and on ``k L**2 / H**2`` (for ``k2``, the lateral scale), so a stiff long
lever and a soft short one are both well inside.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..generated import formulas

__all__ = ["Parameter", "Effect", "EFFECTS", "NAMES", "DAMPING", "public_name", "spring_parameters"]


@dataclass(frozen=True)
class Parameter:
    """A nonlinear parameter: name, unit, internal transform, bounds (internal coordinates).

    ``name`` is the internal coordinate (the derivations' symbol), ``public`` the name reports use
    (:mod:`pfmdyn.names`; default ``name``).  ``log``: internal is log10 of the value;
    ``inverse``: internal is 1/value (a loss factor, 0 meaning no loss); otherwise the value is
    ``scale`` times the internal coordinate (the tilt: the derivations' angle in rad is minus the
    public tilt in degrees).
    """

    name: str
    unit: str
    lower: float
    upper: float
    log: bool = False
    inverse: bool = False
    description: str = ""
    public: str = ""
    scale: float = 1.0

    @property
    def key(self) -> str:
        """The name reports use.

        >>> Parameter("gamma", "", 0.5, 1.0, public="tip_position").key
        'tip_position'
        """
        return self.public or self.name

    def value(self, internal: float) -> float:
        """Physical value of an internal coordinate.

        >>> Parameter("inv_q", "", 0.0, 0.5, inverse=True).value(0.01)
        100.0
        """
        if self.inverse:
            return math.inf if internal <= 0 else 1.0 / internal
        return 10.0**internal if self.log else self.scale * float(internal)

    def stderr(self, internal: float, sd: float) -> float:
        """Uncertainty of the physical value from that of the internal one (delta method)."""
        if self.inverse:
            return math.inf if internal <= 0 else sd / internal**2
        return self.value(internal) * math.log(10) * sd if self.log else abs(self.scale) * sd


@dataclass(frozen=True)
class Effect:
    """One component of the discrepancy model (see module docstring)."""

    name: str
    parameters: tuple[Parameter, ...]
    null: tuple[float, ...]
    seeds: tuple[float, ...]
    derivation: str
    columns: int = 0
    moves_resonances: bool = False
    spectrum_only: bool = False


_LOSS = "internal friction: complex modulus E (1 + i/Q)"
EFFECTS: dict[str, Effect] = {e.name: e for e in (
    Effect("damping_internal", (Parameter("inv_q", "", 0.0, 0.5, inverse=True, description=_LOSS,
                                          public="quality_factor"),),
           (0.0,), (0.003, 0.01, 0.03), "derivations/damping.py"),
    Effect("damping_viscous", (Parameter("g", "", 0.0, 1.0, public="viscous_loss",
                                         description="viscous force c u_t per length: 1/Q of free mode 1"),),
           (0.0,), (0.01, 0.03, 0.1), "derivations/damping.py"),
    Effect("damping_contact", (Parameter("x", "", 0.0, 5.0, public="contact_loss",
                                         description="dashpot eta parallel to k1: omega1 eta / k1"),),
           (0.0,), (0.003, 0.02, 0.1), "derivations/damping.py"),
    Effect("tip_mass", (Parameter("mu", "", 0.0, 3.0, description="tip mass / beam mass",
                                  public="tip_mass_ratio"),),
           (0.0,), (0.03, 0.05, 0.08, 0.13, 0.2, 0.3, 0.45, 0.7, 1.0, 1.5), "derivations/tip_mass.py",
           moves_resonances=True),
    Effect("tip_setback", (Parameter("gamma", "", 0.5, 1.0, description="tip position / L", public="tip_position"),),
           (1.0,), (0.98, 0.95, 0.92, 0.89, 0.86, 0.83, 0.8, 0.77, 0.74, 0.71, 0.68),
           "derivations/tip_setback.py", moves_resonances=True),
    Effect("tilt", (Parameter("alpha", "deg", -0.8, 0.8, public="tilt", scale=-180.0 / math.pi,
                              description="beam inclination, positive when the free end is nearer the sample"),),
           (0.0,), (-0.45, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.45), "derivations/tilt.py",
           moves_resonances=True),
    Effect("lateral_stiffness", (), (), (), "derivations/elastic_contact.py", moves_resonances=True),
    Effect("background", (), (), (), "pfmdyn/discrepancy/model.py (additive cross-talk)", columns=2,
           spectrum_only=True),
    # The laser spot moves no resonance: it reweights the modes (and can put a zero between
    # them), so only a spectrum shows it; its seeds span where users put the spot.
    Effect("spot_position", (Parameter("sigma", "", 0.3, 1.0, public="spot_position",
                                       description="detection (laser) spot x_s / L"),),
           (1.0,), (0.98, 0.95, 0.92, 0.89, 0.86, 0.83, 0.8, 0.77, 0.74, 0.71, 0.68, 0.65, 0.6, 0.55, 0.5),
           "derivations/detection.py", spectrum_only=True),
)}
"""Component name -> :class:`Effect` (``lateral_stiffness``'s parameter ``k2`` is a spring)."""

DAMPING = {"internal": "damping_internal", "viscous": "damping_viscous", "contact": "damping_contact"}
"""Damping mechanism -> component name; every one is reported as the effect ``damping``."""

NAMES = ("damping", "tip_setback", "tip_mass", "background", "lateral_stiffness", "tilt", "spot_position")
"""The effect vocabulary of reports."""


def public_name(component: str) -> str:
    """Report name of a component.

    >>> public_name("damping_viscous"), public_name("tilt")
    ('damping', 'tilt')
    """
    return "damping" if component.startswith("damping_") else component


def spring_parameters(meta, vertical_only: bool) -> tuple[Parameter, ...]:
    """``k1`` (and ``k2`` unless ``vertical_only``) with bounds scaled to the cantilever.

    >>> from types import SimpleNamespace
    >>> p = spring_parameters(SimpleNamespace(k=26.0, L=450e-6, H=12e-6), False)
    >>> [(q.name, round(q.lower, 2), round(q.upper, 2)) for q in p]
    [('k1', -0.59, 7.41), ('k2', -1.44, 7.56)]
    """
    a = math.log10(meta.k)
    b = math.log10(formulas.k2_from_ratio(1.0, meta.k, meta.H, meta.L))
    k1 = Parameter("k1", "N/m", a - 2.0, a + 6.0, log=True, description="normal contact stiffness")
    k2 = Parameter("k2", "N/m", b - 6.0, b + 3.0, log=True, description="lateral contact stiffness")
    return (k1,) if vertical_only else (k1, k2)


def spring_grid(meta, count_k1: int, count_k2: int):
    """Start grids (internal log10) for ``k1`` (``k/10 .. 1e4 k``) and ``k2`` (lateral scale)."""
    import numpy as np
    a = math.log10(meta.k) + np.linspace(-1, 4.3, count_k1)
    b = math.log10(formulas.k2_from_ratio(1.0, meta.k, meta.H, meta.L)) + np.linspace(-4.5, 1, count_k2)
    return a, b
