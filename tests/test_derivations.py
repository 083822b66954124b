"""The derived solutions: residuals, limits between families, and an independent solver."""
from __future__ import annotations

import mpmath as mp
import pytest
import sympy as sp

from pfmdyn.derivations import (elastic_contact, free_end, frictionless, indentation, pinned,
                                sliding_friction, torsion)
from pfmdyn.derivations.beam import (H, L, beta, d1, d2, f0, is_identically_zero, k, k1, k2, q0,
                                     residuals)
from pfmdyn.derivations.checks.core import compare
from pfmdyn.derivations.limits import param_limit
from pfmdyn.derivations.sliding_friction import f_l

FAMILIES = {
    "elastic": elastic_contact.solve, "frictionless": frictionless.solve,
    "frictionless-stiff": frictionless.solve_stiff, "pinned": pinned.solve, "free": free_end.solve,
    "friction": sliding_friction.solve, "indentation": indentation.solve,
    "indentation-stiff": indentation.solve_stiff,
}


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_solution_satisfies_ode_and_boundary_conditions(name):
    res = residuals(FAMILIES[name]())
    assert {key: is_identically_zero(val) for key, val in res.items()} == {key: True for key in res}


def test_residual_check_detects_a_wrong_solution():
    sol = free_end.solve()
    wrong = type(sol)(sol.problem, sol.denominator, {**sol.slope, f0: -sol.slope[f0]}, sol.deflection)
    assert not is_identically_zero(residuals(wrong)["theta"])


# --- an independent solver: Krylov-Duncan basis, numeric 4x4 system, 50 digits --------------

def _kd(z):
    """Krylov-Duncan functions and their z-derivatives up to third order, at z."""
    ch, c, sh, s = mp.cosh(z), mp.cos(z), mp.sinh(z), mp.sin(z)
    K = [(ch + c) / 2, (sh + s) / 2, (ch - c) / 2, (sh - s) / 2]
    # d/dz cycles K1 -> K4 -> K3 -> K2 -> K1
    order = {0: 3, 3: 2, 2: 1, 1: 0}
    derivs = [K]
    for _ in range(3):
        derivs.append([derivs[-1][order[i]] for i in range(4)])
    return derivs


def _numeric_tip(bcs, pars, load):
    """Solve u'''' = kappa^4 u + q0/EI on [0, L] with the Krylov-Duncan basis; return (u(L), u'(L))."""
    Lv, kv, bv = pars["L"], pars["k"], pars["beta"]
    EIv, kap = kv * Lv**3 / 3, bv / Lv
    part = -load / (EIv * kap**4)  # constant particular solution
    D = _kd(bv)
    # u = sum a_i K_i(kappa x) + part; clamped end: K1(0) = 1, others 0 with their derivatives ->
    # u(0) = a1 + part = 0, u'(0) = kappa a2 = 0.  Unknowns a3, a4 remain.
    a1 = -part

    def U(n, a3, a4):
        return kap**n * (a1 * D[n][0] + a3 * D[n][2] + a4 * D[n][3]) + (part if n == 0 else 0)

    rows, rhs = [], []
    for bc in bcs:
        base = bc(lambda n: U(n, 0, 0), EIv)
        r3 = bc(lambda n: U(n, 1, 0), EIv) - base
        r4 = bc(lambda n: U(n, 0, 1), EIv) - base
        rows.append([r3, r4])
        rhs.append(-base)
    a3, a4 = mp.lu_solve(mp.matrix(rows), mp.matrix(rhs))
    return U(0, a3, a4), U(1, a3, a4)


@pytest.mark.parametrize("seed", range(4))
def test_elastic_contact_matches_independent_krylov_duncan_solution(seed):
    import random
    rng = random.Random(seed)
    mp.mp.dps = 50
    pars = {"L": mp.mpf(rng.uniform(0.5, 2)), "k": mp.mpf(rng.uniform(0.5, 2)), "beta": mp.mpf(rng.uniform(0.3, 12))}
    sp_vals = {"k1": rng.uniform(0.1, 50), "k2": rng.uniform(0.1, 50), "H": rng.uniform(0.05, 0.5),
               "d1": rng.uniform(-1, 1), "d2": rng.uniform(-1, 1), "f0": rng.uniform(-1, 1), "q0": rng.uniform(-1, 1)}
    v = {key: mp.mpf(val) for key, val in sp_vals.items()}
    bcs = [lambda U, EI: EI * U(2) - v["k2"] * v["H"] * (v["d2"] - v["H"] * U(1)),
           lambda U, EI: EI * U(3) - (-v["f0"] + v["k1"] * (U(0) - v["d1"]))]
    _, theta_num = _numeric_tip(bcs, pars, v["q0"])
    sol = elastic_contact.solve()
    theta = sum(sol.theta(dv) * dv for dv in (d1, d2, f0, q0))
    subs = {L: pars["L"], k: pars["k"], beta: pars["beta"], k1: v["k1"], k2: v["k2"], H: v["H"],
            d1: v["d1"], d2: v["d2"], f0: v["f0"], q0: v["q0"]}
    theta_sym = sp.lambdify(list(subs), theta, "mpmath")(*subs.values())
    assert abs(theta_sym - theta_num) <= mp.mpf(10) ** -40 * max(1, abs(theta_num))


# --- limits between families --------------------------------------------------------------------

def _same(a, b):
    return compare(a, b).is_(1)


def test_k2_to_zero_gives_frictionless_contact():
    el, fr = elastic_contact.solve(), frictionless.solve()
    for drive in (d1, f0, q0):
        assert _same(el.theta(drive).subs(k2, 0), fr.theta(drive))
    assert param_limit(el.theta(d2), k2, 0) == 0


def test_stiff_frictionless_contact_gives_pinned_and_stiff_families():
    fr = frictionless.solve()
    assert _same(param_limit(fr.theta(q0), k1, sp.oo), pinned.solve().theta(q0))
    assert _same(param_limit(fr.theta(d1), k1, sp.oo), frictionless.solve_stiff().theta(d1))
    assert _same(param_limit(indentation.solve().theta(d1), k1, sp.oo), indentation.solve_stiff().theta(d1))


def test_k1_to_zero_gives_free_end():
    el = elastic_contact.solve()
    for drive in (f0, q0):
        assert _same(el.theta(drive).subs({k1: 0, k2: 0}), free_end.solve().theta(drive))


def test_indentation_is_frictionless_contact_without_load():
    for drive in (d1, f0):
        assert _same(indentation.solve().theta(drive), frictionless.solve().theta(drive))


def test_sliding_friction_static_slope_is_that_of_a_tip_moment():
    # A moment f_l H at the tip of a static cantilever turns it by f_l H L / EI = 3 f_l H / (k L^2).
    from pfmdyn.derivations.limits import low_frequency
    static = low_frequency(sliding_friction.solve().theta(f_l))
    assert sp.simplify(static - 3 * H / (k * L**2)) == 0


def test_torsion_solutions_satisfy_their_equations():
    x = torsion.x
    sol, _ = torsion.general_solution()
    assert sp.simplify(sol.diff(x, 2) + torsion.xi**2 * sol) == 0
    twist = torsion.solve_elastic().tip_twist
    assert sp.simplify(sp.limit(twist, torsion.k2t, sp.oo) - torsion.d3 / H) == 0
