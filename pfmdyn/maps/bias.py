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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.deconvolve import nulling_bias, nulling_bias_gradient
from ..errors import UserError

__all__ = ["BiasBasis", "QUANTITIES", "basis", "linear_maps", "project"]

QUANTITIES = {
    "electrostatic": ("response units per unit d1 per V",
                      "electrostatic term G_elec: |slope of the response with DC bias| (first band)"),
    "electrostatic_stderr": ("response units per unit d1 per V", "standard error of electrostatic"),
    "electrostatic_phase": ("rad", "arg G_elec (first band)"),
    "nulling_bias": ("V", "DC bias at which the response is smallest, V_surf - d_eff / G_elec (first band)"),
    "nulling_bias_stderr": ("V", "standard error of nulling_bias"),
}
"""Maps written when the data have a bias axis (name -> (unit, description))."""


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
    if np.unique(v).size < 2:
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
    """Gradients of Re z and Im z, ``z = sum_q w_q c_q``, over ``(Re c_0, Im c_0, Re c_1, ...)``."""
    e_re = np.zeros(2 * len(weights))
    e_re[0::2] = weights
    e_im = np.roll(e_re, 1)
    return e_re, e_im


def _stderr(gradient, cov):
    return np.sqrt(np.abs(np.einsum("ni,nij,nj->n", gradient, cov, gradient)))


def linear_maps(c, cov, bias: BiasBasis, surface_potential_v: float = 0.0) -> dict[str, np.ndarray]:
    """Maps of the first band's amplitudes ``c`` (n, m) with covariance ``cov`` (n, 2m, 2m) over
    ``(Re c_0, Im c_0, Re c_1, Im c_1)``: ``amplitude``, ``phase`` (of ``d_eff``, the response at
    ``V_surf``) with ``amplitude_stderr``, and with a bias axis the maps of :data:`QUANTITIES`.

    Examples
    --------
    >>> b = basis([-1.0, 0.0, 1.0])
    >>> line = (2.0 + 1.0j) + (1.0 - 0.5j) * np.array([-1.0, 0.0, 1.0])      # b + s V
    >>> c = (b.q.T @ line)[None]          # the amplitudes on the basis
    >>> out = linear_maps(c, np.zeros((1, 4, 4)), b, surface_potential_v=0.5)
    >>> complex(np.round(out["amplitude"][0] * np.exp(1j * out["phase"][0]), 12))
    (2.5+0.75j)
    >>> float(out["nulling_bias"][0]), round(float(out["electrostatic"][0]), 12)
    (-1.2, 1.11803398875)
    """
    wb, ws = bias.r_inv[0], bias.r_inv[-1]
    intercept, slope = c @ wb, c @ ws
    w_eff = wb + surface_potential_v * ws if bias.has_bias else wb
    d_eff = c @ w_eff
    out = {"amplitude": np.abs(d_eff), "phase": np.angle(d_eff),
           "amplitude_stderr": _stderr(_abs_gradient(d_eff, w_eff), cov)}
    if bias.has_bias:
        (b_re, b_im), (s_re, s_im) = _parts(wb), _parts(ws)
        with np.errstate(divide="ignore", invalid="ignore"):    # a zero slope has no nulling bias
            g = nulling_bias_gradient(intercept, slope)
            v_null = nulling_bias(intercept, slope)
        grad = g[0][:, None] * b_re + g[1][:, None] * b_im + g[2][:, None] * s_re + g[3][:, None] * s_im
        out.update(electrostatic=np.abs(slope), electrostatic_phase=np.angle(slope),
                   electrostatic_stderr=_stderr(_abs_gradient(slope, ws), cov),
                   nulling_bias=v_null, nulling_bias_stderr=_stderr(grad, cov))
    return out


def _abs_gradient(z, weights):
    """Gradient of ``|z|`` (n,) over the real parameters, for ``z = sum_q w_q c_q``."""
    e_re, e_im = _parts(weights)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (z.real[:, None] * e_re + z.imag[:, None] * e_im) / np.abs(z)[:, None]
