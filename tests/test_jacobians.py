"""Jacobians of the transfer functions (the generated elastic contact, the composed lever) against central
finite differences.

Random points over realistic ranges (k 0.05-50 N/m, L 100-500 um, H 3-20 um, k1/k 1-1e4,
k2/k1 0-1.5, tip mass 0-1, tip at 0.6-1 L, spot at 0.3-1 L; ``beta`` from below the first mode
(the composed lever from the quasi-static 1e-3) to about the hundredth, with the phase of a
damped ``beta``), fixed seed.  Each partial is compared with ``(f(p + h) - f(p - h)) / 2h`` of
the function itself (``pfmdyn.composed``: its :func:`slope_and_jacobian` against differences of
its :func:`slope`, read at the free end and at a spot); the discrepancy model's chain rule
(damping, rotation, free root) likewise with differences of its slopes.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pfmdyn import composed
from pfmdyn.generated import elastic_contact

N = 200

# The composed lever behind the generated families' interface (arguments by name).
AT_END = SimpleNamespace(
    __name__="composed.at_end", PARAMETERS=composed.PARAMETERS, JACOBIAN_PARAMETERS=composed.JACOBIAN_PARAMETERS,
    slope=lambda beta, **p: composed.at_end.slope(beta, composed.Parameters(**p)),
    slope_and_jacobian=lambda beta, **p: composed.at_end.slope_and_jacobian(beta, composed.Parameters(**p)))
AT_SPOT = SimpleNamespace(
    __name__="composed.slope", PARAMETERS=("sigma",) + composed.PARAMETERS,
    JACOBIAN_PARAMETERS=composed.SPOT_JACOBIAN_PARAMETERS,
    slope=lambda beta, sigma, **p: composed.slope(beta, composed.Parameters(**p), sigma),
    slope_and_jacobian=lambda beta, sigma, **p: composed.slope_and_jacobian(beta, composed.Parameters(**p), sigma))
COMPOSED = (AT_END, AT_SPOT)


def _points(module, seed):
    """Arguments by name at N random points (realistic ranges, see module docstring)."""
    rng = np.random.default_rng(seed)
    k = 10 ** rng.uniform(np.log10(0.05), np.log10(50), N)
    k1 = k * 10 ** rng.uniform(0, 4, N)
    k2 = k1 * rng.uniform(0, 1.5, N)
    alpha = rng.uniform(-0.5, 0.5, N)
    # Down to 0.05 where the series branch applies; the composed lever from the quasi-static 1e-3.
    low = 1e-3 if module in COMPOSED else 0.05
    beta = 10 ** rng.uniform(np.log10(low), np.log10(300), N) * np.exp(-1j * rng.uniform(0, 0.03, N))
    args = {"beta": beta, "k": k, "k1": k1, "k2": k2, "H": rng.uniform(3e-6, 20e-6, N),
            "L": rng.uniform(100e-6, 500e-6, N), "mu": rng.uniform(0, 1, N), "gamma": rng.uniform(0.6, 1, N),
            "rho_g": rng.uniform(0, 0.02, N),   # r_g about H/4 over L
            "sigma": rng.uniform(0.3, 0.999, N),
            "kvv": k1 * np.cos(alpha) ** 2 + k2 * np.sin(alpha) ** 2,
            "kll": k1 * np.sin(alpha) ** 2 + k2 * np.cos(alpha) ** 2,
            "kvl": (k1 - k2) * np.sin(alpha) * np.cos(alpha)}
    # The spot's slope has a kink in sigma and gamma where they meet (the moment jumps there).
    near = np.abs(args["sigma"] - args["gamma"]) < 1e-3
    args["sigma"][near] = np.minimum(args["gamma"][near] + 2e-3, 0.999)
    args["sigma"][near & (args["gamma"] > 0.99)] = 0.9
    return {name: args[name] for name in ("beta",) + module.PARAMETERS}


@pytest.mark.parametrize("module", [elastic_contact, AT_END, AT_SPOT], ids=lambda m: m.__name__)
def test_jacobian_matches_central_differences(module):
    args = _points(module, 11)
    values, jac = module.slope_and_jacobian(**args)
    reference = module.slope(**args)
    for v, r in zip(values, reference):
        # Same expressions, other CSE (composed: the same solve): equal to rounding.
        np.testing.assert_allclose(v, r, rtol=2e-9, atol=0)
    # Relative accuracy of the values themselves (composed: ~1e-13, tests/test_composed.py).
    accuracy = 1e-12
    for j, name in enumerate(module.JACOBIAN_PARAMETERS):
        p = args[name]
        # Steps relative to the parameter's scale (springs: k, so a zero k2 or kvl still moves).
        scale = np.abs(p) if name in ("beta", "k", "k1", "kvv") else (
            args["k"] if name in ("k2", "kll", "kvl") else np.ones(N))
        h = 1e-6 * scale
        # Fourth-order differences: truncation ~ (h / distance to the nearest pole)**4, small
        # also where a lightly damped resonance sits next to a sample point.
        up, down = (module.slope(**{**args, name: p + s * h}) for s in (1, -1))
        up2, down2 = (module.slope(**{**args, name: p + s * h}) for s in (2, -2))
        for i, (d, u, w, u2, w2, v) in enumerate(zip((t[j] for t in jac), up, down, up2, down2, values)):
            fd = (8 * (u - w) - (u2 - w2)) / (12 * h)
            # Tolerance: FD truncation near sharp resonances, plus the FD noise floor ~ err(T) / h.
            tol = 1e-5 * np.abs(d) + 10 * accuracy * np.abs(v) / h
            bad = np.abs(d - fd) > tol
            assert not bad.any(), (name, i, args["beta"][bad][:3], d[bad][:3], fd[bad][:3])


def test_characteristic_jacobian_moves_resonances():
    """-D_p / D_beta at a root is the root's motion: compare with re-solved roots."""
    from pfmdyn.roots.bracket import refine
    args = {"k": 2.0, "kvv": 150.0, "kll": 40.0, "kvl": 3.0, "H": 1e-5, "L": 2.2e-4, "mu": 0.2, "gamma": 0.9, "rho_g": 0.02}
    F = lambda b, **kw: composed.characteristic(b, composed.Parameters(**{**args, **kw}))  # noqa: E731
    grid = np.linspace(0.5, 12, 2000)
    vals = F(grid)
    i = int(np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[1])
    root = float(refine(F, grid[i], grid[i + 1], rtol=1e-14))
    _, d = composed.characteristic_and_jacobian(root, composed.Parameters(**args))
    names = composed.JACOBIAN_PARAMETERS
    for j, name in enumerate(names[1:], 1):
        h = 1e-6 * max(abs(args[name]), 1.0)
        moved = [float(refine(lambda b, kw={name: args[name] + s}: F(b, **kw), grid[i] - 0.05, grid[i + 1] + 0.05,
                              rtol=1e-14)) for s in (h, -h)]
        np.testing.assert_allclose(-d[j] / d[0], (moved[0] - moved[1]) / (2 * h), rtol=1e-5, atol=1e-9)


@pytest.mark.parametrize("effects", [("damping_internal", "tip_mass"), ("damping_viscous", "tip_setback", "tilt"),
                                     ("damping_contact", "tip_mass", "tip_setback", "background"),
                                     ("damping_viscous", "tip_setback", "tilt", "spot_position"),
                                     ("damping_fluid", "tip_mass", "tip_setback")])
def test_model_jacobian_matches_central_differences(effects):
    """The discrepancy model's chain rule (damping, rotation, free root, spot) against differences."""
    from types import SimpleNamespace

    from pfmdyn.discrepancy.model import Model
    rng = np.random.default_rng(5)
    meta = SimpleNamespace(spring_constant=2.4, tip_height=1e-5, length=2.23e-4, free_resonance=63.2e3)
    model = Model(meta, effects)
    lower, upper = (np.array([getattr(p, b) for p in model.parameters]) for b in ("lower", "upper"))
    x = lower + (upper - lower) * rng.uniform(0.2, 0.8, len(lower))
    freq = np.linspace(150e3, 1300e3, 300)
    T, dT = model.slopes_and_jacobian(freq, x)
    np.testing.assert_allclose(T, np.array(model.slopes(freq, x)), rtol=1e-9)
    def central(j, h):
        up, down = x.copy(), x.copy()
        up[j] += h
        down[j] -= h
        return (np.array(model.slopes(freq, up)) - np.array(model.slopes(freq, down))) / (2 * h)

    for j in range(len(x)):
        h = 1e-6 * max(1.0, abs(x[j]))
        # Richardson extrapolation: the sharp resonances make plain central differences' h**2 term visible.
        fd = (4 * central(j, h / 2) - central(j, h)) / 3
        scale = np.abs(T).max(axis=1, keepdims=True)
        bad = np.abs(dT[:, j] - fd) > 1e-5 * np.abs(fd) + 1e-7 * scale
        assert not bad.any(), (model.parameters[j].name, dT[:, j][bad][:3], fd[bad][:3], freq[bad.any(axis=0)][:3])


def test_design_derivative_times_coefficients():
    """``(dA/dx_j) c`` of the design matrix (rows = frequency x bias, background, dashpot column)."""
    from types import SimpleNamespace

    from pfmdyn.discrepancy.model import Model
    rng = np.random.default_rng(8)
    model = Model(SimpleNamespace(spring_constant=0.3, tip_height=4e-6, length=4.5e-4, free_resonance=2.1e3),
                  ("damping_contact", "tilt", "background"))
    lower, upper = (np.array([getattr(p, b) for p in model.parameters]) for b in ("lower", "upper"))
    x = lower + (upper - lower) * rng.uniform(0.3, 0.7, len(lower))
    freq_u = np.linspace(5e3, 60e3, 200)
    inverse = np.repeat(np.arange(200), 3)
    bias = np.tile([-2.0, 0.5, 3.0], 200)
    coef = rng.normal(size=model.n_linear) + 1j * rng.normal(size=model.n_linear)
    A, dT = model.design_and_partials(freq_u, inverse, bias, x)
    v = model.design_derivative_times(inverse, bias, dT, coef)
    for j in range(len(x)):
        h = 1e-6 * max(1.0, abs(x[j]))
        up, down = x.copy(), x.copy()
        up[j] += h
        down[j] -= h
        fd = (model.design(freq_u, inverse, bias, up) - model.design(freq_u, inverse, bias, down)) @ coef / (2 * h)
        np.testing.assert_allclose(v[:, j], fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())
    assert np.array_equal(A, model.design(freq_u, inverse, bias, x))      # the values of the same read-out


@pytest.mark.parametrize("contact", [False, True])
def test_resonance_sensitivity_matches_differences(contact):
    """d f_n / d (internal parameters) of the discrepancy model's resonances, free and in contact, with a
    tip mass and a set-back (the free root moves with both), against central differences of the roots."""
    from types import SimpleNamespace

    from pfmdyn.discrepancy.model import Model
    from pfmdyn.discrepancy.undamped_modes import resonance_sensitivity, resonances
    meta = SimpleNamespace(spring_constant=2.4, tip_height=1e-5, length=2.23e-4, free_resonance=54.55e3)
    model = Model(meta, ("tip_mass", "tip_setback"))
    x = np.array([2.0, 1.0, 0.05, 0.9])
    f = resonances(model, x, contact, 1.2e6)
    got = resonance_sensitivity(model, x, contact, f)
    for j in range(len(x)):
        h = 1e-6
        up, down = x.copy(), x.copy()
        up[j] += h
        down[j] -= h
        fd = (resonances(model, up, contact, 1.2e6) - resonances(model, down, contact, 1.2e6)) / (2 * h)
        np.testing.assert_allclose(got[:, j], fd, rtol=1e-4, atol=1e-3 * f.max() * 1e-3)
