"""Compiled residual and Jacobian of one discrepancy fit (:class:`pfmdyn.discrepancy.model._Problem`).

A least-squares fit evaluates its model a few hundred times on one spectrum; in NumPy each evaluation
is some forty calls on small arrays (the design's columns, their norms, the Gram matrix and its
eigen-decomposition, the amplitudes, the residual, Kaufman's Jacobian,
:mod:`pfmdyn.fitting.projection`), most of the time their overhead.  Here the same steps take two
compiled calls (numba) around NumPy's eigen-decomposition of the small Gram matrix (numba's would
add seconds to a fresh install's first run, compiling LAPACK's bindings), writing into arrays the fit
allocates once: :func:`design_and_gram` (the design from the slopes at the unique frequencies, each
column a slope or the background's ramp, times the bias or not:
:data:`pfmdyn.discrepancy.effects.BASE_COLUMNS`; its columns scaled to unit norm, their Gram matrix)
and :func:`residual_and_jacobian` (the amplitudes with the same eigenvalue cutoff, the residual, the
Jacobian).  Each row has a weight (the fit's rows are a spectrum's folded per frequency,
:func:`pfmdyn.fitting.projection.bias_nodes`; 1 for rows as measured).  The NumPy path is the reference
(``tests/test_discrepancy_kernel.py``).

Imported lazily (numba's import stays out of the command line's start-up).
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["design_and_gram", "residual_and_jacobian"]


@numba.njit(cache=True)
def design_and_gram(T, inverse, bias, weight, ramp, source, per_volt, y, A, As, scale, G, Ay):
    """The design ``A`` (rows, columns) from the slopes ``T`` (4, unique frequencies), its columns over their
    norms ``As`` (``scale``: one over each norm, 0 for a column of zero or non-finite norm, as
    :func:`pfmdyn.fitting.projection.project`), their Gram matrix ``G = As^H As`` and ``Ay = As^H y``.

    Column ``j`` is slope ``source[j]`` (``-1``: ``ramp``) at each row's frequency ``inverse``, times the
    row's ``bias`` where ``per_volt[j]``, times the row's ``weight``.

    Examples
    --------
    >>> T = np.array([[1.0 + 1j, 2.0], [0.5, 1j], [0.1, 0.2], [3.0, 1.0]], complex)
    >>> A, As, scale, G, Ay = (np.empty((4, 2), complex), np.empty((4, 2), complex), np.empty(2),
    ...                        np.empty((2, 2), complex), np.empty(2, complex))
    >>> design_and_gram(T, np.array([0, 1, 0, 1]), np.array([0.0, 0.0, 1.0, 1.0]), np.ones(4), np.ones(4),
    ...                 np.array([0, 3]), np.array([False, True]), np.ones(4, complex), A, As, scale, G, Ay)
    >>> A[:, 1].real.tolist(), bool(np.allclose(G.diagonal(), 1.0))       # V T_q; unit columns
    ([0.0, 0.0, 3.0, 1.0], True)
    """
    rows, m = A.shape
    # the column norms summed in row order, as NumPy's norm along the rows
    norms = np.zeros(m)
    for i in range(rows):
        u = inverse[i]
        for c in range(m):
            v = complex(ramp[i]) if source[c] < 0 else T[source[c], u]
            a = weight[i] * (bias[i] * v if per_volt[c] else v)
            A[i, c] = a
            norms[c] += a.real * a.real + a.imag * a.imag
    for c in range(m):
        norm = np.sqrt(norms[c])
        scale[c] = 1.0 / norm if np.isfinite(norm) and norm > 0 else 0.0
    G[:, :] = 0.0
    Ay[:] = 0.0
    for i in range(rows):
        for c in range(m):
            a = A[i, c]
            s = complex(a.real * scale[c], a.imag * scale[c])
            As[i, c] = s if np.isfinite(s.real) and np.isfinite(s.imag) else 0.0
        for a in range(m):
            conj = As[i, a].conjugate()
            for b in range(m):
                G[a, b] += conj * As[i, b]
            Ay[a] += conj * y[i]


@numba.njit(cache=True)
def residual_and_jacobian(dT, inverse, bias, weight, source, per_volt, y, sigma, A, As, scale, Ay, w, V, cutoff,
                          jacobian, amplitudes, residual, J):
    """From :func:`design_and_gram`'s arrays and the Gram matrix's eigenvalues ``w`` and vectors ``V``: the
    amplitudes (the pseudo-inverse, eigenvalues below ``cutoff`` of the largest dropped), the residual
    ``(y - A c) / sigma`` as ``[Re, Im]`` (non-finite: 1e6 times the row's weight, as the rows it stands for
    would count) and, with ``jacobian``, Kaufman's
    ``-(I - P) (dA/dx_j) c / sigma`` from the slopes' partials ``dT`` (4, parameters, unique frequencies)
    into ``J`` (2 rows, parameters; non-finite: 0).

    Examples
    --------
    >>> T = np.array([[1.0 + 1j, 2.0], [0.5, 1j], [0.1, 0.2], [3.0, 1.0]], complex)
    >>> rows, bias, columns = np.array([0, 1, 0, 1]), np.array([0.0, 0.0, 1.0, 1.0]), (np.array([0, 3]), np.array([False, True]))
    >>> y = np.array([1.0 + 1j, 2.0, 1.0 + 1j, 2.0])
    >>> A, As, scale, G, Ay = (np.empty((4, 2), complex), np.empty((4, 2), complex), np.empty(2),
    ...                        np.empty((2, 2), complex), np.empty(2, complex))
    >>> design_and_gram(T, rows, bias, np.ones(4), np.ones(4), *columns, y, A, As, scale, G, Ay)
    >>> c, r, J = np.empty(2, complex), np.empty(8), np.empty((8, 0))
    >>> residual_and_jacobian(np.empty((4, 0, 2), complex), rows, bias, np.ones(4), *columns, y, 1.0, A, As, scale, Ay,
    ...                       *np.linalg.eigh(G), 1e-13, False, c, r, J)
    >>> bool(np.allclose(c, [1.0, 0.0], rtol=0, atol=1e-12)), bool(np.abs(r).max() < 1e-12)  # y: the first column
    (True, True)
    """
    rows, m = A.shape
    top = max(w.max(), 1e-300)
    inv_w = np.zeros(m)
    for a in range(m):
        if w[a] > cutoff * top:
            inv_w[a] = 1.0 / w[a]
    ginv = np.zeros((m, m), np.complex128)
    for a in range(m):
        for b in range(m):
            v = 0j
            for q in range(m):
                v += V[a, q] * inv_w[q] * V[b, q].conjugate()
            ginv[a, b] = v
    for a in range(m):
        v = 0j
        for b in range(m):
            v += ginv[a, b] * Ay[b]
        amplitudes[a] = complex(v.real * scale[a], v.imag * scale[a])
    inv_sigma = 1.0 / sigma
    for i in range(rows):
        v = y[i]
        for c in range(m):
            v -= A[i, c] * amplitudes[c]
        re, im = v.real * inv_sigma, v.imag * inv_sigma
        residual[i] = re if np.isfinite(re) else 1e6 * weight[i]
        residual[rows + i] = im if np.isfinite(im) else 1e6 * weight[i]
    if not jacobian:
        return
    # (dA/dx_j) c per unique frequency: the bias-free and the per-volt parts
    p, n = dT.shape[1], dT.shape[2]
    fixed, per = np.zeros((n, p), np.complex128), np.zeros((n, p), np.complex128)
    for c in range(m):
        if source[c] < 0:
            continue
        for j in range(p):
            for u in range(n):
                if per_volt[c]:
                    per[u, j] += dT[source[c], j, u] * amplitudes[c]
                else:
                    fixed[u, j] += dT[source[c], j, u] * amplitudes[c]
    D = np.empty((rows, p), np.complex128)
    AD = np.zeros((m, p), np.complex128)
    for i in range(rows):
        for j in range(p):
            d = weight[i] * (fixed[inverse[i], j] + bias[i] * per[inverse[i], j])
            D[i, j] = d
            for a in range(m):
                AD[a, j] += As[i, a].conjugate() * d
    GAD = np.zeros((m, p), np.complex128)
    for a in range(m):
        for j in range(p):
            v = 0j
            for b in range(m):
                v += ginv[a, b] * AD[b, j]
            GAD[a, j] = v
    for i in range(rows):
        for j in range(p):
            v = D[i, j]
            for a in range(m):
                v -= As[i, a] * GAD[a, j]
            re, im = -v.real * inv_sigma, -v.imag * inv_sigma
            J[i, j] = re if np.isfinite(re) else 0.0
            J[rows + i, j] = im if np.isfinite(im) else 0.0
