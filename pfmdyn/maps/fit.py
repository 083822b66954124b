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
``log k1``, ``log Q``, ``log k2`` (when the frequencies hold two or more bands, one per contact
mode: one mode cannot separate ``k1`` from ``k2``, so with one band ``k2 = 0``), ``g`` and ``x``
are fitted by a Levenberg-Marquardt iteration that treats every pixel of a block at once, each
pixel with its own damping factor.

Cost is dominated by the generated transfer function over ``(pixels, frequencies)``; one
*design evaluation* per iteration gives the transfer functions and their derivatives for the
whole block (:meth:`BeamMapModel.design`), and the derivatives of the projected residual follow
from them in closed form (Golub and Pereyra 1973).  The covariance of all parameters, nonlinear
and amplitudes, is ``s**2`` times the inverse normal matrix of the full problem at the solution
(:func:`_covariance`); its nonlinear block is the variable-projection one.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from ..cantilever import Cantilever
from ..errors import UserError
from ..discrepancy.model import free_root
from ..generated import damping, elastic_contact, tip_setback
from ..generated.characteristic import BETA1_FREE
from . import bias as bias_axis

__all__ = ["BeamMapModel", "CHUNK", "MECHANISMS", "fit_block", "quantities", "bands", "parse_model"]

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
    "gap": ("1", "relative residual |y - model| / |y|"),
    "explained": ("1", "1 where the model explains the pixel (gap below threshold), else 0"),
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
    """Mechanisms of a ``--model`` spec ``elastic[+viscous][+contact][+distributed]``.

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
    """Cantilever metadata in SI units, the frequency vector of the map and the damping mechanisms.

    Examples
    --------
    >>> m = BeamMapModel(k=2.0, L=225e-6, f1=75e3, H=10e-6, frequency_hz=np.linspace(3e5, 4e5, 8))
    >>> m.shape_functions(np.array([200.0]), np.array([80.0])).shape
    (1, 8)
    >>> m.parameters
    ('log_k1', 'log_q')
    """

    k: float
    L: float
    f1: float
    H: float
    frequency_hz: np.ndarray
    mechanisms: tuple[str, ...] = ("internal",)
    bias_v: np.ndarray | None = None
    """DC tip bias of each spectrum of a pixel (V), or None: one spectrum per pixel."""
    tip_position: float = 1.0
    """``gamma``: the tip sits at ``gamma L`` (set back from the free end when below 1)."""
    tip_mass: float = 0.0
    """``mu``: the tip's mass over the lever's."""

    @property
    def outputs(self) -> dict[str, tuple[str, str]]:
        """The per-pixel maps this model writes (:func:`quantities`)."""
        return quantities(self.mechanisms, self.bias_v is not None)

    @functools.cached_property
    def bands(self) -> list[slice]:
        """The frequency bands (one per contact mode driven)."""
        return bands(self.frequency_hz)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Internal nonlinear parameters, in the order of the fit's columns."""
        names = ["log_k1", "log_q"] + (["log_k2"] if len(self.bands) > 1 else [])
        extra = {"viscous": "g", "contact": "x"}
        return tuple(names + [extra[m] for m in self.mechanisms if m in extra])

    def _arguments(self, inv_q, g, k1, k2, x):
        """``beta`` and the springs relative to the complex EI, with the damping factors.

        Internal friction makes EI complex, ``k -> k (1 + i/Q)``; the transfer function depends
        on the springs only through ``k1 / k`` and ``k2 / k``, so ``k`` stays real and the
        contact springs are divided by that factor (the dashpot multiplies ``k1``).
        """
        f = np.asarray(self.frequency_hz, float)
        r = f / self.f1
        beta0 = Cantilever(self.k, self.f1, self.L).beta(f)
        if self.tip_mass:       # the measured f1 is the loaded lever's: its root is not BETA1_FREE
            beta0 = beta0 * free_root(self.k, self.H, self.L, self.tip_mass, self.tip_position) / BETA1_FREE
        # Without drag the beta factor does not depend on r: keep it one number per pixel.
        r_beta = r if "viscous" in self.mechanisms else 1.0
        beta_factor, k_factor, _, mu_factor = damping.factors(r_beta, inv_q, g, 0.0)
        k1_factor = damping.factors(r, 0.0, 0.0, x)[2] if "contact" in self.mechanisms else 1.0
        return (beta0, r, r_beta, beta0 * beta_factor, k1 * k1_factor / k_factor, k2 / k_factor, k_factor,
                self.tip_mass * mu_factor)

    def _transfer(self, beta, k1e, k2e, mu, jacobian):
        """Slopes per drive and (with ``jacobian``) per drive the partials w.r.t. (beta, k1, k2,
        mu), None where not needed: the generated elastic contact for a massless tip at the end,
        else the generated set-back solution (springs on the beam axes, no tilt)."""
        if self.tip_position == 1.0 and not self.tip_mass:
            if not jacobian:
                return elastic_contact.slope(beta, self.k, k1e, k2e, self.H, self.L), None
            values, partials = elastic_contact.slope_and_jacobian(beta, self.k, k1e, k2e, self.H, self.L)
            return values, [(*p, None) for p in partials]
        args = (beta, self.k, k1e, k2e, 0.0, self.H, self.L, mu, self.tip_position, 0.0)
        if not jacobian:
            return tip_setback.slope(*args), None
        wanted = ("beta", "kvv", "kll", "mu")
        # the tip mass moves with drag only (mu_factor); otherwise its partial multiplies zero
        wrt = wanted if self.tip_mass and "viscous" in self.mechanisms else wanted[:3]
        values, partials = tip_setback.slope_and_jacobian(*args, wrt=wrt)
        index = [tip_setback.JACOBIAN_PARAMETERS.index(name) for name in wanted]
        return values, [tuple(p[i] for i in index) for p in partials]

    def _physical(self, p):
        """(inv_q, g, k1, k2, x) of internal parameters ``p`` (``(n, n_p)``), each ``(n, 1)``."""
        col = {name: p[:, i, None] for i, name in enumerate(self.parameters)}
        zero = np.zeros_like(col["log_k1"])
        return (np.exp(-col["log_q"]), col.get("g", zero), np.exp(col["log_k1"]),
                np.exp(col["log_k2"]) if "log_k2" in col else zero, col.get("x", zero))

    def shape_functions(self, k1, q, k2=0.0, g=0.0, x=0.0) -> np.ndarray:
        """Tip slope per unit d1 at every frequency, shape ``(len(k1), n_freq)``."""
        col = [np.asarray(v, float) * np.ones(np.shape(k1)) for v in (1.0 / np.asarray(q, float), g, k1, k2, x)]
        _, _, _, beta, k1e, k2e, _, mu = self._arguments(*(c[:, None] for c in col))
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
        beta0, r, r_beta, beta, k1e, k2e, k_factor, mu = self._arguments(inv_q, g, k1, k2, x)
        values, partials = self._transfer(beta, k1e, k2e, mu, jacobian)
        if not jacobian:
            return np.stack([values[i] for i in self.drives], axis=1), None
        (dbf_inv_q, dbf_g, _), (dkf_inv_q, _, _), _, (_, dmf_g, _) = damping.d_factors(r_beta, inv_q, g, 0.0)
        dk1f_x = damping.d_factors(r, 0.0, 0.0, x)[2][2] if "contact" in self.mechanisms else 0.0
        d = np.empty((len(self.parameters), len(k1), len(self.drives), values[0].shape[-1]), complex)
        for j, drive in enumerate(self.drives):
            d_beta, d_k1, d_k2, d_mu = partials[drive]
            # d/d inv_q of k1e, k2e (both divided by k_factor) and of beta
            spring_loss = -dkf_inv_q / k_factor * (d_k1 * k1e + d_k2 * k2e)
            chain = {"log_k1": d_k1 * k1e, "log_k2": d_k2 * k2e,
                     "log_q": -inv_q * (d_beta * beta0 * dbf_inv_q + spring_loss),
                     "g": d_beta * beta0 * dbf_g + (0.0 if d_mu is None else d_mu * self.tip_mass * dmf_g),
                     "x": d_k1 * k1 * dk1f_x / k_factor}
            for i, name in enumerate(self.parameters):
                d[i, :, j] = chain[name]
        return np.stack([values[i] for i in self.drives], axis=1), d


def _project(g, dg, y, band_list):
    """Variable projection of ``y`` ``(n, m, n_freq)`` (``m`` bias components) on the transfer
    functions ``g`` ``(n, K, n_freq)``, with amplitudes of their own for every component and
    band: amplitudes ``(n, m, n_bands, K)``, real residual ``(n, 2 m n_freq)`` and, given ``dg``
    ``(n_p, n, K, n_freq)``, its Jacobian ``(n, 2 m n_freq, n_p)``, the exact derivative of the
    projection: ``dc = (A^H A)^-1 (dA^H r - A^H dA c)``, ``dr = -dA c - A dc``."""
    c, r = [], np.empty_like(y)
    dr = None if dg is None else np.empty((dg.shape[0],) + y.shape, complex)
    for b in band_list:
        A, yb = g[..., b], y[..., b]
        AhA = np.einsum("nkf,nlf->nkl", A.conj(), A)
        scale = np.maximum(np.einsum("nkk->nk", AhA).real, 1e-300) ** -0.5     # equilibrate the columns
        inverse = np.linalg.inv(AhA * scale[:, :, None] * scale[:, None, :]) * scale[:, :, None] * scale[:, None, :]
        cb = np.einsum("nkl,nlf,nmf->nmk", inverse, A.conj(), yb)
        r[..., b] = rb = yb - np.einsum("nmk,nkf->nmf", cb, A)
        c.append(cb)
        if dg is not None:
            dA = dg[..., b]
            dA_c = np.einsum("pnkf,nmk->pnmf", dA, cb)
            rhs = np.einsum("pnkf,nmf->pnmk", dA.conj(), rb) - np.einsum("nkf,pnmf->pnmk", A.conj(), dA_c)
            dc = np.einsum("nkl,pnml->pnmk", inverse, rhs)
            dr[..., b] = -(dA_c + np.einsum("pnmk,nkf->pnmf", dc, A))
    n = len(y)
    J = None if dr is None else np.concatenate([dr.real, dr.imag], axis=2).reshape(len(dr), n, -1).transpose(1, 2, 0)
    return np.stack(c, axis=2), np.concatenate([r.real, r.imag], axis=1).reshape(n, -1), J


def _start(model, y, q0, k1_range):
    """Best (k1, Q) per pixel and k2/k1 of the grid (:func:`_grid`): ``log_k1``, ``log_q``
    ``(n_ratio, n)``, ``log_ratio`` ``(n_ratio,)``; k1 and Q refined by the vertex of the
    parabola through the best grid value and its neighbours on each axis."""
    log_k1, log_q, log_ratio, g = _grid(model.k, model.L, model.f1, model.H,
                                        np.asarray(model.frequency_hz, float).tobytes(), q0, tuple(k1_range),
                                        model.tip_position, model.tip_mass)
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
def _grid(k, L, f1, H, frequency_bytes, q0, k1_range, tip_position, tip_mass):
    """Shape functions of the start grid, computed once per cantilever, frequencies and range:
    log-spaced k1 over the part of ``k1_range`` that puts a resonance inside a band, Q over
    ``q0 / 16`` to ``4 q0`` (levers have Q 5-500), and with two or more bands (k2 fitted) k2/k1 of
    0.1, 0.4 and 1 (the lateral spring moves the modes of stiff contacts: k2 = 0 starts them
    decades off).

    A resonance moves by at most half the relative change of k1 (less on stiff contacts), and a
    sharp one correlates only with a start that places it within a few line widths: 48 steps over
    the four decades of the default range move it by up to 10 %, over the k1 whose resonance lies
    in the band by far less.
    """
    f = np.frombuffer(frequency_bytes)
    model = BeamMapModel(k, L, f1, H, f, tip_position=tip_position, tip_mass=tip_mass)
    log_ratio = np.log([0.1, 0.4, 1.0]) if len(model.bands) > 1 else np.array([-np.inf])
    log_k1 = _resonant(model, np.log(np.geomspace(*k1_range, 400)), q0, np.exp(log_ratio))
    log_q = np.log(q0 * np.geomspace(1 / 16, 4, 7))
    ratio, q, k1 = (np.exp(a).ravel() for a in np.meshgrid(log_ratio, log_q, log_k1, indexing="ij"))
    return log_k1, log_q, log_ratio, model.shape_functions(k1, q, k2=ratio * k1)


def _resonant(model, log_k1, q0, ratios, count=48):
    """``count`` log-spaced k1 from four steps below the smallest to four above the largest of
    ``log_k1`` whose response peaks inside a band (not at its edges) for some k2/k1 of ``ratios``;
    all of ``log_k1``'s range when none does (a band away from every resonance)."""
    k1 = np.exp(np.tile(log_k1, len(ratios)))
    g = np.abs(model.shape_functions(k1, np.full(k1.size, 4 * q0), k2=np.repeat(ratios, len(log_k1)) * k1))
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


def _bounds(model, k1_range):
    limits = {"log_k1": (k1_range[0] / 10, k1_range[1] * 10), "log_q": (1.0, 1e5),
              "log_k2": (k1_range[0] / 100, k1_range[1] * 10)}
    lower = [math.log(limits[n][0]) if n in limits else 0.0 for n in model.parameters]
    upper = [math.log(limits[n][1]) if n in limits else {"g": 1.0, "x": 5.0}[n] for n in model.parameters]
    return np.array(lower), np.array(upper)


def _initial(model, y, q0, k1_range, iterations, tolerance):
    """Starting parameters: the (k1, Q) grid (with two or more bands, the lowest of the fits
    started at each k2/k1 of the grid); with extra damping mechanisms, the fitted baseline with
    the extras switched off (nested, so the fit never ends worse than the baseline)."""
    if model.mechanisms != ("internal",):
        base = replace(model, mechanisms=("internal",))
        p_base = _levenberg_marquardt(base, y, _initial(base, y, q0, k1_range, iterations, tolerance),
                                      _bounds(base, k1_range), iterations, tolerance)[0]
        return np.stack([p_base[:, base.parameters.index(n)] if n in base.parameters else np.zeros(len(y))
                         for n in model.parameters], axis=1)
    log_k1, log_q, log_ratio = _start(model, y, q0, k1_range)
    start = {"log_k1": log_k1, "log_q": log_q, "log_k2": log_k1 + log_ratio[:, None]}
    p = np.stack([start[n] for n in model.parameters], axis=2)          # (n_ratio, n, n_p)
    if len(p) == 1:
        return p[0]
    # k1 and k2 trade off against each other: one start per k2/k1, the fit that ends lowest wins
    p, *_, cost, _, _ = _levenberg_marquardt(model, np.concatenate([y] * len(p)), p.reshape(-1, p.shape[2]),
                                             _bounds(model, k1_range), iterations, tolerance)
    best = np.argmin(cost.reshape(-1, len(y)), axis=0)
    return p.reshape(-1, len(y), p.shape[1])[best, np.arange(len(y))]


def _levenberg_marquardt(model, y, p, bounds, iterations, tolerance):
    """All pixels at once, one design evaluation per iteration; returns (p, c, r, J, cost, g, dg).

    A step predicted to gain less than 100 ``tolerance`` is the last one (Gauss-Newton converges
    quadratically: the next would gain below ``tolerance``), so its point gets values only; ``J``
    and the transfer function ``g`` and its derivatives ``dg`` then stay those of the previous
    point, a fraction of a standard error away.
    """
    lower, upper = bounds
    n_p, band_list = p.shape[1], model.bands
    g, dg = model.design(p)
    c, r, J = _project(g, dg, y, band_list)
    cost = np.sum(r**2, axis=1)
    lam = np.full(len(y), 1e-3)
    dof = max(r.shape[1] - n_p - 2 * c[0].size, 1)
    active = np.arange(len(y))   # pixels still moving: converged ones cost nothing more
    for _ in range(iterations):
        Ja, ra, la = J[active], r[active], lam[active]
        JtJ = np.einsum("nki,nkj->nij", Ja, Ja)
        grad = np.einsum("nki,nk->ni", Ja, ra)
        A = JtJ + la[:, None, None] * (JtJ * np.eye(n_p) + 1e-12 * np.eye(n_p))
        step = np.clip(p[active] - np.linalg.solve(A, grad[..., None])[..., 0], lower, upper) - p[active]
        # predicted decrease of the cost (Gauss-Newton) in units of the tolerance
        gain = -np.einsum("ni,ni->n", step, grad) / (tolerance * cost[active] / dof)
        moving = (gain > 1) & (la < 1e8)
        active, step, gain = active[moving], step[moving], gain[moving]
        if active.size == 0:
            break
        finished = np.zeros(len(active), bool)
        for last in (False, True):
            sel = (gain < 100) == last
            if not sel.any():
                continue
            act = active[sel]
            trial = p[act] + step[sel]
            g_t, dg_t = model.design(trial, jacobian=not last)
            c_t, r_t, J_t = _project(g_t, dg_t, y[act], band_list)
            cost_t = np.sum(r_t**2, axis=1)
            better = cost_t < cost[act]
            idx = act[better]
            p[idx], c[idx], r[idx], cost[idx] = trial[better], c_t[better], r_t[better], cost_t[better]
            if not last:
                J[idx], g[idx], dg[:, idx] = J_t[better], g_t[better], dg_t[:, better]
            lam[act] = np.where(better, lam[act] / 3, lam[act] * 4)
            finished[np.flatnonzero(sel)[better]] = last
        active = active[~finished]
    return p, c, r, J, cost, g, dg


def fit_block(model: BeamMapModel, response, *, q0=100.0, k1_range=None, iterations=40,
              gap_threshold=0.2, tolerance=1e-3, surface_potential_v=None) -> dict[str, np.ndarray]:
    """Fit every pixel of ``response``, :data:`CHUNK` pixels at once.

    ``response`` is complex, ``(..., n_freq)``, or ``(..., n_bias, n_freq)`` when the model has
    biases.  Returns the arrays of :attr:`BeamMapModel.outputs`, each of the pixel shape
    ``response.shape[:-1]`` (``[:-2]`` with biases), plus ``cost`` (the squared relative
    residual).  A pixel stops when the predicted decrease of its cost is below ``tolerance``
    times the noise variance (the step is then ~``sqrt(tolerance)`` standard errors).
    ``surface_potential_v`` (V) places ``d_eff`` (``amplitude``, ``phase``) on the response-bias
    line (None: the fitted ``V_surf`` with ``+distributed``, else 0).  k1, k2 and Q are fitted
    as logarithms: their standard errors are half the width of ``exp(log x +- sd)``,
    ``x sinh(sd)`` (``x sd`` when small; huge, not small, when the data leave ``x`` undetermined,
    e.g. k2 driven to its bound on a soft contact).

    Examples
    --------
    >>> f = np.linspace(2.5e5, 4.5e5, 48)
    >>> m = BeamMapModel(k=2.0, L=225e-6, f1=75e3, H=10e-6, frequency_hz=f)
    >>> y = 3e-3 * m.shape_functions(np.array([300.0]), np.array([60.0]))
    >>> out = fit_block(m, y)
    >>> round(float(out["k1"][0]), 6), round(float(out["quality_factor"][0]), 6)
    (300.0, 60.0)

    With biases, the electrostatic slope and the nulling bias (here ``1e-3 (V - 2)``):

    >>> mb = replace(m, bias_v=np.array([-2.0, 0.0, 2.0]))
    >>> out = fit_block(mb, 1e-3 * (mb.bias_v[:, None] - 2.0) * m.shape_functions(np.array([300.0]), np.array([60.0])))
    >>> round(float(out["electrostatic"]), 9), round(float(out["nulling_bias"]), 9)
    (0.001, 2.0)
    """
    bias = bias_axis.basis(model.bias_v)
    y = np.ascontiguousarray(response, complex)     # the sums' rounding follows the memory layout
    tail = (len(model.bias_v), len(model.frequency_hz)) if bias.has_bias else (len(model.frequency_hz),)
    if y.shape[-len(tail):] != tail:
        raise UserError(f"response has shape {y.shape}; its last axes must be {tail} (biases, frequencies)")
    shape = y.shape[:-len(tail)]
    y = y.reshape(-1, bias.q.shape[0], tail[-1])
    k1_range = k1_range or (model.k, 1e4 * model.k)
    settings = (q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v)
    parts = [_fit_pixels(model, y[i:i + CHUNK], *settings) for i in range(0, max(len(y), 1), CHUNK)]
    return {name: np.concatenate([part[name] for part in parts]).reshape(shape) for name in parts[0]}


def _covariance(model, g, dg, c, noise):
    """Covariance of ``(p, Re c, Im c)`` per pixel, ``(n, n_p + 2 c.size, ...)``: ``noise`` times
    the inverse normal matrix of the full (unprojected) problem at the solution.  Its ``p`` block
    is the variable-projection one; the amplitudes' block also carries their correlation with
    ``p`` (an amplitude's error grows with that of the resonance it sits on).  The amplitude
    columns are ``(Re, Im)`` pairs in ``c``'s (component, band, drive) order (:func:`_column`).

    The residual in band ``j`` of component ``q`` is ``y - sum_k c_qjk g_k``, so the normal
    matrix has closed-form blocks: with ``D_i = sum_k c_qjk dg_ik``, ``Re(D^H D)`` for ``p``,
    ``Re(D_i^H g_k)`` and ``-Im(...)`` between ``p_i`` and ``(Re, Im) c_qjk``, and the real form
    of ``g^H g`` between the amplitudes of one component and band.
    """
    n, m, n_bands, K = c.shape
    n_p = dg.shape[0]
    N = np.zeros((n, n_p + 2 * c[0].size, n_p + 2 * c[0].size))
    for j, b in enumerate(model.bands):
        gb = g[..., b]
        D = np.einsum("pnkf,nmk->pnmf", dg[..., b], c[:, :, j])
        N[:, :n_p, :n_p] += np.einsum("pnmf,inmf->npi", D.conj(), D).real
        cross = np.einsum("pnmf,nkf->npmk", D.conj(), gb)
        H = np.einsum("nkf,nlf->nkl", gb.conj(), gb)
        block = np.empty((n, 2 * K, 2 * K))
        block[:, 0::2, 0::2] = block[:, 1::2, 1::2] = H.real
        block[:, 0::2, 1::2], block[:, 1::2, 0::2] = -H.imag, H.imag
        for q in range(m):
            cols = _column(n_p, q, j, 0, n_bands, K) + np.arange(2 * K)
            N[:, :n_p, cols[0::2]], N[:, :n_p, cols[1::2]] = cross[:, :, q].real, -cross[:, :, q].imag
            N[:, cols[:, None], cols] = block
    N[:, n_p:, :n_p] = N[:, :n_p, n_p:].transpose(0, 2, 1)
    size = np.sqrt(np.maximum(np.einsum("nii->ni", N), 1e-300))      # columns of very different scales
    inverse = np.linalg.pinv(N / (size[:, :, None] * size[:, None, :]), hermitian=True)
    return inverse / (size[:, :, None] * size[:, None, :]) * noise[:, None, None]


def _column(n_p, q, j, k, n_bands, K) -> int:
    """Index of ``Re c_qjk`` (``Im`` is the next) among the covariance's parameters."""
    return n_p + 2 * ((q * n_bands + j) * K + k)


def _fit_pixels(model, y, q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v):
    scale = np.sqrt(np.sum(np.abs(y) ** 2, axis=(1, 2)))
    scale[scale == 0] = 1.0
    y, outside = bias_axis.project(y / scale[:, None, None], bias)
    names = model.parameters
    p = _initial(model, y, q0, k1_range, iterations, tolerance)
    p, c, _, _, cost, g, dg = _levenberg_marquardt(model, y, p, _bounds(model, k1_range), iterations, tolerance)
    cost = cost + outside
    dof = max(2 * bias.q.shape[0] * y.shape[2] - len(names) - 2 * c[0].size, 1)
    cov = _covariance(model, g, dg, c, cost / dof)
    sd = {n: np.sqrt(np.abs(cov[:, i, i])) for i, n in enumerate(names)}
    with np.errstate(over="ignore"):
        spread = {n: np.sinh(sd[n]) for n in ("log_k1", "log_q", "log_k2") if n in sd}     # see fit_block
    col = {n: p[:, i] for i, n in enumerate(names)}
    k1 = np.exp(col["log_k1"])
    k2 = np.exp(col["log_k2"]) if "log_k2" in col else np.full(len(y), np.nan)
    gap = np.sqrt(cost)
    _, m, n_bands, K = c.shape
    first = np.concatenate([_column(len(names), q, 0, 0, n_bands, K) + np.arange(2 * K) for q in range(m)])
    band = model.bands[0]
    linear = bias_axis.linear_maps(c[:, :, 0], cov[:, first[:, None], first], bias, surface_potential_v,
                                   g[..., band])
    out = {"k1": k1, "k1_stderr": k1 * spread["log_k1"], "k2": k2, "k2_stderr": k2 * spread.get("log_k2", np.nan),
           "quality_factor": np.exp(col["log_q"]), "quality_factor_stderr": np.exp(col["log_q"]) * spread["log_q"],
           "viscous_loss": col.get("g"), "viscous_loss_stderr": sd.get("g"),
           "contact_loss": col.get("x"), "contact_loss_stderr": sd.get("x"),
           "gap": gap, "explained": (gap < gap_threshold).astype(float), "cost": cost}
    out.update({name: value * scale if name in _SCALED else value for name, value in linear.items()})
    return {name: out[name] for name in [*model.outputs, "cost"]}


_SCALED = {"amplitude", "amplitude_stderr", "electrostatic", "electrostatic_stderr"}
"""Linear maps in response units (the fit works on spectra scaled to unit norm)."""
