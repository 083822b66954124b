"""Batched per-pixel fit of the elastic-contact beam response to band-excitation spectra.

At each pixel the measured response is ``c_b * A_v(f; k1, k2, damping)``: the tip slope per
unit vertical surface displacement of the elastic-contact cantilever
(:mod:`pfmdyn.generated.elastic_contact`), damped by the substitution of
:mod:`pfmdyn.generated.damping` (internal friction ``1/Q`` always; viscous drag ``g`` and a
contact dashpot ``x`` when the model names them), with one complex amplitude ``c_b`` per
frequency band (d_eff amplitude and phase, arbitrary instrument units; bands are driven and
demodulated separately).  ``+distributed`` adds the response to a load along the lever (the
electrostatic force on the lever's body) with amplitudes of its own.  With a bias axis
(:mod:`pfmdyn.maps.bias`) every band and drive has two amplitudes, an intercept and a slope per
volt of DC bias.  The amplitudes enter linearly and are projected out (variable projection);
``k1``, ``Q``, ``k2`` (as log10; ``k2`` when the frequencies hold two or more bands, one per contact
mode; one mode cannot separate ``k1`` from ``k2``, so with one band ``k2`` follows the contact's
policy, :meth:`pfmdyn.Contact.tie`: a stated ratio, or Mindlin's at Poisson 0.3, as ``pfmdyn
stiffness`` and ``pfmdyn discrepancy`` do; a given ``k2`` is held), ``g`` and ``x`` are fitted by a Levenberg-Marquardt iteration that treats every pixel of a block at once, each
pixel with its own damping factor.

Cost is dominated by the generated transfer function over ``(pixels, frequencies)``; one
*design evaluation* per iteration gives the transfer functions and their derivatives for the
whole block (:meth:`BeamMapModel.design`), and the derivatives of the projected residual follow
from them in closed form (Golub and Pereyra 1973; :mod:`pfmdyn.fitting.projection`, shared with
``pfmdyn discrepancy``).  The iteration and the covariance of all parameters, nonlinear and
amplitudes, are the batched engine's (:mod:`pfmdyn.fitting.batched`, shared with the SHO fit).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from ..cantilever import Cantilever, Contact, damping_substitution
from ..errors import UserError
from ..fitting.noise import GAP_LIMIT, gap, noise_sigmas
from ..fitting.parameters import CONTACT_LOSS, LN10, VISCOUS_LOSS, Parameter
from ..fitting.parameters import bounds as parameter_bounds
from ..fitting.batched import amplitude_column, band_covariance, levenberg_marquardt, project_bands
from .. import composed
from ..generated import damping, elastic_contact, formulas
from ..generated.tilt_rotation import rotated
from . import bias as bias_axis

__all__ = ["BeamMapModel", "CHUNK", "MECHANISMS", "fit_block", "fittable", "quantities", "bands", "parse_model"]

CHUNK = 256
"""Pixels fitted together: large enough to make the per-call overhead negligible, small enough
for the ``(pixels, frequencies)`` temporaries to stay in cache (1024 at once is ~1.5x slower)."""

MECHANISMS = ("internal", "viscous", "contact", "distributed")
"""Mechanisms a map model may hold: damping (``internal`` always: the baseline; viscous drag, a
contact dashpot) and the electrostatic load distributed along the lever (a second transfer
function, :attr:`BeamMapModel.drives`)."""

# name -> (unit, description) of the per-pixel output arrays
_QUANTITIES = {
    "k1": ("N/m", "vertical contact stiffness"),
    "k1_stderr": ("N/m", "standard error of k1"),
    "k2": ("N/m", "longitudinal contact stiffness (two or more bands; else NaN)"),
    "k2_stderr": ("N/m", "standard error of k2"),
    "quality_factor": ("1", "quality factor Q of the beam loss 1/Q (internal friction)"),
    "quality_factor_stderr": ("1", "standard error of Q"),
    "viscous_loss": ("1", "viscous drag g = c / (rho S omega1): 1/Q of free mode 1 under drag alone"),
    "viscous_loss_stderr": ("1", "standard error of viscous_loss"),
    "contact_loss": ("1", "contact dashpot x = omega1 eta / k1: loss tangent of the contact at f1"),
    "contact_loss_stderr": ("1", "standard error of contact_loss"),
    "amplitude": ("response units per unit d1",
                  "d_eff amplitude |c| (first band; with biases the response at V = V_surf: intercept + V_surf slope)"),
    "amplitude_stderr": ("response units per unit d1", "standard error of amplitude"),
    "phase": ("rad", "d_eff phase arg c (first band)"),
    **bias_axis.QUANTITIES, **bias_axis.DISTRIBUTED, **bias_axis.SURFACE,
    "gap": ("1", "noise-normalised RMS residual sqrt(mean |y - model|^2) / sigma: 1 = fitted to the noise "
                 "(sigma from the pixel's spectra, pfmdyn.fitting.noise, as pfmdyn discrepancy)"),
    "at_bound": ("1", "1 where a fitted parameter sits at its bound: the model cannot reach the data there, "
                      "so nothing is reported for the pixel"),
    "explained": ("1", "1 where the model explains the pixel (gap below the threshold, default 2, no parameter at "
                       "a bound), else 0"),
}
_REQUIRES = {"viscous_loss": {"viscous"}, "viscous_loss_stderr": {"viscous"},
             "contact_loss": {"contact"}, "contact_loss_stderr": {"contact"},
             **dict.fromkeys(bias_axis.QUANTITIES, {"bias"}), **dict.fromkeys(bias_axis.DISTRIBUTED, {"distributed"}),
             **dict.fromkeys(bias_axis.SURFACE, {"distributed", "bias"})}
"""What a model must hold (mechanisms, a bias axis) to write a quantity (others: always)."""


def quantities(mechanisms=("internal",), bias: bool = False) -> dict[str, tuple[str, str]]:
    """Output arrays (name -> (unit, description)) of a model with these damping mechanisms
    (and the electrostatic maps when the map has a ``bias`` axis).

    >>> list(quantities(("internal", "viscous")))[4:8]
    ['quality_factor', 'quality_factor_stderr', 'viscous_loss', 'viscous_loss_stderr']
    >>> [name for name in quantities(bias=True) if "bias" in name]
    ['nulling_bias', 'nulling_bias_stderr']
    """
    have = set(mechanisms) | ({"bias"} if bias else set())
    return {name: v for name, v in _QUANTITIES.items() if _REQUIRES.get(name, set()) <= have}


def parse_model(spec: str) -> tuple[str, ...]:
    """Mechanisms of a model spec ``elastic[+viscous][+contact][+distributed]``.

    >>> parse_model("elastic+contact")
    ('internal', 'contact')
    """
    names = spec.split("+")
    unknown = [n for n in names[1:] if n not in MECHANISMS[1:]]
    if names[0] != "elastic" or unknown:
        raise UserError(f"unknown model {spec!r}: use 'auto' or elastic[+viscous][+contact][+distributed]")
    return ("internal",) + tuple(m for m in MECHANISMS[1:] if m in names)


def model_name(mechanisms) -> str:
    """Inverse of :func:`parse_model`.

    >>> model_name(("internal", "viscous"))
    'elastic+viscous'
    """
    return "+".join(["elastic", *[m for m in mechanisms if m != "internal"]])


def bands(frequency_hz) -> list[slice]:
    """Split a sorted frequency vector into bands at gaps wider than 10 median steps.

    >>> bands([1.0, 2.0, 3.0, 50.0, 51.0])
    [slice(0, 3, None), slice(3, 5, None)]
    """
    f = np.asarray(frequency_hz, float)
    step = np.diff(f)
    cuts = np.flatnonzero(step > 10 * np.median(step)) + 1 if step.size else []
    edges = [0, *list(cuts), len(f)]
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


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
    """k1 (N/m) the start grid covers (None: ``k`` to ``1e4 k``); the fit's bounds are a decade
    wider."""

    @property
    def k(self) -> float:
        return self.lever.spring_constant

    @property
    def L(self) -> float:
        return self.lever.length

    @property
    def f1(self) -> float:
        return self.lever.free_resonance

    @property
    def H(self) -> float:
        return self.lever.tip_height or 0.0

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
        return tuple(self.k1_range) if self.k1_range else (self.k, 1e4 * self.k)

    @functools.cached_property
    def parameters(self) -> tuple[Parameter, ...]:
        """Nonlinear parameters, in the order of the fit's columns: ``k1``, ``Q`` (log10), ``k2``
        (log10, when fitted), then the damping mechanisms' losses.  Bounds: k1 a decade beyond
        :attr:`k1_span`, k2 from a tenth of its lower end, Q 1 to 1e5 (its upper bound is no loss:
        the null)."""
        lo, hi = self.k1_span
        out = [Parameter("k1", "N/m", math.log10(lo / 10), math.log10(hi * 10), transform="log10",
                         description="vertical contact stiffness"),
               Parameter("q", "1", 0.0, 5.0, transform="log10", public="quality_factor", null=5.0,
                         description="quality factor Q of the beam loss 1/Q (internal friction)")]
        if self.k2_mode == "free":
            out.append(Parameter("k2", "N/m", math.log10(lo / 100), math.log10(hi * 10), transform="log10",
                                 null=math.log10(lo / 100), description="longitudinal contact stiffness"))
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

    @property
    def _composed(self) -> bool:
        """Whether the lever needs the composed (set-back) model: the elastic-contact family is
        the paper's massless, untilted tip at the free end."""
        return not self.lever.is_paper_probe

    def _arguments(self, inv_q, g, k1, k2, x):
        """``(beta0, r, beta, k1 / k_factor, k2 / k_factor, k_factor, mu)``: the undamped ``beta``,
        ``r = f / f1``, and the damping substitution (:func:`pfmdyn.cantilever.damping_substitution`).

        Internal friction makes EI complex, ``k -> k (1 + i/Q)``; the transfer function depends
        on the springs only through ``k1 / k`` and ``k2 / k``, so ``k`` stays real and the
        contact springs are divided by that factor (the dashpot multiplies ``k1``).  A heavy tip
        moves the lever's first free root (:meth:`pfmdyn.Cantilever.free_root`); a medium
        (:attr:`pfmdyn.Cantilever.medium`) loads it at every frequency, ``r`` then from the vacuum ``f1``.
        """
        f = np.asarray(self.frequency_hz, float)
        f1 = self.lever.vacuum_resonance          # the lever's own (free_resonance without a medium)
        r = f / f1
        beta0 = formulas.beta_from_frequency(f, f1, self.lever.free_root())
        # a medium's load is a drag of its own beside the fitted one (derivations/damping.py: fluid_as_drag)
        drag = g if self.lever.medium is None else g + 1j * r * self.lever.fluid_load(f)
        d = damping_substitution(r, beta0, 1.0, k1, self.lever.tip_mass_ratio, inv_q, drag, x)   # k = 1: d.k is the factor
        return beta0, r, d.beta, d.k1 / d.k, k2 / d.k, d.k, d.mu

    def _transfer(self, beta, k1e, k2e, mu, jacobian):
        """Slopes per drive and (with ``jacobian``) per drive the partials w.r.t. (beta, k1, k2,
        mu), None where not needed: the generated elastic contact for the paper's probe, else the
        generated composed model (set-back, heavy or tilted tip: springs rotated onto the beam
        axes, so the partials w.r.t. k1 and k2 combine those w.r.t. kvv, kll, kvl)."""
        if not self._composed:
            if not jacobian:
                return elastic_contact.slope(beta, self.k, k1e, k2e, self.H, self.L), None
            values, partials = elastic_contact.slope_and_jacobian(beta, self.k, k1e, k2e, self.H, self.L)
            return values, [(*p, None) for p in partials]
        alpha = self.lever.alpha
        # read at the laser spot or, by default, at the free end
        spot = self.lever.spot_position
        module, at = (composed.at_end, ()) if spot == 1.0 else (composed.at_spot, (spot,))
        args = (beta, *at, self.k, *rotated(k1e, k2e, alpha), self.H, self.L, mu, self.lever.tip_position,
                self.lever.rho_g)
        if not jacobian:
            return module.slope(*args), None
        wanted = ("beta", "kvv", "kll", "kvl", "mu")
        # the tip mass moves with drag only (mu_factor); otherwise its partial multiplies zero
        moving_mass = self.lever.tip_mass_ratio and "viscous" in self.mechanisms
        values, partials = module.slope_and_jacobian(*args, wrt=wanted if moving_mass else wanted[:4])
        c, s = math.cos(alpha), math.sin(alpha)
        index = {name: module.JACOBIAN_PARAMETERS.index(name) for name in wanted}
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
            # log10 coordinates: d/d(log10 v) = ln(10) v d/dv
            chain = {"k1": (d_k1 * k1e + tied) * LN10, "k2": d_k2 * k2e * LN10,
                     "q": -inv_q * LN10 * (d_beta * beta0 * dbf_inv_q + spring_loss),
                     "g": d_beta * beta0 * dbf_g + (0.0 if d_mu is None else d_mu * self.lever.tip_mass_ratio * dmf_g),
                     "x": d_k1 * k1 * dk1f_x / k_factor}
            for i, name in enumerate(self.names):
                d[i, :, j] = chain[name]
        return np.stack([values[i] for i in self.drives], axis=1), d


def _start(model, y, q0, k1_range):
    """Best (k1, Q) per pixel and k2/k1 of the grid (:func:`_grid`): ``log_k1``, ``log_q``
    ``(n_ratio, n)``, ``log_ratio`` ``(n_ratio,)``; k1 and Q refined by the vertex of the
    parabola through the best grid value and its neighbours on each axis."""
    log_k1, log_q, log_ratio, g = _grid(model.lever, model.contact, np.asarray(model.frequency_hz, float).tobytes(),
                                        q0, tuple(k1_range))
    n, m = y.shape[:2]
    # one matrix product over (pixel, bias component) rows: batched products of 1-row matrices are slow
    proj = sum(np.sum(np.abs(y[..., b].reshape(n * m, -1) @ g[:, b].conj().T).reshape(n, m, -1) ** 2, axis=1)
               / np.sum(np.abs(g[:, b]) ** 2, axis=1) for b in model.bands)
    proj = proj.reshape(n, len(log_ratio), -1).transpose(1, 0, 2).reshape(-1, len(log_q), len(log_k1))
    iq, ik = np.unravel_index(np.argmax(proj.reshape(len(proj), -1), axis=1), proj.shape[1:])
    rows = np.arange(len(proj))
    return (_vertex(proj[rows, iq], ik, log_k1).reshape(-1, n), _vertex(proj[rows, :, ik], iq, log_q).reshape(-1, n),
            log_ratio)


@functools.lru_cache(maxsize=8)
def _grid(lever, contact, frequency_bytes, q0, k1_range):
    """Shape functions of the start grid, computed once per lever, contact policy, frequencies and
    range: log-spaced k1 over the part of ``k1_range`` that puts a resonance inside a band, Q over
    ``q0 / 16`` to ``4 q0`` (levers have Q 5-500), and, when k2 is fitted (two or more bands),
    k2/k1 of 0.1, 0.4 and 1 (the lateral spring moves the modes of stiff contacts: k2 = 0 starts
    them decades off); otherwise k2 follows the policy (``log_ratio`` NaN).

    A resonance moves by at most half the relative change of k1 (less on stiff contacts), and a
    sharp one correlates only with a start that places it within a few line widths: 48 steps over
    the four decades of the default range move it by up to 10 %, over the k1 whose resonance lies
    in the band by far less.
    """
    model = BeamMapModel(lever, np.frombuffer(frequency_bytes), contact=contact)
    free = model.k2_mode == "free"
    log_ratio = np.log10([0.1, 0.4, 1.0]) if free else np.array([np.nan])
    log_k1 = _resonant(model, np.log10(np.geomspace(*k1_range, 400)), q0, 10.0**log_ratio)
    log_q = np.log10(q0 * np.geomspace(1 / 16, 4, 7))
    ratio, q, k1 = (10.0**a.ravel() for a in np.meshgrid(log_ratio, log_q, log_k1, indexing="ij"))
    return log_k1, log_q, log_ratio, model.shape_functions(k1, q, k2=ratio * k1 if free else None)


def _resonant(model, log_k1, q0, ratios, count=48):
    """``count`` log-spaced k1 from four steps below the smallest to four above the largest of
    ``log_k1`` whose response peaks inside a band (not at its edges) for some k2/k1 of ``ratios``
    (NaN: k2 by the model's policy); all of ``log_k1``'s range when none does (a band away from
    every resonance)."""
    k1 = 10.0**np.tile(log_k1, len(ratios))
    k2 = None if np.isnan(ratios).all() else np.repeat(ratios, len(log_k1)) * k1
    g = np.abs(model.shape_functions(k1, np.full(k1.size, 4 * q0), k2=k2))
    inside = np.zeros(k1.size, bool)
    for b in model.bands:
        peak = np.argmax(g[:, b], axis=1)
        inside |= (peak > 0) & (peak < b.stop - b.start - 1)
    hit = np.flatnonzero(inside.reshape(len(ratios), -1).any(axis=0))
    if hit.size == 0:
        return np.linspace(log_k1[0], log_k1[-1], count)
    lo, hi = log_k1[max(hit[0] - 4, 0)], log_k1[min(hit[-1] + 4, len(log_k1) - 1)]
    return np.linspace(lo, hi, count)


def _vertex(values, best, axis):
    """Abscissa of the parabola's vertex through ``values[best - 1 : best + 2]`` on an evenly
    spaced ``axis`` (the grid value itself at an edge or without curvature)."""
    inner = np.clip(best, 1, len(axis) - 2)
    rows = np.arange(len(values))
    lo, mid, hi = (values[rows, inner + d] for d in (-1, 0, 1))
    curvature = lo - 2 * mid + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where((best == inner) & (curvature < 0), 0.5 * (lo - hi) / curvature, 0.0)
    return axis[best] + np.clip(shift, -0.5, 0.5) * (axis[1] - axis[0])


def _initial(model, y, q0, k1_range, iterations, tolerance):
    """Starting parameters: the (k1, Q) grid (with two or more bands, the lowest of the fits
    started at each k2/k1 of the grid); with extra damping mechanisms, the fitted baseline with
    the extras switched off (nested, so the fit never ends worse than the baseline)."""
    if model.mechanisms != ("internal",):
        base = replace(model, mechanisms=("internal",))
        p_base = levenberg_marquardt(base, y, _initial(base, y, q0, k1_range, iterations, tolerance),
                                      parameter_bounds(base.parameters), iterations, tolerance)[0]
        return np.stack([p_base[:, base.names.index(p.name)] if p.name in base.names else np.full(len(y), p.null)
                         for p in model.parameters], axis=1)
    log_k1, log_q, log_ratio = _start(model, y, q0, k1_range)
    start = {"k1": log_k1, "q": log_q, "k2": log_k1 + log_ratio[:, None]}
    p = np.stack([start[n] for n in model.names], axis=2)          # (n_ratio, n, n_p)
    if len(p) == 1:
        return p[0]
    # k1 and k2 trade off against each other: one start per k2/k1, the fit that ends lowest wins
    p, *_, cost, _, _ = levenberg_marquardt(model, np.concatenate([y] * len(p)), p.reshape(-1, p.shape[2]),
                                             parameter_bounds(model.parameters), iterations, tolerance)
    best = np.argmin(cost.reshape(-1, len(y)), axis=0)
    return p.reshape(-1, len(y), p.shape[1])[best, np.arange(len(y))]


def fit_block(model: BeamMapModel, response, *, q0=100.0, k1_range=None, iterations=40,
              gap_threshold=GAP_LIMIT, tolerance=1e-3, surface_potential_v=None) -> dict[str, np.ndarray]:
    """Fit every pixel of ``response``, :data:`CHUNK` pixels at once.

    ``response`` is complex, ``(..., n_freq)``, or ``(..., n_bias, n_freq)`` when the model has
    biases.  Returns the arrays of :attr:`BeamMapModel.outputs`, each of the pixel shape
    ``response.shape[:-1]`` (``[:-2]`` with biases), plus ``cost`` (the squared relative
    residual).  ``gap`` is the noise-normalised RMS residual (:mod:`pfmdyn.fitting.noise`); a pixel
    is ``explained`` below ``gap_threshold`` (2: a misfit the noise does not explain is above).  A pixel stops when the predicted decrease of its cost is below ``tolerance``
    times the noise variance (the step is then ~``sqrt(tolerance)`` standard errors).
    ``surface_potential_v`` (V) places ``d_eff`` (``amplitude``, ``phase``) on the response-bias
    line (None: the fitted ``V_surf`` with ``+distributed``, else 0).  A pixel whose spectra hold
    NaN or inf, or are all zero, is masked: NaN in every map, ``explained`` 0.  k1, k2 and Q are fitted
    as logarithms: their standard errors are half the width of ``exp(log x +- sd)``,
    ``x sinh(sd)`` (``x sd`` when small; huge, not small, when the data leave ``x`` undetermined,
    e.g. k2 driven to its bound on a soft contact).

    Examples
    --------
    >>> f = np.linspace(2.5e5, 4.5e5, 48)
    >>> m = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), f)
    >>> y = 3e-3 * m.shape_functions(np.array([300.0]), np.array([60.0]))
    >>> out = fit_block(m, y)
    >>> round(float(out["k1"][0]), 6), round(float(out["quality_factor"][0]), 6)
    (300.0, 60.0)

    With biases, the electrostatic slope and the nulling bias (here ``1e-3 (V - 2)``):

    >>> mb = replace(m, bias_v=np.array([-2.0, 0.0, 2.0]))
    >>> out = fit_block(mb, 1e-3 * (mb.bias_v[:, None] - 2.0) * m.shape_functions(np.array([300.0]), np.array([60.0])))
    >>> round(float(out["electrostatic"]), 9), round(float(out["nulling_bias"]), 9)
    (0.001, 2.0)

    A pixel with a NaN is masked, the others fitted:

    >>> y2 = np.concatenate([y, np.full_like(y, np.nan)])
    >>> out = fit_block(m, y2)
    >>> out["k1"].round(6).tolist(), out["explained"].tolist()
    ([300.0, nan], [1.0, 0.0])
    """
    bias = bias_axis.basis(model.bias_v)
    y = np.ascontiguousarray(response, complex)     # the sums' rounding follows the memory layout
    tail = (len(model.bias_v), len(model.frequency_hz)) if bias.has_bias else (len(model.frequency_hz),)
    if y.shape[-len(tail):] != tail:
        raise UserError(f"response has shape {y.shape}; its last axes must be {tail} (biases, frequencies)")
    shape = y.shape[:-len(tail)]
    y = y.reshape(-1, bias.q.shape[0], tail[-1])
    if k1_range:
        model = replace(model, k1_range=tuple(k1_range))
    k1_range = model.k1_span
    settings = (q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v)
    fitted = np.flatnonzero(fittable(y))
    out = {name: np.full(len(y), np.nan) for name in [*model.outputs, "cost"]}
    out["explained"][:] = 0.0
    for i in range(0, len(fitted), CHUNK):
        rows = fitted[i:i + CHUNK]
        for name, value in _fit_pixels(model, y[rows], *settings).items():
            out[name][rows] = value
    return {name: value.reshape(shape) for name, value in out.items()}


def fittable(spectra) -> np.ndarray:
    """Which pixels of ``spectra`` (pixels first) can be fitted: not those holding NaN or inf, nor
    those with no response at all (a dropped spectrum), which the fit masks.

    >>> fittable(np.array([[1.0, 2.0], [np.nan, 1.0], [0.0, 0.0]])).tolist()
    [True, False, False]
    """
    axes = tuple(range(1, np.ndim(spectra)))
    return np.all(np.isfinite(spectra), axis=axes) & np.any(spectra != 0, axis=axes)


def _fit_pixels(model, y, q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v):
    scale = np.sqrt(np.sum(np.abs(y) ** 2, axis=(1, 2)))
    scale[scale == 0] = 1.0
    # the noise of each pixel's spectra as pfmdyn discrepancy estimates it (floored: noise-free data)
    sigma = np.maximum(noise_sigmas(model.frequency_hz, model.bias_v, y), 1e-15 * scale)
    count = y.shape[1] * y.shape[2]
    y, outside = bias_axis.project(y / scale[:, None, None], bias)
    names = model.names
    p = _initial(model, y, q0, k1_range, iterations, tolerance)
    p, c, _, _, cost, g, dg = levenberg_marquardt(model, y, p, parameter_bounds(model.parameters), iterations, tolerance)
    cost = cost + outside
    dof = max(2 * bias.q.shape[0] * y.shape[2] - len(names) - 2 * c[0].size, 1)
    cov = band_covariance(model, g, dg, c, cost / dof)
    sd = {n: np.sqrt(np.abs(cov[:, i, i])) for i, n in enumerate(names)}
    col = {n: p[:, i] for i, n in enumerate(names)}
    # half the width of 10**(log10 x +- sd): see fit_block
    spread = {q.name: q.spread(col[q.name], sd[q.name]) / q.values(col[q.name]) for q in model.parameters if q.log}
    k1 = 10.0**col["k1"]
    k2 = model.k2_of(k1, col.get("k2"))
    k2_sd = k2 * spread["k2"] if "k2" in spread else (
        np.zeros(len(y)) if model.k2_mode == "fixed" else k2 * spread["k1"])
    gap_map = gap(cost * (scale / sigma) ** 2, count)
    at_bound = np.any([q.at_bound(col[q.name]) for q in model.parameters], axis=0)
    _, m, n_bands, K = c.shape
    first = np.concatenate([amplitude_column(len(names), q, 0, 0, n_bands, K) + np.arange(2 * K) for q in range(m)])
    band = model.bands[0]
    linear = bias_axis.linear_maps(c[:, :, 0], cov[:, first[:, None], first], bias, surface_potential_v,
                                   g[..., band])
    out = {"k1": k1, "k1_stderr": k1 * spread["k1"], "k2": k2, "k2_stderr": k2_sd,
           "quality_factor": 10.0**col["q"], "quality_factor_stderr": 10.0**col["q"] * spread["q"],
           "viscous_loss": col.get("g"), "viscous_loss_stderr": sd.get("g"),
           "contact_loss": col.get("x"), "contact_loss_stderr": sd.get("x"),
           "gap": gap_map, "at_bound": at_bound.astype(float),
           "explained": ((gap_map < gap_threshold) & ~at_bound).astype(float), "cost": cost}
    out.update({name: value * scale if name in _SCALED else value for name, value in linear.items()})
    # a parameter at its bound is where the fit was stopped, not a measurement: report nothing there
    for name in out:
        if name not in _ALWAYS and out[name] is not None:
            out[name] = np.where(at_bound, np.nan, out[name])
    return {name: out[name] for name in [*model.outputs, "cost"]}


_ALWAYS = {"gap", "at_bound", "explained", "cost"}
"""Outputs reported at every pixel, also where the fit sits at a bound."""


_SCALED = {"amplitude", "amplitude_stderr", "electrostatic", "electrostatic_stderr"}
"""Linear maps in response units (the fit works on spectra scaled to unit norm)."""
