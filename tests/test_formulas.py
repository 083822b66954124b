"""Generated closed-form relations against hand-typed ones, and no re-definitions under pfmdyn/.

Each generated relation is checked at random points over real ranges against a version typed
here, and, where one exists, against an independent route (the finite-element beam of
``tests/fe_beam.py``, mpmath roots, NumPy polynomial roots); the checks through public
functions exercise the places that call it.
"""
from __future__ import annotations

import ast
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import mpmath as mp
import numpy as np
import pytest
from scipy.optimize import brentq

# The independent FE beam lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam  # noqa: E402
from pfmdyn.generated import characteristic, formulas  # noqa: E402

PACKAGE = Path(__file__).resolve().parent.parent / "pfmdyn"
GENERATED = PACKAGE.parent / "generated"
RNG = np.random.default_rng(2006)


def test_geometry_formulas_match_hand_typed_ones():
    E, w, t, L, rho = 169e9, 35e-6, RNG.uniform(1e-6, 8e-6, 20), RNG.uniform(100e-6, 500e-6, 20), 2330.0
    inertia = w * t**3 / 12
    np.testing.assert_allclose(formulas.spring_constant_from_geometry(E, w, t, L),
                               3 * E * inertia / L**3, rtol=1e-14)
    np.testing.assert_allclose(
        formulas.free_resonance_from_geometry(E, w, t, L, rho, characteristic.BETA1_FREE),
        characteristic.BETA1_FREE**2 / (2 * math.pi * L**2) * np.sqrt(E * inertia / (rho * w * t)),
        rtol=1e-14)
    k = formulas.spring_constant_from_geometry(E, w, t, L)
    np.testing.assert_allclose(formulas.youngs_modulus_from_spring_constant(k, w, t, L), E, rtol=1e-14)
    np.testing.assert_allclose(formulas.height_per_slope(L), 2 * L / 3, rtol=1e-15)


def test_contact_formulas_match_hand_typed_ones():
    k1, r, p = RNG.uniform(1, 1e4, 20), RNG.uniform(5e-9, 100e-9, 20), RNG.uniform(1e-9, 1e-6, 20)
    np.testing.assert_allclose(formulas.reduced_modulus(k1, r, p), np.sqrt(k1**3 / (6 * r * p)), rtol=1e-14)
    nu = np.linspace(0, 0.5, 11)
    np.testing.assert_allclose(formulas.mindlin_k2_over_k1(nu), 2 * (1 - nu) / (2 - nu), rtol=1e-15)


def test_nulling_bias_matches_hand_typed_one():
    b = RNG.normal(size=20) + 1j * RNG.normal(size=20)
    c = RNG.normal(size=20) + 1j * RNG.normal(size=20)
    np.testing.assert_allclose(formulas.nulling_bias(b.real, b.imag, c.real, c.imag),
                               -np.real(b * np.conj(c)) / np.abs(c) ** 2, rtol=1e-13)
    v = RNG.normal(size=20)
    assert np.allclose(formulas.nulling_bias((-c * v).real, (-c * v).imag, c.real, c.imag), v)


def test_capacitive_load_matches_hand_typed_one():
    w, H = RNG.uniform(20e-6, 50e-6, 10), RNG.uniform(5e-6, 20e-6, 10)
    np.testing.assert_allclose(formulas.capacitive_load_per_volt2(8.8541878128e-12, w, H),
                               8.8541878128e-12 * w / H**2, rtol=1e-15)


def _free_roots(count):
    """The first roots of 1 + cos(b) cosh(b) (the free cantilever), by mpmath."""
    guesses = [(2 * n - 1) * math.pi / 2 for n in range(1, count + 1)]
    return np.array([float(mp.findroot(lambda b: 1 + mp.cos(b) * mp.cosh(b), g)) for g in guesses])


def _levers(seed, count):
    """(k N/m, L m, f1 Hz, H m) over the real ranges."""
    rng = np.random.default_rng(seed)
    return zip(10 ** rng.uniform(math.log10(0.05), math.log10(50), count), rng.uniform(100e-6, 500e-6, count),
               10 ** rng.uniform(4, 6, count), rng.uniform(5e-6, 20e-6, count))


def test_beta_and_frequency_scale_as_the_modes_of_a_finite_element_beam():
    """f_n / f_1 = (beta_n / beta_1)**2: the free modes of an independent FE beam, by every caller."""
    from pfmdyn import Cantilever
    from pfmdyn.analysis.stiffness import z_from_frequency
    from pfmdyn.roots.branches import frequency_ratio

    roots = _free_roots(4)
    for k, L, f1, H in _levers(7, 4):
        f = FEBeam(k, L, f1, H, n_elements=120).free_resonances(4)
        np.testing.assert_allclose(formulas.beta_from_frequency(f, f[0], roots[0]), roots, rtol=1e-6)
        np.testing.assert_allclose(formulas.frequency_from_beta(roots, f[0], roots[0]), f, rtol=1e-6)
        np.testing.assert_allclose(z_from_frequency(f, f[0]), roots, rtol=1e-6)
        np.testing.assert_allclose(Cantilever(k, f[0], L).beta(f).real, roots, rtol=1e-6)
        np.testing.assert_allclose(frequency_ratio("indentation", roots, roots[0]), f / f[0], rtol=1e-6)
    f, f1, b1 = 10 ** RNG.uniform(3, 7, 50), 10 ** RNG.uniform(4, 6, 50), RNG.uniform(1.2, 1.9, 50)
    np.testing.assert_allclose(formulas.beta_from_frequency(f, f1, b1), b1 * np.sqrt(f / f1), rtol=1e-14)
    np.testing.assert_allclose(formulas.frequency_from_beta(formulas.beta_from_frequency(f, f1, b1), f1, b1), f,
                               rtol=1e-13)
    # The first-order change against a central difference of frequency_from_beta.
    beta, d_beta, d_b1, h = RNG.uniform(1, 30, 50), RNG.normal(size=50), RNG.normal(size=50), 1e-6
    f = formulas.frequency_from_beta(beta, f1, b1)
    step = (formulas.frequency_from_beta(beta + h * d_beta, f1, b1 + h * d_b1)
            - formulas.frequency_from_beta(beta - h * d_beta, f1, b1 - h * d_b1)) / (2 * h)
    assert np.all(np.abs(formulas.frequency_change(f, beta, d_beta, b1, d_b1) - step) < 1e-7 * f)


def test_free_resonances_with_a_tip_mass_scale_from_the_loaded_root():
    """The discrepancy model's free resonances (beta1 of the loaded lever) against the FE beam."""
    from pfmdyn.discrepancy.model import Model
    from pfmdyn.discrepancy.undamped_modes import resonances

    for (k, L, f1, H), mu, gamma in zip(_levers(8, 3), (0.05, 0.3, 1.0), (1.0, 0.95, 0.85)):
        fe = FEBeam(k, L, f1, H, mu=mu, gamma=gamma, n_elements=120).free_resonances(3)
        model = Model(SimpleNamespace(spring_constant=k, tip_height=H, length=L, free_resonance=fe[0]),
                      ("tip_mass", "tip_setback"))
        got = resonances(model, [0.0, 0.0, mu, gamma], False, 1.05 * fe[-1])
        np.testing.assert_allclose(got, fe, rtol=1e-6)


def test_resonance_grid_and_sensitivity_follow_the_refined_resonances():
    """The discrepancy model's quick (interpolated) resonances and d f_n / d p against its refined
    ones and their central differences: each maps roots beta to Hz through the loaded beta1."""
    from pfmdyn.discrepancy.model import Model
    from pfmdyn.discrepancy.undamped_modes import resonance_sensitivity, resonances, resonances_many

    lever = SimpleNamespace(spring_constant=2.0, tip_height=1e-5, length=2.2e-4, free_resonance=6e4)
    model = Model(lever, ("tip_mass", "tip_setback"))
    internal = np.array([math.log10(150.0), math.log10(60.0), 0.2, 0.9])
    exact = resonances(model, internal, True, 1.2e6)
    [quick] = resonances_many(model, [internal], True, 1.2e6)
    np.testing.assert_allclose(quick, exact, rtol=5e-4)         # linear interpolation: 1e-4 and 4e-4 here
    # Both search up to f_max in Hz: a resonance just above it is left out, just below it is kept.
    for f_max, count in ((exact[1] * (1 - 1e-4), 1), (exact[1] * (1 + 1e-4), 2)):
        assert len(resonances(model, internal, True, f_max)) == count
        assert len(resonances_many(model, [internal], True, f_max)[0]) == count
    got = resonance_sensitivity(model, internal, True, exact)
    for j in range(len(internal)):
        step = np.zeros(len(internal))
        step[j] = 1e-5
        diff = (resonances(model, internal + step, True, 1.2e6) - resonances(model, internal - step, True, 1.2e6)) / 2e-5
        np.testing.assert_allclose(got[:, j], diff, rtol=1e-4, atol=1e-6 * exact.max())


def test_a_start_grids_rows_of_several_tips_get_each_their_own_resonances():
    """:func:`resonances_many` of rows with different tips (the free root found once per tip) against each row
    alone, to the bit, and against the refined resonances."""
    from pfmdyn.discrepancy.model import Model
    from pfmdyn.discrepancy.undamped_modes import resonances, resonances_many

    lever = SimpleNamespace(spring_constant=0.8, tip_height=1.4e-5, length=3.1e-4, free_resonance=2.2e4)
    model = Model(lever, ("tip_mass", "tip_setback"))
    rng = np.random.default_rng(7)
    tips = [(0.0, 1.0), (0.3, 1.0), (0.3, 0.85), (0.05, 0.95)]
    rows = np.array([[rng.uniform(0.5, 3.5), rng.uniform(-1.0, 2.0), *tips[i % len(tips)]] for i in range(10)])
    together = resonances_many(model, rows, True, 4e5)
    for row, roots in zip(rows, together):
        assert np.array_equal(roots, resonances_many(model, [row], True, 4e5)[0])
        np.testing.assert_allclose(roots, resonances(model, row, True, 4e5), rtol=2e-3)


def test_k2_ratio_is_the_group_the_elastic_characteristic_depends_on():
    """Contact resonances of the FE beam (k1, k2 in SI) are roots of the dimensionless
    characteristic at k1/k and k2_ratio(k2, k, H, L): a wrong group moves them."""
    roots = _free_roots(1)
    rng = np.random.default_rng(9)
    for k, L, f1, H in _levers(9, 4):
        k1, k2 = k * 10 ** rng.uniform(0, 3), k * 10 ** rng.uniform(0, 3)
        beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, n_elements=120)
        f_free = beam.free_resonances(1)[0]
        b = formulas.k2_ratio(k2, k, H, L)
        assert b == pytest.approx(k2 * H**2 / (k * L**2), rel=1e-14)
        assert formulas.k2_from_ratio(b, k, H, L) == pytest.approx(k2, rel=1e-14)
        F = lambda z: characteristic.elastic(z, np, k1_over_k=k1 / k, k2_ratio=b)   # noqa: E731
        for z in formulas.beta_from_frequency(beam.contact_resonances(2), f_free, roots[0]):
            assert brentq(F, z * (1 - 1e-3), z * (1 + 1e-3)) == pytest.approx(z, rel=1e-6)
    k2, k, H, L = 10 ** RNG.uniform(-1, 4, 30), 10 ** RNG.uniform(-1.3, 1.7, 30), RNG.uniform(5e-6, 2e-5, 30), \
        RNG.uniform(1e-4, 5e-4, 30)
    np.testing.assert_allclose(formulas.k2_from_ratio(formulas.k2_ratio(k2, k, H, L), k, H, L), k2, rtol=1e-14)


def test_contact_dashpot_and_viscous_width_as_reported_by_a_fit():
    """eta = x k1 / (2 pi f1) and the width g f1, typed here, against FitResult.parameters()."""
    from pfmdyn.discrepancy.model import FitResult, Model

    x, k1, f1 = RNG.uniform(1e-4, 0.1, 20), 10 ** RNG.uniform(-1, 4, 20), 10 ** RNG.uniform(4, 6, 20)
    np.testing.assert_allclose(formulas.contact_dashpot(x, k1, f1), x * k1 / (2 * math.pi * f1), rtol=1e-14)
    g = RNG.uniform(1e-4, 0.2, 20)
    np.testing.assert_allclose(formulas.viscous_width(g, f1), g * f1, rtol=1e-15)
    meta = SimpleNamespace(spring_constant=2.0, tip_height=1e-5, length=2e-4, free_resonance=6e4)
    model = Model(meta, ("damping_contact", "damping_viscous"))
    internal = np.array([math.log10(150.0), math.log10(90.0), 0.02, 0.01])
    fit = FitResult(model, internal, np.eye(4) * 1e-12, np.zeros(8), 1.0, 4)
    out = fit.parameters()
    assert out["eta"]["value"] == pytest.approx(0.02 * 150.0 / (2 * math.pi * 6e4), rel=1e-12)
    assert out["viscous_width_hz"]["value"] == pytest.approx(0.01 * 6e4, rel=1e-12)


def test_viscous_width_is_every_free_modes_half_power_width():
    """Drag alone: each free mode's f_n / Q_n, from the damped model's complex roots, is viscous_width."""
    from pfmdyn.discrepancy.model import Model
    from pfmdyn.discrepancy.undamped_modes import resonances
    from pfmdyn.discrepancy.quality import loss_factors
    from pfmdyn.io.tables import Metadata

    meta = Metadata(spring_constant=2.0, length=2e-4, width=3e-5, tip_height=1e-5, free_resonance=6e4)
    model = Model(meta, ("damping_viscous",))
    f = resonances(model, [0.0, 0.0, 0.0], False, 2e6)
    for g in (0.002, 0.02):
        width = f * loss_factors(model, [0.0, 0.0, g], False, f)
        np.testing.assert_allclose(width, formulas.viscous_width(g, meta.free_resonance), rtol=1e-3)


def test_stiffness_limits_are_stated_as_frequency_ratios(capsys):
    """Out of range, `pfmdyn stiffness` names the pinned limit and free mode 2 as f/f1 = (beta/beta1)**2."""
    from pfmdyn import cli

    free = _free_roots(2)
    pinned = float(mp.findroot(lambda b: mp.tan(b) - mp.tanh(b), 3.93))
    code = cli.main(["stiffness", "--free-resonance", "60e3", "--contact", "300e3", "--spring-constant", "2",
                     "--k2", "0", "--length", "2e-4", "--tip-height", "1e-5"])
    err = capsys.readouterr().err
    assert code == 2
    assert f"stiff limit {(pinned / free[0]) ** 2:.6g}" in err and f"free mode 2 ({(free[1] / free[0]) ** 2:.6g})" in err


def test_spring_bounds_scale_with_the_lever():
    """k2's bounds in the discrepancy fit sit around k L**2 / H**2, where k2_ratio = 1."""
    from pfmdyn.discrepancy.effects import spring_parameters

    for k, L, _, H in _levers(10, 5):
        k1, k2 = spring_parameters(SimpleNamespace(spring_constant=k, length=L, tip_height=H), False)
        assert (k2.lower, k2.upper) == pytest.approx(math.log10(k * L**2 / H**2) + np.array([-6.0, 3.0]), abs=1e-12)
        assert (k1.lower, k1.upper) == pytest.approx(math.log10(k) + np.array([-2.0, 6.0]), abs=1e-12)


def test_peak_widths_of_damped_oscillators_are_f0_over_q():
    from pfmdyn.discrepancy.peaks import peak_widths

    for f0, q in zip(10 ** RNG.uniform(4, 6, 4), 10 ** RNG.uniform(1, 2.5, 4)):
        f = f0 * np.linspace(0.5, 1.5, 4001)
        y = 1 / (f0**2 - f**2 + 1j * f * f0 / q)
        peaks, widths = peak_widths(SimpleNamespace(frequency_hz=f, bias_v=np.zeros_like(f), response=y))
        # The pole f0 sqrt(1 - 1/(4 q**2)) + i f0 / (2 q): the width is f0 / q exactly.
        assert peaks == pytest.approx([f0 * math.sqrt(1 - 0.25 / q**2)], rel=1e-5)
        assert widths == pytest.approx([f0 / q], rel=1e-6)


def test_oscillator_spectral_density_matches_complex_arithmetic():
    f0, q = 10 ** RNG.uniform(4, 6, 10), 10 ** RNG.uniform(math.log10(5), math.log10(500), 10)
    amplitude, white = 10 ** RNG.uniform(-15, -12, 10), 10 ** RNG.uniform(-15, -13, 10)
    for args in zip(f0, q, amplitude, white):
        f = args[0] * np.linspace(0.01, 3, 1001)
        response = args[2] / (1 - (f / args[0]) ** 2 + 1j * f / (args[0] * args[1]))
        np.testing.assert_allclose(formulas.oscillator_asd(f, *args), np.sqrt(np.abs(response) ** 2 + args[3] ** 2),
                                   rtol=1e-12)


def test_quality_factor_and_width_from_an_oscillators_complex_root():
    """The roots of -w**2 + i w w0/Q + w0**2 (NumPy) give back 1/Q and the width w0/Q."""
    w0, q = 10 ** RNG.uniform(4, 7, 20), 10 ** RNG.uniform(math.log10(5), math.log10(500), 20)
    for a, b in zip(w0, q):
        root = max(np.roots([-1.0, 1j * a / b, a**2]), key=lambda r: r.real)
        assert root.imag > 0
        assert formulas.loss_factor_from_root(root.real, root.imag) == pytest.approx(1 / b, rel=1e-10)
        assert formulas.half_power_width_from_root(root.imag) == pytest.approx(a / b, rel=1e-10)


def test_thermal_peaks_are_numbered_by_the_free_beams_frequency_ratios():
    """Mode 2 of a free lever sits at (beta2/beta1)**2 = 6.267 f1; a peak at 3.5 f1 is no flexural mode."""
    from pfmdyn.analysis.thermal import fit_thermal_peaks, oscillator_asd

    roots = _free_roots(2)
    f1 = 4e4
    f = np.linspace(0, 3.2e5, 16001)
    asd = (oscillator_asd(f, f1, 150.0, 2e-14, 1e-14) + oscillator_asd(f, (roots[1] / roots[0]) ** 2 * f1, 300.0,
                                                                        1e-15, 0.0)
           + oscillator_asd(f, 3.5 * f1, 200.0, 1e-15, 0.0))
    peaks = fit_thermal_peaks(f, asd)
    assert [p.mode for p in peaks] == [1, 2]
    assert peaks[1].frequency_hz == pytest.approx((roots[1] / roots[0]) ** 2 * f1, rel=1e-4)


def test_domain_responses_of_eqs_37_38_match_complex_arithmetic():
    from pfmdyn.analysis.domains import domain_amplitudes, domain_responses, electrostatic_amplitude

    g, v_dc, v_av = RNG.normal(size=30), RNG.uniform(-10, 10, 30), RNG.uniform(-1, 1, 30)
    d_el = electrostatic_amplitude(g, v_dc, v_av)
    np.testing.assert_allclose(d_el, g * (v_dc - v_av), rtol=1e-13)
    d_eff, psi = RNG.normal(size=30), RNG.uniform(-math.pi, math.pi, 30)
    plus, minus = domain_responses(d_eff, d_el, psi)
    background = d_el * (np.cos(psi) + 1j * np.sin(psi))
    np.testing.assert_allclose(plus, d_eff + background, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(minus, -d_eff + background, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(np.array(domain_amplitudes(d_eff, d_el, psi)), np.abs([plus, minus]), rtol=1e-12)


def _generated_names():
    names = set()
    for path in GENERATED.glob("*.py"):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
                names.add(node.name)
    return names


def test_no_module_under_pfmdyn_redefines_a_generated_formula():
    """A function named like a generated one must call it (e.g. to check its input), not retype it."""
    # the composed lever's entry points share the families' generic names (it assembles, not retypes)
    names = _generated_names() - {"slope", "deflection", "twist", "characteristic", "slope_and_jacobian"}
    assert {"reduced_modulus", "spring_constant_from_geometry"} <= names
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and node.name in names:
                calls = {c.func.attr for c in ast.walk(node)
                         if isinstance(c, ast.Call) and isinstance(c.func, ast.Attribute)}
                if node.name not in calls:
                    offenders.append(f"{path.relative_to(PACKAGE)}: {node.name}")
    assert not offenders, offenders


@pytest.mark.parametrize("text", ["2 * cantilever.length / 3", "np.sqrt(k1**3 / (6 * r * p))",
                                  "3 * youngs_modulus * inertia / length**3",
                                  "np.real(piezo * np.conj(g))", "np.real(intercept * np.conj(slope))",
                                  "EPSILON_0 * width / H**2", "2 * v_null * part(slope)",
                                  "(lever.spring_constant + k1_pm) / k1_pm", "/ lever.free_resonance) ** 2 - 1)"])
def test_hand_typed_versions_are_gone(text):
    hits = [p.name for p in PACKAGE.rglob("*.py") if text in p.read_text(encoding="utf-8")]
    assert not hits, hits


def test_sho_response_is_bglibs_and_its_log_partials_are_derivatives():
    """BGlib's SHO typed from its documentation, A e^{i phi} w0^2 / (f^2 - i f w0/Q - w0^2) with A = 1,
    phi = 0; the partials against central differences in log w0 and log Q."""
    f, f0, q = RNG.uniform(1e5, 5e5, 20), RNG.uniform(1e5, 5e5, 20), np.exp(RNG.uniform(np.log(5), np.log(500), 20))
    np.testing.assert_allclose(formulas.sho_response(f, f0, q), f0**2 / (f**2 - 1j * f * f0 / q - f0**2), rtol=1e-13)
    assert np.allclose(formulas.sho_response(1e3, 3e5, 50.0), -1.0, rtol=1e-4)     # -1 far below: BGlib's + pi
    assert np.isclose(formulas.sho_response(3e5, 3e5, 50.0), 50j)                   # i Q at resonance
    h = 1e-6
    for partial, scale in ((formulas.sho_response_d_log_resonance, (np.exp(h), 1.0)),
                           (formulas.sho_response_d_log_quality, (1.0, np.exp(h)))):
        up = formulas.sho_response(f, f0 * scale[0], q * scale[1])
        down = formulas.sho_response(f, f0 / scale[0], q / scale[1])
        np.testing.assert_allclose(partial(f, f0, q), (up - down) / (2 * h), rtol=1e-6, atol=1e-6 * np.abs(up).max())


def test_two_frequency_oscillator_gives_back_the_oscillator_through_its_two_points():
    """An oscillator typed here, D f0**2 / (f0**2 - f**2 + i f f0/Q) over f0 10 kHz-3 MHz, Q 5-500, any
    complex D; DART's two drives 0.3-3 widths apart about a centre up to a width off the peak."""
    n = 200
    f0, q = np.exp(RNG.uniform(np.log(1e4), np.log(3e6), n)), np.exp(RNG.uniform(np.log(5), np.log(500), n))
    d = np.exp(RNG.uniform(np.log(1e-13), np.log(1e-9), n) + 1j * RNG.uniform(-np.pi, np.pi, n))
    centre = f0 * (1 + RNG.uniform(-1, 1, n) / q)
    df = f0 / q * RNG.uniform(0.3, 3, n)
    f1, f2 = centre - df / 2, centre + df / 2
    z1, z2 = ((f0**2 - f**2 + 1j * f * f0 / q) / (d * f0**2) for f in (f1, f2))
    parts = (f1, f2, z1.real, z1.imag, z2.real, z2.imag)
    np.testing.assert_allclose(np.sqrt(formulas.two_frequency_resonance_squared(*parts)), f0, rtol=1e-9)
    np.testing.assert_allclose(formulas.two_frequency_width(*parts), f0 / q, rtol=1e-7)
    np.testing.assert_allclose(formulas.two_frequency_drive(*parts), d, rtol=1e-7)


def test_point_mass_contact_stiffness_and_gain_of_a_mass_on_two_springs():
    """A mass on springs k and k1 (k1 to a surface moving d): its resonance from the stiffness over the mass,
    the static deflection by solving the force balance numerically."""
    k, k1, m = np.exp(RNG.uniform(np.log(0.05), np.log(50), 20)), np.exp(RNG.uniform(np.log(0.05), np.log(5e4), 20)), 1e-11
    f_free, f_contact = np.sqrt(k / m) / (2 * np.pi), np.sqrt((k + k1) / m) / (2 * np.pi)
    np.testing.assert_allclose(formulas.point_mass_contact_stiffness(f_contact, f_free, k), k1, rtol=1e-9)
    gain = [brentq(lambda x: kk * x + kk1 * (x - 1.0), -1, 2, xtol=1e-15) for kk, kk1 in zip(k, k1)]
    np.testing.assert_allclose(formulas.point_mass_static_gain(k, k1), gain, rtol=1e-12)
