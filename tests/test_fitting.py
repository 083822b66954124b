"""The fitting core shared by ``pfmdyn discrepancy`` and ``pfmdyn map`` (:mod:`pfmdyn.fitting`).

Checked against independent routes: NumPy's complex least squares for the projection, central
finite differences of the projected residual for its Jacobian, the inverse of an explicitly built
real normal matrix for the covariance; the parameter transforms by round trips; and the gap of a
map pixel against the discrepancy's fit result on the same residual and noise.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from pfmdyn import Cantilever
from pfmdyn.discrepancy.model import FitResult, Model
from pfmdyn.fitting.noise import noise_sigma
from pfmdyn.fitting.parameters import CONTACT_LOSS, INTERNAL_LOSS, Parameter
from pfmdyn.fitting.projection import covariance, jacobian_covariance, normal_matrix, project
from pfmdyn.maps.beam import BeamMapModel
from pfmdyn.maps.fit import fit_block


def _complex(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


def test_projection_is_complex_least_squares():
    """Batched projection of random problems (pixels, rows, columns) with two right-hand sides,
    columns of scales 1e-6 to 1e3: coefficients and residual as NumPy's lstsq gives them."""
    rng = np.random.default_rng(3)
    A = _complex(rng, 5, 40, 3) * np.array([1e-6, 1.0, 1e3])
    y = _complex(rng, 5, 40, 2)
    pr = project(A, y)
    for i in range(len(A)):
        c, *_ = np.linalg.lstsq(A[i], y[i], rcond=None)
        np.testing.assert_allclose(pr.amplitudes[i], c, rtol=1e-9)
        np.testing.assert_allclose(pr.residual[i], y[i] - A[i] @ c, atol=1e-12 * np.abs(y[i]).max())
    # the residual is orthogonal to every column
    assert np.abs(np.einsum("bnm,bnq->bmq", A.conj(), pr.residual)).max() < 1e-9 * np.abs(A).max() * np.abs(y).max()


def _design(p, t):
    """A smooth nonlinear design: two damped complex exponentials and a constant column."""
    return np.stack([np.exp((1j * p[0] - 0.1) * t), np.exp((1j * p[1] - 0.2 * p[0]) * t), np.ones_like(t) + 0j], axis=1)


def _design_derivative(p, t):
    """d design / d p_i, shape (p, rows, columns)."""
    e0, e1 = np.exp((1j * p[0] - 0.1) * t), np.exp((1j * p[1] - 0.2 * p[0]) * t)
    zero = np.zeros_like(e0)
    return np.array([np.stack([1j * t * e0, -0.2 * t * e1, zero], axis=1),
                     np.stack([zero, 1j * t * e1, zero], axis=1)])


def test_projected_jacobian_against_finite_differences():
    """The Golub-Pereyra Jacobian of the projected residual equals central differences (to 1e-7);
    Kaufman's approximation (without the term in the residual) does not, on data far from the
    model."""
    rng = np.random.default_rng(5)
    t = np.linspace(0, 3, 60)
    p = np.array([1.3, 2.1])
    y = (_design(np.array([1.25, 2.2]), t) @ np.array([1.0, 0.5j, 0.2]) + 0.3 * _complex(rng, t.size))[None, :, None]

    def residual(q):
        return project(_design(q, t)[None], y).residual[0, :, 0]

    pr = project(_design(p, t)[None], y)
    dA = _design_derivative(p, t)[None]                           # (1, p, rows, columns)
    c, r = pr.amplitudes, pr.residual
    exact = pr.jacobian(dA @ c[:, None], np.conj(np.swapaxes(dA, -1, -2)) @ r[:, None])[0, :, :, 0]
    kaufman = pr.jacobian(dA @ c[:, None])[0, :, :, 0]
    h = 1e-6
    fd = np.array([(residual(p + h * e) - residual(p - h * e)) / (2 * h) for e in np.eye(2)])
    np.testing.assert_allclose(exact, fd, atol=1e-7 * np.abs(fd).max())
    assert np.abs(kaufman - fd).max() > 1e-3 * np.abs(fd).max()


def test_covariance_is_the_inverse_normal_matrix():
    """For a full-rank real Jacobian the covariance is scale (J^T J)^-1, equilibrated or not; a
    direction the data do not constrain makes its parameters undetermined (infinite variance)."""
    rng = np.random.default_rng(7)
    J = rng.standard_normal((30, 4)) * np.array([1e-4, 1.0, 1e2, 3.0])
    expected = 2.5 * np.linalg.inv(J.T @ J)
    np.testing.assert_allclose(covariance(J.T @ J, 2.5), expected, rtol=1e-9)
    np.testing.assert_allclose(jacobian_covariance(J, 2.5), expected, rtol=1e-6)
    degenerate = np.column_stack([J[:, :3], J[:, 2]])
    assert np.isinf(jacobian_covariance(degenerate).diagonal()[2:]).all()
    assert np.isfinite(jacobian_covariance(degenerate).diagonal()[:2]).all()


def test_normal_matrix_against_the_explicit_real_jacobian():
    """The closed-form blocks of the full problem's normal matrix over (p, Re c, Im c), two
    right-hand sides sharing the columns, against J^T J of the Jacobian built column by column."""
    rng = np.random.default_rng(9)
    n_p, rows, m, q = 2, 25, 3, 2
    A, D = _complex(rng, rows, m), _complex(rng, n_p, rows, q)           # D_i = dA_i c per right-hand side
    columns = [-D[i] for i in range(n_p)]                               # d r / d p_i
    for j in range(q):
        for k in range(m):
            for unit in (1.0, 1j):                                      # d r / d (Re, Im) c_jk = -(1, i) a_k
                d = np.zeros((rows, q), complex)
                d[:, j] = -unit * A[:, k]
                columns.append(d)
    J = np.stack([np.concatenate([d.real.ravel(), d.imag.ravel()]) for d in columns], axis=1)
    np.testing.assert_allclose(normal_matrix(D[None], A[None])[0], J.T @ J, atol=1e-10 * np.abs(J.T @ J).max())


@pytest.mark.parametrize("parameter, values", [
    (Parameter("k1", "N/m", -1.0, 7.0, transform="log10"), [0.3, 26.0, 4.5e5]),
    (INTERNAL_LOSS, [5.0, 120.0, math.inf]),
    (Parameter("alpha", "deg", -0.8, 0.8, scale=-180.0 / math.pi), [-12.0, 0.0, 17.5]),
    (CONTACT_LOSS, [0.0, 0.02, 3.0]),
])
def test_parameter_transforms_round_trip(parameter, values):
    """value(internal(v)) == v for every transform; the spread of a small internal error is the
    delta method's standard error."""
    internal = parameter.internal(np.array(values))
    np.testing.assert_allclose(parameter.values(internal), values, rtol=1e-12)
    assert [parameter.value(float(x)) for x in internal] == pytest.approx(values, rel=1e-12)
    finite = np.isfinite(parameter.values(internal)) & (internal != 0)
    for x in internal[finite]:
        assert parameter.spread(np.array([x]), np.array([1e-6]))[0] == pytest.approx(parameter.stderr(x, 1e-6),
                                                                                     rel=1e-6)


def test_map_and_discrepancy_give_one_gap():
    """A noisy pixel fitted by ``pfmdyn map``: its gap equals that of the discrepancy's fit result
    holding the same residual (rebuilt from the fitted k1, Q and d_eff) with the noise estimated
    the same way; and both read about 1 on a residual that is noise."""
    f = np.linspace(2.5e5, 4.5e5, 96)
    model = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), f)
    clean = 3e-3 * model.shape_functions(np.array([300.0]), np.array([60.0]))[0]
    noise = 0.01 * np.abs(clean).max() * _complex(np.random.default_rng(11), f.size) / math.sqrt(2)
    y = clean + noise
    out = fit_block(model, y[None])
    prediction = (out["amplitude"][0] * np.exp(1j * out["phase"][0])
                  * model.shape_functions(out["k1"], out["quality_factor"])[0])
    sigma = noise_sigma(f, np.zeros(f.size), y)
    meta = SimpleNamespace(spring_constant=2.0, tip_height=10e-6, length=225e-6, free_resonance=75e3)
    result = FitResult(Model(meta), np.zeros(2), np.zeros((2, 2)), y - prediction, sigma, 6)
    assert result.gap == pytest.approx(float(out["gap"][0]), rel=1e-6)
    assert 0.8 < result.gap < 1.25 and out["explained"][0] == 1.0


def _reference_noise(f, v, y):
    """The module's estimate written out point by point: differences of orders 2-6 along sorted
    frequency at each bias, the straight line in bias at each frequency with three biases or more,
    the smallest refined estimate held within 0.7 of the second differences'."""
    from scipy.special import gammaincinv
    estimates = []
    for m in (2, 3, 4, 5, 6):
        d = np.concatenate([np.diff(y[v == b][np.argsort(f[v == b])], m) for b in np.unique(v)])
        estimates.append(math.sqrt(np.median(np.abs(d) ** 2) / (math.comb(2 * m, m) * math.log(2))))
    refined = min(estimates[1:])
    if len(np.unique(v)) >= 3:
        lines = []
        for x in np.unique(f):
            at = f == x
            design = np.stack([np.ones(at.sum()), v[at]], axis=1)
            residual = y[at] - design @ np.linalg.lstsq(design, y[at], rcond=None)[0]
            lines.append(np.sum(np.abs(residual) ** 2) / gammaincinv(at.sum() - 2, 0.5))
        refined = min(refined, math.sqrt(np.median(lines)))
    return min(estimates[0], max(refined, 0.7 * estimates[0]))


@pytest.mark.parametrize("n_bias", [1, 2, 5])
def test_noise_of_many_spectra_is_each_spectrum_s(n_bias):
    """:func:`noise_sigmas` (all spectra of a block at once) equals :func:`noise_sigma` of each
    spectrum and the estimate written out point by point, to 1e-12: resonances on a shuffled
    frequency grid, with and without biases, noise from none to dominant."""
    from pfmdyn.fitting.noise import noise_sigmas
    rng = np.random.default_rng(40 + n_bias)
    f = rng.permutation(np.linspace(2.9e5, 3.1e5, 96))
    bias = np.linspace(-4.0, 6.0, n_bias) if n_bias > 1 else None
    v = np.repeat(np.zeros(1) if bias is None else bias, f.size)
    f0, q = rng.uniform(2.95e5, 3.05e5, 12), np.exp(rng.uniform(np.log(5), np.log(500), 12))
    clean = f0[:, None, None]**2 / (f**2 - 1j * f * f0[:, None, None] / q[:, None, None] - f0[:, None, None]**2)
    clean = clean * (1.0 + 0.3 * (np.zeros(1) if bias is None else bias)[None, :, None])
    y = clean + np.r_[0.0, np.geomspace(1e-6, 10.0, 11)][:, None, None] * _complex(rng, 12, n_bias, f.size)
    sigmas = noise_sigmas(f, bias, y)
    for s, spectrum in zip(sigmas, y.reshape(12, -1)):
        assert s == pytest.approx(noise_sigma(np.tile(f, n_bias), v, spectrum), rel=1e-12)
        assert s == pytest.approx(max(_reference_noise(np.tile(f, n_bias), v, spectrum),
                                      1e-15 * np.linalg.norm(spectrum)), rel=1e-12)


@pytest.mark.parametrize("setpoints", [[0.1] * 3, [0.0, -0.3 + 3 * 0.1, 0.1 * 3 - 0.3]])
def test_noise_leaves_out_frequencies_at_one_setpoint(setpoints):
    """The line in bias at a frequency measured at one bias several times (equal biases whose mean
    misses them by an ulp, or one bias written as computed) has no slope: the estimate from the
    lines' residuals is that of the frequencies at three biases or more alone (the module's lines),
    to 1e-12, without a warning, whatever the rows' order."""
    from pfmdyn.fitting.noise import _bias_noise
    rng = np.random.default_rng(12)
    f = np.linspace(2.9e5, 3.1e5, 40)
    line_f, line_v = np.repeat(f, 5), np.tile(np.linspace(-4.0, 6.0, 5), f.size)
    one_f, one_v = np.repeat(f + 1e3, len(setpoints)), np.tile(setpoints, f.size)
    F, V = np.r_[line_f, one_f], np.r_[line_v, one_v]
    y = (1 + 0.3 * V) * 3e5**2 / (F**2 - 1j * F * 3e5 / 50 - 3e5**2) + 0.05 * _complex(rng, F.size)
    order = rng.permutation(F.size)
    with np.errstate(all="raise"):
        mixed = _bias_noise(F[order], V[order], y[order][None])
    alone = _bias_noise(line_f, line_v, y[None, :line_f.size])
    assert mixed[0] == pytest.approx(alone[0], rel=1e-12)
