"""Batched per-pixel fit of the elastic-contact beam response to band-excitation spectra.

At each pixel the measured response is ``c * A_v(f; k1, Q)``: the tip slope per unit vertical
surface displacement of the elastic-contact cantilever (generated code, via
:meth:`pfmdyn.Cantilever.elastic_response`), with contact stiffness ``k1``, loss ``1/Q`` and a
complex amplitude ``c`` (d_eff amplitude and phase, arbitrary instrument units).  ``c`` enters
linearly and is projected out; ``log k1`` and ``log Q`` are fitted by a Levenberg-Marquardt
iteration that treats every pixel of a block at once, with its own damping per pixel.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..cantilever import Cantilever

__all__ = ["BeamMapModel", "fit_block", "QUANTITIES"]

# name -> (unit, description) of the per-pixel output arrays
QUANTITIES = {
    "k1": ("N/m", "vertical contact stiffness"),
    "k1_stderr": ("N/m", "standard error of k1"),
    "quality_factor": ("1", "quality factor Q of the beam loss 1/Q"),
    "amplitude": ("response units per unit d1", "d_eff amplitude |c|"),
    "phase": ("rad", "d_eff phase arg c"),
    "gap": ("1", "relative residual |y - model| / |y|"),
    "explained": ("1", "1 where the model explains the pixel (gap below threshold), else 0"),
}


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

    def shape_functions(self, k1, q) -> np.ndarray:
        """Tip slope per unit d1 at every frequency, shape ``(len(k1), n_freq)``."""
        f = np.asarray(self.frequency_hz, float)
        beta1 = Cantilever(self.k, self.f1, self.L).beta(f)
        loss = (1 - 1j / np.asarray(q, float)[:, None]) ** 0.25
        from ..transfer import tip_slope_transfer
        return tip_slope_transfer(beta1[None, :] * loss, k=self.k, k1=np.asarray(k1, float)[:, None],
                                  k2=0.0, H=self.H, L=self.L).vertical


def _project(g, y):
    """Best complex amplitude per pixel and the residual ``y - c g``."""
    c = np.sum(g.conj() * y, axis=1) / np.sum(np.abs(g) ** 2, axis=1)
    return c, y - c[:, None] * g


def _residual(model, p, y):
    g = model.shape_functions(np.exp(p[:, 0]), np.exp(p[:, 1]))
    c, r = _project(g, y)
    return c, np.concatenate([r.real, r.imag], axis=1)


def _jacobian(model, p, y, r):
    """Derivatives of the projected residual w.r.t. (log k1, log Q): forward differences."""
    cols = []
    for j, h in enumerate((1e-6, 1e-6)):
        q = p.copy()
        q[:, j] += h
        cols.append((_residual(model, q, y)[1] - r) / h)
    return np.stack(cols, axis=2)


def _start(model, y, q0, k1_range):
    """Best k1 per pixel on a logarithmic grid (one shape function per grid value)."""
    grid = np.geomspace(*k1_range, 60)
    g = model.shape_functions(grid, np.full(grid.size, q0))
    proj = np.abs(y @ g.conj().T) ** 2 / np.sum(np.abs(g) ** 2, axis=1)
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
    p = np.stack([_start(model, y, q0, k1_range), np.full(len(y), math.log(q0))], axis=1)
    _, r = _residual(model, p, y)
    cost = np.sum(r**2, axis=1)
    lam = np.full(len(y), 1e-2)
    active = np.arange(len(y))   # pixels still moving: converged ones cost nothing more
    for _ in range(iterations):
        if active.size == 0:
            break
        pa, ra, ya, la = p[active], r[active], y[active], lam[active]
        J = _jacobian(model, pa, ya, ra)
        JtJ = np.einsum("nki,nkj->nij", J, J)
        grad = np.einsum("nki,nk->ni", J, ra)
        A = JtJ + la[:, None, None] * (JtJ * np.eye(2) + 1e-12 * np.eye(2))
        step = -np.linalg.solve(A, grad[..., None])[..., 0]
        trial = np.clip(pa + step, np.log([k1_range[0] / 10, 1.0]), np.log([k1_range[1] * 10, 1e5]))
        _, r_new = _residual(model, trial, ya)
        c_new = np.sum(r_new**2, axis=1)
        better = c_new < cost[active]
        idx = active[better]
        p[idx], r[idx], cost[idx] = trial[better], r_new[better], c_new[better]
        lam[active] = np.where(better, la / 3, la * 4)
        small = np.max(np.abs(step), axis=1) < 1e-8
        active = active[~((better & small) | (lam[active] > 1e8))]
    J = _jacobian(model, p, y, r)
    JtJ = np.einsum("nki,nkj->nij", J, J)
    dof = max(r.shape[1] - 4, 1)
    cov = np.linalg.pinv(JtJ) * (cost / dof)[:, None, None]
    c, _ = _residual(model, p, y)
    k1 = np.exp(p[:, 0])
    gap = np.sqrt(cost)
    out = {"k1": k1, "k1_stderr": k1 * np.sqrt(np.abs(cov[:, 0, 0])), "quality_factor": np.exp(p[:, 1]),
           "amplitude": np.abs(c) * scale, "phase": np.angle(c), "gap": gap,
           "explained": (gap < gap_threshold).astype(float)}
    return {name: v.reshape(shape) for name, v in out.items()}
