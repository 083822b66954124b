"""Generated closed-form relations against hand-typed ones, and no re-definitions under pfmdyn/."""
from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from pfmdyn.generated import characteristic, formulas

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


def _generated_names():
    names = set()
    for path in GENERATED.glob("*.py"):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
                names.add(node.name)
    return names


def test_no_module_under_pfmdyn_redefines_a_generated_formula():
    """A function named like a generated one must call it (e.g. to check its input), not retype it."""
    names = _generated_names() - {"slope", "deflection", "twist", "characteristic"}
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
                                  "EPSILON_0 * width / H**2", "2 * v_null * part(slope)"])
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
