"""A discrepancy fit on a spectrum's rows folded per frequency (:func:`pfmdyn.fitting.projection.bias_nodes`)
against the same fit on the measured rows (the fit's own code with the rows left as they are).

A finite-element spectrum (:func:`fe_beam.acquisition_case`, ``tests/test_discrepancy_kernel.py``'s: four
biases per frequency, viscous damping)
thinned and padded at random (fixed seed): frequencies with one to five rows, one with a single bias, one
whose rows all share a bias, some with a bias repeated beside others.  Folding changes only where the
sums are rounded: the cost of every evaluation agrees within 1e-12, ``J^T J`` and ``J^T r`` within 1e-10 of
their size (3e-12 at worst here: the compiled projection sums in loops, and the Gram matrix's condition,
1e5 at these points, multiplies the rounding), compiled and NumPy; a fit's parameters within 1e-9, its
misfit within 1e-10, residual and prediction within 1e-9 of their size and covariance within 1e-6
(3e-8 here: it inverts ``J^T J``, whose condition multiplies the rounding).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_discrepancy_kernel import spectrum as measured  # noqa: E402,F401  (the FE spectrum, a fixture)

from pfmdyn.discrepancy import fit_kernel  # noqa: E402
from pfmdyn.discrepancy import model as model_module  # noqa: E402
from pfmdyn.discrepancy import spectrum as spectrum_module  # noqa: E402
from pfmdyn.discrepancy.model import Model, bounds, fit  # noqa: E402
from pfmdyn.fitting.noise import noise_sigma  # noqa: E402
from pfmdyn.fitting.projection import BiasNodes, bias_nodes  # noqa: E402
from pfmdyn.io.tables import SpectrumData  # noqa: E402

MODELS = [("damping_viscous",), ("damping_contact", "background"), ("damping_internal", "tip_setback", "spot_position")]


def _as_measured(frequency_hz, bias_v, response) -> BiasNodes:
    """The rows as they are: what :func:`bias_nodes` leaves when it folds nothing."""
    freq_u, inverse = np.unique(frequency_hz, return_inverse=True)
    return BiasNodes(freq_u, inverse, np.asarray(bias_v, float), np.ones(len(bias_v)), np.asarray(response), 0.0,
                     False)


@pytest.fixture(scope="module")
def spectrum(measured):
    data = measured[0]
    rng = np.random.default_rng(38)
    f, v, y = data.frequency_hz, data.bias_v, data.response
    freq_u, inverse = np.unique(f, return_inverse=True)
    keep = rng.random(len(f)) < 0.7
    keep[np.unique(inverse, return_index=True)[1]] = True          # every frequency keeps a row
    keep[inverse == 5] = False
    keep[np.flatnonzero(inverse == 5)[0]] = True                    # a single bias
    same = np.flatnonzero(inverse == 9)
    keep[same[1:]] = False                                          # one bias, three times (below)
    extra = np.concatenate([np.repeat(same[:1], 2), rng.choice(len(f), 40, replace=False)])
    noise = noise_sigma(f, v, y) * (rng.standard_normal(len(extra)) + 1j * rng.standard_normal(len(extra))) / 2**0.5
    f, v, y = (np.concatenate([a[keep], a[extra]]) for a in (f, v, y))
    y[keep.sum():] += noise                                         # a bias repeated: another draw of the noise
    order = rng.permutation(len(f))
    data = SpectrumData(data.metadata, f[order], v[order], y[order])
    nodes = bias_nodes(data.frequency_hz, data.bias_v, data.response)
    count = np.bincount(nodes.inverse)
    assert nodes.folded and {1, 2} == set(count) and len(nodes.response) < 0.8 * len(f)
    assert np.bincount(np.unique(data.frequency_hz, return_inverse=True)[1]).max() >= 5
    return data, noise_sigma(data.frequency_hz, data.bias_v, data.response)


def _start(model, data, rng):
    lower, upper = bounds(model)
    x = rng.uniform(np.maximum(lower, -3.0), np.minimum(upper, 3.0))
    k = np.log10(data.metadata.spring_constant)
    x[:2] = k + rng.uniform(0.5, 2.0), k + rng.uniform(1.0, 3.0)
    return np.clip(x, lower, upper)


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("effects", MODELS)
def test_folded_rows_give_the_measured_rows_cost_and_products(spectrum, effects, compiled, monkeypatch):
    data, sigma = spectrum
    monkeypatch.setattr(model_module, "COMPILED", compiled)
    model = Model(data.metadata, effects)
    folded = model_module._Problem(model, data, sigma)
    monkeypatch.setattr(model_module, "bias_nodes", _as_measured)
    measured = model_module._Problem(model, data, sigma)
    assert len(folded.y) < 0.7 * len(measured.y)
    rng = np.random.default_rng(len(effects))
    for _ in range(3):
        x = _start(model, data, rng)
        r, J = folded.residual(x), folded.jacobian(x)
        r_ref, J_ref = measured.residual(x), measured.jacobian(x)
        assert np.isclose(r @ r, r_ref @ r_ref, rtol=1e-12, atol=0)
        for got, want in ((J.T @ J, J_ref.T @ J_ref), (J.T @ r, J_ref.T @ r_ref)):
            assert np.max(np.abs(got - want)) <= 1e-10 * np.max(np.abs(want))


@pytest.mark.parametrize("effects", MODELS[:2])
def test_a_fit_on_folded_rows_is_the_fit_on_the_measured_rows(spectrum, effects, monkeypatch):
    data, sigma = spectrum
    model = Model(data.metadata, effects)
    starts = [_start(model, data, np.random.default_rng(7))]
    got = fit(model, data, starts, sigma, max_nfev=30)
    monkeypatch.setattr(model_module, "bias_nodes", _as_measured)
    want = fit(model, data, starts, sigma, max_nfev=30)
    assert np.max(np.abs(got.internal - want.internal)) < 1e-9
    assert np.isclose(got.chi2, want.chi2, rtol=1e-10, atol=0)
    assert np.allclose(got.covariance, want.covariance, rtol=1e-6, atol=0)
    for a, b in ((got.residual, want.residual), (got.prediction, want.prediction)):
        assert a.shape == b.shape and np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b))


def test_start_grid_cost_is_the_measured_rows(spectrum, monkeypatch):
    data, _ = spectrum
    problem = spectrum_module.SpectrumProblem(data)
    model = Model(data.metadata, ("damping_viscous", "background"))
    rng = np.random.default_rng(3)
    xs = [_start(model, data, rng) for _ in range(3)]
    got = [problem.cost(model, x) for x in xs]
    problem._nodes, problem._costs = _as_measured(data.frequency_hz, data.bias_v, data.response), {}
    assert np.allclose(got, [problem.cost(model, x) for x in xs], rtol=1e-12, atol=0)


def test_a_frequency_the_model_cannot_read_counts_as_its_rows():
    """Slopes not finite at a frequency: its folded rows (weight ``w``) count as the ``w**2`` measured rows
    would (1e6 each, real and imaginary), the rest as they are."""
    rng = np.random.default_rng(5)
    f = np.repeat(np.arange(6.0), 4)[2:]
    v = rng.uniform(-3.0, 3.0, len(f))
    y = rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))
    T = rng.standard_normal((4, 6)) + 1j * rng.standard_normal((4, 6))
    T[2, 4] = np.nan
    source, per_volt = np.array([0, 2, 3, -1]), np.array([False, True, False, True])

    def cost(nodes):
        rows, m = len(nodes.response), len(source)
        A, As, G = np.empty((rows, m), complex), np.empty((rows, m), complex), np.empty((m, m), complex)
        scale, Ay, c, r = np.empty(m), np.empty(m, complex), np.empty(m, complex), np.empty(2 * rows)
        ramp = nodes.frequency_hz[nodes.inverse] / nodes.frequency_hz.max()
        fit_kernel.design_and_gram(T, nodes.inverse, nodes.bias_v, nodes.weight, ramp, source, per_volt,
                                   nodes.response, A, As, scale, G, Ay)
        fit_kernel.residual_and_jacobian(np.zeros((4, 0, 6), complex), nodes.inverse, nodes.bias_v, nodes.weight,
                                         source, per_volt, nodes.response, 1.0, A, As, scale, Ay,
                                         *np.linalg.eigh(G), 1e-13, False, c, r, np.empty((2 * rows, 0)))
        return r @ r + nodes.constant

    full = cost(_as_measured(f, v, y))
    assert full > 8e12                                              # four rows at 1e6, real and imaginary
    assert np.isclose(cost(bias_nodes(f, v, y)), full, rtol=1e-12, atol=0)
