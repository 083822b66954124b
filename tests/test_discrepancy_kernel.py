"""The compiled evaluation of a discrepancy fit (:func:`pfmdyn.discrepancy.fit_kernel.evaluate`) against
its NumPy reference (:class:`pfmdyn.discrepancy.model._Problem` with ``COMPILED`` off).

A finite-element spectrum (:func:`fe_beam.acquisition_case`: three bands, four biases, viscous damping),
models with each kind of design column (the baseline's, the contact dashpot's ``T_f``, the background's
ramp) and effects that move the resonances or the reading, at springs k1/k 3-1e3 and other parameters
drawn within their bounds (fixed seed), on the fit's rows (folded per frequency, two per frequency here;
``tests/test_discrepancy_rows.py`` holds them to the measured rows).  The design is the same arithmetic:
equal to the bit.  The
projection sums in another order (loops, not BLAS), and near-dependent columns (the Gram matrix's
condition reaches 1e5 at these points) multiply the rounding: residual and Jacobian agree within 1e-12
of their largest entry or ten times what the NumPy path itself moves when the rows come in another
order, whichever is larger (1e-11 at worst here; agreeing to 1e-12 where the condition is below 1e3).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import acquisition_case  # noqa: E402

from pfmdyn.discrepancy import model as model_module  # noqa: E402
from pfmdyn.discrepancy.model import Model, bounds  # noqa: E402
from pfmdyn.fitting.noise import noise_sigma  # noqa: E402
from pfmdyn.fitting.projection import bias_nodes  # noqa: E402
from pfmdyn.io.tables import read  # noqa: E402

MODELS = [(), ("damping_viscous",), ("damping_internal", "tip_setback", "spot_position"),
          ("tilt", "tip_mass", "damping_fluid"), ("damping_contact",), ("damping_viscous", "background")]


@pytest.fixture(scope="module")
def spectrum(tmp_path_factory):
    text, _ = acquisition_case(2, "band_viscous")
    path = tmp_path_factory.mktemp("kernel") / "s.csv"
    path.write_text(text)
    data = read(path)
    return data, noise_sigma(data.frequency_hz, data.bias_v, data.response)


def _evaluated(compiled, model, data, sigma, x, monkeypatch, order=None):
    """Residual, Jacobian and design of ``model`` at ``x`` on the fit's rows (folded per frequency,
    :func:`pfmdyn.fitting.projection.bias_nodes`); with ``order``, of those rows taken in that order,
    returned in the original one."""
    monkeypatch.setattr(model_module, "COMPILED", compiled)
    problem = model_module._Problem(model, data, sigma)
    if order is not None:
        for name in ("inverse", "bias", "weight", "y"):
            setattr(problem, name, getattr(problem, name)[order])
    r, J, A = problem.residual(x), problem.jacobian(x), problem._at(x)[0].copy()
    if order is None:
        return r, J, A
    back = np.argsort(order)
    both = np.concatenate([back, back + len(back), np.arange(2 * len(back), len(r))])   # then the folded misfit
    return r[both], J[both], A[back]


@pytest.mark.parametrize("effects", MODELS)
def test_compiled_evaluation_agrees_with_numpy(spectrum, effects, monkeypatch):
    data, sigma = spectrum
    model = Model(data.metadata, effects)
    lower, upper = bounds(model)
    rng = np.random.default_rng(len(effects))
    k = np.log10(data.metadata.spring_constant)
    order = rng.permutation(len(bias_nodes(data.frequency_hz, data.bias_v, data.response).response))
    for _ in range(3):
        x = rng.uniform(np.maximum(lower, -3.0), np.minimum(upper, 3.0))
        x[:2] = k + rng.uniform(0.5, 3.0), k + rng.uniform(1.0, 4.0)
        r, J, A = _evaluated(True, model, data, sigma, x, monkeypatch)
        r_ref, J_ref, A_ref = _evaluated(False, model, data, sigma, x, monkeypatch)
        r_moved, J_moved, _ = _evaluated(False, model, data, sigma, x, monkeypatch, order)
        assert np.array_equal(A, A_ref)
        for got, want, moved in ((r, r_ref, r_moved), (J, J_ref, J_moved)):
            size = np.max(np.abs(want))
            assert size > 0
            assert np.max(np.abs(got - want)) <= max(1e-12 * size, 10 * np.max(np.abs(moved - want)))
