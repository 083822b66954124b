"""The elastic-contact beam response of a band-excitation map pixel, with its derivatives for the
batched fit.

At each pixel the measured response is ``c_b * A_v(f; k1, k2, damping)``: the tip slope per
unit vertical surface displacement of the elastic-contact cantilever
(:mod:`pfmdyn.generated.elastic_contact`), damped by the substitution of
:mod:`pfmdyn.generated.damping` (internal friction ``1/Q`` always; viscous drag ``g`` and a
contact dashpot ``x`` when the model names them), with one complex amplitude ``c_b`` per
frequency band (d_eff amplitude and phase, arbitrary instrument units; bands are driven and
demodulated separately).  ``+distributed`` adds the response to a load along the lever (the
electrostatic force on the lever's body) with amplitudes of its own.  With a bias axis
(:mod:`pfmdyn.maps.bias`) every band and drive has two amplitudes, an intercept and a slope per
volt of DC bias.

The nonlinear parameters are ``k1``, ``Q``, ``k2`` (as log10; ``k2`` when the frequencies hold two or
more bands, one per contact mode; one mode cannot separate ``k1`` from ``k2``, so with one band ``k2``
follows the contact's policy, :meth:`pfmdyn.Contact.tie`: a stated ratio, or Mindlin's at Poisson
0.3, as ``pfmdyn stiffness`` and ``pfmdyn discrepancy`` do; a given ``k2`` is held), ``g`` and ``x``.
One *design evaluation* gives the transfer functions and their derivatives for a whole block of
pixels (:meth:`BeamMapModel.design`), which the batched fit (:mod:`pfmdyn.maps.fit`) iterates on.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from ..cantilever import Cantilever, Contact, damping_substitution
from ..fitting.parameters import CONTACT_LOSS, LN10, VISCOUS_LOSS, Parameter
from .. import composed
from ..generated import damping, elastic_contact, formulas
from ..generated.tilt_rotation import rotated
from .outputs import quantities
from .spec import bands

__all__ = ["BeamMapModel", "POLICY_GRID", "k1_input_share"]

POLICY_GRID = 60
"""Values of ``k1`` (log-spaced over the fit's bounds: six decades) at which an assumed k2 tie's share of its standard error is
computed (:meth:`BeamMapModel.k1_policy_stderr`); it varies slowly with ``k1``."""


@dataclass(frozen=True)
class BeamMapModel:
    """The lever and contact (:class:`pfmdyn.Cantilever`, :class:`pfmdyn.Contact`), the frequency
    vector of the map and the mechanisms fitted.

    The lever carries the tip geometry (position, mass ratio, tilt) the map is fitted with; the
    contact its ``k2`` policy (:attr:`k2_mode`).

    Examples
    --------
    >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
    >>> m = BeamMapModel(lever, np.linspace(3e5, 4e5, 8))
    >>> m.shape_functions(np.array([200.0]), np.array([80.0])).shape
    (1, 8)
    >>> [p.name for p in m.parameters], m.k2_mode
    (['k1', 'q'], 'tied')
    """

    lever: Cantilever
    frequency_hz: np.ndarray
    mechanisms: tuple[str, ...] = ("internal",)
    bias_v: np.ndarray | None = None
    """DC tip bias of each spectrum of a pixel (V), or None: one spectrum per pixel."""
    contact: Contact = Contact()
    """The k2 policy: ``k2`` held, ``k2_over_k1``/``poisson`` tied, or nothing said (free with two
    or more bands, Mindlin's tie with one)."""
    k1_range: tuple[float, float] | None = None
    """k1 (N/m) the start grid covers (None: the lever's spring constant to 1e4 times it); the
    fit's bounds are a decade wider."""
    tip_height_uncertainty: float = 0.0
    """Standard uncertainty of the lever's tip height (m), whose share :meth:`k1_policy_stderr` adds."""

    @property
    def outputs(self) -> dict[str, tuple[str, str]]:
        """The per-pixel maps this model writes (:func:`quantities`)."""
        return quantities(self.mechanisms, self.bias_v is not None)

    @functools.cached_property
    def bands(self) -> list[slice]:
        """The frequency bands (one per contact mode driven)."""
        return bands(self.frequency_hz)

    @property
    def k2_mode(self) -> str:
        """``fixed`` (a given k2), ``tied`` (k2 = ratio k1: a stated ratio, or one band) or ``free``."""
        if self.contact.k2 is not None:
            return "fixed"
        return "tied" if self.contact.ratio is not None or len(self.bands) < 2 else "free"

    def describe_k2(self) -> str:
        """The k2 policy in words, for the summary and the Zarr attributes.

        >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
        >>> BeamMapModel(lever, np.linspace(3e5, 4e5, 8)).describe_k2()
        'k2 tied to k1 at 0.824 (Mindlin, Poisson ratio 0.3: one contact mode cannot separate k1 from k2)'
        """
        if self.k2_mode == "fixed":
            return f"k2 held at {self.contact.k2:g} N/m"
        if self.k2_mode == "free":
            return "k2 fitted (two or more contact-mode bands)"
        if self.contact.ratio is not None:
            return f"k2 tied to k1 at {self.contact.ratio:.3g} ({self.contact.describe_k2()})"
        from ..cantilever import DEFAULT_POISSON
        return (f"k2 tied to k1 at {self.contact.tie():.3g} (Mindlin, Poisson ratio {DEFAULT_POISSON:g}: one "
                "contact mode cannot separate k1 from k2)")

    @property
    def k1_span(self) -> tuple[float, float]:
        """:attr:`k1_range` or its default."""
        k = self.lever.spring_constant
        return tuple(self.k1_range) if self.k1_range else (k, 1e4 * k)

    @functools.cached_property
    def parameters(self) -> tuple[Parameter, ...]:
        """Nonlinear parameters, in the order of the fit's columns: ``k1``, ``Q`` (log10), ``k2``
        (log10, when fitted), then the damping mechanisms' losses.  Bounds: k1 a decade beyond
        :attr:`k1_span`, k2 from a tenth of its lower end, Q 1 to 1e5 (its upper bound is no loss:
        the null)."""
        lo, hi = self.k1_span
        out = [Parameter("k1", "N/m", math.log10(lo / 10), math.log10(hi * 10), transform="log10"),
               Parameter("q", "1", 0.0, 5.0, transform="log10", public="quality_factor", null=5.0)]
        if self.k2_mode == "free":
            out.append(Parameter("k2", "N/m", math.log10(lo / 100), math.log10(hi * 10), transform="log10",
                                 null=math.log10(lo / 100)))
        extra = {"viscous": VISCOUS_LOSS, "contact": CONTACT_LOSS}
        return tuple(out + [extra[m] for m in self.mechanisms if m in extra])

    @property
    def names(self) -> tuple[str, ...]:
        """Internal names of :attr:`parameters`."""
        return tuple(p.name for p in self.parameters)

    def k2_of(self, k1, log_k2=None):
        """``k2`` by the policy at contact stiffness ``k1`` (``log_k2``, log10, when fitted)."""
        mode = self.k2_mode
        if mode == "free":
            return 10.0**log_k2
        if mode == "fixed":
            return np.full_like(np.asarray(k1, float), self.contact.k2)
        return self.contact.tie() * np.asarray(k1, float)

    def k1_policy_stderr(self, k1) -> np.ndarray:
        """The share of the assumed inputs in the standard error of ``k1`` (N/m, each pixel), as ``pfmdyn
        stiffness`` states them (:func:`pfmdyn.analysis.contact_resonance.covariance_by_source`): with one
        band and no k2 policy stated, ``k2`` is tied by Mindlin at an assumed Poisson's ratio, whose spread
        (:func:`pfmdyn.analysis.stiffness_report.assumed_tie_uncertainty`) moves the ``k1`` that puts the
        contact resonance where it was measured; so does the tip height (:attr:`tip_height_uncertainty`)
        where ``k2`` is tied or held.  0 where neither acts: k2 fitted (then ``k2 H^2`` takes up the tip
        height), or held at 0 on an untilted lever.  The share at :data:`POLICY_GRID` values of ``k1``
        across the fit's bounds, interpolated in ``log k1``.

        >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
        >>> m = BeamMapModel(lever, np.linspace(3e5, 4e5, 8))
        >>> sd = m.k1_policy_stderr(np.array([150.0, np.nan]))
        >>> bool(0.005 < sd[0] / 150.0 < 0.02), float(sd[1])        # under 1 %: one contact mode near 4 f1
        (True, 0.0)
        >>> float(BeamMapModel(lever, np.linspace(3e5, 4e5, 8), contact=Contact(poisson=0.3)).k1_policy_stderr(150.0))
        0.0
        >>> held = BeamMapModel(lever, np.linspace(3e5, 4e5, 8), contact=Contact(k2=100.0), tip_height_uncertainty=1e-6)
        >>> bool(held.k1_policy_stderr(150.0) > 0.01 * 150.0)       # 10 % of the tip height: k2 H^2 by 20 %
        True
        """
        k1 = np.asarray(k1, float)
        out = np.zeros(k1.shape)
        ok = np.isfinite(k1) & (k1 > 0)
        if self._policy_shares is not None and ok.any():
            grid, share = self._policy_shares
            out[ok] = k1[ok] * np.interp(np.log(k1[ok]), grid, share)
        return out

    @property
    def _policy_shares(self):
        """``(log k1, relative share)`` at :data:`POLICY_GRID` values across the fit's bounds of ``k1``; None
        when no assumed input acts.  Cached per process (a map's workers get the model anew for each task)."""
        from ..analysis.stiffness_report import assumed_tie_uncertainty
        lateral = self.lever.tip_height is not None or self.lever.alpha != 0.0
        tie = assumed_tie_uncertainty() if self.k2_mode == "tied" and self.contact.ratio is None else 0.0
        height = self.tip_height_uncertainty if self.lever.tip_height is not None and (
            self.k2_mode == "tied" or self.k2_mode == "fixed" and (self.contact.k2 or self.lever.alpha)) else 0.0
        if not lateral or not (tie or height):
            return None
        lo, hi = self.k1_span
        held = self.contact.k2 if self.k2_mode == "fixed" else None
        return _policy_shares(self.lever, self.contact.tie() if held is None else None, held,
                              float(np.median(self.frequency_hz)), lo / 10, hi * 10, tie, height)

    @property
    def _composed(self) -> bool:
        """Whether the lever needs the composed (set-back) model: the elastic-contact family is
        the paper's massless, untilted tip at the free end."""
        return not self.lever.is_paper_probe

    def _arguments(self, inv_q, g, k1, k2, x):
        """``(beta0, r, beta, k1 / k_factor, k2 / k_factor, k_factor, mu)``: the undamped ``beta``,
        ``r = f / f1`` (its first value only when the damping does not depend on frequency), and
        the damping substitution (:func:`pfmdyn.cantilever.damping_substitution`).

        Internal friction makes EI complex, ``k -> k (1 + i/Q)``; the transfer function depends
        on the springs only through ``k1 / k`` and ``k2 / k``, so ``k`` stays real and the
        contact springs are divided by that factor (the dashpot multiplies ``k1``).  A heavy tip
        moves the lever's first free root (:meth:`pfmdyn.Cantilever.free_root`); a medium
        (:attr:`pfmdyn.Cantilever.medium`) loads it at every frequency, ``r`` then from the vacuum ``f1``.
        """
        f = np.asarray(self.frequency_hz, float)
        f1 = self.lever.vacuum_resonance          # the lever's own (free_resonance without a medium)
        beta0 = formulas.beta_from_frequency(f, f1, self.lever.free_root())
        # internal friction alone damps every frequency alike: its factors once per pixel, not per frequency
        alike = self.lever.medium is None and not {"viscous", "contact"} & set(self.mechanisms)
        r = f[:1] / f1 if alike else f / f1
        # a medium's load is a drag of its own beside the fitted one (derivations/damping.py: fluid_as_drag)
        drag = g if self.lever.medium is None else g + 1j * r * self.lever.fluid_load(f)
        d = damping_substitution(r, beta0, 1.0, k1, self.lever.tip_mass_ratio, inv_q, drag, x)   # k = 1: d.k is the factor
        return beta0, r, d.beta, d.k1 / d.k, k2 / d.k, d.k, d.mu

    def _transfer(self, beta, k1e, k2e, mu, jacobian):
        """Slopes per drive and (with ``jacobian``) per drive the partials w.r.t. (beta, k1, k2,
        mu), None where not needed (as are the elastic contact's partials of drives not in
        :attr:`drives`): the generated elastic contact for the paper's probe, else the generated
        composed model (set-back, heavy or tilted tip: springs rotated onto the beam
        axes, so the partials w.r.t. k1 and k2 combine those w.r.t. kvv, kll, kvl)."""
        lever = self.lever
        height = lever.tip_height or 0.0        # no tip height: the lateral force has no lever arm
        k, length = lever.spring_constant, lever.length
        if not self._composed:
            if not jacobian:
                return elastic_contact.slope(beta, k, k1e, k2e, height, length), None
            values, partials = elastic_contact.slope_and_jacobian(beta, k, k1e, k2e, height, length,
                                                                  drives=self.drives)
            return values, [(*p, None) for p in partials]
        alpha = lever.alpha
        # read at the laser spot or, by default, at the free end
        spot = lever.spot_position
        reading = composed.at_end if spot == 1.0 else composed.Reading(spot)
        kvv, kll, kvl = rotated(k1e, k2e, alpha)
        parameters = lever.model_parameters(None)._replace(kvv=kvv, kll=kll, kvl=kvl, mu=mu)
        if not jacobian:
            return reading.slope(beta, parameters), None
        wanted = ("beta", "kvv", "kll", "kvl", "mu")
        # the tip mass moves with drag only (mu_factor); otherwise its partial multiplies zero
        moving_mass = self.lever.tip_mass_ratio and "viscous" in self.mechanisms
        values, partials = reading.slope_and_jacobian(beta, parameters, wrt=wanted if moving_mass else wanted[:4])
        c, s = math.cos(alpha), math.sin(alpha)
        index = {name: reading.JACOBIAN_PARAMETERS.index(name) for name in wanted}
        out = []
        for p in partials:
            d_vv, d_ll, d_vl = (p[index[n]] for n in ("kvv", "kll", "kvl"))
            out.append((p[index["beta"]], d_vv * c * c + d_ll * s * s + d_vl * s * c,
                        d_vv * s * s + d_ll * c * c - d_vl * s * c, p[index["mu"]] if moving_mass else None))
        return values, out

    def _physical(self, p):
        """(inv_q, g, k1, k2, x) of internal parameters ``p`` (``(n, n_p)``), each ``(n, 1)``."""
        col = {name: p[:, i, None] for i, name in enumerate(self.names)}
        zero = np.zeros_like(col["k1"])
        k1 = 10.0**col["k1"]
        return (10.0**-col["q"], col.get("g", zero), k1, self.k2_of(k1, col.get("k2")), col.get("x", zero))

    def shape_functions(self, k1, q, k2=None, g=0.0, x=0.0) -> np.ndarray:
        """Tip slope per unit d1 at every frequency, shape ``(len(k1), n_freq)``; ``k2`` by the
        policy (:meth:`k2_of`) unless given."""
        k1 = np.asarray(k1, float)
        k2 = self.k2_of(k1, 0.0 * k1) if k2 is None and self.k2_mode != "free" else (0.0 if k2 is None else k2)
        col = [np.asarray(v, float) * np.ones(np.shape(k1)) for v in (1.0 / np.asarray(q, float), g, k1, k2, x)]
        _, _, beta, k1e, k2e, _, mu = self._arguments(*(c[:, None] for c in col))
        return self._transfer(beta, k1e, k2e, mu, jacobian=False)[0][0]

    @property
    def drives(self) -> tuple[int, ...]:
        """Drives (indices into the generated ``DRIVES``) with a transfer function of their own:
        ``d1`` (which also carries the local electrostatic force, ``f0 + k1 d1`` at the tip),
        and ``q0``, the distributed electrostatic load on the lever, with ``+distributed``."""
        return (0, 3) if "distributed" in self.mechanisms else (0,)

    def design(self, p, jacobian=True):
        """Transfer functions ``(n, n_drives, n_freq)`` at internal parameters ``p`` ``(n, n_p)``
        and their derivatives ``(n_p, n, n_drives, n_freq)`` (None unless ``jacobian``): one call
        of the generated values-and-partials (w.r.t. ``beta``, ``k1``, ``k2``), chained with the
        generated derivatives of the damping factors.
        """
        inv_q, g, k1, k2, x = self._physical(p)
        beta0, r, beta, k1e, k2e, k_factor, mu = self._arguments(inv_q, g, k1, k2, x)
        values, partials = self._transfer(beta, k1e, k2e, mu, jacobian)
        if not jacobian:
            return np.stack([values[i] for i in self.drives], axis=1), None
        (dbf_inv_q, dbf_g, _), (dkf_inv_q, _, _), (_, _, dk1f_x), (_, dmf_g, _) = damping.d_factors(r, inv_q, g, x)
        d = np.empty((len(self.parameters), len(k1), len(self.drives), values[0].shape[-1]), complex)
        for j, drive in enumerate(self.drives):
            d_beta, d_k1, d_k2, d_mu = partials[drive]
            # d/d inv_q of k1e, k2e (both divided by k_factor) and of beta
            spring_loss = -dkf_inv_q / k_factor * (d_k1 * k1e + d_k2 * k2e)
            # a tied k2 (k2 = ratio k1) moves with k1; a held one does not
            tied = d_k2 * k2e if self.k2_mode == "tied" else 0.0
            # log10 coordinates: d/d(log10 v) = ln(10) v d/dv; only the fitted parameters' chains
            chain = {"k1": lambda: (d_k1 * k1e + tied) * LN10, "k2": lambda: d_k2 * k2e * LN10,
                     "q": lambda: -inv_q * LN10 * (d_beta * beta0 * dbf_inv_q + spring_loss),
                     "g": lambda: d_beta * beta0 * dbf_g + (0.0 if d_mu is None else
                                                           d_mu * self.lever.tip_mass_ratio * dmf_g),
                     "x": lambda: d_k1 * k1 * dk1f_x / k_factor}
            for i, name in enumerate(self.names):
                d[i, :, j] = chain[name]()
        return np.stack([values[i] for i in self.drives], axis=1), d


@functools.lru_cache(maxsize=32)
def _policy_shares(lever: Cantilever, ratio: float | None, held: float | None, middle_hz: float, low: float,
                   high: float, tie_stderr: float, height_stderr: float):
    grid = np.geomspace(low, high, POLICY_GRID)
    return np.log(grid), np.array([k1_input_share(lever, ratio, held, middle_hz, k, tie_stderr, height_stderr)
                                   for k in grid])


def k1_input_share(lever: Cantilever, ratio: float | None, held: float | None, middle_hz: float, k1: float,
                   tie_stderr: float, height_stderr: float) -> float:
    """The relative standard error of ``k1`` from the tie's ratio (``tie_stderr``) and the tip height
    (``height_stderr``, m), ``k2 = ratio k1`` or ``held``: at the contact root ``beta`` nearest ``middle_hz``
    (Newton from there), the measured ``beta`` held, ``d k1 / d p = -F_p / (F_k1 + ratio F_k2)`` of the
    characteristic ``F(beta, k1, k2; H)`` (central differences), the two in quadrature.

    >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
    >>> round(k1_input_share(lever, 0.8, None, 3.5e5, 150.0, 0.0, 1e-6), 4)    # 10 % of H: k2 H^2 by 20 %
    0.0336
    """
    from ..analysis.contact_resonance import betas, characteristic

    def F(b, a, c, lv=lever):
        return float(np.real(characteristic(b, lv, a, c, lv.tip_position)))

    def k2(a):
        return held if ratio is None else ratio * a

    b = float(betas(lever, middle_hz))
    with np.errstate(all="ignore"):
        for _ in range(50):
            h = 1e-7 * b
            step = -F(b, k1, k2(k1)) * 2 * h / (F(b + h, k1, k2(k1)) - F(b - h, k1, k2(k1)))
            if not math.isfinite(step):
                return 0.0
            b += step
            if abs(step) < 1e-12 * b:
                break
        e = 1e-6 * k1
        d_k1 = (F(b, k1 + e, k2(k1)) - F(b, k1 - e, k2(k1))) / (2 * e)
        d_k2 = (F(b, k1, k2(k1) + e) - F(b, k1, k2(k1) - e)) / (2 * e)
        slope = d_k1 + (ratio or 0.0) * d_k2
        shares = [d_k2 * tie_stderr]          # F_ratio = k1 F_k2: relative to k1, F_k2
        if height_stderr:
            eh = 1e-6 * lever.tip_height
            up, down = (replace(lever, tip_height=lever.tip_height + s) for s in (eh, -eh))
            shares.append((F(b, k1, k2(k1), up) - F(b, k1, k2(k1), down)) / (2 * eh) * height_stderr / k1)
        share = math.hypot(*shares) / abs(slope)
    return float(share) if math.isfinite(share) else 0.0
