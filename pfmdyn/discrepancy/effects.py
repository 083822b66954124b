"""The effect library of ``pfmdyn discrepancy``: one :class:`Effect` component per effect.

An effect (in the spirit of lmfit's ``Parameter``/``Model``) states everything the fitting
loop needs: its nonlinear parameters (unit, internal coordinate, bounds), the internal
values that switch it off exactly (``null``: the model without it is nested, so a fit
started there is never worse), seed values for fresh starts (for an effect that moves the
resonances, the profile along which the springs are matched to the peaks, dense enough that
one lies near each exact match: :func:`pfmdyn.discrepancy.peaks.match_starts`), how many
linear design columns it adds, whether it moves the undamped resonances, whether only a
spectrum can show it (``spectrum_only``: background; damping shows in a table's Q values),
and the derivation it comes from.  ``damping`` is one effect name with three mechanisms
(components ``damping_internal``, ``damping_viscous``, ``damping_contact``,
:mod:`pfmdyn.derivations.damping`).

Bounds of the springs depend on the cantilever: :func:`spring_parameters` centres them on
``k`` (for ``k1``) and on ``k L**2 / H**2`` (for ``k2``, the lateral scale), so a stiff long
lever and a soft short one are both well inside.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..fitting.parameters import CONTACT_LOSS, INTERNAL_LOSS, VISCOUS_LOSS, Parameter
from ..generated import formulas

__all__ = ["Effect", "EFFECTS", "NAMES", "DAMPING", "public_name", "spring_parameters"]


@dataclass(frozen=True)
class Effect:
    """One component of the discrepancy model (see module docstring)."""

    name: str
    parameters: tuple[Parameter, ...]
    derivation: str
    columns: int = 0
    moves_resonances: bool = False
    spectrum_only: bool = False

    @property
    def null(self) -> tuple[float, ...]:
        """Internal values that switch the effect off."""
        return tuple(p.null for p in self.parameters)

    @property
    def seeds(self) -> tuple[float, ...]:
        """Seed values of the effect's (one) parameter for fresh starts."""
        return self.parameters[0].seeds if self.parameters else ()


EFFECTS: dict[str, Effect] = {e.name: e for e in (
    Effect("damping_internal", (INTERNAL_LOSS,), "derivations/damping.py"),
    Effect("damping_viscous", (VISCOUS_LOSS,), "derivations/damping.py"),
    Effect("damping_contact", (CONTACT_LOSS,), "derivations/damping.py"),
    Effect("tip_mass", (Parameter("mu", "", 0.0, 3.0, description="tip mass / beam mass", public="tip_mass_ratio",
                                  null=0.0, seeds=(0.03, 0.05, 0.08, 0.13, 0.2, 0.3, 0.45, 0.7, 1.0, 1.5)),),
           "derivations/tip_mass.py", moves_resonances=True),
    Effect("tip_setback", (Parameter("gamma", "", 0.5, 1.0, description="tip position / L", public="tip_position",
                                     null=1.0, seeds=(0.98, 0.95, 0.92, 0.89, 0.86, 0.83, 0.8, 0.77, 0.74, 0.71,
                                                      0.68)),),
           "derivations/tip_setback.py", moves_resonances=True),
    Effect("tilt", (Parameter("alpha", "deg", -0.8, 0.8, public="tilt", scale=-180.0 / math.pi, null=0.0,
                              seeds=(-0.45, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.45),
                              description="beam inclination, positive when the free end is nearer the sample"),),
           "derivations/tilt.py", moves_resonances=True),
    Effect("lateral_stiffness", (), "derivations/elastic_contact.py", moves_resonances=True),
    Effect("background", (), "pfmdyn/discrepancy/model.py (additive cross-talk)", columns=2, spectrum_only=True),
)}
"""Component name -> :class:`Effect` (``lateral_stiffness``'s parameter ``k2`` is a spring)."""

DAMPING = {"internal": "damping_internal", "viscous": "damping_viscous", "contact": "damping_contact"}
"""Damping mechanism -> component name; every one is reported as the effect ``damping``."""

NAMES = ("damping", "tip_setback", "tip_mass", "background", "lateral_stiffness", "tilt")
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
    k1 = Parameter("k1", "N/m", a - 2.0, a + 6.0, transform="log10", description="normal contact stiffness")
    k2 = Parameter("k2", "N/m", b - 6.0, b + 3.0, transform="log10", null=-math.inf,
                   description="lateral contact stiffness")
    return (k1,) if vertical_only else (k1, k2)


def spring_grid(meta, count_k1: int, count_k2: int):
    """Start grids (internal log10) for ``k1`` (``k/10 .. 1e4 k``) and ``k2`` (lateral scale)."""
    import numpy as np
    a = math.log10(meta.k) + np.linspace(-1, 4.3, count_k1)
    b = math.log10(formulas.k2_from_ratio(1.0, meta.k, meta.H, meta.L)) + np.linspace(-4.5, 1, count_k2)
    return a, b
