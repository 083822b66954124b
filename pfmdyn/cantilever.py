"""The one description of the probe: lever, tip, detection point, damping (SI), and the contact.

:class:`Cantilever` is what every command, reader and report means by "the lever": spring
constant, first free resonance and length, with optionally the tip's height, position, mass and
rotary inertia, the tilt, the laser spot and the losses.  :class:`Contact` is the tip-sample
contact: ``k1``, and ``k2`` or a policy tying it to ``k1``.  Names, units and plausible values
are those of :mod:`pfmdyn.names` (one name from file key to flag to JSON key).

The dimensionless frequency of the derivations is ``beta`` with ``beta**4 = omega**2 rho S
L**4 / EI``.  For a given cantilever it follows from the measured first free resonance ``f1``:
``beta = beta_1 sqrt(f / f1)``, ``beta_1`` the first free root of the lever *with its tip*
(``1.8751040687...``, the root of ``1 + cos(beta) cosh(beta)``, for a massless tip; smaller for
a heavy tip).  Losses are the damping substitution of ``derivations/damping.py``
(``generated/damping.py``): internal friction ``E (1 + i/Q)`` and viscous drag ``g``; the contact
dashpot belongs to :class:`Contact`.  Responses are complex.

:meth:`Cantilever.response` evaluates the composed model (:mod:`pfmdyn.composed`: tip
set back, tip mass, tilted springs, every damping mechanism) and serves every probe.  The
per-family methods (``elastic_response``, ``free_response``, ...) are made from the family
registry (``derivations/families.py``, field ``method``): each evaluates the paper's family,
whose tip sits massless at the free end of an untilted lever.

The module stays whole at about 600 lines: :class:`Cantilever` with the family methods made
onto it is over 400 of them, and what could leave (the contact, the damping substitution, the
free root) is the part of the one description of the probe that the lever's methods read.
"""
from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, fields, replace
from functools import cached_property, lru_cache
from typing import NamedTuple

import numpy as np

from . import composed, transfer
from .constants import BOLTZMANN
from .errors import UserError
from .medium import Medium, load_ratio, mass_per_length
from .generated import damping, families, formulas
from .generated.characteristic import BETA1_FREE
from .generated.tilt_rotation import rotated
from .names import checked
from .roots.bracket import refine

__all__ = ["Cantilever", "Contact", "BETA1_FREE", "DEFAULT_POISSON", "Damped", "damping_substitution", "free_root"]

DEFAULT_POISSON = 0.3
"""Poisson's ratio of the Mindlin tie ``k2 = c k1`` when one contact mode must fix both springs
and the user named no policy (a typical oxide or polymer sample)."""


@dataclass(frozen=True)
class Cantilever:
    """An Euler-Bernoulli cantilever with its tip, in SI units (names: :mod:`pfmdyn.names`).

    Parameters
    ----------
    spring_constant : float
        ``k = 3 EI / L**3`` in N/m.
    free_resonance : float
        First free flexural resonance ``f1`` in Hz, as measured (the lever with its tip).
    length : float
        ``L`` in m.
    quality_factor : float
        ``Q`` of the complex modulus ``E (1 + i/Q)`` (``inf``: lossless).
    tip_height : float, optional
        ``H`` in m: the lever arm of the lateral contact force (needed with ``k2`` or a tilt).
    width : float, optional
        ``w`` in m (geometry only; no resonance depends on it).
    tip_position : float
        ``x_tip / L``: 1 at the free end.
    tip_mass_ratio : float
        Tip mass over the lever's mass.
    tip_gyration_radius : float
        Radius of gyration ``r_g`` of the tip (m): rotary inertia ``J = m_tip r_g**2``.
    tilt : float
        Inclination in degrees, positive when the free end is nearer the sample than the clamp.
    spot_position : float
        ``x_s / L`` of the detection (laser) spot: 1 at the free end.
    viscous_loss : float
        Viscous drag ``g = c / (rho S omega1)`` (1/Q of free mode 1 under drag alone).
    medium : pfmdyn.medium.Medium, optional
        The fluid around the lever (None: vacuum, the paper's case).  Its load per unit length
        (Sader's hydrodynamic function, :mod:`pfmdyn.medium`) enters Eq. 2 as added mass and
        damping at every frequency; it needs ``width``.  ``free_resonance`` is then the first
        resonance *in the medium*, as measured there; the vacuum one follows from Sader's relation
        (:attr:`vacuum_resonance`).

    Examples
    --------
    >>> c = Cantilever.from_geometry(length=225e-6, width=40e-6, thickness=3e-6,
    ...                              youngs_modulus=169e9, density=2330.0)
    >>> round(c.spring_constant, 3), round(c.free_resonance / 1e3, 2)   # N/m, kHz
    (4.006, 81.53)
    >>> round(float(c.beta(c.free_resonance).real), 10)
    1.8751040687
    >>> Cantilever(2.0, 7e4, 2e-4, tip_mass_ratio=0.2).free_root() < BETA1_FREE   # a heavy tip
    True
    """

    spring_constant: float
    free_resonance: float
    length: float
    quality_factor: float = math.inf
    tip_height: float | None = None
    width: float | None = None
    tip_position: float = 1.0
    tip_mass_ratio: float = 0.0
    tip_gyration_radius: float = 0.0
    tilt: float = 0.0
    spot_position: float = 1.0
    viscous_loss: float = 0.0
    medium: Medium | None = None

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in ("tip_height", "width", "medium"):
                continue
            if f.name == "medium":
                if not isinstance(value, Medium):
                    raise UserError(f"medium must be a pfmdyn.medium.Medium, got {value!r}")
                if self.width is None:
                    raise UserError("a lever in a medium needs its width (the fluid acts across it)")
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise UserError(f"{f.name} must be a number, got {value!r}")
            if f.name == "quality_factor" and value == math.inf:
                continue
            checked(f.name, value)

    @classmethod
    def from_geometry(cls, *, length, width, thickness, youngs_modulus, density,
                      quality_factor=math.inf, medium: Medium | None = None) -> "Cantilever":
        """Rectangular section from SI geometry and material (m, Pa, kg/m**3), in vacuum or in ``medium``.

        ``k = E w t**3 / (4 L**3)``; ``f1 = BETA1_FREE**2 / (2 pi L**2) sqrt(E I / (rho S))``
        with ``I = w t**3 / 12`` and ``S = w t`` (in vacuum; in a medium, :meth:`with_medium`).

        >>> from pfmdyn.medium import Medium
        >>> wet = Cantilever.from_geometry(length=225e-6, width=40e-6, thickness=3e-6, youngs_modulus=169e9,
        ...                                density=2330.0, medium=Medium.water(298.15))
        >>> round(wet.vacuum_resonance / 1e3, 2), round(wet.free_resonance / 1e3, 2)   # kHz
        (81.53, 30.72)
        """
        for name, value in [("length", length), ("width", width), ("thickness", thickness),
                            ("youngs_modulus", youngs_modulus), ("density", density)]:
            if not value > 0:
                raise UserError(f"{name} must be positive, got {value!r}")
        k = formulas.spring_constant_from_geometry(youngs_modulus, width, thickness, length)
        f1 = formulas.free_resonance_from_geometry(youngs_modulus, width, thickness, length,
                                                   density, BETA1_FREE)
        lever = cls(float(k), float(f1), length, quality_factor, width=width)
        return lever if medium is None else lever.with_medium(medium)

    @classmethod
    def from_values(cls, values: dict) -> "Cantilever":
        """A cantilever from a mapping of names (:data:`pfmdyn.names.LEVER`, ``quality_factor``,
        ``viscous_loss``) to SI values; other keys are ignored.

        >>> Cantilever.from_values({"spring_constant": 2, "free_resonance": 7e4, "length": 2e-4,
        ...                         "k1": 100}).tip_position
        1.0
        """
        own = {f.name for f in fields(cls)}
        missing = [n for n in ("spring_constant", "free_resonance", "length") if values.get(n) is None]
        if missing:
            raise UserError("the lever needs " + ", ".join(missing))
        return cls(**{k: v for k, v in values.items() if k in own and v is not None})

    def to_dict(self) -> dict:
        """The description as names -> SI values (``None``: not known).

        >>> sorted(Cantilever(2.0, 7e4, 2e-4).to_dict())[:3]
        ['free_resonance', 'length', 'medium']
        """
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["medium"] = None if self.medium is None else self.medium.name
        return out

    @property
    def alpha(self) -> float:
        """The derivations' tilt angle (rad, ``derivations/tilt.py``): positive there when the
        free end is *farther* from the sample, so ``alpha = -radians(tilt)``."""
        return -math.radians(self.tilt)

    @property
    def rho_g(self) -> float:
        """The derivations' tip radius of gyration ``r_g / L`` (``derivations/tip_mass.py``)."""
        return self.tip_gyration_radius / self.length

    @property
    def is_paper_probe(self) -> bool:
        """True when the paper's families apply: massless tip at the free end, no tilt, spot at L."""
        return (self.tip_position == 1.0 and self.tip_mass_ratio == 0.0 and self.tilt == 0.0
                and self.spot_position == 1.0 and self.tip_gyration_radius == 0.0)

    def _tip_height(self, contact: "Contact | None" = None) -> float:
        lateral = self.tilt != 0.0 or (contact is not None and contact.k2_of(contact.k1 or 0.0) != 0.0)
        if self.tip_height is None:
            if lateral:
                raise UserError("tip_height is needed with k2 or a tilt", quantity="tip_height")
            return 0.0
        return self.tip_height

    def free_root(self) -> float:
        """``beta_1``: the first free root of this lever with its tip (1.8751... when massless)."""
        return free_root(self.spring_constant, self.tip_height or 0.0, self.length,
                          self.tip_mass_ratio, self.tip_position, self.rho_g)

    def beta(self, frequency) -> np.ndarray:
        """Dimensionless frequency ``beta`` (complex) for frequencies in Hz (> 0).

        ``beta = beta_1 sqrt(f / f1)`` times the damping factor of the internal friction and
        drag (``generated/damping.py``); the spring constant becomes ``k (1 + i/Q)``.

        >>> c = Cantilever(1.0, 1e5, 1e-4)
        >>> round(float(c.beta(4e5).real), 6)   # beta scales as sqrt(f)
        3.750208
        """
        return self._damped(_positive(frequency)).beta

    @cached_property
    def vacuum_resonance(self) -> float:
        """The first free resonance in vacuum (Hz): ``free_resonance`` itself without a medium; in one,
        from Sader's first-mode relation ``f = f_vac / sqrt(1 + T Re Gamma(f))`` with the fluid's mass
        ratio ``T`` (its load over the lever's mass per length ``k beta1**4 / (3 L omega_vac**2)``, times
        :meth:`beam_share`: a tip's mass is none of the fluid's), solved for ``f_vac`` in closed form.

        >>> from pfmdyn.medium import Medium
        >>> lever = Cantilever(27.0, 1.8e5, 225e-6, width=40e-6, medium=Medium.air(313.15))
        >>> round(lever.vacuum_resonance / lever.free_resonance, 5)
        1.00292
        """
        if self.medium is None:
            return self.free_resonance
        # the load ratio is proportional to 1 / mass per length, i.e. to omega_vac**2: evaluate it
        # for the mass per length a lever of vacuum resonance f would have, then scale
        at_f = load_ratio(self.medium, self.free_resonance, self.width,
                          self.beam_mass_per_length(self.free_resonance)).real * self.beam_share()
        denominator = 1.0 - at_f
        if not denominator > 0:
            raise UserError(f"the medium's load exceeds the lever's inertia at {self.free_resonance:g} Hz "
                            "(check the spring constant, length and width)")
        return self.free_resonance / math.sqrt(denominator)

    def beam_share(self) -> float:
        """The share of the first free mode's inertia that is the beam's, ``(beta_1 / 1.8751)**4`` (Rayleigh's
        quotient, the mode's shape taken unchanged); the rest is the tip's, which a fluid does not load: Sader's
        relation (:attr:`vacuum_resonance`) scales the fluid's mass ratio by it.

        >>> Cantilever(2.0, 7e4, 2e-4).beam_share(), round(Cantilever(2.0, 7e4, 2e-4, tip_mass_ratio=0.25).beam_share(), 4)
        (1.0, 0.4962)
        """
        return (self.free_root() / BETA1_FREE)**4 if self.tip_mass_ratio else 1.0

    def beam_mass_per_length(self, vacuum_resonance: float) -> float:
        """The lever's own mass per length (kg/m) if its first vacuum resonance, *with its tip*, is
        ``vacuum_resonance`` (Hz): ``k beta1**4 / (3 L omega1**2)`` with this lever's root ``beta1``
        (:meth:`free_root`), so that a tip mass, which lowers both, leaves the lever's mass unchanged.

        >>> bare = Cantilever(2.0, 7e4, 2e-4)
        >>> heavy = Cantilever(2.0, 7e4, 2e-4, tip_mass_ratio=0.5)
        >>> f_heavy = 7e4 * (heavy.free_root() / BETA1_FREE)**2        # the same beam with the mass
        >>> round(heavy.beam_mass_per_length(f_heavy) / bare.beam_mass_per_length(7e4), 12)
        1.0
        """
        mass = mass_per_length(self.spring_constant, self.length, vacuum_resonance)
        return mass * (self.free_root() / BETA1_FREE)**4 if self.tip_mass_ratio else mass

    def with_medium(self, medium: Medium, width: float | None = None) -> "Cantilever":
        """This lever, whose ``free_resonance`` is its vacuum one (a lever from its geometry, a data
        sheet), put in ``medium``: the same lever with the first resonance it has there (Sader's relation,
        the inverse of :attr:`vacuum_resonance`, by fixed-point iteration).

        >>> from pfmdyn.medium import Medium
        >>> vacuum = Cantilever(2.0, 7e4, 2e-4, width=3e-5)
        >>> wet = vacuum.with_medium(Medium.water(298.15))
        >>> round(wet.free_resonance), round(wet.vacuum_resonance)
        (28975, 70000)
        """
        lever = replace(self, width=self.width if width is None else width, medium=medium)
        f_vac = self.free_resonance
        mass = self.beam_mass_per_length(f_vac)
        f = f_vac
        for _ in range(100):
            # Sader's relation forward, f = f_vac / sqrt(1 + T Re Gamma(f)), with the lever's own mass
            f_next = f_vac / math.sqrt(1.0 + load_ratio(medium, f, lever.width, mass).real * self.beam_share())
            if abs(f_next / f - 1) < 1e-14:
                return replace(lever, free_resonance=f_next)
            f = f_next
        raise UserError(f"no first resonance in {medium.name} found for this lever")

    def fluid_load(self, frequency):
        """The medium's load per unit length over the lever's inertia at ``frequency`` (Hz, real or
        complex): ``beta**4 -> beta**4 (1 + load)``; real part added mass, imaginary part (negative)
        the loss (:func:`pfmdyn.medium.load_ratio`); 0 in vacuum.

        >>> from pfmdyn.medium import Medium
        >>> wet = Cantilever(2.0, 3e4, 2e-4, width=3e-5, medium=Medium.water(298.15))
        >>> load = wet.fluid_load(3e4); round(load.real, 2), round(load.imag, 2)
        (7.62, -2.24)
        """
        if self.medium is None:
            return 0.0
        return load_ratio(self.medium, frequency, self.width, self.beam_mass_per_length(self.vacuum_resonance))

    def _damped(self, frequency, contact: "Contact | None" = None, fluid: float = 1.0) -> "Damped":
        """:func:`damping_substitution` of this lever (and ``contact``'s ``k1`` and dashpot) at
        ``frequency`` (Hz, real or complex); a medium's load, ``fluid`` times it (a continuation from
        vacuum), enters as a drag (``g + i r load``, ``derivations/damping.py``: ``fluid_as_drag``)."""
        b1 = self.free_root() if self.tip_mass_ratio else BETA1_FREE
        f1 = self.vacuum_resonance
        k1, loss = (contact.k1, contact.contact_loss) if contact is not None else (0.0, 0.0)
        r = frequency / f1
        drag = self.viscous_loss
        if self.medium is not None:
            drag = drag + 1j * r * fluid * self.fluid_load(frequency)
        return damping_substitution(r, formulas.beta_from_frequency(frequency, f1, b1),
                                    self.spring_constant, k1, self.tip_mass_ratio,
                                    1.0 / self.quality_factor, drag, loss)

    def model_arguments(self, frequency, contact: "Contact | None" = None,
                        fluid: float = 1.0) -> tuple[complex, composed.Parameters]:
        """The composed model's arguments ``(beta, parameters)`` (:mod:`pfmdyn.composed`) at ``frequency``
        in Hz, with the damping substituted.

        The frequency may be complex (a damped mode's root); ``contact=None`` is the free lever.
        :meth:`response` and the damped modes of :mod:`pfmdyn.analysis.resonances` both read the
        model through this one substitution.

        >>> c = Cantilever(2.0, 7e4, 2e-4, quality_factor=100.0, tilt=10.0, tip_height=1e-5)
        >>> beta, p = c.model_arguments(7e4, Contact(k1=50.0))
        >>> round(float(abs(beta)), 4), [round(float(np.real(x)), 3) for x in (p.kvv, p.kll, p.kvl)]
        (1.8751, [48.492, 1.508, -8.551])
        >>> c.model_arguments(7e4)[1][1:5]                                        # free: no springs
        (0.0, 0.0, 0.0, 1e-05)
        """
        damped = self._damped(frequency, contact, fluid)
        return damped.beta, self.model_parameters(contact, k1=damped.k1)._replace(k=damped.k, mu=damped.mu)

    def model_parameters(self, contact: "Contact | None" = None, *, k1=None) -> composed.Parameters:
        """The composed model's parameters (:class:`pfmdyn.composed.Parameters`: ``k, kvv, kll, kvl, H, L,
        mu, gamma, rho_g``) without damping: the one place they are built from a probe.

        The contact springs in the lever's axes (the tilt rotates ``k1``, ``k2``; zeros when
        ``contact`` is None); ``k1``, when given, replaces the contact's before the rotation (the
        contact dashpot's complex ``k1``, :func:`damping_substitution`).

        >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, tilt=10.0)
        >>> k, kvv, kll, kvl, H, *_ = lever.model_parameters(Contact(k1=50.0))
        >>> k, round(float(kvv), 3), round(float(kll), 3), round(float(kvl), 3), H
        (2.0, 48.492, 1.508, -8.551, 1e-05)
        """
        if contact is None:
            springs, height = (0.0, 0.0, 0.0), self.tip_height or 0.0
        else:
            springs = rotated(contact.k1 if k1 is None else k1, contact.k2_of(contact.k1), self.alpha)
            height = self._tip_height(contact)
        return composed.Parameters(self.spring_constant, *springs, height, self.length, self.tip_mass_ratio,
                                   self.tip_position, self.rho_g)

    def response(self, frequency, contact: "Contact") -> transfer.ElasticTransfer:
        """Slope at the laser spot per unit ``d1, d2, f0, q0`` at ``frequency`` (Hz) of the composed model.

        Set-back, heavy, tilted tips, the tip's rotary inertia and every damping mechanism at once
        (:mod:`pfmdyn.composed`), read at ``spot_position`` (the free end by default); equal to :meth:`elastic_response` for the paper's probe.

        >>> c = Cantilever(2.0, 7e4, 2e-4, quality_factor=100.0, tip_height=1e-5)
        >>> contact = Contact(k1=50.0, k2=20.0)
        >>> r = c.response([1e5, 3e5], contact)
        >>> bool(np.allclose(r.vertical, c.elastic_response([1e5, 3e5], k1=50.0, k2=20.0, H=1e-5).vertical))
        True
        """
        if contact.k1 is None:
            raise UserError("the contact needs k1", quantity="k1")
        beta, parameters = self.model_arguments(_positive(frequency), contact)
        with np.errstate(all="ignore"):
            slopes = composed.slope(beta, parameters, self.spot_position)
        return transfer.ElasticTransfer(*(np.asarray(s, dtype=complex) for s in slopes))

    def base_driven(self, frequency, contact: "Contact | None" = None) -> transfer.BaseTransfer:
        """Driven at the base (the clamp moved by ``y0``: a dither piezo), per unit ``y0``: the slope at
        the laser spot and the deflection there relative to the base, at ``frequency`` (Hz), free
        (``contact=None``) or in contact, with the damping substituted (:mod:`pfmdyn.composed`).

        >>> lever = Cantilever(2.0, 7e4, 2e-4, quality_factor=50.0)
        >>> r = lever.base_driven([7e2, 7e4])
        >>> round(float(abs(r.deflection[0])), 6), round(float(abs(r.deflection[1])), 1)   # beta**4 / 8; 1.566 Q
        (0.000155, 78.3)
        """
        beta, parameters = self.model_arguments(_positive(frequency), contact)
        with np.errstate(all="ignore"):
            (slope,), (deflection,) = composed.response(beta, parameters, self.spot_position, drives=("y0",))
        return transfer.BaseTransfer(np.asarray(slope, dtype=complex), np.asarray(deflection - 1.0, dtype=complex))

    def thermal_noise(self, frequency, temperature: float, contact: "Contact | None" = None) -> transfer.ThermalNoise:
        """The thermal spectrum at the laser spot, every mode at once, at ``frequency`` (Hz) and
        ``temperature`` (K): one-sided power spectral densities of the slope and the deflection.

        Fluctuation-dissipation: ``S_y(f) = -4 k_B T Im chi_yy / omega``, with ``chi_yy`` the response
        of ``y`` to the force that does work on it, applied at the spot (a couple for the slope, a
        force for the deflection), from the composed lever with a bare point there
        (:data:`pfmdyn.composed.PROBE_DRIVES`).  Only the losses make noise: a lossless lever has none
        between its resonances.

        >>> lever = Cantilever(2.0, 7e4, 2e-4, quality_factor=100.0)
        >>> psd = lever.thermal_noise([7e3, 7e4], 300.0)
        >>> [f"{v:.3g}" for v in psd.deflection]            # m**2/Hz: the floor, the first mode's peak
        ['1.92e-27', '1.83e-24']
        """
        f = _positive(frequency)
        if not temperature > 0:
            raise UserError(f"the temperature must be above 0 K, got {temperature!r}")
        beta, parameters = self.model_arguments(f, contact)
        with np.errstate(all="ignore"):
            (_, per_couple), (per_force, _) = composed.response(beta, parameters, self.spot_position,
                                                                drives=composed.PROBE_DRIVES, probe=self.spot_position)
        scale = -2.0 * BOLTZMANN * temperature / (np.pi * f)
        return transfer.ThermalNoise(scale * np.imag(per_couple), scale * np.imag(per_force))




def _positive(frequency) -> np.ndarray:
    """Frequencies in Hz as a float array; not positive and finite: ValueError."""
    f = np.asarray(frequency, dtype=float)
    if not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("frequency must be positive and finite (Hz)")
    return f


class Damped(NamedTuple):
    """The model's ``beta``, ``k``, ``k1`` and ``mu`` with the damping substituted, and the
    generated factors ``(beta, k, k1, mu)`` that made them (the chain rule of a fit needs them)."""

    beta: object
    k: object
    k1: object
    mu: object
    factors: tuple


def damping_substitution(r, beta, k, k1, mu, inv_q, g, x) -> Damped:
    """The undamped model's ``beta``, ``k``, ``k1`` and ``mu`` damped at ``r = f / f1``
    (``derivations/damping.py``, generated: :func:`pfmdyn.generated.damping.factors`).

    Internal friction ``inv_q`` (1/Q of the modulus), viscous drag ``g`` and the contact dashpot
    ``x`` (loss tangent at f1).  The one place the substitution is applied: the probe's responses
    and resonances, the discrepancy model and its quality factors, and the map fit.  ``r`` may be
    complex (a damped mode's root); arrays broadcast.

    >>> d = damping_substitution(1.5, 2.0, 1.0, 100.0, 0.1, 0.01, 0.02, 0.03)
    >>> complex(d.k), complex(d.k1), round(float(abs(d.beta)), 6)
    ((1+0.01j), (100+4.5j), 2.000019)
    """
    factors = damping.factors(r, inv_q, g, x)
    beta_f, k_f, k1_f, mu_f = factors
    return Damped(beta * beta_f, k * k_f, k1 * k1_f, mu * mu_f, factors)


@lru_cache(maxsize=4096)
def free_root(k, H, L, mu, gamma, rho_g=0.0) -> float:
    """First free root ``beta`` with a tip mass ``mu`` (radius of gyration ``rho_g L``) at ``gamma L``
    (1.8751... at ``mu = 0``).

    The characteristic of the composed model (:mod:`pfmdyn.composed`) with no contact has
    one root in ``(0.3, BETA1_FREE]`` (a tip mass only lowers it): bracketed on a grid, refined.

    >>> round(free_root(1.0, 1e-5, 1e-4, 0.0, 1.0, 0.0), 10)
    1.8751040687
    """
    if mu == 0.0:
        return BETA1_FREE
    free = composed.Parameters(k=k, kvv=0.0, kll=0.0, kvl=0.0, H=H, L=L, mu=mu, gamma=gamma, rho_g=rho_g)
    char = lambda b: composed.characteristic(b, free)  # noqa: E731
    grid = np.linspace(0.3, BETA1_FREE + 1e-9, 65)
    with np.errstate(all="ignore"):
        vals = char(grid)
    change = np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) <= 0)
    if len(change) != 1:
        return float(refine(char, 0.3, BETA1_FREE + 1e-9, rtol=1e-14))
    i = change[0]
    return float(refine(char, grid[i], grid[i + 1], vals[i], vals[i + 1], rtol=1e-14))


@dataclass(frozen=True)
class Contact:
    """The tip-sample contact: ``k1`` (N/m) and ``k2`` or a policy tying it to ``k1``.

    At most one of ``k2`` (given), ``k2_over_k1`` (``k2 = X k1``) and ``poisson`` (the
    Hertz-Mindlin ratio of a sample of that Poisson's ratio) may be given; with none, ``k2``
    is free where the data determine it and :data:`DEFAULT_POISSON`'s Mindlin tie where they
    cannot (:meth:`tie`).  ``contact_loss`` is the contact dashpot (``derivations/damping.py``).

    >>> round(Contact(k1=100.0, poisson=0.3).k2_of(100.0), 3)
    82.353
    >>> Contact(k1=100.0, k2=5.0).k2_of(100.0), Contact(k1=100.0).k2_of(100.0)
    (5.0, 0.0)
    >>> Contact(k2=1.0, poisson=0.3)
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: give one of k2, k2_over_k1 and poisson, not several
    """

    k1: float | None = None
    k2: float | None = None
    k2_over_k1: float | None = None
    poisson: float | None = None
    contact_loss: float = 0.0

    def __post_init__(self):
        for name in ("k1", "k2", "k2_over_k1", "poisson", "contact_loss"):
            if getattr(self, name) is not None:
                checked(name, getattr(self, name))
        if sum(v is not None for v in (self.k2, self.k2_over_k1, self.poisson)) > 1:
            raise UserError("give one of k2, k2_over_k1 and poisson, not several")

    @property
    def ratio(self) -> float | None:
        """``k2 / k1`` of the stated tie (``k2_over_k1`` or Mindlin), or None."""
        if self.k2_over_k1 is not None:
            return float(self.k2_over_k1)
        if self.poisson is not None:
            return float(formulas.mindlin_k2_over_k1(self.poisson))
        return None

    def tie(self) -> float:
        """``k2 / k1`` to use when the data cannot fix ``k2`` (one contact mode): the stated tie,
        else Mindlin at :data:`DEFAULT_POISSON`; a given ``k2`` has no tie (NaN).

        >>> round(Contact().tie(), 6), Contact(k2_over_k1=0.5).tie()
        (0.823529, 0.5)
        """
        if self.k2 is not None:
            return math.nan
        ratio = self.ratio
        return float(formulas.mindlin_k2_over_k1(DEFAULT_POISSON)) if ratio is None else ratio

    def describe_k2(self) -> str:
        """The k2 policy in words, for reports.

        >>> Contact(poisson=0.25).describe_k2()
        'k2 tied to k1 (Mindlin, Poisson ratio 0.25: k2 = 0.857 k1)'
        """
        if self.k2 is not None:
            return f"k2 = {self.k2:g} N/m (given)"
        if self.poisson is not None:
            return f"k2 tied to k1 (Mindlin, Poisson ratio {self.poisson:g}: k2 = {self.ratio:.3g} k1)"
        if self.k2_over_k1 is not None:
            return f"k2 tied to k1 (k2 = {self.k2_over_k1:g} k1, given)"
        return "k2 free"

    def policy(self, lever: "Cantilever") -> tuple["Contact", str]:
        """The k2 law every command applies to ``lever`` and its words: a stated one as it is; none stated,
        k2 left out where it cannot act (no tip height, no tilt), else tied to k1 by Mindlin at
        :data:`DEFAULT_POISSON` (assumed, and said).  ``pfmdyn stiffness``, ``resonances``, ``spot`` and
        ``map`` share it, so a k1 one of them finds gives back its resonance in another.

        >>> lever = Cantilever(2.0, 75e3, 2e-4, tip_height=10e-6)
        >>> tied, words = Contact(k1=300.0).policy(lever); round(tied.k2_of(300.0), 3), words.split(" (")[0]
        (247.059, "k2 tied to k1 by Mindlin at Poisson's ratio 0.3")
        >>> Contact(k1=300.0).policy(Cantilever(2.0, 75e3, 2e-4))[0].k2_of(300.0)
        0.0
        """
        if self.k2 is not None or self.ratio is not None:
            return self, self.describe_k2()
        if lever.tip_height is None and lever.tilt == 0.0:
            return self, "k2 left out: without a tip height the lateral spring does not act on the lever"
        tied = replace(self, poisson=DEFAULT_POISSON)
        return tied, (f"k2 tied to k1 by Mindlin at Poisson's ratio {DEFAULT_POISSON:g} (assumed: k2 = {tied.ratio:.3g} "
                      "k1; give k2, k2_over_k1 or poisson)")

    def k2_of(self, k1) -> float:
        """``k2`` at contact stiffness ``k1``: given, tied, or 0 when nothing is said (:meth:`policy` says what
        the commands assume)."""
        if self.k2 is not None:
            return float(self.k2)
        ratio = self.ratio
        return 0.0 if ratio is None else ratio * k1


_EXAMPLE = {"k1": 10.0, "k2": 5.0, "H": 1e-5}
"""Parameter values of the generated methods' doctests (N/m, m)."""
_OWN = ("k", "L")
"""Registry parameters the cantilever supplies itself."""


def _response_method(row):
    """``Cantilever.<row.method>``: the family's transfer at frequencies in Hz, with losses."""
    extra = [p for p in row.parameters if p not in _OWN]
    keyword = inspect.Parameter.KEYWORD_ONLY
    displacement = "deflection" in row.outputs   # then ``output`` chooses slope or displacement
    signature = inspect.Signature(
        [inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD) for p in ("self", "frequency")]
        + [inspect.Parameter(p, keyword) for p in extra]
        + ([inspect.Parameter("output", keyword, default="slope")] if displacement else []),
        return_annotation=f"transfer.{row.result}")

    def response(self, frequency, **kwargs):
        given = signature.bind(self, frequency, **kwargs).arguments
        if not self.is_paper_probe:
            raise UserError(f"{row.method} is the paper's family ({row.equations}): massless tip at the free end, "
                            "no tilt, spot at the end; use Cantilever.response for this lever")
        damped = self._damped(_positive(frequency))
        values = transfer.check_parameters({p: given[p] for p in extra})
        return transfer.evaluate(row.module, damped.beta, {"k": damped.k, "L": self.length, **values},
                                 given.get("output"))

    call = ", ".join(["[1e3, 1e6]"] + [f"{p}={_EXAMPLE[p]!r}" for p in extra])
    fields = getattr(transfer, row.result)._fields
    response.__name__ = row.method
    response.__qualname__ = f"Cantilever.{row.method}"
    response.__signature__ = signature
    response.__doc__ = f"""Tip {'slope or displacement' if displacement else 'slope'} per unit {', '.join(row.drives)} \
({row.equations}) at ``frequency`` in Hz.

    :func:`pfmdyn.transfer.{row.function}` at this cantilever's ``beta`` and ``k`` with
    its internal friction substituted; parameters ({', '.join(extra) or 'none'}) as there.

    >>> r = Cantilever(1.0, 1e5, 1e-4, quality_factor=100.0).{row.method}({call})
    >>> r._fields, r[0].shape, r[0].dtype
    ({fields!r}, (2,), dtype('complex128'))
    """
    return response


for _row in families.FAMILIES:
    if _row.method:
        setattr(Cantilever, _row.method, _response_method(_row))
