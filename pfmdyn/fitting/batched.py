"""A batched Levenberg-Marquardt over variable projection: many spectra fitted at once.

Each spectrum ``y`` ``(m, n_freq)`` (``m`` components sharing the columns, e.g. a map pixel's
bias components) is modelled band by band as complex amplitudes times transfer functions,
``y[:, b] ~ c_b g(p)[:, b]``; the amplitudes are projected out (:mod:`pfmdyn.fitting.projection`)
and the nonlinear parameters ``p`` follow a Levenberg-Marquardt iteration that treats every
spectrum of a block at once, each with its own damping factor.  A *model* is anything with

* ``bands``: the frequency bands, a list of slices (each gets amplitudes of its own);
* ``design(p, jacobian=True)``: the transfer functions ``(n, K, n_freq)`` at parameters ``p``
  ``(n, n_p)`` and their partials ``(n_p, n, K, n_freq)`` (None unless ``jacobian``).

``pfmdyn map``'s beam model (:class:`pfmdyn.maps.beam.BeamMapModel`) and its simple harmonic
oscillator (:mod:`pfmdyn.maps.sho`) are two.  The covariance of all parameters, nonlinear and
amplitudes, is the noise times the inverse normal matrix of the full problem at the solution
(:func:`band_covariance`); its nonlinear block is the variable-projection one.
"""
from __future__ import annotations

import numpy as np

from .projection import covariance, normal_matrix, project

__all__ = ["project_bands", "levenberg_marquardt", "band_covariance", "amplitude_column"]


def project_bands(g, dg, y, band_list):
    """Variable projection of ``y`` ``(n, m, n_freq)`` (``m`` components) on the transfer
    functions ``g`` ``(n, K, n_freq)``, with amplitudes of their own for every component and
    band (:func:`pfmdyn.fitting.projection.project`, one band at a time).

    Returns amplitudes ``(n, m, n_bands, K)``, the real residual ``(n, 2 m n_freq)`` and, given
    ``dg`` ``(n_p, n, K, n_freq)``, its Jacobian ``(n, 2 m n_freq, n_p)``, the exact
    (Golub-Pereyra) derivative of the projection (None without ``dg``).

    >>> g = np.ones((1, 1, 4), complex)
    >>> c, r, J = project_bands(g, None, 2j * g[:, None, 0], [slice(0, 2), slice(2, 4)])
    >>> c.shape, np.round(c.ravel(), 12).tolist(), float(abs(r).max()), J
    ((1, 1, 2, 1), [2j, 2j], 0.0, None)
    """
    c, r = [], np.empty_like(y)
    dr = None if dg is None else np.empty((dg.shape[0],) + y.shape, complex)
    for b in band_list:
        A, yb = g[..., b], y[..., b]
        projection = project(np.swapaxes(A, 1, 2), np.swapaxes(yb, 1, 2))
        cb = np.swapaxes(projection.amplitudes, 1, 2)
        r[..., b] = rb = yb - np.einsum("nmk,nkf->nmf", cb, A)
        c.append(cb)
        if dg is not None:
            dA = dg[..., b]
            dA_c = np.einsum("pnkf,nmk->npfm", dA, cb)
            dA_h_r = np.einsum("pnkf,nmf->npkm", dA.conj(), rb)
            dr[..., b] = np.einsum("npfm->pnmf", projection.jacobian(dA_c, dA_h_r))
    n = len(y)
    J = None if dr is None else np.concatenate([dr.real, dr.imag], axis=2).reshape(len(dr), n, -1).transpose(1, 2, 0)
    return np.stack(c, axis=2), np.concatenate([r.real, r.imag], axis=1).reshape(n, -1), J


def levenberg_marquardt(model, y, p, bounds, iterations, tolerance):
    """Fit ``model`` (module docstring) to every spectrum of ``y`` ``(n, m, n_freq)`` from
    starts ``p`` ``(n, n_p)`` within ``bounds`` ``(lower, upper)``, one design evaluation per
    iteration for the whole block.

    Returns ``(p, c, r, J, cost, g, dg)``: parameters, amplitudes, real residual and its
    Jacobian (:func:`project_bands`), the cost ``sum r**2`` per spectrum, the transfer functions
    and their partials.  A spectrum stops when the predicted decrease of its cost is below
    ``tolerance`` times its noise variance (cost over degrees of freedom); a step predicted to
    gain less than 100 ``tolerance`` is the last one (Gauss-Newton converges quadratically: the
    next would gain below ``tolerance``), so its point gets values only: ``J``, ``g`` and ``dg``
    then stay those of the previous point, a fraction of a standard error away.

    Examples
    --------
    A decay rate ``exp(p)`` and a complex amplitude, two spectra at once:

    >>> class Decay:
    ...     t, bands = np.linspace(0.0, 1.0, 16), [slice(None)]
    ...     def design(self, p, jacobian=True):
    ...         g = np.exp(-np.exp(p[:, :1]) * self.t)[:, None, :] + 0j
    ...         return g, (-np.exp(p[:, 0, None, None]) * self.t * g)[None] if jacobian else None
    >>> y = (2 - 1j) * Decay().design(np.log([[1.5], [4.0]]), False)[0]
    >>> p, c, *_ = levenberg_marquardt(Decay(), y, np.zeros((2, 1)), ([-5.0], [5.0]), 40, 1e-6)
    >>> np.exp(p[:, 0]).round(9).tolist(), np.round(c[:, 0, 0, 0], 9).tolist()
    ([1.5, 4.0], [(2-1j), (2-1j)])
    """
    lower, upper = bounds
    n_p, band_list = p.shape[1], model.bands
    g, dg = model.design(p)
    c, r, J = project_bands(g, dg, y, band_list)
    cost = np.sum(r**2, axis=1)
    lam = np.full(len(y), 1e-3)
    dof = max(r.shape[1] - n_p - 2 * c[0].size, 1)
    active = np.arange(len(y))   # spectra still moving: converged ones cost nothing more
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
            c_t, r_t, J_t = project_bands(g_t, dg_t, y[act], band_list)
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


def band_covariance(model, g, dg, c, noise):
    """Covariance of ``(p, Re c, Im c)`` per spectrum, ``(n, n_p + 2 c.size, ...)``: ``noise``
    times the inverse normal matrix of the full (unprojected) problem at the solution
    (:func:`pfmdyn.fitting.projection.covariance`).

    Its ``p`` block is the variable-projection one; the amplitudes' block also carries their
    correlation with ``p`` (an amplitude's error grows with that of the resonance it sits on).
    The amplitude columns are ``(Re, Im)`` pairs in ``c``'s (component, band, transfer
    function) order (:func:`amplitude_column`); every band adds its normal matrix
    (:func:`pfmdyn.fitting.projection.normal_matrix`, the components as right-hand sides).

    >>> class Line:
    ...     bands = [slice(None)]
    >>> g, dg = np.ones((1, 1, 4), complex), np.zeros((1, 1, 1, 4), complex)
    >>> cov = band_covariance(Line(), g, dg, np.ones((1, 1, 1, 1), complex), np.ones(1))
    >>> cov.shape, cov[0, 1:, 1:].round(12).tolist()      # 1/4 for Re c and Im c of 4 points
    ((1, 3, 3), [[0.25, 0.0], [0.0, 0.25]])
    """
    n, m, n_bands, K = c.shape
    n_p = dg.shape[0]
    N = np.zeros((n, n_p + 2 * c[0].size, n_p + 2 * c[0].size))
    for j, b in enumerate(model.bands):
        D = np.einsum("pnkf,nmk->npfm", dg[..., b], c[:, :, j])
        cols = np.concatenate([np.arange(n_p)] + [amplitude_column(n_p, q, j, 0, n_bands, K) + np.arange(2 * K)
                                                  for q in range(m)])
        N[:, cols[:, None], cols] += normal_matrix(D, np.swapaxes(g[..., b], 1, 2))
    return covariance(N, noise)


def amplitude_column(n_p, q, j, k, n_bands, K) -> int:
    """Index of ``Re c_qjk`` (``Im`` is the next) among :func:`band_covariance`'s parameters:
    ``n_p`` nonlinear ones first, then component ``q``, band ``j``, transfer function ``k``.

    >>> amplitude_column(2, 0, 1, 0, 2, 1)
    4
    """
    return n_p + 2 * ((q * n_bands + j) * K + k)
