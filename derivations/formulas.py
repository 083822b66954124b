"""Closed-form relations used numerically, each derived here from the derivations it rests on.

Numeric code calls them from ``generated/formulas.py`` (written by ``pfmdyn codegen``,
:mod:`derivations.codegen.formulas`); hand-typed versions survive only as independent
checks in the tests.  Each :class:`Formula` names its arguments (SI) and its source.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from . import calibration as cal
from . import contact_mechanics as cm
from . import damping as dm
from . import domain_contrast as dc
from . import hydrodynamics as hyd
from .beam import EI, H, L, beta, f0, k, k2
from .elastic_contact import tip_conditions
from .free_end import solve as solve_free_end
from .paper import printed as P

__all__ = ["Formula", "formulas"]

E, width, thickness, density, beta1 = sp.symbols(
    "youngs_modulus width thickness density beta1", positive=True)
k1, radius, load, frequency = sp.symbols("k1 tip_radius load frequency", positive=True)
b_re, b_im, c_re, c_im, bias = sp.symbols("b_re b_im c_re c_im bias", real=True)
eps0, tip_height, v_ac, dv, tau = sp.symbols("epsilon_0 H V_ac dV tau", positive=True)


@dataclass(frozen=True)
class Formula:
    """``name(*arguments) = expr``: one generated function."""

    name: str
    arguments: tuple[sp.Symbol, ...]
    expr: sp.Expr
    summary: str
    source: str


def _only(solutions):
    assert len(solutions) == 1, solutions
    return solutions[0]


@lru_cache(maxsize=None)
def formulas() -> tuple[Formula, ...]:
    """Every formula, in a fixed order.

    >>> {f.name: f.expr for f in formulas()}["spring_constant_from_geometry"]
    thickness**3*width*youngs_modulus/(4*L**3)
    """
    inertia = width * thickness**3 / 12
    spring = _only(sp.solve(sp.Eq(EI, E * inertia), k))
    # beta**4 = omega**2 rho S L**4 / EI (Eq. 2), EI = E I, S = w t; beta1: first free root.
    omega = _only(sp.solve(sp.Eq(beta1**4, frequency**2 * density * width * thickness * L**4
                                 / (E * inertia)), frequency))
    # Response b + c V, linear in the DC bias V (drives f0 and q0 are proportional to V - V_surf).
    power = (b_re + c_re * bias)**2 + (b_im + c_im * bias)**2
    null = _only(sp.solve(sp.diff(power, bias), bias))
    # Parallel-plate force of the cantilever (area L w) at separation H; first harmonic per
    # unit length and per V_ac dV.  Its magnitude: the sign (attractive) is the caller's.
    plate = eps0 * L * width * (dv + v_ac * sp.cos(tau))**2 / (2 * tip_height**2)
    harmonic = sp.integrate(plate * sp.cos(tau), (tau, 0, 2 * sp.pi)) / sp.pi
    free = solve_free_end()
    height_per_slope = sp.limit(free.tip_deflection(f0) / free.theta(f0), beta, 0)
    return (
        Formula("spring_constant_from_geometry", (E, width, thickness, L), spring,
                "spring constant k (N/m) of a rectangular beam: EI = k L**3 / 3 with I = w t**3 / 12",
                "derivations/beam.py: EI"),
        Formula("youngs_modulus_from_spring_constant", (k, width, thickness, L),
                _only(sp.solve(sp.Eq(k, spring), E)),
                "Young's modulus (Pa) giving spring constant k: the inverse of spring_constant_from_geometry",
                "derivations/beam.py: EI"),
        Formula("free_resonance_from_geometry", (E, width, thickness, L, density, beta1),
                omega / (2 * sp.pi),
                "first free resonance f1 (Hz) from beta1**4 = omega**2 rho S L**4 / EI",
                "derivations/beam.py: kappa, Eq. 2"),
        Formula("height_per_slope", (L,), height_per_slope,
                "static tip deflection per tip slope under a tip force, u0(L)/theta = 2L/3",
                "derivations/free_end.py: solve(), beta -> 0"),
        Formula("nulling_bias", (b_re, b_im, c_re, c_im), null,
                "real bias V minimising |b + c V| (the response vanishes there when b/c is real)",
                "derivations/formulas.py: d|b + c V|**2/dV = 0"),
        Formula("capacitive_load_per_volt2", (eps0, width, tip_height),
                sp.simplify(harmonic / (L * v_ac * dv)),
                "magnitude of the first-harmonic capacitive load q0 per unit length per V_ac dV (N/m per V**2)",
                "derivations/formulas.py: parallel-plate force eps0 L w (dV + V_ac cos)**2/(2 H**2)"),
        Formula("reduced_modulus", (k1, radius, load),
                _only(sp.solve(sp.Eq(cm.hertz_stiffness().subs({cm.R: radius, cm.P: load}), k1),
                               cm.E_star)),
                "reduced modulus E* (Pa) of a Hertz contact of stiffness k1 at tip radius R and load P",
                "derivations/contact_mechanics.py: hertz_stiffness()"),
        Formula("mindlin_k2_over_k1", (cm.nu,), sp.factor(1 / cm.mindlin_ratio()),
                "k2/k1 of a rigid sphere on an isotropic sample (Hertz normal, Mindlin tangential)",
                "derivations/contact_mechanics.py: mindlin_ratio()"),
        *_frequency_scaling(),
        *_lateral_spring(),
        *_damping(),
        *_oscillator(),
        *_domain_contrast(),
        *_domain_contrast_printed(),
        *_band_excitation_sho(),
        *_two_frequency_oscillator(),
        *_point_mass(),
        *_calibration(),
    )


def _calibration() -> tuple[Formula, ...]:
    """The free lever's calibration (:mod:`derivations.calibration`, :mod:`derivations.hydrodynamics`)."""
    source = "derivations/calibration.py"
    f0, q, a = sp.symbols("f0 q amplitude", positive=True)
    reynolds = sp.Symbol("reynolds")        # complex at a damped mode's frequency
    return (
        *(Formula(f"thermal_factor_{detection}{'' if region == 'beyond' else '_inside'}", (cal.sigma, cal.gamma),
                  cal.thermal_factor(detection, region),
                  f"chi of k_tip = chi kB T / <d*^2> for the first mode read as a {detection} at the spot sigma = x_s/L "
                  f"through a static sensitivity measured with the tip at gamma = x_tip/L, spot "
                  f"{'beyond' if region == 'beyond' else 'inside'} the tip (sigma {'>=' if region == 'beyond' else '<='} "
                  f"gamma; {0.817 if detection == 'slope' else 0.971} at sigma = gamma = 1)",
                  f"{source}: thermal_factor({detection!r}, {region!r})")
          for detection in ("slope", "deflection") for region in ("beyond", "inside")),
        Formula("sader_spring_constant", (cal.rho_fluid, cal.width, L, cal.Q, cal.gamma_i, cal.f_fluid),
                cal.sader_spring_constant(),
                "Sader's spring constant (N/m) from the fluid density, lever width and length, the first mode's Q and "
                "frequency (Hz) in the fluid and Gamma_i there", f"{source}: sader_spring_constant()"),
        Formula("mass_per_length", (k, L, sp.Symbol("free_resonance", positive=True)), cal.mass_per_length(),
                "the lever's mass per length rho_c h b (kg/m) from k, L and its first resonance in vacuum (Hz)",
                f"{source}: mass_per_length()"),
        Formula("oscillator_mean_square", (f0, q, a), cal.oscillator_mean_square(),
                "mean square of the oscillator whose ASD is A f0**2/|f0**2 - f**2 + i f f0/q| (area under its PSD)",
                f"{source}: oscillator_mean_square()"),
        Formula("circular_hydrodynamic_function", (reynolds,), hyd.circular(conjugate=True, re=reynolds),
                "Sader's hydrodynamic function of a circular cylinder in pfmdyn's exp(+i omega t) convention: "
                "conj(Gamma_circ) at a real Reynolds number, analytic at a complex one",
                "derivations/hydrodynamics.py: circular(conjugate=True)"),
        Formula("rectangular_correction_real", (hyd.tau,), hyd.rectangular_correction("real"),
                "real part of Sader's fitted correction Omega(tau), tau = log10 Re (valid 1e-6 <= Re <= 1e4)",
                "derivations/hydrodynamics.py: OMEGA (Sader 1998, Eq. 21)"),
        Formula("rectangular_correction_imag", (hyd.tau,), hyd.rectangular_correction("imag"),
                "imaginary part of Sader's fitted correction Omega(tau), tau = log10 Re (valid 1e-6 <= Re <= 1e4)",
                "derivations/hydrodynamics.py: OMEGA (Sader 1998, Eq. 21)"),
    )


def _band_excitation_sho() -> tuple[Formula, ...]:
    """The simple harmonic oscillator (SHO) that band-excitation tools fit, in BGlib's convention,
    with its partials w.r.t. the logarithms of the resonance frequency and the quality factor.

    ``x'' + (w0/Q) x' + w0**2 x = w0**2 F`` at ``e^{i w t}`` gives ``X/F = w0**2 / (w0**2 - w**2 +
    i w w0/Q)``, which depends on frequencies only through ``w/w0 = f/f0``.  BGlib writes
    ``A e^{i phi} w0**2 / (f**2 - i f w0/Q - w0**2)``: the same response times ``-1``, so its
    phase is the usual one plus pi and ``A`` is the response's magnitude far below resonance.
    """
    f, f0, q = sp.symbols("frequency resonance_frequency quality_factor", positive=True)
    w, w0, x = sp.symbols("omega omega_0 X")
    motion = -w**2 * x + sp.I * w * (w0 / q) * x + w0**2 * x - w0**2
    usual = _only(sp.solve(motion, x)).subs({w: 2 * sp.pi * f, w0: 2 * sp.pi * f0})
    bglib = sp.factor(-usual)
    assert sp.simplify(bglib - f0**2 / (f**2 - sp.I * f * f0 / q - f0**2)) == 0
    source = "derivations/formulas.py: SHO x'' + (w0/Q) x' + w0**2 x = w0**2 F, times -1 (BGlib)"
    return (
        Formula("sho_response", (f, f0, q), bglib,
                "SHO response per unit amplitude in BGlib's convention (-1 far below resonance: phase + pi)", source),
        Formula("sho_response_d_log_resonance", (f, f0, q), sp.factor(f0 * sp.diff(bglib, f0)),
                "partial of sho_response w.r.t. log(resonance_frequency)", source),
        Formula("sho_response_d_log_quality", (f, f0, q), sp.factor(q * sp.diff(bglib, q)),
                "partial of sho_response w.r.t. log(quality_factor)", source),
    )


def _two_frequency_oscillator() -> tuple[Formula, ...]:
    """The oscillator through two complex signals (DART: Gannepalli, Yablon, Proksch and Kalinin,
    Nanotechnology 22, 355705 (2011)), from the SHO's response ``s = D w0**2 / (w0**2 - w**2 + i w w0/Q)``
    (the motion of :func:`_band_excitation_sho`, in the usual sign).

    With ``z_j = 1/s_j`` at ``f_j`` and ``c = D f0**2``: ``c z_j = f0**2 - f_j**2 + i f_j f0/Q``, linear in
    ``(Re c, Im c, f0**2, f0/Q)``; the two signals' four real parts fix them.
    """
    f, f0, q = sp.symbols("frequency resonance_frequency quality_factor", positive=True)
    w, w0, x = sp.symbols("omega omega_0 X")
    f1, f2 = sp.symbols("f1 f2", positive=True)
    z = sp.symbols("z1_re z1_im z2_re z2_im", real=True)
    c_re_, c_im_, f0_squared, width_ = sp.symbols("c_re c_im resonance_squared width", real=True)
    usual = _only(sp.solve(-w**2 * x + sp.I * w * (w0 / q) * x + w0**2 * x - w0**2, x)).subs(
        {w: 2 * sp.pi * f, w0: 2 * sp.pi * f0})
    equations = []
    for f_j, z_re, z_im in ((f1, *z[:2]), (f2, *z[2:])):
        # s_j = D usual(f_j), so c z_j = D f0**2 / s_j = f0**2 / usual(f_j)
        residual = (c_re_ + sp.I * c_im_) * (z_re + sp.I * z_im) - sp.expand(f0**2 / usual).subs(
            {f: f_j, q: f0 / width_}).subs(f0, sp.sqrt(f0_squared))
        equations += sp.expand(residual).as_real_imag()
    matrix, rhs = sp.linear_eq_to_matrix(equations, [c_re_, c_im_, f0_squared, width_])
    c_re, c_im, resonance_squared, width = (sp.factor(v) for v in matrix.LUsolve(rhs))
    arguments = (f1, f2, *z)
    source = "derivations/formulas.py: SHO through two points, c z_j = f0**2 - f_j**2 + i f_j f0/Q"
    what = "of the oscillator through the signals s1 = 1/z1 at f1 and s2 = 1/z2 at f2 (Hz)"
    return (
        Formula("two_frequency_resonance_squared", arguments, resonance_squared,
                f"squared resonance f0**2 (Hz**2) {what}", source),
        Formula("two_frequency_width", arguments, width, f"half-power width f0/Q (Hz) {what}", source),
        Formula("two_frequency_drive", arguments, sp.factor((c_re + sp.I * c_im) / resonance_squared),
                f"static response D (complex, the signals' unit) {what}", source),
    )


def _point_mass() -> tuple[Formula, ...]:
    """The lever as a point mass ``m`` on its spring ``k``, the contact a spring ``k1`` to a surface moving
    ``d``: ``m x'' + k x + k1 (x - d) = 0``.  Free, it rings at ``(2 pi f0)**2 = k/m``; in contact at
    ``(2 pi fc)**2 = (k + k1)/m``; statically ``x = d k1 / (k + k1)``."""
    m, fc, x, d = sp.symbols("m frequency x d", positive=True)
    f0_ = sp.Symbol("free_resonance", positive=True)
    mass = _only(sp.solve(sp.Eq((2 * sp.pi * f0_)**2 * m, k), m))
    source = "derivations/formulas.py: point mass m x'' + k x + k1 (x - d) = 0"
    return (
        Formula("point_mass_contact_stiffness", (fc, f0_, k),
                _only(sp.solve(sp.Eq((2 * sp.pi * fc)**2 * mass, k + k1), k1)),
                "contact stiffness k1 (N/m) of a point-mass lever (k, free resonance f0) in contact at fc (Hz)",
                source),
        Formula("point_mass_static_gain", (k, k1), _only(sp.solve(k * x + k1 * (x - d), x)) / d,
                "static deflection per surface displacement of a point-mass lever on a contact spring k1",
                source),
    )


def _frequency_scaling() -> tuple[Formula, ...]:
    """beta <-> f of one lever: Eq. 2's beta**4 = omega**2 rho S L**4 / EI, written for the
    mode at ``f`` and for the first free mode (``beta1`` at ``f1``), so that rho S L**4 / EI
    drops out.  ``beta1`` is the first free root of the lever at hand (1.8751... for a bare
    lever; a tip mass or set-back moves it)."""
    f1, rho_s, b = sp.symbols("free_resonance rho_S beta", positive=True)

    def dispersion(root, f):
        return sp.Eq(root**4, (2 * sp.pi * f)**2 * rho_s * L**4 / EI)

    # The lever's rho S L**4 / EI from its first free mode, then the mode at f.
    scaled = dispersion(b, frequency).subs(rho_s, _only(sp.solve(dispersion(beta1, f1), rho_s)))
    source = "derivations/beam.py: kappa, Eq. 2 (beta**4 = omega**2 rho S L**4 / EI)"
    # First-order change of f when beta and beta1 move (f1 fixed), written with f itself.
    f_of_beta = _only(sp.solve(scaled, frequency))
    d_b, d_b1 = sp.symbols("d_beta d_beta1", real=True)
    change = (sp.diff(f_of_beta, b) * d_b + sp.diff(f_of_beta, beta1) * d_b1).subs(
        f1, _only(sp.solve(sp.Eq(f_of_beta, frequency), f1)))
    return (
        Formula("beta_from_frequency", (frequency, f1, beta1), _only(sp.solve(scaled, b)),
                "dimensionless frequency beta of a mode at frequency f (Hz) of a lever whose first free root "
                "beta1 rings at f1", source),
        Formula("frequency_from_beta", (b, f1, beta1), f_of_beta,
                "frequency (Hz) of the mode at dimensionless frequency beta, the inverse of beta_from_frequency",
                source),
        Formula("frequency_change", (frequency, b, d_b, beta1, d_b1), sp.factor(change),
                "first-order change (Hz) of a mode at frequency f when its root beta moves by d_beta and the "
                "free root beta1 by d_beta1 (f1 fixed)", source),
    )


def _lateral_spring() -> tuple[Formula, ...]:
    """k2 H**2/(k L**2): the moment stiffness of the longitudinal spring at the tip (Eq. 4a's
    ``-k2 H**2 u0'(L)``) over ``k L**2``; the elastic-contact characteristic depends on
    ``k2``, ``H`` and ``L`` only through it (``generated/characteristic.py`` is written in it)."""
    U = sp.symbols("U0:4")
    moment = sp.diff(tip_conditions(U)[0], U[1])        # EI u0''(L) + k2 H**2 u0'(L) - k2 H d2 = 0
    ratio = sp.Symbol("k2_ratio", positive=True)
    group = moment / (k * L**2)
    source = "derivations/elastic_contact.py: tip_conditions() (Eq. 4a)"
    return (
        Formula("k2_ratio", (k2, k, H, L), group,
                "dimensionless longitudinal contact stiffness k2 H**2/(k L**2)", source),
        Formula("k2_from_ratio", (ratio, k, H, L), _only(sp.solve(sp.Eq(group, ratio), k2)),
                "longitudinal contact stiffness k2 (N/m) from k2 H**2/(k L**2), the inverse of k2_ratio", source),
    )


def _damping() -> tuple[Formula, ...]:
    """The contact dashpot and the viscous half-power width in SI, from the damping substitution."""
    f1, g, x = sp.symbols("free_resonance viscous_loss contact_loss", positive=True)
    # The dashpot's normal force (k1 + i omega eta) at omega = r omega1 is k1 (1 + i x r).
    dashpot = sp.Eq(k1 + sp.I * dm.r * dm.omega1 * dm.eta, dm.substitution()["k1"].subs(dm.k1, k1))
    eta = _only(sp.solve(dashpot, dm.eta)).subs({dm.omega1: 2 * sp.pi * f1, dm.xc: x})
    width = (dm.half_power_width("viscous") * f1).subs(dm.g, g)
    source = "derivations/damping.py"
    return (
        Formula("contact_dashpot", (x, k1, f1), eta,
                "contact dashpot eta (N s/m) of the loss tangent x = omega1 eta / k1 at the first free resonance f1",
                f"{source}: substitution()"),
        Formula("viscous_width", (g, f1), width,
                "half-power width (Hz) of every free mode under viscous drag g = c/(rho S omega1) alone",
                f"{source}: half_power_width('viscous')"),
    )


def _oscillator() -> tuple[Formula, ...]:
    """One mode as a damped oscillator ``x'' + (omega0/Q) x' + omega0**2 x = omega0**2 F/k``
    (time dependence ``exp(i omega t)``): its power spectrum, and 1/Q from its complex root."""
    w, w0, inv_q = sp.symbols("omega omega0 inv_q", positive=True)
    f, f_0, q, amplitude, white = sp.symbols("f f0 q amplitude white", positive=True)
    oscillator = -w**2 + sp.I * w * w0 * inv_q + w0**2
    # Response per static response (1 at omega = 0), its squared modulus in Hz; the
    # denominator is kept a sum of squares (expanded, it cancels near the resonance).
    denominator = oscillator.subs({w: 2 * sp.pi * f, w0: 2 * sp.pi * f_0, inv_q: 1 / q})
    modulus2 = sum(sp.factor_terms(part(denominator))**2 for part in (sp.re, sp.im))
    power = sp.factor_terms((2 * sp.pi * f_0)**4 / modulus2)
    asd = sp.sqrt(white**2 + amplitude**2 * power)
    # A complex root omega = a + i b: real and imaginary parts of the oscillator vanish.
    a, b_ = sp.symbols("root_re root_im", positive=True)
    parts = sp.expand_complex(sp.expand(oscillator.subs(w, a + sp.I * b_)))
    solution = _only(sp.solve([sp.re(parts), sp.im(parts)], [w0, inv_q], dict=True))
    source = "derivations/formulas.py: damped oscillator x'' + (omega0/Q) x' + omega0**2 x"
    return (
        Formula("oscillator_asd", (f, f_0, q, amplitude, white), asd,
                "amplitude spectral density at f (Hz) of a mode at f0 with quality factor q and static "
                "amplitude A over a white floor w", f"{source}: |response|**2"),
        Formula("loss_factor_from_root", (a, b_), solution[inv_q],
                "1/Q of a mode from its complex root a + i b (Im > 0, exp(i omega t); any frequency scale)",
                f"{source}: complex root"),
        Formula("half_power_width_from_root", (b_,), sp.simplify(solution[w0] * solution[inv_q]),
                "half-power width omega0/Q of a mode from the imaginary part b of its complex root (same units)",
                f"{source}: complex root"),
    )


def _domain_contrast() -> tuple[Formula, ...]:
    """|PR+-|, arg PR+ - arg PR- and their leading orders (Section IV.3), any real signs.

    The derivation's symbols are positive; the numeric functions take any real d_eff, d_el,
    so the arguments here are real symbols substituted in.
    """
    d, e, p = sp.symbols("d_eff d_el psi", real=True)
    real = {dc.d_eff: d, dc.d_el: e, dc.psi: p}
    plus, minus = (sp.sqrt(a.subs(real)) for a in dc.amplitudes_squared())
    pr_plus, pr_minus = (r.subs(real) for r in dc.responses())
    product = sp.expand(sp.expand_complex(pr_plus * sp.conjugate(pr_minus)))
    phase = sp.atan2(sp.trigsimp(sp.im(product)), sp.trigsimp(sp.re(product)))
    small_el = dc.phase_difference_series("electrostatic").subs(dc.psi, p).subs(dc.eps, e / d)
    small_piezo = dc.phase_difference_series("piezoelectric").subs(dc.psi, p).subs(dc.eps, d / e)
    source = "derivations/domain_contrast.py"
    # Leading-order amplitudes, for d_eff > 0 (small electrostatic part) or d_el > 0 (small
    # piezoresponse); numeric code reaches other signs by PR -> -PR, which keeps |PR|.
    leading = []
    for name, small, regime in (("electrostatic", "electrostatic", "|d_el| << d_eff (d_eff > 0)"),
                                ("piezo", "piezoelectric", "|d_eff| << d_el (d_el > 0)")):
        for sign, amplitude in zip("+-", dc.amplitude_series(small)):
            leading.append(Formula(
                f"domain_amplitude_{'plus' if sign == '+' else 'minus'}_small_{name}", (d, e, p),
                amplitude.subs(real), f"leading order of |PR{sign}| for {regime}",
                f"{source}: amplitude_series('{small}')"))
    # Eq. 41's line b + c V in the bias, less its bias-free part d: the electrostatic term.
    d0, G, V, Vs = sp.symbols("d G V V_surf", real=True)
    slope, intercept = dc.linear_fit_in_bias()
    g_elec, v_dc, v_av = sp.symbols("g_elec v_dc v_av", real=True)
    electrostatic = sp.expand(slope * V + intercept - d0).subs({G: g_elec, V: v_dc, Vs: v_av}, simultaneous=True)
    return (
        Formula("electrostatic_term", (g_elec, v_dc, v_av), sp.factor_terms(electrostatic),
                "electrostatic term d_el = G_elec (V_dc - V_av) of Eqs. 37-38 (units of G_elec times V)",
                f"{source}: linear_fit_in_bias()"),
        Formula("domain_response_plus", (d, e, p), pr_plus, "complex response PR+ over the c+ domain (Eqs. 37-38)",
                f"{source}: responses()"),
        Formula("domain_response_minus", (d, e, p), pr_minus, "complex response PR- over the c- domain (Eqs. 37-38)",
                f"{source}: responses()"),
        Formula("domain_amplitude_plus", (d, e, p), plus, "|PR+| over the c+ domain", f"{source}: amplitudes_squared()"),
        Formula("domain_amplitude_minus", (d, e, p), minus, "|PR-| over the c- domain", f"{source}: amplitudes_squared()"),
        Formula("domain_phase_difference", (d, e, p), phase,
                "arg PR+ - arg PR- in (-pi, pi], the argument of PR+ conj(PR-)", f"{source}: responses()"),
        Formula("domain_phase_difference_small_electrostatic", (d, e, p), small_el,
                "leading order of arg PR+ - arg PR- for |d_el| << |d_eff| (before wrapping to (-pi, pi])",
                f"{source}: phase_difference_series('electrostatic')"),
        Formula("domain_phase_difference_small_piezo", (d, e, p), small_piezo,
                "leading order of arg PR+ - arg PR- for |d_eff| << |d_el|",
                f"{source}: phase_difference_series('piezoelectric')"),
        *leading,
    )


def _domain_contrast_printed() -> tuple[Formula, ...]:
    """The paper's Eqs. 39-40 and its small-piezoresponse phase as printed (see the errata),
    from their one transcription in ``derivations/paper/printed.py``, for comparison only.

    Eq. 39's phase takes ``PR+-`` as given (the paper leaves open whether they are
    amplitudes or signed responses), so they are arguments of their own there.
    """
    d, e, p, phi = sp.symbols("d_eff d_el psi phi", real=True)
    pr_plus, pr_minus = sp.symbols("pr_plus pr_minus", real=True)
    real = {P.d_eff: d, P.d_el: e, P.psi: p, P.phi: phi}
    tan_phase = P.tan_phase.xreplace({P.PR_plus_amp: pr_plus, P.PR_minus_amp: pr_minus}).subs(real)
    source = "derivations/paper/printed.py"
    return (
        Formula("paper_eq39_amplitude_plus", (d, e, phi), P.PR_plus_amp.subs(real),
                "|PR+| of Eq. 39 as printed (an erratum: the cross term lacks a factor 2)", f"{source}: PR_plus_amp"),
        Formula("paper_eq39_amplitude_minus", (d, e, phi), P.PR_minus_amp.subs(real),
                "|PR-| of Eq. 39 as printed (an erratum)", f"{source}: PR_minus_amp"),
        Formula("paper_eq39_tan_phase", (e, p, pr_plus, pr_minus), tan_phase,
                "tan of the phase shift of Eq. 39 as printed (an erratum), PR+- as given", f"{source}: tan_phase"),
        Formula("paper_eq40_phase_difference", (d, e, p), P.small_el_phase.subs(real),
                "small-electrostatic phase difference of Eq. 40 as printed (an erratum)", f"{source}: small_el_phase"),
        Formula("paper_small_piezo_phase_difference", (d, e, p), P.small_piezo_phase.subs(real),
                "small-piezoresponse phase difference of Section IV.3 as printed (an erratum)",
                f"{source}: small_piezo_phase"),
    )
