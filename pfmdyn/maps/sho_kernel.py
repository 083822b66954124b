"""The SHO fit of :mod:`pfmdyn.maps.sho` compiled: one spectrum at a time, no NumPy call per spectrum.

:func:`fit_sho` runs, for every spectrum of a block, the same arithmetic as the NumPy path of
:func:`pfmdyn.maps.sho.fit_spectra` (its reference, held to it by ``tests/test_maps_sho.py``):
the Sanathanan-Koerner guess of ``sho._guess`` (its 4 x 4 real normal matrix written out: the
columns ``y w``, ``i x y w``, ``w``, ``i w`` make half its entries vanish), the projection of the
complex amplitude (:func:`pfmdyn.fitting.projection.project` with one column) and the
Levenberg-Marquardt of :func:`pfmdyn.fitting.batched.levenberg_marquardt` on ``(log f0, log Q)``
with its damping, bounds and stopping rules, then the covariance of
:func:`pfmdyn.fitting.batched.band_covariance` (a 4 x 4 symmetric eigenproblem, by Jacobi
rotations).  The SHO and its partials are the generated formulas
(:mod:`pfmdyn.generated.formulas`) compiled as they are.  Work arrays are made once per call,
the kernel runs without the GIL (threads may fit blocks side by side), and numba caches the
machine code on disk (the first call of a fresh install compiles it, 10-20 s; later processes
load it in about a second).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ..compiled import forget_when_changed
from ..fitting import noise, projection
from ..fitting.noise import DIFFERENCE_ORDERS, MAX_REFINEMENT, PIXEL_FLOOR
from ..fitting.projection import CUTOFF
from ..generated import formulas

__all__ = ["fit_sho"]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
_sho = numba.njit(inline="always")(formulas.sho_response)
_sho_d_log_f0 = numba.njit(inline="always")(formulas.sho_response_d_log_resonance)
_sho_d_log_q = numba.njit(inline="always")(formulas.sho_response_d_log_quality)

_ESTIMATE_SCALES = np.array([math.comb(2 * m, m) * math.log(2) for m in DIFFERENCE_ORDERS])
"""``median |d|**2 / sigma**2`` of white complex noise's differences of each order."""
_COVARIANCE_CUTOFF = 1e-15      # pfmdyn.fitting.projection.covariance's default


def fit_sho(frequency_hz, spectra, q_range, bounds, iterations: int, tolerance: float,
            threads: int = 1) -> dict[str, np.ndarray]:
    """Guess (Q within ``q_range``) and fit (``(log f0, log Q)`` within ``bounds``) an SHO to every
    spectrum ``(n, n_freq)`` over one sorted band, each divided by its norm, the spectra shared
    among ``threads`` threads (at least 64 each): ``norm``, ``total``
    (``sum |y/norm - mean|**2``), guess and fit parameters
    ``(log f0, log Q)``, complex amplitudes and residual sums of squares, ``spread`` (the
    standard deviation of ``log f0`` and ``log Q`` mapped through ``sinh``, as ``sho.fit_spectra``)
    and ``sigma``, the noise (:func:`pfmdyn.fitting.noise.noise_sigmas` of each spectrum alone).
    A spectrum holding NaN or inf, or nothing but zeros, is masked: NaN everywhere.

    >>> f = np.linspace(290e3, 310e3, 64)
    >>> y = 2e-3 * formulas.sho_response(f, 301.2e3, 150.0)[None]
    >>> out = fit_sho(f, y, (0.1, 1e5), (np.log([145e3, 0.1]), np.log([620e3, 1e5])), 40, 1e-3)
    >>> np.exp(out["p"][0]).round(6).tolist(), round(float(abs(out["c"][0] * out["norm"][0])), 9)
    ([301200.0, 150.0], 0.002)
    """
    f = np.ascontiguousarray(frequency_hz, float)
    # a band of wider spectra (strided rows) is copied: numba compiles _fit_all once per layout (3 s)
    y = np.ascontiguousarray(spectra, complex)
    n = len(y)
    out = {"norm": np.empty(n), "total": np.empty(n), "guess_p": np.empty((n, 2)), "guess_c": np.empty(n, complex),
           "guess_cost": np.empty(n), "p": np.empty((n, 2)), "c": np.empty(n, complex), "cost": np.empty(n),
           "spread": np.empty((n, 2)), "sigma": np.empty(n)}
    centre = float(np.mean(f))
    settings = (f, f / centre, centre, float(q_range[0]), float(q_range[1]), np.asarray(bounds[0], float),
                np.asarray(bounds[1], float), iterations, tolerance, _ESTIMATE_SCALES)

    def fit(rows):
        _fit_all(y[rows], *settings, *(values[rows] for values in out.values()))

    if threads > 1 and n >= 64 * threads:
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(fit, [slice(i * n // threads, (i + 1) * n // threads) for i in range(threads)]))
    else:
        fit(slice(None))
    return out


@_jit
def _fit_all(y, f, x, centre, q_min, q_max, lower, upper, iterations, tolerance, estimate_scales, norm, total, guess_p,
             guess_c, guess_cost, p_out, c_out, cost_out, spread, sigma):
    """:func:`fit_sho` on the rows of ``y``, into the output arrays after ``estimate_scales``."""
    nf = f.size
    yn = np.empty(nf, np.complex128)
    weight = np.empty(nf)
    # rows: the transfer function, its two partials and the residual, at the current point and a trial
    now, then = np.empty((4, nf), np.complex128), np.empty((4, nf), np.complex128)
    normal, rhs, scale, vectors = np.empty((4, 4)), np.empty(4), np.empty(4), np.empty((4, 4))
    p, trial, moments, moments_t = np.empty(2), np.empty(2), np.empty(5), np.empty(5)
    differences, squares = np.empty(nf, np.complex128), np.empty(nf)
    dof = max(2 * nf - 4, 1)
    for i in range(y.shape[0]):
        s = 0.0
        for k in range(nf):
            s += y[i, k].real ** 2 + y[i, k].imag ** 2
        if not (s > 0 and math.isfinite(s)):
            for values in (norm, total, guess_cost, cost_out, sigma):
                values[i] = math.nan
            for values in (guess_c, c_out):
                values[i] = complex(math.nan, math.nan)
            for values in (guess_p, p_out, spread):
                values[i, 0] = values[i, 1] = math.nan
            continue
        length = math.sqrt(s)
        mean = 0j
        for k in range(nf):
            yn[k] = y[i, k] / length
            mean += yn[k]
        mean /= nf
        spread_y = 0.0
        for k in range(nf):
            spread_y += (yn[k] - mean).real ** 2 + (yn[k] - mean).imag ** 2
        norm[i], total[i] = length, spread_y
        sigma[i] = max(_noise(y[i], differences, squares, estimate_scales), PIXEL_FLOOR * length)

        x0, q = _guess(x, yn, q_min, q_max, weight, normal, rhs, scale)
        p[0], p[1] = math.log(x0 * centre), math.log(q)
        guess_p[i, 0], guess_p[i, 1] = p[0], p[1]
        c, cost = _evaluate(f, yn, p, True, now, moments)
        guess_c[i], guess_cost[i] = c, cost
        lam = 1e-3
        for _ in range(iterations):
            a00, a01, a11, b0, b1 = moments[0], moments[1], moments[2], moments[3], moments[4]
            # (JtJ + lam (diag JtJ + 1e-12)) d = grad, solved by Gaussian elimination with pivoting
            m00, m11 = a00 + lam * (a00 + 1e-12), a11 + lam * (a11 + 1e-12)
            d0, d1 = _solve2(m00, a01, a01, m11, b0, b1)
            step0 = min(max(p[0] - d0, lower[0]), upper[0]) - p[0]
            step1 = min(max(p[1] - d1, lower[1]), upper[1]) - p[1]
            # predicted decrease of the cost (Gauss-Newton) in units of the tolerance
            gain = -(step0 * b0 + step1 * b1) / (tolerance * cost / dof)
            if not (gain > 1 and lam < 1e8):
                break
            last = gain < 100
            trial[0], trial[1] = p[0] + step0, p[1] + step1
            c_t, cost_t = _evaluate(f, yn, trial, not last, then, moments_t)
            if cost_t < cost:
                p[0], p[1], c, cost = trial[0], trial[1], c_t, cost_t
                if not last:
                    now, then, moments, moments_t = then, now, moments_t, moments
                lam /= 3
                if last:
                    break
            else:
                lam *= 4
        p_out[i, 0], p_out[i, 1], c_out[i], cost_out[i] = p[0], p[1], c, cost
        _spread(now, c, cost / dof, normal, vectors, scale, spread[i])


@_jit
def _noise(y, differences, squares, estimate_scales):
    """:func:`pfmdyn.fitting.noise.noise_sigma` of one spectrum at sorted frequencies without biases
    (no line in bias to fit): the medians of ``|d|**2`` of the differences of each order (their
    ``np.diff`` iteration, in place), the smallest refined estimate held within
    :data:`~pfmdyn.fitting.noise.MAX_REFINEMENT` of the second differences'."""
    nf = y.size
    differences[:] = y
    first = refined = math.inf
    j = 0
    for order in range(1, DIFFERENCE_ORDERS[-1] + 1):
        for k in range(nf - order):
            differences[k] = differences[k + 1] - differences[k]
        if order < DIFFERENCE_ORDERS[0]:
            continue
        count = nf - order
        for k in range(count):
            squares[k] = differences[k].real ** 2 + differences[k].imag ** 2
        half = count // 2
        median = _select(squares, count, half)
        if count % 2 == 0:       # the mean of the two middle values, as np.median
            below = squares[0]
            for k in range(1, half):
                below = max(below, squares[k])
            median = (below + median) / 2
        estimate = math.sqrt(median / estimate_scales[j])
        j += 1
        if order == DIFFERENCE_ORDERS[0]:
            first = estimate
        else:
            refined = min(refined, estimate)
    return min(first, max(refined, MAX_REFINEMENT * first))


@_jit
def _select(a, n, k):
    """The ``k``-th smallest of ``a[:n]``, reordering ``a`` so that the ``k`` before it are no larger
    (Hoare's selection; Lomuto's partition without branches, the middle element as pivot)."""
    lo, hi = 0, n - 1
    while lo < hi:
        mid = (lo + hi) // 2
        pivot = a[mid]
        a[mid] = a[hi]
        store = lo
        for i in range(lo, hi):
            value = a[i]
            a[i] = a[store]
            a[store] = value
            store += value < pivot
        a[hi] = a[store]
        a[store] = pivot
        if k == store:
            return pivot
        if k < store:
            hi = store - 1
        else:
            lo = store + 1
    return a[k]


@_jit
def _guess(x, y, q_min, q_max, weight, normal, rhs, scale, passes=3):
    """``sho._guess`` for one spectrum: ``(f0 / centre, Q)``.  The unknowns
    ``(u, v, Re c, Im c)`` of ``y w (x**2 - u - i x v) = c w``; with columns ``y w``, ``i x y w``,
    ``w``, ``i w`` the normal matrix's entries (0, 1) and (2, 3) and the right-hand side's entry 1
    vanish."""
    nf = x.size
    for k in range(nf):
        weight[k] = 1.0
    x0 = q = 1.0
    for _ in range(passes):
        normal[:] = 0.0
        rhs[:] = 0.0
        for k in range(nf):
            w, xk = weight[k], x[k]
            a, b = y[k].real * w, y[k].imag * w
            m = a * a + b * b
            normal[0, 0] += m
            normal[0, 2] += w * a
            normal[0, 3] += w * b
            normal[1, 1] += xk * xk * m
            normal[1, 2] -= xk * w * b
            normal[1, 3] += xk * w * a
            normal[2, 2] += w * w
            rhs[0] += xk * xk * m
            rhs[2] += xk * xk * w * a
            rhs[3] += xk * xk * w * b
        normal[3, 3] = normal[2, 2]
        # scaled to unit diagonal (plus a ridge of 1e-12), as sho._guess solves it
        for j in range(4):
            scale[j] = math.sqrt(max(normal[j, j], 1e-300))
        for j in range(4):
            rhs[j] /= scale[j]
            for k in range(j, 4):
                normal[j, k] /= scale[j] * scale[k]
                normal[k, j] = normal[j, k]
            normal[j, j] += 1e-12
        _solve4(normal, rhs)
        u = min(max(rhs[0] / scale[0], (x[0] / 2) ** 2), (2 * x[nf - 1]) ** 2)
        x0 = math.sqrt(u)
        q = min(max(x0 / max(abs(rhs[1] / scale[1]), x0 / q_max), q_min), q_max)
        top = 0.0
        for k in range(nf):
            weight[k] = 1.0 / math.sqrt((x[k] ** 2 - u) ** 2 + (x[k] * (x0 / q)) ** 2)      # 1 / |D|
            top = max(top, weight[k])
        for k in range(nf):
            weight[k] /= top
    return x0, q


@_jit
def _evaluate(f, y, p, jacobian, rows, moments):
    """The SHO at ``p`` into ``rows[0]`` (and its partials into ``rows[1:3]`` with ``jacobian``),
    its amplitude projected out of ``y`` (:func:`pfmdyn.fitting.projection.project`, one column)
    and the residual into ``rows[3]``; returns ``(amplitude, cost)``.  With ``jacobian``, ``moments`` gets
    ``J^T J`` (00, 01, 11) and ``J^T r`` (0, 1) of the real residual's exact (Golub-Pereyra)
    Jacobian."""
    nf = f.size
    g, dg0, dg1, r = rows[0], rows[1], rows[2], rows[3]
    f0, q = math.exp(p[0]), math.exp(p[1])
    gg = 0.0
    for k in range(nf):
        g[k] = _sho(f[k], f0, q)
        gg += g[k].real ** 2 + g[k].imag ** 2
    norm = math.sqrt(gg)
    usable = math.isfinite(norm) and norm > 0
    inv_norm = 1.0 / norm if usable else 0.0        # a column of no usable norm gets no weight
    gram, ahy = 0.0, 0j
    for k in range(nf):
        a = g[k] * inv_norm
        gram += a.real ** 2 + a.imag ** 2
        ahy += a.conjugate() * y[k]
    ginv = 1.0 / gram if gram > CUTOFF * max(gram, 1e-300) else 0.0     # project()'s cutoff, a 1 x 1 Gram matrix
    coefficient = ginv * ahy
    cost = 0.0
    for k in range(nf):
        r[k] = y[k] - g[k] * inv_norm * coefficient
        cost += r[k].real ** 2 + r[k].imag ** 2
    amplitude = coefficient * inv_norm
    if not jacobian:
        return amplitude, cost
    ahd0 = ahd1 = dhr0 = dhr1 = 0j
    for k in range(nf):
        dg0[k] = _sho_d_log_f0(f[k], f0, q)
        dg1[k] = _sho_d_log_q(f[k], f0, q)
        a = (g[k] * inv_norm).conjugate()
        ahd0 += a * (dg0[k] * amplitude)
        ahd1 += a * (dg1[k] * amplitude)
        dhr0 += dg0[k].conjugate() * r[k]
        dhr1 += dg1[k].conjugate() * r[k]
    # dr/dp_i = -(D_i - A G^-1 A^H D_i + A G^-1 dA_i^H r / |a|),  D_i = dA_i c
    w0 = ginv * ahd0 - ginv * (dhr0 * inv_norm)
    w1 = ginv * ahd1 - ginv * (dhr1 * inv_norm)
    moments[:] = 0.0
    for k in range(nf):
        a = g[k] * inv_norm
        v0 = a * w0 - dg0[k] * amplitude
        v1 = a * w1 - dg1[k] * amplitude
        moments[0] += v0.real ** 2 + v0.imag ** 2
        moments[1] += v0.real * v1.real + v0.imag * v1.imag
        moments[2] += v1.real ** 2 + v1.imag ** 2
        moments[3] += v0.real * r[k].real + v0.imag * r[k].imag
        moments[4] += v1.real * r[k].real + v1.imag * r[k].imag
    return amplitude, cost


@_jit
def _spread(rows, c, noise, normal, vectors, size, out):
    """``sinh`` of the standard deviations of ``log f0`` and ``log Q`` into ``out``: ``noise``
    times the inverse of the real normal matrix of ``(log f0, log Q, Re c, Im c)`` at the
    transfer function ``rows[0]``, its partials ``rows[1:3]`` and the amplitude ``c``, equilibrated, eigenvalues
    below 1e-15 of the largest cut (:func:`pfmdyn.fitting.batched.band_covariance`)."""
    g, dg0, dg1 = rows[0], rows[1], rows[2]
    normal[:] = 0.0
    for k in range(g.size):
        d0, d1, gk = dg0[k] * c, dg1[k] * c, g[k]
        normal[0, 0] += d0.real ** 2 + d0.imag ** 2
        normal[0, 1] += d0.real * d1.real + d0.imag * d1.imag
        normal[1, 1] += d1.real ** 2 + d1.imag ** 2
        cross0, cross1 = d0.conjugate() * gk, d1.conjugate() * gk
        normal[0, 2] += cross0.real
        normal[0, 3] -= cross0.imag
        normal[1, 2] += cross1.real
        normal[1, 3] -= cross1.imag
        normal[2, 2] += gk.real ** 2 + gk.imag ** 2
    normal[3, 3] = normal[2, 2]
    for j in range(4):
        size[j] = math.sqrt(max(normal[j, j], 1e-300))
    for j in range(4):
        for k in range(j, 4):
            normal[j, k] /= size[j] * size[k]
            normal[k, j] = normal[j, k]
    _eigh4(normal, vectors)
    top = max(max(normal[0, 0], normal[1, 1]), max(normal[2, 2], normal[3, 3]))
    for j in range(2):
        variance = 0.0
        for k in range(4):
            w = normal[k, k]
            if w > _COVARIANCE_CUTOFF * max(top, 1e-300):
                variance += vectors[j, k] ** 2 / w
        out[j] = math.sinh(math.sqrt(abs(variance * noise / size[j] ** 2)))


@_jit
def _eigh4(a, v):
    """Eigenvalues of the symmetric ``a`` onto its diagonal, eigenvectors into the columns of ``v``
    (cyclic Jacobi rotations, to rounding)."""
    n = a.shape[0]
    v[:] = 0.0
    for j in range(n):
        v[j, j] = 1.0
    for _ in range(50):
        off = diagonal = 0.0
        for j in range(n):
            diagonal += a[j, j] ** 2
            for k in range(j + 1, n):
                off += a[j, k] ** 2
        if off <= 1e-36 * diagonal:
            return
        for j in range(n - 1):
            for k in range(j + 1, n):
                if a[j, k] == 0.0:
                    continue
                theta = (a[k, k] - a[j, j]) / (2.0 * a[j, k])
                t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                cos = 1.0 / math.sqrt(t * t + 1.0)
                sin = t * cos
                for m in range(n):      # columns j, k, then rows j, k
                    amj, amk = a[m, j], a[m, k]
                    a[m, j], a[m, k] = cos * amj - sin * amk, sin * amj + cos * amk
                for m in range(n):
                    ajm, akm = a[j, m], a[k, m]
                    a[j, m], a[k, m] = cos * ajm - sin * akm, sin * ajm + cos * akm
                for m in range(n):
                    vmj, vmk = v[m, j], v[m, k]
                    v[m, j], v[m, k] = cos * vmj - sin * vmk, sin * vmj + cos * vmk


@_jit
def _solve2(a00, a01, a10, a11, b0, b1):
    """The solution of a 2 x 2 system by Gaussian elimination with partial pivoting."""
    if abs(a10) > abs(a00):
        a00, a01, a10, a11, b0, b1 = a10, a11, a00, a01, b1, b0
    factor = a10 / a00
    x1 = (b1 - factor * b0) / (a11 - factor * a01)
    return (b0 - a01 * x1) / a00, x1


@_jit
def _solve4(a, b):
    """Solve ``a x = b`` in place (``b`` becomes ``x``; ``a`` is overwritten) by Gaussian
    elimination with partial pivoting."""
    n = b.size
    for j in range(n):
        pivot = j
        for k in range(j + 1, n):
            if abs(a[k, j]) > abs(a[pivot, j]):
                pivot = k
        if pivot != j:
            for m in range(n):
                a[j, m], a[pivot, m] = a[pivot, m], a[j, m]
            b[j], b[pivot] = b[pivot], b[j]
        for k in range(j + 1, n):
            factor = a[k, j] / a[j, j]
            for m in range(j, n):
                a[k, m] -= factor * a[j, m]
            b[k] -= factor * b[j]
    for j in range(n - 1, -1, -1):
        s = b[j]
        for m in range(j + 1, n):
            s -= a[j, m] * b[m]
        b[j] = s / a[j, j]


# the generated SHO response and the fitting core's constants are compiled in here
forget_when_changed(__name__, formulas, noise, projection)
