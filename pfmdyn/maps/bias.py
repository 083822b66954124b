"""The bias axis of a map: the electrostatic term and the nulling bias at every pixel.

At each pixel the spectra are measured at several DC tip biases ``V``.  The first-harmonic
response is linear in ``V`` (Eq. 41): ``R(f, V) = T(f) (b + s V)`` in each frequency band, where
``T`` is the elastic-contact transfer function per unit surface displacement ``d1``.  The local
electrostatic force ``f0``, proportional to ``V - V_surf``, drives the tip through the same
transfer function (the tip force enters the boundary condition as ``f0 + k1 d1``, Eq. 4b), so
one ``T`` carries both terms:

* ``s`` is the electrostatic term ``G_elec``: the response per volt of DC bias;
* ``b + s V_surf`` is ``d_eff``, the electromechanical response (it needs ``V_surf``);
* ``V_null = -Re(b conj(s)) / |s|^2`` is the bias at which the response is smallest
  (:func:`pfmdyn.analysis.deconvolve.nulling_bias`, generated from the derivation).

The fit uses an orthonormal basis ``Q`` of the span of ``(1, V)`` over the bias steps, the ``Q``
of ``[1, V] = Q R``: the spectra projected on ``Q``'s columns share ``T`` and have one complex
amplitude each (so the centring of the biases never matters for the conditioning), and the part
of the data outside that span, a response that is not linear in bias (e.g. polarisation
switching), counts as residual.  Intercept and slope are ``R^-1`` times the basis amplitudes.
This is the line of :func:`pfmdyn.fitting.bias_line.bias_lines` with the bias grid every pixel
shares factored once, inside each band's fit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.deconvolve import nulling_bias, nulling_bias_gradient
from ..errors import UserError
from ..fitting.bias_line import rounding_spread

__all__ = ["DISTRIBUTED", "QUANTITIES", "SURFACE", "BiasBasis", "basis", "linear_maps", "project"]

QUANTITIES = {
    "electrostatic": ("response units per unit d1 per V",
                      "electrostatic term G_elec: |slope of the response with DC bias| (local force; first band)"),
    "electrostatic_stderr": ("response units per unit d1 per V", "standard error of electrostatic"),
    "electrostatic_phase": ("rad", "arg G_elec (first band)"),
    "nulling_bias": ("V", "DC bias at which the response at the first band's resonance peak is smallest "
                          "(V_surf - d_eff / G_elec; the same at every frequency without +distributed)"),
    "nulling_bias_stderr": ("V", "standard error of nulling_bias"),
}
"""Maps written when the data have a bias axis (name -> (unit, description))."""

DISTRIBUTED = {
    "distributed": ("response units per unit q0",
                    "distributed electrostatic load on the lever: |amplitude of its response| (first band; "
                    "per volt of DC bias with a bias axis)"),
    "distributed_stderr": ("response units per unit q0", "standard error of distributed"),
}
"""Maps of the model ``+distributed``."""

SURFACE = {
    "surface_potential": ("V", "V_surf: the bias that nulls the distributed load (+distributed with a bias axis)"),
    "surface_potential_stderr": ("V", "standard error of surface_potential"),
}
"""Maps of the model ``+distributed`` on data with a bias axis."""


@dataclass(frozen=True)
class BiasBasis:
    """Orthonormal basis ``q`` (n_bias, m) of the bias columns and ``r_inv`` (m, m), which maps
    the basis amplitudes to (intercept, slope); ``m = 1`` (intercept only) without a bias axis."""

    q: np.ndarray
    r_inv: np.ndarray

    @property
    def has_bias(self) -> bool:
        return self.q.shape[1] > 1


def basis(bias_v) -> BiasBasis:
    """The basis of ``(1, V)`` over the biases ``bias_v`` (None: one spectrum, no bias axis).

    >>> v = np.array([-1.0, 0.0, 1.0, 2.0])
    >>> b = basis(v)
    >>> b.q.shape, bool(np.allclose(b.q.T @ b.q, np.eye(2)))
    ((4, 2), True)
    >>> bool(np.allclose(b.q @ np.linalg.inv(b.r_inv), np.column_stack([np.ones(4), v])))   # Q R = [1, V]
    True
    """
    if bias_v is None:
        return BiasBasis(np.ones((1, 1)), np.ones((1, 1)))
    v = np.asarray(bias_v, float)
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise UserError("bias_v must be a finite one-dimensional array")
    if v.size < 2 or np.sum((v - v.mean()) ** 2) <= v.size * rounding_spread(v):     # one setpoint, rounding aside
        raise UserError(f"bias_v needs at least two distinct biases to separate the electrostatic term, got {v.tolist()}")
    q, r = np.linalg.qr(np.column_stack([np.ones_like(v), v]))
    return BiasBasis(q, np.linalg.inv(r))


def project(y, bias: BiasBasis):
    """Spectra ``y`` (n, n_bias, n_freq) on the basis: ``(n, m, n_freq)`` and the squared norm
    of the part outside it ``(n,)`` (the response not linear in bias)."""
    if not bias.has_bias:
        return y, np.zeros(len(y))
    inside = np.einsum("bq,nbf->nqf", bias.q, y)
    outside = np.sum(np.abs(y) ** 2, axis=(1, 2)) - np.sum(np.abs(inside) ** 2, axis=(1, 2))
    return inside, np.maximum(outside, 0.0)


def _parts(weights):
    """Gradients of Re z and Im z, ``z = sum W c`` over the first band's amplitudes ``c`` (n, m, K),
    for complex weights ``W`` broadcasting to (n, m, K): over ``(Re c, Im c)`` pairs, (n, 2 m K)."""
    w = np.asarray(weights, complex)
    w = w.reshape(-1, w.shape[-2] * w.shape[-1]) if w.ndim == 3 else w.reshape(1, -1)
    g_re, g_im = np.empty((len(w), 2 * w.shape[1])), np.empty((len(w), 2 * w.shape[1]))
    g_re[:, 0::2], g_re[:, 1::2] = w.real, -w.imag
    g_im[:, 0::2], g_im[:, 1::2] = w.imag, w.real
    return g_re, g_im


def _stderr(gradient, cov):
    """Delta-method standard error from a gradient (one row, or one per pixel) and ``cov``."""
    gradient = np.broadcast_to(gradient, (len(cov), cov.shape[-1]))
    return np.sqrt(np.abs(np.einsum("ni,nij,nj->n", gradient, cov, gradient)))


def _abs(z, parts):
    """``|z|`` (n,) and its gradient, from the gradients ``parts`` of Re z and Im z."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(z), (z.real[:, None] * parts[0] + z.imag[:, None] * parts[1]) / np.abs(z)[:, None]


def _nulling(intercept, slope, p_intercept, p_slope):
    """The generated nulling bias of the line ``intercept + slope V`` and its gradient."""
    with np.errstate(divide="ignore", invalid="ignore"):    # a zero slope has no nulling bias
        value = nulling_bias(intercept, slope)
        g = nulling_bias_gradient(intercept, slope)
    grad = (g[0][:, None] * p_intercept[0] + g[1][:, None] * p_intercept[1]
            + g[2][:, None] * p_slope[0] + g[3][:, None] * p_slope[1])
    return value, grad


def _on(weights_q, k, K):
    """Weights (m, K) selecting drive ``k`` with bias-component weights ``weights_q`` (m,)."""
    w = np.zeros((len(weights_q), K))
    w[:, k] = weights_q
    return w


def linear_maps(c, cov, bias: BiasBasis, surface_potential_v=None, g=None) -> dict[str, np.ndarray]:
    """Maps of the first band's amplitudes ``c`` (n, m, K), for ``m`` bias components and ``K``
    drives (``d1``; ``q0`` with ``+distributed``), with covariance ``cov`` (n, 2mK, 2mK) over
    their ``(Re, Im)`` pairs in (component, drive) order; ``g`` (n, K, n_freq) are the transfer
    functions over the first band (for the resonance peak of ``+distributed``).

    ``amplitude``, ``phase``, ``amplitude_stderr``: ``d_eff``, the ``d1`` term (with a bias axis
    the response at ``V_surf``: ``surface_potential_v``, else the fitted one with
    ``+distributed``, else 0).  With a bias axis the maps of :data:`QUANTITIES`; with
    ``+distributed`` those of :data:`DISTRIBUTED` (and :data:`SURFACE` with a bias axis).

    Examples
    --------
    >>> b = basis([-1.0, 0.0, 1.0])
    >>> line = (2.0 + 1.0j) + (1.0 - 0.5j) * np.array([-1.0, 0.0, 1.0])      # b + s V
    >>> c = (b.q.T @ line)[None, :, None]          # the amplitudes on the basis
    >>> out = linear_maps(c, np.zeros((1, 4, 4)), b, surface_potential_v=0.5)
    >>> complex(np.round(out["amplitude"][0] * np.exp(1j * out["phase"][0]), 12))
    (2.5+0.75j)
    >>> float(out["nulling_bias"][0]), round(float(out["electrostatic"][0]), 12)
    (-1.2, 1.11803398875)
    """
    n, m, K = c.shape
    flat = c.reshape(n, -1)
    wb, ws = bias.r_inv[0], bias.r_inv[-1]
    out = {}
    if K > 1:                                    # the distributed load's amplitude (its slope with a bias axis)
        w = _on(ws if bias.has_bias else wb, 1, K)
        value, grad = _abs(flat @ w.ravel(), _parts(w))
        out.update(distributed=value, distributed_stderr=_stderr(grad, cov))
    if not bias.has_bias:
        w = _on(wb, 0, K)
        d_eff = flat @ w.ravel()
        value, grad = _abs(d_eff, _parts(w))
        return {**out, "amplitude": value, "phase": np.angle(d_eff), "amplitude_stderr": _stderr(grad, cov)}
    (b, pb), (s, ps) = ((flat @ _on(w, 0, K).ravel(), _parts(_on(w, 0, K))) for w in (wb, ws))
    value, grad = _abs(s, ps)
    out.update(electrostatic=value, electrostatic_stderr=_stderr(grad, cov), electrostatic_phase=np.angle(s))
    if K > 1:
        (e, pe), (h, ph) = ((flat @ _on(w, 1, K).ravel(), _parts(_on(w, 1, K))) for w in (wb, ws))
        v_surf, grad_surf = _nulling(e, h, pe, ph)
        out.update(surface_potential=v_surf, surface_potential_stderr=_stderr(grad_surf, cov))
        # the nulling bias at the resonance peak of the first band: the total response there
        peak = np.argmax(np.abs(np.einsum("nkf,nk->nf", g, np.stack([s, h], axis=1))), axis=1)
        t = g[np.arange(n), :, peak]                                            # (n, K)
        w_i, w_s = wb[None, :, None] * t[:, None, :], ws[None, :, None] * t[:, None, :]
        total_i, total_s = np.einsum("nmk,nmk->n", w_i, c), np.einsum("nmk,nmk->n", w_s, c)
        v_null, grad_null = _nulling(total_i, total_s, _parts(w_i), _parts(w_s))
    else:
        v_null, grad_null = _nulling(b, s, pb, ps)
    out.update(nulling_bias=v_null, nulling_bias_stderr=_stderr(grad_null, cov))
    if surface_potential_v is None and K > 1:         # fitted: d_eff = b + s V_surf, V_surf uncertain too
        d_eff = b + s * v_surf
        parts = tuple(pb[i] + v_surf[:, None] * ps[i] + (s.real, s.imag)[i][:, None] * grad_surf for i in range(2))
    else:
        v = surface_potential_v or 0.0
        d_eff, parts = b + v * s, tuple(pb[i] + v * ps[i] for i in range(2))
    value, grad = _abs(d_eff, parts)
    return {**out, "amplitude": value, "phase": np.angle(d_eff), "amplitude_stderr": _stderr(grad, cov)}
