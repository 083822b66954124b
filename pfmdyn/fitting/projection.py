"""Variable projection: complex linear amplitudes solved out of a nonlinear fit, and covariances.

A model linear in complex amplitudes ``c`` given the nonlinear parameters ``p``,
``y ~ A(p) c``, is fitted over ``p`` alone: at every ``p`` the amplitudes are the linear least
squares solution (:func:`project`) and the residual ``r = y - A c`` is the projection of ``y``
off the columns of ``A``.  Its Jacobian (Golub and Pereyra 1973) is

``dr/dp_i = -(I - P) dA_i c - A G^-1 dA_i^H r``,   ``G = A^H A``, ``P = A G^-1 A^H``;

the second term vanishes at an exact fit and Kaufman's approximation drops it
(:meth:`Projection.jacobian`).  The covariance of ``(p, Re c, Im c)`` is the inverse of the real
normal matrix of the unprojected problem (:func:`normal_matrix`, :func:`covariance`); its ``p``
block is the variable-projection one.

Everything is batched over leading axes: ``A`` of shape ``(..., n, m)`` and ``y`` of shape
``(..., n, q)`` (``q`` right-hand sides sharing the columns, e.g. the bias components of a map
pixel), so a block of map pixels ``(pixels, n, m)`` and one spectrum ``(1, n, m)`` run the
same code.

A spectrum's rows that share a frequency enter such a design only through ``g(f)`` or ``V g(f)`` (a column
independent of the bias ``V`` or per volt), so :func:`bias_nodes` folds them into at most two weighted rows
with the same Gram matrix, the same products with the data and the same misfit up to a constant.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bias_line import _sums

__all__ = ["Projection", "project", "normal_matrix", "covariance", "jacobian_covariance", "BiasNodes",
           "bias_nodes"]

CUTOFF = 1e-13
"""Eigenvalues of the column-scaled Gram matrix below this fraction of the largest get no weight:
near-dependent column combinations get no amplitude rather than a huge one."""


@dataclass
class Projection:
    """The linear least-squares solution of ``y ~ A c`` (batched; see module docstring).

    ``norms`` are the column norms, ``scaled`` the columns divided by them, ``gram_inverse`` the
    pseudo-inverse of their Gram matrix, ``coefficients`` ``c`` ``(..., m, q)``, ``prediction``
    ``A c`` and ``residual`` ``y - A c`` ``(..., n, q)``.
    """

    norms: np.ndarray
    scaled: np.ndarray
    gram_inverse: np.ndarray
    coefficients: np.ndarray
    prediction: np.ndarray
    residual: np.ndarray

    def jacobian(self, design_times_c, design_h_residual=None):
        """``dr/dp`` ``(..., p, n, q)`` from ``dA_i c`` (``design_times_c``, ``(..., p, n, q)``)
        and, for the exact Golub-Pereyra derivative, ``dA_i^H r`` (``design_h_residual``,
        ``(..., p, m, q)``; None: Kaufman's approximation ``-(I - P) dA_i c``).

        >>> rng = np.random.default_rng(0)
        >>> A = rng.standard_normal((1, 6, 2)) + 0j
        >>> pr = project(A, rng.standard_normal((1, 6, 1)) + 0j)
        >>> bool(pr.jacobian(A[:, None, :, :1]).round(12).any())      # a column of A: projected away
        False
        """
        As, ginv = self.scaled, self.gram_inverse
        AsH = np.conj(np.swapaxes(As, -1, -2))[..., None, :, :]
        v = design_times_c - As[..., None, :, :] @ (ginv[..., None, :, :] @ (AsH @ design_times_c))
        if design_h_residual is not None:
            v = v + As[..., None, :, :] @ (ginv[..., None, :, :] @ (design_h_residual / self.norms[..., None, :, None]))
        return -v

    @property
    def amplitudes(self) -> np.ndarray:
        """The coefficients in the units of the unscaled columns, ``(..., m, q)``."""
        return self.coefficients / self.norms[..., :, None]


def project(A, y, cutoff: float = CUTOFF) -> Projection:
    """Solve ``y ~ A c`` by the column-scaled normal equations with an eigenvalue cutoff.

    ``A`` ``(..., n, m)``, ``y`` ``(..., n, q)``; columns of zero or non-finite norm get no weight.

    >>> A = np.array([[[1.0, 0.0], [0.0, 1e-9], [1.0, 1e-9]]])
    >>> pr = project(A, np.array([[[1.0], [2e-9], [1.0 + 2e-9]]]))
    >>> np.round(pr.amplitudes[0, :, 0].real, 6).tolist()
    [1.0, 2.0]
    """
    norms = np.linalg.norm(A, axis=-2)
    norms[~(np.isfinite(norms) & (norms > 0))] = np.inf
    As = A / norms[..., None, :]
    As[~np.isfinite(As)] = 0.0
    AsH = np.conj(np.swapaxes(As, -1, -2))
    w, V = np.linalg.eigh(AsH @ As)
    keep = w > cutoff * np.maximum(w.max(axis=-1, keepdims=True), 1e-300)
    inv_w = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    ginv = (V * inv_w[..., None, :]) @ np.conj(np.swapaxes(V, -1, -2))
    c = ginv @ (AsH @ y)
    prediction = As @ c
    return Projection(norms, As, ginv, c, prediction, y - prediction)


def normal_matrix(design_times_c, A) -> np.ndarray:
    """Real normal matrix of the unprojected problem ``r = y - A c`` over ``(p, Re c, Im c)``.

    ``design_times_c`` ``(..., p, n, q)`` holds ``D_i = dA_i c`` for each right-hand side, ``A``
    ``(..., n, m)`` the columns shared by the ``q`` right-hand sides, each with amplitudes of its
    own.  Amplitude columns are ordered (right-hand side, column) with ``(Re, Im)`` pairs.  The
    blocks are ``Re(D^H D)`` for ``p``, ``Re(D_i^H a_k)`` and ``-Im(...)`` between ``p_i`` and
    ``(Re, Im) c_k``, and the real form of ``A^H A`` for the amplitudes of one right-hand side.

    >>> A = np.array([[[1.0 + 1j], [2.0]]])
    >>> (normal_matrix(np.zeros((1, 1, 2, 1), complex), A)[0] + 0.0).tolist()
    [[0.0, 0.0, 0.0], [0.0, 6.0, 0.0], [0.0, 0.0, 6.0]]
    """
    D = design_times_c
    n_p, q, m = D.shape[-3], D.shape[-1], A.shape[-1]
    batch = A.shape[:-2]
    N = np.zeros(batch + (n_p + 2 * q * m,) * 2)
    N[..., :n_p, :n_p] = np.einsum("...pnq,...inq->...pi", D.conj(), D).real
    cross = np.einsum("...pnq,...nk->...pqk", D.conj(), A)
    H = np.einsum("...nk,...nl->...kl", A.conj(), A)
    block = np.empty(batch + (2 * m, 2 * m))
    block[..., 0::2, 0::2] = block[..., 1::2, 1::2] = H.real
    block[..., 0::2, 1::2], block[..., 1::2, 0::2] = -H.imag, H.imag
    for j in range(q):
        cols = n_p + 2 * j * m + np.arange(2 * m)
        N[..., :n_p, cols[0::2]], N[..., :n_p, cols[1::2]] = cross[..., j, :].real, -cross[..., j, :].imag
        N[..., cols[:, None], cols] = block
    N[..., n_p:, :n_p] = np.swapaxes(N[..., :n_p, n_p:], -1, -2)
    return N


def covariance(normal, scale=1.0, *, equilibrate: bool = True, cutoff: float = 1e-15,
               undetermined: float | None = None) -> np.ndarray:
    """``scale`` times the pseudo-inverse of the real normal matrix ``normal`` ``(..., k, k)``.

    ``equilibrate`` scales the matrix to unit diagonal first (parameters of very different
    scales); eigenvalues below ``cutoff`` of the largest get no weight.  With ``undetermined``, a
    parameter with a share above it in such a direction (one the data do not constrain) gets
    infinite variance (and zero covariance with the others) instead.

    >>> covariance(np.array([[4.0, 0.0], [0.0, 1.0]])).diagonal().tolist()
    [0.25, 1.0]
    >>> covariance(np.array([[1.0, 1.0], [1.0, 1.0]]), undetermined=1e-3).diagonal().tolist()
    [inf, inf]
    """
    N = np.asarray(normal, float)
    if equilibrate:
        size = np.sqrt(np.maximum(np.einsum("...ii->...i", N), 1e-300))
        outer = size[..., :, None] * size[..., None, :]
    else:
        outer = np.ones(N.shape[-1:] * 2)
    w, V = np.linalg.eigh(N / outer)
    good = w > cutoff * np.maximum(w.max(axis=-1, keepdims=True), 1e-300)
    inv_w = np.where(good, 1.0 / np.where(good, w, 1.0), 0.0)
    cov = (V * inv_w[..., None, :]) @ np.swapaxes(V, -1, -2) / outer * np.asarray(scale)[..., None, None]
    if undetermined is not None:
        loose = np.any((np.abs(V) > undetermined) & ~good[..., None, :], axis=-1)
        both = loose[..., :, None] & loose[..., None, :]
        cov = np.where(loose[..., :, None] | loose[..., None, :], np.where(both, np.inf, 0.0), cov)
    return cov


def jacobian_covariance(jacobian, scale=1.0) -> np.ndarray:
    """``scale (J^T J)^-1`` of a real Jacobian ``(rows, p)`` (non-finite entries read as 0): the
    normal matrix unequilibrated, eigenvalues below 1e-16 of the largest cut, and a parameter
    with a share above 1e-3 in a direction the data do not constrain undetermined (infinite
    variance).

    >>> jacobian_covariance(np.array([[1.0, 1.0], [2.0, 2.0]])).diagonal().tolist()
    [inf, inf]
    """
    J = np.asarray(jacobian, float)
    if not J.size:
        return np.zeros((J.shape[1], J.shape[1]))
    J = np.where(np.isfinite(J), J, 0.0)
    return covariance(J.T @ J, scale, equilibrate=False, cutoff=1e-16, undetermined=1e-3)


@dataclass(frozen=True)
class BiasNodes:
    """A spectrum's rows folded per frequency (:func:`bias_nodes`): ``frequency_hz`` (the unique
    frequencies, sorted), per folded row ``inverse`` (its frequency's index), ``bias_v`` (its node),
    ``weight`` and ``response``; ``constant``, the misfit no design of such columns reaches, and
    ``folded``, whether any rows were folded (else the rows are the spectrum's, in its order,
    weight 1, constant 0)."""

    frequency_hz: np.ndarray
    inverse: np.ndarray
    bias_v: np.ndarray
    weight: np.ndarray
    response: np.ndarray
    constant: float
    folded: bool


def bias_nodes(frequency_hz, bias_v, response) -> BiasNodes:
    """The rows of a spectrum for a design whose columns are ``g(f)`` or ``V g(f)``, at most two per frequency.

    At a frequency with ``n`` rows of biases ``V_i`` (mean ``m``, standard deviation ``s``) the two
    rows at the nodes ``m +- s``, each of weight ``sqrt(n / 2)`` (times the design's row), carry the
    same bias Gram matrix ``sum [1, V_i]^T [1, V_i]``; their responses ``(sum y +- sum (V_i - m) y_i / s)
    / sqrt(2 n)`` the same products ``sum y``, ``sum V y``.  Equal biases: one row at that bias,
    weight ``sqrt(n)``, response ``sum y / sqrt(n)``.  For every such design ``A`` and amplitudes
    ``c``, ``sum |y - A c|**2`` over the rows equals the folded rows' sum plus ``constant`` (the
    residual of the straight line in bias at each frequency), and a row of weight ``w`` stands for
    ``w**2`` rows.  Rows with a non-finite coordinate, or no two at one frequency: left as they are.

    >>> f, v = np.array([2.0, 1.0, 2.0, 1.0, 2.0, 3.0]), np.array([0.0, 1.0, 1.0, 1.0, 3.0, 5.0])
    >>> y = np.exp(1j * np.arange(6.0))
    >>> nodes = bias_nodes(f, v, y)
    >>> nodes.inverse.tolist(), nodes.bias_v.round(6).tolist(), nodes.weight.round(6).tolist()
    ([0, 1, 1, 2], [1.0, 2.580552, 0.086114, 5.0], [1.414214, 1.224745, 1.224745, 1.0])
    >>> A = np.stack([np.ones(6), v * f], axis=1)            # columns g(f) = 1 and V g(f) = V f
    >>> u, w = nodes.inverse, nodes.weight[:, None]
    >>> folded = np.stack([np.ones(4), nodes.bias_v * nodes.frequency_hz[u]], axis=1) * w
    >>> c = np.array([0.3 - 1j, 0.2j])
    >>> full, part = np.sum(np.abs(y - A @ c) ** 2), np.sum(np.abs(nodes.response - folded @ c) ** 2)
    >>> bool(np.isclose(full, part + nodes.constant, rtol=1e-14)), bool(np.allclose(A.T @ A, folded.T @ folded))
    (True, True)
    >>> bias_nodes(f, v, np.where(f == 3.0, np.nan, y)).folded         # a response not measured: rows as they are
    False
    """
    frequency_hz, bias_v = np.asarray(frequency_hz, float), np.asarray(bias_v, float)
    response = np.asarray(response)
    freq_u, inverse = np.unique(frequency_hz, return_inverse=True)
    n_u = len(freq_u)
    count = np.bincount(inverse, minlength=n_u)
    finite = np.isfinite(frequency_hz).all() and np.isfinite(bias_v).all() and np.isfinite(response).all()
    if not finite or count.max(initial=0) < 2:
        return BiasNodes(freq_u, inverse, bias_v, np.ones(len(bias_v)), response, 0.0, False)
    order = np.argsort(inverse, kind="stable")
    starts = np.concatenate([[0], np.cumsum(count)[:-1]])
    equal = np.minimum.reduceat(bias_v[order], starts) == np.maximum.reduceat(bias_v[order], starts)
    mean = np.bincount(inverse, bias_v, n_u) / count
    centred = np.where(equal[inverse], 0.0, bias_v - mean[inverse])
    spread = np.bincount(inverse, centred**2, n_u)                   # sum (V - m)**2, 0 where all equal
    total = _sums(inverse, response, n_u)
    moment = _sums(inverse, centred * response, n_u)                # sum (V - m) y
    slope = np.where(equal, 0.0, moment / np.where(equal, 1.0, spread))
    sd = np.sqrt(spread / count)
    lean = np.where(equal, 0.0, moment / np.where(equal, 1.0, sd))
    line = total[inverse] / count[inverse] + centred * slope[inverse]
    constant = float(np.sum(np.abs(response - line) ** 2))
    rows = np.where(equal, 1, 2)
    u = np.repeat(np.arange(n_u), rows)                             # each folded row's frequency
    second = np.zeros(len(u), bool)
    second[np.cumsum(rows)[~equal] - 1] = True                      # the node m - s of each unequal frequency
    sign = np.where(second, -1.0, 1.0)
    node = np.where(equal[u], bias_v[order][starts][u], mean[u] + sign * sd[u])
    weight = np.sqrt(count[u] / rows[u])
    folded = (total[u] + sign * lean[u]) / np.sqrt(rows[u] * count[u])
    return BiasNodes(freq_u, u, node, weight, folded, constant, True)
