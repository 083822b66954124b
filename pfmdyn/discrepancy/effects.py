"""The effect library of ``pfmdyn discrepancy``: one :class:`Effect` component per effect.

An effect (in the spirit of lmfit's ``Parameter``/``Model``) states everything the fitting
loop needs: its nonlinear parameters (unit, internal coordinate, bounds), the internal
values that switch it off exactly (``null``: the model without it is nested, so a fit
started there is never worse), seed values for fresh starts (for an effect that moves the
resonances, the profile along which the springs are matched to the peaks, dense enough that
one lies near each exact match: :func:`pfmdyn.discrepancy.peaks.match_starts`), how many
linear design columns it adds, whether it moves the undamped resonances, whether only a
spectrum can show it (``spectrum_only``: background, the laser spot; damping shows in a
table's Q values), and the derivation it comes from; and what it does to the model: each component is a subclass
of :class:`Effect` that gives its chain-rule term of the Jacobian (:class:`Chain`), the
generated partials that needs, its design columns (:data:`BASE_COLUMNS`), and the quantities
derived from its parameters, so that adding an effect is adding one component (parameters:
:class:`pfmdyn.fitting.parameters.Parameter`).  ``damping`` is one effect name with three mechanisms
(components ``damping_internal``, ``damping_viscous``, ``damping_contact``,
:mod:`pfmdyn.derivations.damping`).

Bounds of the springs depend on the cantilever: :func:`spring_parameters` centres them on
``k`` (for ``k1``) and on ``k L**2 / H**2`` (for ``k2``, the lateral scale), so a stiff long
lever and a soft short one are both well inside.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..fitting.parameters import CONTACT_LOSS, FLUID_LOSS, INTERNAL_LOSS, VISCOUS_LOSS, Parameter
from .. import composed
from ..generated import damping, formulas

__all__ = ["Effect", "Chain", "EFFECTS", "NAMES", "DAMPING", "BASE_COLUMNS", "RAMP", "public_name",
           "spring_parameters", "drag", "fluid_law"]

RAMP = -1
"""The column source of the background's ramp ``f / f_max`` (the others: a slope's index)."""
BASE_COLUMNS = ((0, False), (1, False), (3, False), (2, True), (3, True))
"""The baseline's design columns as ``(source, per volt)``: the slope per unit ``(d1, d2, f0, q0)`` of that
index (or :data:`RAMP`), times the row's bias when per volt: ``T_d1, T_d2, T_q, V T_f, V T_q``; an effect's
``columns`` follow in the library's order."""


def fluid_law(r):
    """The drag per unit ``fluid_loss`` at ``r = f / f1`` (complex allowed): ``sqrt(r)``, a half-power
    width growing as ``sqrt(f)``: the loss of a Stokes layer, Sader's ``Gamma`` at high Reynolds
    number (``1 + 2 sqrt(2) (1 + i) / sqrt(Re)``), carried as a drag
    (:func:`pfmdyn.derivations.damping.fluid_as_drag`).  The added mass of the same term is left out:
    the fit takes the measured resonances as they are; a lever of known width in a known medium has the
    whole load from :class:`pfmdyn.Cantilever` (``medium``).

    >>> complex(fluid_law(4.0))
    (2+0j)
    """
    return np.sqrt(r)


def drag(coords, r):
    """The drag the damping substitution takes: the viscous ``g`` and the fluid's law.

    >>> complex(drag({"g": 0.01, "fluid": 0.0}, 2.0))
    (0.01+0j)
    """
    return coords["g"] + coords["fluid"] * fluid_law(r) if coords["fluid"] else coords["g"]


@dataclass
class Chain:
    """What the chain rule composes at one parameter vector (:meth:`pfmdyn.discrepancy.model.Model.slopes_and_jacobian`).

    ``part``: the generated partials of the four slopes w.r.t. :data:`pfmdyn.composed.JACOBIAN_PARAMETERS`
    (0 where not computed); ``rotation_partials``: the rotated spring tensor's partials
    (:func:`pfmdyn.generated.tilt_rotation.rotated_jacobian`, for :meth:`rotation`); ``coords``:
    :meth:`~pfmdyn.discrepancy.model.Model.coords`; ``root_r``
    the undamped ``beta`` at each frequency, ``b1`` and ``d_b1`` the free root and its derivatives
    w.r.t. ``(mu, gamma)``; ``factors`` the generated damping factors (:mod:`pfmdyn.generated.damping`)
    at ``r = f / f1`` and the losses ``loss`` ``(inv_q, g, x)``; ``spring`` the damped ``k1``.
    """

    part: dict
    rotation_partials: tuple
    coords: dict
    meta: object
    root_r: object
    b1: float
    d_b1: tuple
    factors: tuple
    r: object
    loss: tuple
    spring: object
    _rotation: dict = field(default_factory=dict, repr=False)
    _d_factors: dict = field(default_factory=dict, repr=False)

    def rotation(self, i: int):
        """d slopes / d (k1 in beam axes, k2, alpha)[i] through the rotated spring tensor, formed when
        asked (the tilt's, products with arrays, only with a tilt)."""
        if i not in self._rotation:
            part, rot = self.part, self.rotation_partials
            self._rotation[i] = part["kvv"] * rot[0][i] + part["kll"] * rot[1][i] + part["kvl"] * rot[2][i]
        return self._rotation[i]

    def d_factors_wrt(self, q: int) -> tuple:
        """The damping factors' derivatives w.r.t. the ``q``-th loss (:func:`pfmdyn.generated.damping.d_factors_wrt`),
        formed when a damping component asks (a model without one never does; one asks for its own loss's)."""
        if q not in self._d_factors:
            self._d_factors[q] = damping.d_factors_wrt(self.r, *self.loss, q)
        return self._d_factors[q]


@dataclass(frozen=True)
class Effect:
    """One component of the discrepancy model (see module docstring): its parameters and what
    it does to the model.  The base class moves nothing; a subclass gives its behaviour:

    * :meth:`jacobian`: d slopes / d each of its internal parameters, by the chain rule
      (:class:`Chain`), and :meth:`partials` the generated partials that needs;
    * ``columns``: the linear design columns it adds, as :data:`BASE_COLUMNS`'s.
    """

    name: str
    parameters: tuple[Parameter, ...]
    derivation: str
    columns: tuple[tuple[int, bool], ...] = ()
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

    @property
    def frees_lateral_spring(self) -> bool:
        """Whether the effect fits ``k2`` where the baseline holds it at 0 (a vertical-only baseline)."""
        return False

    def partials(self, coords) -> set[str]:
        """The generated partials its :meth:`jacobian` uses at coordinates ``coords``."""
        return set()

    def reading(self, coords):
        """Where the model reads the slope when the effect is present: None (the free end,
        :data:`pfmdyn.composed.at_end`) or another :class:`pfmdyn.composed.Reading`."""
        return None

    def jacobian(self, chain: Chain) -> tuple:
        """d slopes (4, n) / d each internal parameter, in order."""
        return ()

    def derived(self, values: dict, meta) -> dict:
        """Reported quantities that follow from its parameters' ``values`` (:meth:`FitResult.parameters`)."""
        return {}


@dataclass(frozen=True)
class Damping(Effect):
    """One damping mechanism: the generated substitution of :mod:`pfmdyn.generated.damping`
    (complex ``beta``, ``k``, ``k1`` and tip mass), the loss ``index``-th of ``(1/Q, g, x)``;
    ``uses``: the generated partials its factors move (the others' factors stay 1)."""

    index: int = 0
    uses: tuple[str, ...] = ()

    def partials(self, coords) -> set[str]:
        return set(self.uses)

    def jacobian(self, chain: Chain) -> tuple:
        d_f, part, c = chain.d_factors_wrt(self.index), chain.part, chain.coords
        return (part["beta"] * (chain.root_r * d_f[0]) + part["k"] * (chain.meta.spring_constant * d_f[1])
                + chain.rotation(0) * (c["k1"] * d_f[2]) + part["mu"] * (c["mu"] * d_f[3]),)


@dataclass(frozen=True)
class ViscousDamping(Damping):
    """Viscous drag; reports the half-power width it gives every peak (Hz)."""

    def partials(self, coords) -> set[str]:
        # drag acts on a tip mass too (its mass factor)
        return set(self.uses) | ({"mu"} if coords["mu"] != 0.0 else set())

    def derived(self, values: dict, meta) -> dict:
        loss = values["viscous_loss"]
        if loss["value"] is None:
            return {}
        width = formulas.viscous_width(loss["value"], meta.free_resonance)
        stderr = None if loss.get("stderr") is None else float(formulas.viscous_width(loss["stderr"], meta.free_resonance))
        return {"viscous_width_hz": {"value": float(width), "stderr": stderr, "unit": "Hz",     # linear in the loss
                                     "determined": loss["determined"]}}


@dataclass(frozen=True)
class FluidDamping(ViscousDamping):
    """A fluid's drag growing as ``sqrt(f)`` (:func:`fluid_law`): the viscous term times the law."""

    def jacobian(self, chain: Chain) -> tuple:
        d_f, part, c = chain.d_factors_wrt(1), chain.part, chain.coords
        law = fluid_law((chain.root_r / chain.b1) ** 2)
        return (law * (part["beta"] * (chain.root_r * d_f[0]) + part["mu"] * (c["mu"] * d_f[3])),)

    def derived(self, values: dict, meta) -> dict:
        return {}


@dataclass(frozen=True)
class ContactDamping(Damping):
    """A dashpot beside ``k1``: ``T_d1`` no longer carries the constant part of ``f0``, so ``T_f``
    is a column of its own (coefficient ``f0`` at zero bias); reports the dashpot ``eta``."""

    columns: tuple[tuple[int, bool], ...] = ((2, False),)

    def derived(self, values: dict, meta) -> dict:
        if not values.get("k1", {}).get("value"):
            return {}
        loss = values["contact_loss"]
        eta = formulas.contact_dashpot(loss["value"], values["k1"]["value"], meta.free_resonance)
        return {"eta": {"value": float(eta), "stderr": None, "unit": "N s/m", "determined": loss["determined"]}}


@dataclass(frozen=True)
class TipMass(Effect):
    """A point mass ``mu`` (tip mass / beam mass) at the tip; it lowers the free root too."""

    def partials(self, coords) -> set[str]:
        return {"mu", "beta"}

    def jacobian(self, chain: Chain) -> tuple:
        part = chain.part
        return (part["mu"] * chain.factors[3] + part["beta"] * (chain.root_r / chain.b1 * chain.factors[0] * chain.d_b1[0]),)


@dataclass(frozen=True)
class TipSetback(Effect):
    """The tip at ``gamma L`` from the clamp; with a tip mass the free root moves with it."""

    def partials(self, coords) -> set[str]:
        return {"gamma"} | ({"beta"} if coords["mu"] != 0.0 else set())

    def jacobian(self, chain: Chain) -> tuple:
        part = chain.part
        return (part["gamma"] + part["beta"] * (chain.root_r / chain.b1 * chain.factors[0] * chain.d_b1[1]),)


@dataclass(frozen=True)
class Tilt(Effect):
    """The lever inclined by ``alpha``: the spring tensor rotated onto the beam axes."""

    def partials(self, coords) -> set[str]:
        return {"kvl"}

    def jacobian(self, chain: Chain) -> tuple:
        return (chain.rotation(2),)


@dataclass(frozen=True)
class LateralStiffness(Effect):
    """``k2`` fitted where the baseline holds it at 0 (a vertical-only baseline): a spring
    (:func:`spring_parameters`), placed beside ``k1``."""

    @property
    def frees_lateral_spring(self) -> bool:
        return True


@dataclass(frozen=True)
class Background(Effect):
    """Additive cross-talk, two linear columns ``(b0 + b1 V) f / f_max``."""

    columns: tuple[tuple[int, bool], ...] = ((RAMP, False), (RAMP, True))


@dataclass(frozen=True)
class SpotPosition(Effect):
    """The slope read at the laser spot ``x_s = spot_position L`` (a :class:`pfmdyn.composed.Reading`)
    instead of the free end: it reweights the modes (and can put a zero between them) but moves
    no resonance, so its Jacobian term has no free-root part."""

    def reading(self, coords):
        return composed.Reading(coords["spot_position"])

    def partials(self, coords) -> set[str]:
        return {"sigma"}        # the generated module's symbol for x_s / L (pfmdyn.composed)

    def jacobian(self, chain: Chain) -> tuple:
        return (chain.part["sigma"],)


EFFECTS: dict[str, Effect] = {e.name: e for e in (
    Damping("damping_internal", (INTERNAL_LOSS,), "derivations/damping.py", index=0, uses=("beta", "k")),
    ViscousDamping("damping_viscous", (VISCOUS_LOSS,), "derivations/damping.py", index=1, uses=("beta",)),
    FluidDamping("damping_fluid", (FLUID_LOSS,), "derivations/damping.py", index=1, uses=("beta",)),
    ContactDamping("damping_contact", (CONTACT_LOSS,), "derivations/damping.py", index=2),
    TipMass("tip_mass", (Parameter("mu", "", 0.0, 3.0, public="tip_mass_ratio",
                                   null=0.0, seeds=(0.03, 0.05, 0.08, 0.13, 0.2, 0.3, 0.45, 0.7, 1.0, 1.5)),),
            "derivations/tip_mass.py", moves_resonances=True),
    TipSetback("tip_setback", (Parameter("gamma", "", 0.5, 1.0, public="tip_position",
                                         null=1.0, seeds=(0.98, 0.95, 0.92, 0.89, 0.86, 0.83, 0.8, 0.77, 0.74, 0.71,
                                                          0.68)),),
               "derivations/pieces.py", moves_resonances=True),
    Tilt("tilt", (Parameter("alpha", "deg", -0.8, 0.8, public="tilt", scale=-180.0 / math.pi, null=0.0,
                            seeds=(-0.45, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3, 0.45)),),
         "derivations/tilt.py", moves_resonances=True),
    LateralStiffness("lateral_stiffness", (), "derivations/elastic_contact.py", moves_resonances=True),
    Background("background", (), "pfmdyn/discrepancy/model.py (additive cross-talk)", spectrum_only=True),
    # The laser spot moves no resonance: it reweights the modes (and can put a zero between
    # them), so only a spectrum shows it; its seeds span where users put the spot.
    SpotPosition("spot_position", (Parameter("spot_position", "", 0.3, 1.0, null=1.0,
                                             seeds=(0.98, 0.95, 0.92, 0.89, 0.86, 0.83, 0.8, 0.77, 0.74, 0.71, 0.68,
                                                    0.65, 0.6, 0.55, 0.5)),),
                 "derivations/pieces.py", spectrum_only=True),
)}
"""Component name -> :class:`Effect` (``lateral_stiffness``'s parameter ``k2`` is a spring)."""

DAMPING = {"internal": "damping_internal", "viscous": "damping_viscous", "fluid": "damping_fluid",
           "contact": "damping_contact"}
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
    >>> p = spring_parameters(SimpleNamespace(spring_constant=26.0, length=450e-6, tip_height=12e-6), False)
    >>> [(q.name, round(q.lower, 2), round(q.upper, 2)) for q in p]
    [('k1', -0.59, 7.41), ('k2', -1.44, 7.56)]
    """
    a = math.log10(meta.spring_constant)
    b = math.log10(formulas.k2_from_ratio(1.0, meta.spring_constant, meta.tip_height, meta.length))
    k1 = Parameter("k1", "N/m", a - 2.0, a + 6.0, transform="log10")
    k2 = Parameter("k2", "N/m", b - 6.0, b + 3.0, transform="log10", null=-math.inf)
    return (k1,) if vertical_only else (k1, k2)


def spring_grid(meta, count_k1: int, count_k2: int):
    """Start grids (internal log10) for ``k1`` (``k/10 .. 1e4 k``) and ``k2`` (lateral scale)."""
    import numpy as np
    a = math.log10(meta.spring_constant) + np.linspace(-1, 4.3, count_k1)
    b = (math.log10(formulas.k2_from_ratio(1.0, meta.spring_constant, meta.tip_height, meta.length))
         + np.linspace(-4.5, 1, count_k2))
    return a, b
