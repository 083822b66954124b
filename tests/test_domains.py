"""Domain contrast (Eqs. 37-40): exact forms, the order of the correct limits, and the printed forms."""
import numpy as np
import pytest

from pfmdyn.analysis import domains

RNG = np.random.default_rng(37)
D_EFF = RNG.uniform(-3, 3, 200)
D_EL = RNG.uniform(-3, 3, 200)
PSI = RNG.uniform(-np.pi, np.pi, 200)
# Angles away from the zeros of sin and cos, where leading terms vanish and orders shift.
PSI_GENERIC = np.array([0.4, 1.1, 2.0, -0.7, -2.5])


def angular_distance(a, b):
    return np.abs(np.angle(np.exp(1j * (a - b))))


def test_responses_are_eqs_37_38():
    plus, minus = domains.domain_responses(D_EFF, D_EL, PSI)
    background = D_EL * np.exp(1j * PSI)
    np.testing.assert_allclose(plus, D_EFF + background, rtol=0, atol=1e-14)
    np.testing.assert_allclose(minus, -D_EFF + background, rtol=0, atol=1e-14)


def test_exact_amplitudes_match_complex_arithmetic_and_closed_form():
    plus, minus = domains.domain_responses(D_EFF, D_EL, PSI)
    amp_plus, amp_minus = domains.domain_amplitudes(D_EFF, D_EL, PSI)
    np.testing.assert_allclose(amp_plus, np.abs(plus), rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(amp_minus, np.abs(minus), rtol=1e-13, atol=1e-14)
    cross = 2 * D_EFF * D_EL * np.cos(PSI)
    np.testing.assert_allclose(amp_plus**2, D_EFF**2 + D_EL**2 + cross, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(amp_minus**2, D_EFF**2 + D_EL**2 - cross, rtol=1e-12, atol=1e-12)


def test_exact_phase_difference_matches_complex_arithmetic():
    plus, minus = domains.domain_responses(D_EFF, D_EL, PSI)
    delta = domains.phase_difference(D_EFF, D_EL, PSI)
    assert np.all((delta > -np.pi) & (delta <= np.pi))
    np.testing.assert_array_less(angular_distance(delta, np.angle(plus) - np.angle(minus)), 1e-12)
    # The correct counterpart of the printed Eq. 39.
    np.testing.assert_allclose(np.tan(delta), 2 * D_EL * D_EFF * np.sin(PSI) / (D_EFF**2 - D_EL**2), rtol=1e-9)


@pytest.mark.parametrize("d_el", [0.0, -0.0])
def test_pure_piezoresponse_gives_plus_pi_with_either_zero_sign(d_el):
    assert np.all(domains.phase_difference(np.array([1.0, -2.0]), d_el, np.array([0.3, -0.3])) == np.pi)


def order_of_error(error_at):
    """Observed order p of error ~ eps**p from eps = 1e-2 and 1e-3."""
    return np.log10(error_at(1e-2) / error_at(1e-3))


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_small_electrostatic_limits_have_the_stated_order(sign):
    d_eff = sign * 2.0

    def amplitude_error(eps):
        exact = domains.domain_amplitudes(d_eff, eps * 2.0, PSI_GENERIC)
        approx = domains.amplitudes_small_electrostatic(d_eff, eps * 2.0, PSI_GENERIC)
        return np.max(np.abs(np.subtract(exact, approx)), axis=0)

    def phase_error(eps):
        exact = domains.phase_difference(d_eff, eps * 2.0, PSI_GENERIC)
        return angular_distance(exact, domains.phase_difference_small_electrostatic(d_eff, eps * 2.0, PSI_GENERIC))

    np.testing.assert_allclose(order_of_error(amplitude_error), 2.0, atol=0.05)
    np.testing.assert_allclose(order_of_error(phase_error), 3.0, atol=0.05)
    eps = 1e-3
    magnitude = np.abs(domains.phase_difference(d_eff, eps * d_eff, PSI_GENERIC))
    np.testing.assert_allclose(magnitude, np.pi - 2 * eps * np.abs(np.sin(PSI_GENERIC)), atol=1e-8)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_small_piezo_limits_have_the_stated_order(sign):
    d_el = sign * 2.0

    def amplitude_error(eps):
        exact = domains.domain_amplitudes(eps * 2.0, d_el, PSI_GENERIC)
        return np.max(np.abs(np.subtract(exact, domains.amplitudes_small_piezo(eps * 2.0, d_el, PSI_GENERIC))), axis=0)

    def phase_error(eps):
        exact = domains.phase_difference(eps * 2.0, d_el, PSI_GENERIC)
        return np.abs(exact - domains.phase_difference_small_piezo(eps * 2.0, d_el, PSI_GENERIC))

    np.testing.assert_allclose(order_of_error(amplitude_error), 2.0, atol=0.05)
    np.testing.assert_allclose(order_of_error(phase_error), 3.0, atol=0.05)


def test_electrostatic_amplitude_feeds_the_exact_forms():
    d_el = domains.electrostatic_amplitude(0.5, 3.0, 1.0)
    assert d_el == 1.0
    np.testing.assert_allclose(domains.domain_amplitudes(1.0, d_el, 0.0), (2.0, 0.0), atol=1e-15)


# --- printed forms: pinned as printed, and shown to differ from the exact results -------------

def test_printed_eq39_amplitude_lacks_the_factor_two():
    printed_plus, printed_minus = domains.paper_eq39_amplitudes(D_EFF, D_EL, PSI)
    exact_plus, exact_minus = domains.domain_amplitudes(D_EFF, D_EL, PSI)
    np.testing.assert_allclose(printed_plus**2 - exact_plus**2, -D_EFF * D_EL * np.cos(PSI), atol=1e-12)
    np.testing.assert_allclose(printed_minus**2 - exact_minus**2, D_EFF * D_EL * np.cos(PSI), atol=1e-12)
    assert np.max(np.abs(printed_plus - exact_plus)) > 0.5


def test_printed_eq39_tan_is_not_the_phase_difference():
    amp_plus, amp_minus = domains.domain_amplitudes(1.0, 0.3, 0.7)
    printed = domains.paper_eq39_tan_phase(0.3, 0.7, amp_plus, amp_minus)
    exact = np.tan(domains.phase_difference(1.0, 0.3, 0.7))
    np.testing.assert_allclose([printed, exact], [-0.0847876766957913, 0.42475891466221394], rtol=1e-12)


def test_printed_eq40_deviation_is_second_order_but_the_true_one_is_first_order():
    def printed_error(eps):
        exact = domains.phase_difference(1.0, eps, PSI_GENERIC)
        return angular_distance(exact, domains.paper_eq40_phase_difference(1.0, eps, PSI_GENERIC))

    np.testing.assert_allclose(order_of_error(printed_error), 1.0, atol=0.05)
    np.testing.assert_allclose(domains.paper_eq40_phase_difference(1.0, 0.1, np.pi / 4), np.pi - 0.01)


def test_printed_small_piezo_phase_is_the_correct_limit_times_cos_over_one_plus_sin_squared():
    printed = domains.paper_small_piezo_phase_difference(1e-3, 1.0, PSI_GENERIC)
    correct = domains.phase_difference_small_piezo(1e-3, 1.0, PSI_GENERIC)
    np.testing.assert_allclose(printed / correct, np.cos(PSI_GENERIC) / (1 + np.sin(PSI_GENERIC) ** 2), rtol=1e-12)
    assert np.max(np.abs(printed - domains.phase_difference(1e-3, 1.0, PSI_GENERIC))) > 1e-3


@pytest.mark.parametrize("small", ["electrostatic", "piezoelectric"])
def test_one_phase_convention_in_derivation_and_numeric_code(small):
    """The derived series and the numeric leading-order forms both mean arg PR+ - arg PR-."""
    from pfmdyn.derivations import domain_contrast as dc
    d_eff, d_el, psi = (1.0, 0.01, 0.7) if small == "electrostatic" else (0.01, 1.0, 0.7)
    eps = d_el / d_eff if small == "electrostatic" else d_eff / d_el
    derived = float(dc.phase_difference_series(small).subs({dc.eps: eps, dc.psi: psi}))
    numeric = (domains.phase_difference_small_electrostatic if small == "electrostatic"
               else domains.phase_difference_small_piezo)(d_eff, d_el, psi)
    exact = domains.phase_difference(d_eff, d_el, psi)
    for value in (numeric, exact):
        assert abs(np.angle(np.exp(1j * (derived - value)))) < 1e-4


def test_generated_leading_amplitudes_match_the_hand_typed_forms():
    """Independent check: |PR+-| ~ |a| +- sgn(a) b cos(psi), a the large part and b the small one."""
    shift = np.sign(D_EFF) * D_EL * np.cos(PSI)
    np.testing.assert_allclose(domains.amplitudes_small_electrostatic(D_EFF, D_EL, PSI),
                               (np.abs(D_EFF) + shift, np.abs(D_EFF) - shift), rtol=1e-13, atol=1e-15)
    shift = np.sign(D_EL) * D_EFF * np.cos(PSI)
    np.testing.assert_allclose(domains.amplitudes_small_piezo(D_EFF, D_EL, PSI),
                               (np.abs(D_EL) + shift, np.abs(D_EL) - shift), rtol=1e-13, atol=1e-15)
