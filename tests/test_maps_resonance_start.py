"""The beam map's short road (:mod:`pfmdyn.maps.resonance_start`: an SHO per band, the springs
from the contact resonances, then the Levenberg-Marquardt) against the fit started from the grid,
on levers drawn over the everyday ranges (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4, Q 5-500),
spectra from the independent finite-element beam (tests/fe_beam.py) with 1 % noise."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn import Cantilever, Contact  # noqa: E402
from pfmdyn.maps import fit  # noqa: E402
from pfmdyn.maps.beam import BeamMapModel  # noqa: E402


def _lever_map(rng, two):
    """A drawn lever's model and four pixels around a drawn k1 (k2 = 0.8 k1 with two bands, else 0)."""
    k, length, height = 10 ** rng.uniform(np.log10(0.05), np.log10(50)), rng.uniform(100e-6, 500e-6), \
        rng.uniform(5e-6, 20e-6)
    f1 = 300e3 * (k / 40) ** (1 / 3) * (125e-6 / length)
    q = 10 ** rng.uniform(np.log10(5), np.log10(500))
    k1 = 10 ** rng.uniform(0, 4) * k * rng.uniform(0.8, 1.25, 4)
    ratio = 0.8 if two else 0.0
    beams = [FEBeam(k, length, f1, height, k1=v, k2=ratio * v, Q=q, n_elements=40) for v in k1]
    modes = np.array([b.contact_resonances(2) for b in beams])
    f = np.concatenate([np.linspace(0.85 * modes[:, m].min(), 1.15 * modes[:, m].max(), 64) for m in range(1 + two)])
    y = np.stack([2e-3 * b.slope(f)[:, 0] for b in beams])
    y = y + 0.01 * np.abs(y).max() * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
    free = float(FEBeam(k, length, f1, height, n_elements=40).free_resonances(1)[0])
    return BeamMapModel(Cantilever(k, free, length, tip_height=height), f, contact=Contact() if two else Contact(k2=0.0)), y


@pytest.mark.parametrize("two", [False, True], ids=["one band", "two bands"])
def test_short_road_finds_the_grid_fit(two, monkeypatch):
    """The short road never ends above the grid's cost, and where both end at one minimum (costs
    within 1e-4, >= 90 % of the pixels; elsewhere the grid's start fell into a worse one) k1 (and k2
    with two bands) agree within 2 %.  The short road starts (nearly) every pixel itself: no pixel
    is refitted from the grid for being unexplained (``gap_threshold`` and ``OUTLIER_GAP`` infinite)."""
    rng = np.random.default_rng(3801 + two)
    monkeypatch.setattr(fit, "OUTLIER_GAP", np.inf)
    started, same = [], []
    short_road = fit.resonance_start

    def counted(*args, **kwargs):
        p, ok = short_road(*args, **kwargs)
        started.append(ok)
        return p, ok

    def nowhere(model, y, **kwargs):
        return np.full((len(y), len(model.names)), np.nan), np.zeros(len(y), bool)

    for _ in range(4 if two else 6):
        model, y = _lever_map(rng, two)
        monkeypatch.setattr(fit, "resonance_start", counted)
        short = fit.fit_block(model, y, gap_threshold=np.inf)
        monkeypatch.setattr(fit, "resonance_start", nowhere)
        grid = fit.fit_block(model, y, gap_threshold=np.inf)
        np.testing.assert_array_less(short["cost"], grid["cost"] * (1 + 1e-4))
        one_minimum = short["cost"] > grid["cost"] * (1 - 1e-4)
        for name in ("k1", "k2") if two else ("k1",):
            np.testing.assert_array_less(np.abs(short[name] / grid[name] - 1)[one_minimum], 0.02, err_msg=name)
        same.append(one_minimum)
    assert np.mean(np.concatenate(started)) >= 0.75 and np.mean(np.concatenate(same)) >= 0.9


def test_internal_friction_factors_once_per_pixel():
    """With internal friction alone the damping factors are evaluated at one frequency per pixel
    (they do not depend on it): the transfer functions and partials equal those of the model with
    viscous drag (evaluated at every frequency) at zero drag."""
    f = np.concatenate([np.linspace(2.5e5, 3.5e5, 40), np.linspace(8e5, 9e5, 40)])
    rng = np.random.default_rng(5)
    for contact in (Contact(), Contact(k2=0.0), Contact(k2_over_k1=0.5)):
        internal = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), f, contact=contact)
        viscous = BeamMapModel(internal.lever, f, mechanisms=("internal", "viscous"), contact=contact)
        p = np.column_stack([rng.uniform(1, 3, 6), rng.uniform(1, 3, 6)] + [rng.uniform(1, 3, 6)] * (len(internal.names) - 2))
        g, d = internal.design(p)
        g_v, d_v = viscous.design(np.column_stack([p, np.zeros(6)]))
        np.testing.assert_allclose(g, g_v, rtol=1e-10, atol=1e-10 * np.abs(g).max())
        np.testing.assert_allclose(d, d_v[:len(internal.names)], rtol=1e-10, atol=1e-10 * np.abs(d).max())


def test_a_misread_resonance_is_fitted_again_from_the_grid(monkeypatch):
    """Two bands whose second holds a weak mode beside an antiresonance (k1 = 174 N/m, k2 = 0.5
    k1): the SHO's linearised guess alone (no SHO fit) misreads it, and the short road ends in a
    minimum that almost explains the data (gap 1.6-1.9 where the map's is 0.93, k1 off by > 2 %).
    Those pixels are fitted again from the grid (:data:`pfmdyn.maps.fit.OUTLIER_GAP`): every k1
    within 2 %."""
    from pfmdyn.maps import resonance_start
    k, length, f1, height = 2.0, 225e-6, 75e3, 10e-6
    rng = np.random.default_rng(7)
    values = np.array([100.0, 174.11011266, 303.1433133, 527.80316431])
    index = np.repeat(np.arange(4), 16)
    beams = [FEBeam(k, length, f1, height, k1=v, k2=0.5 * v, Q=80.0, n_elements=40) for v in values]
    modes = np.array([b.contact_resonances(2) for b in beams])
    f = np.concatenate([np.linspace(0.9 * modes[:, m].min(), 1.1 * modes[:, m].max(), 64) for m in (0, 1)])
    y = np.stack([2e-3 * np.exp(0.3j) * b.slope(f)[:, 0] for b in beams])[index]
    y = y + 0.01 * np.abs(y).max(axis=1, keepdims=True) * (rng.standard_normal(y.shape)
                                                           + 1j * rng.standard_normal(y.shape)) / np.sqrt(2)
    free = float(FEBeam(k, length, f1, height, n_elements=40).free_resonances(1)[0])
    model = BeamMapModel(Cantilever(k, free, length, tip_height=height), f)
    sho_fit = resonance_start.fit_spectra
    monkeypatch.setattr(resonance_start, "fit_spectra", lambda f, y, **kwargs: sho_fit(f, y, iterations=0))
    error = {}
    for outlier in (np.inf, fit.OUTLIER_GAP):
        monkeypatch.setattr(fit, "OUTLIER_GAP", outlier)
        error[outlier] = np.abs(fit.fit_block(model, y)["k1"] / values[index] - 1)
    assert np.sum(error[np.inf] > 0.02) >= 3 and np.all(error[fit.OUTLIER_GAP] < 0.02)
