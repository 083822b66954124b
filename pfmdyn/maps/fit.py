"""Batched per-pixel fit of the elastic-contact beam response to band-excitation spectra.

At each pixel the measured response is ``c_b * A_v(f; k1, k2, Q)``: the tip slope per unit
vertical surface displacement of the elastic-contact cantilever (generated code, via
:meth:`pfmdyn.Cantilever.elastic_response`), with contact stiffnesses ``k1``, ``k2``, loss
``1/Q`` and one complex amplitude ``c_b`` per frequency band (d_eff amplitude and phase,
arbitrary instrument units; bands are driven and demodulated separately).  The amplitudes
enter linearly and are projected out (variable projection); ``log k1``, ``log Q`` and, when
the frequencies hold two or more bands (one per contact mode), ``log k2`` are fitted by a
Levenberg-Marquardt iteration that treats every pixel of a block at once, with its own damping
per pixel.  One contact mode cannot separate ``k1`` from ``k2``: with one band ``k2 = 0``.
The covariance of the fitted parameters is ``s**2 (J^T J)^-1`` of the projected residual,
the marginal covariance of the full problem (Golub and Pereyra 1973).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..cantilever import Cantilever
from ..generated import damping, elastic_contact

__all__ = ["BeamMapModel", "fit_block", "QUANTITIES", "bands"]

# name -> (unit, description) of the per-pixel output arrays
QUANTITIES = {
    "k1": ("N/m", "vertical contact stiffness"),
    "k1_stderr": ("N/m", "standard error of k1"),
    "k2": ("N/m", "longitudinal contact stiffness (two or more bands; else NaN)"),
    "k2_stderr": ("N/m", "standard error of k2"),
    "quality_factor": ("1", "quality factor Q of the beam loss 1/Q"),
    "amplitude": ("response units per unit d1", "d_eff amplitude |c| (first band)"),
    "phase": ("rad", "d_eff phase arg c (first band)"),
    "gap": ("1", "relative residual |y - model| / |y|"),
    "explained": ("1", "1 where the model explains the pixel (gap below threshold), else 0"),
}


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
    """Cantilever metadata in SI units and the frequency vector of the map.

    Examples
    --------
    >>> m = BeamMapModel(k=2.0, L=225e-6, f1=75e3, H=10e-6, frequency_hz=np.linspace(3e5, 4e5, 8))
    >>> m.shape_functions(np.array([200.0]), np.array([80.0])).shape
    (1, 8)
    """

    k: float
    L: float
    f1: float
    H: float
    frequency_hz: np.ndarray

    @property
    def bands(self) -> list[slice]:
        """The frequency bands (one per contact mode driven)."""
        return bands(self.frequency_hz)

    def shape_functions(self, k1, q, k2=0.0) -> np.ndarray:
        """Tip slope per unit d1 at every frequency, shape ``(len(k1), n_freq)``."""
        f = np.asarray(self.frequency_hz, float)
        beta1 = Cantilever(self.k, self.f1, self.L).beta(f)
        # Internal friction as derived (derivations/damping.py): the complex modulus E (1 + i/Q)
        # turns beta**4 into beta**4 / (1 + i/Q) and, relative to EI, the contact springs into
        # k / (1 + i/Q).
        beta_factor, modulus, _, _ = damping.factors(1.0, 1.0 / np.asarray(q, float)[:, None], 0.0, 0.0)
        k2 = np.asarray(k2, float)
        k2 = k2[:, None] if k2.ndim else k2
        return elastic_contact.slope(beta1[None, :] * beta_factor, self.k,
                                     np.asarray(k1, float)[:, None] / modulus, k2 / modulus, self.H, self.L)[0]


def _project(g, y, band_list):
    """Best complex amplitude per pixel and band ``(n, n_bands)`` and the residual ``y - c_b g``."""
    c, r = [], np.empty_like(y)
    for b in band_list:
        cb = np.sum(g[:, b].conj() * y[:, b], axis=1) / np.sum(np.abs(g[:, b]) ** 2, axis=1)
        r[:, b] = y[:, b] - cb[:, None] * g[:, b]
        c.append(cb)
    return np.stack(c, axis=1), r


def _residual(model, p, y):
    k2 = np.exp(p[:, 2]) if p.shape[1] > 2 else 0.0
    g = model.shape_functions(np.exp(p[:, 0]), np.exp(p[:, 1]), k2)
    c, r = _project(g, y, model.bands)
    return c, np.concatenate([r.real, r.imag], axis=1)


def _jacobian(model, p, y, r):
    """Derivatives of the projected residual w.r.t. (log k1, log Q[, log k2]): forward differences.

    The one place derivatives are made: generated Jacobians replace this body alone.
    """
    cols, h = [], 1e-6
    for j in range(p.shape[1]):
        q = p.copy()
        q[:, j] += h
        cols.append((_residual(model, q, y)[1] - r) / h)
    return np.stack(cols, axis=2)


def _start(model, y, q0, k1_range):
    """Best k1 per pixel on a logarithmic grid (one shape function per grid value, k2 = 0)."""
    grid = np.geomspace(*k1_range, 60)
    g = model.shape_functions(grid, np.full(grid.size, q0))
    proj = sum(np.abs(y[:, b] @ g[:, b].conj().T) ** 2 / np.sum(np.abs(g[:, b]) ** 2, axis=1)
               for b in model.bands)
    return np.log(grid[np.argmax(proj, axis=1)])


def fit_block(model: BeamMapModel, response, *, q0=100.0, k1_range=None, iterations=40,
              gap_threshold=0.2) -> dict[str, np.ndarray]:
    """Fit every pixel of ``response`` (``(..., n_freq)`` complex) at once.

    Returns the arrays of :data:`QUANTITIES`, each of the pixel shape ``response.shape[:-1]``.

    Examples
    --------
    >>> f = np.linspace(2.5e5, 4.5e5, 48)
    >>> m = BeamMapModel(k=2.0, L=225e-6, f1=75e3, H=10e-6, frequency_hz=f)
    >>> y = 3e-3 * m.shape_functions(np.array([300.0]), np.array([60.0]))
    >>> out = fit_block(m, y)
    >>> round(float(out["k1"][0]), 6), round(float(out["quality_factor"][0]), 6)
    (300.0, 60.0)
    """
    y = np.asarray(response, complex)
    shape = y.shape[:-1]
    y = y.reshape(-1, y.shape[-1])
    scale = np.linalg.norm(y, axis=1)
    scale[scale == 0] = 1.0
    y = y / scale[:, None]
    k1_range = k1_range or (model.k, 1e4 * model.k)
    log_k1 = _start(model, y, q0, k1_range)
    columns = [log_k1, np.full(len(y), math.log(q0))]
    n_bands = len(model.bands)
    if n_bands > 1:
        columns.append(log_k1 + math.log(0.5))   # k2 ~ k1 / 2 (Mindlin: 0.7-0.9 k1)
    p = np.stack(columns, axis=1)
    n_p = p.shape[1]
    lower = np.log([k1_range[0] / 10, 1.0, k1_range[0] / 100][:n_p])
    upper = np.log([k1_range[1] * 10, 1e5, k1_range[1] * 10][:n_p])
    _, r = _residual(model, p, y)
    cost = np.sum(r**2, axis=1)
    lam = np.full(len(y), 1e-2)
    dof = max(r.shape[1] - n_p - 2 * n_bands, 1)
    active = np.arange(len(y))   # pixels still moving: converged ones cost nothing more
    for _ in range(iterations):
        if active.size == 0:
            break
        pa, ra, ya, la = p[active], r[active], y[active], lam[active]
        J = _jacobian(model, pa, ya, ra)
        JtJ = np.einsum("nki,nkj->nij", J, J)
        grad = np.einsum("nki,nk->ni", J, ra)
        A = JtJ + la[:, None, None] * (JtJ * np.eye(n_p) + 1e-12 * np.eye(n_p))
        step = -np.linalg.solve(A, grad[..., None])[..., 0]
        trial = np.clip(pa + step, lower, upper)
        _, r_new = _residual(model, trial, ya)
        c_new = np.sum(r_new**2, axis=1)
        better = c_new < cost[active]
        idx = active[better]
        p[idx], r[idx], cost[idx] = trial[better], r_new[better], c_new[better]
        lam[active] = np.where(better, la / 3, la * 4)
        # Converged when the predicted decrease of the cost (Gauss-Newton decrement) is below
        # 1e-6 of the noise variance: the step is then ~1e-3 standard errors.
        decrement = -np.einsum("ni,ni->n", step, grad)
        small = (decrement < 1e-6 * cost[active] / dof) | (np.max(np.abs(step), axis=1) < 1e-8)
        active = active[~((better & small) | (lam[active] > 1e8))]
    J = _jacobian(model, p, y, r)
    JtJ = np.einsum("nki,nkj->nij", J, J)
    cov = np.linalg.pinv(JtJ) * (cost / dof)[:, None, None]
    c, _ = _residual(model, p, y)
    k1 = np.exp(p[:, 0])
    k2 = np.exp(p[:, 2]) if n_p > 2 else np.full(len(y), np.nan)
    k2_stderr = k2 * np.sqrt(np.abs(cov[:, 2, 2])) if n_p > 2 else k2
    gap = np.sqrt(cost)
    out = {"k1": k1, "k1_stderr": k1 * np.sqrt(np.abs(cov[:, 0, 0])), "k2": k2, "k2_stderr": k2_stderr,
           "quality_factor": np.exp(p[:, 1]),
           "amplitude": np.abs(c[:, 0]) * scale, "phase": np.angle(c[:, 0]), "gap": gap,
           "explained": (gap < gap_threshold).astype(float)}
    return {name: v.reshape(shape) for name, v in out.items()}
