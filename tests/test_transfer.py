"""Public numeric API: static limits, cross-family consistency, validation, physical units."""
from __future__ import annotations

import inspect
import math

import numpy as np
import pytest
import sympy as sp

import pfmdyn
from pfmdyn import Cantilever
from pfmdyn.errors import UserError
from pfmdyn.derivations import elastic_contact, families
from pfmdyn.derivations.beam import H, L, beta, d1, d2, f0, k, k1, k2, q0
from pfmdyn.generated.characteristic import BETA1_FREE, BETA1_FREE_STR

P = dict(k=2.0, k1=30.0, k2=500.0, H=8e-6, L=1.5e-4)
BETAS = np.logspace(-6, 3, 301)


def test_elastic_matches_sympy_transfer_at_a_point():
    """Same ratios and signs as derivations.elastic_contact.transfer() (Eq. 5)."""
    t = elastic_contact.transfer()
    subs = {beta: sp.Rational(37, 10), k: 2, k1: 30, k2: 500, H: sp.Rational(8, 10**6),
            L: sp.Rational(15, 10**5)}
    got = pfmdyn.tip_slope_transfer(3.7, **P)
    for drive, value in zip((d1, d2, f0, q0), got):
        assert float(value) == pytest.approx(float(sp.N(t[drive].subs(subs), 30)), rel=1e-13)


def test_static_limits():
    b = 1e-6
    e = pfmdyn.tip_slope_transfer(b, k=1.0, k1=0.0, k2=0.0, H=1e-5, L=2.0)
    f = pfmdyn.free_end_transfer(b, k=1.0, L=2.0)
    assert float(e.local_force) == pytest.approx(float(f.local_force), rel=1e-12)   # k1=k2=0: free
    assert float(f.local_force) == pytest.approx(3 / (2 * 1.0 * 2.0), rel=1e-12)
    assert float(pfmdyn.pinned_transfer(b, k=4.0).distributed_load) == pytest.approx(-1 / 64, rel=1e-12)
    assert float(pfmdyn.sliding_friction_transfer(b, k=1.0, H=2.0, L=1.0).friction) == pytest.approx(6.0)


def test_elastic_reduces_to_free_end_and_frictionless():
    """k1 = k2 = 0 is the free cantilever; k2 = 0 is frictionless contact, at every beta."""
    e = pfmdyn.tip_slope_transfer(BETAS, k=2.0, k1=0.0, k2=0.0, H=1e-5, L=1e-4)
    f = pfmdyn.free_end_transfer(BETAS, k=2.0, L=1e-4)
    np.testing.assert_allclose(e.local_force, f.local_force, rtol=1e-11)
    np.testing.assert_allclose(e.distributed_load, f.distributed_load, rtol=1e-11)
    e = pfmdyn.tip_slope_transfer(BETAS, k=2.0, k1=7.0, k2=0.0, H=1e-5, L=1e-4)
    fr = pfmdyn.frictionless_transfer(BETAS, k=2.0, k1=7.0, L=1e-4)
    for a, b in [(e.vertical, fr.vertical), (e.local_force, fr.local_force),
                 (e.distributed_load, fr.distributed_load)]:
        scale = np.abs(a) + np.abs(b)
        assert np.all(np.abs(a - b) <= 1e-10 * scale + 1e-300)


def test_stiff_limits():
    """k1 -> oo: frictionless and indentation approach their stiff forms."""
    b = np.array([0.5, 2.0, 7.0])
    soft = pfmdyn.frictionless_transfer(b, k=1.0, k1=1e9, L=1e-4)
    stiff = pfmdyn.frictionless_stiff_transfer(b, k=1.0, L=1e-4)
    np.testing.assert_allclose(soft.vertical, stiff.vertical, rtol=1e-6)
    ind = pfmdyn.indentation_transfer(b, k=1.0, k1=1e9, L=1e-4)
    np.testing.assert_allclose(ind.vertical, pfmdyn.indentation_stiff_transfer(b, k=1.0, L=1e-4).vertical,
                               rtol=1e-6)


def test_torsion():
    z = np.array([1e-6, 0.3, 1.2, 40.0])
    np.testing.assert_allclose(pfmdyn.torsion_force_transfer(z, L=2e-4).lateral,
                               np.tan(z) * 2e-4 / z, rtol=1e-13)
    t = pfmdyn.torsion_elastic_transfer(z, k2t=3e8, H=1e-5, L=2e-4).lateral
    ref = 3e8 * np.sin(z) / (1e-5 * 3e8 * np.sin(z) + z / 2e-4 * np.cos(z))
    np.testing.assert_allclose(t, ref, rtol=1e-13)


def test_complex_beta_and_broadcasting():
    b = BETAS * (1 - 1e-3j)
    k1s = np.array([[1.0], [100.0]])
    with np.errstate(all="raise"):
        out = pfmdyn.tip_slope_transfer(b, k=1.0, k1=k1s, k2=10.0, H=1e-5, L=1e-4)
    assert out.vertical.shape == (2, BETAS.size) and out.vertical.dtype == complex
    assert all(np.all(np.isfinite(v)) for v in out)


@pytest.mark.parametrize("bad,match", [
    (dict(k=-1.0), "k must be positive"),
    (dict(k1=float("nan")), "k1 must be finite"),
    (dict(k2=-3.0), "k2 must be non-negative"),
    (dict(H=0.0), "H must be positive"),
])
def test_validation(bad, match):
    args = {**P, **bad}
    with pytest.raises(ValueError, match=match) as info:
        pfmdyn.tip_slope_transfer(1.0, **args)
    assert "\n" not in str(info.value)


def test_validation_of_beta():
    for b in [0.0, -1.0, float("nan"), [1.0, np.inf]]:
        with pytest.raises(ValueError, match="beta"):
            pfmdyn.free_end_transfer(b, k=1.0, L=1e-4)
    with pytest.raises(ValueError, match="output"):
        pfmdyn.indentation_transfer(1.0, k=1.0, k1=1.0, L=1.0, output="phase")


def test_cantilever_units():
    c = Cantilever.from_geometry(length=2e-4, width=3e-5, thickness=2e-6,
                                 youngs_modulus=1.7e11, density=2330.0)
    assert c.spring_constant == pytest.approx(1.7e11 * 3e-5 * 8e-18 / (4 * 8e-12))
    assert float(c.beta(c.free_resonance).real) == pytest.approx(BETA1_FREE, rel=1e-15)
    assert BETA1_FREE_STR.startswith("1.8751040687119611664")
    # beta**4 = omega**2 rho S L**4 / EI, directly from the geometry.
    omega = 2 * math.pi * 3e5
    ei = 1.7e11 * 3e-5 * 8e-18 / 12
    expected = (omega**2 * 2330.0 * 3e-5 * 2e-6 * 2e-4**4 / ei) ** 0.25
    assert float(c.beta(3e5).real) == pytest.approx(expected, rel=1e-13)
    with pytest.raises(UserError, match="length"):
        Cantilever(1.0, 1e5, -1.0)


def test_free_resonance_in_hz():
    """With losses the free response peaks at f1 and is complex."""
    c = Cantilever(1.0, 7e4, 1e-4, quality_factor=200.0)
    f = np.linspace(5e4, 9e4, 4001)
    r = c.free_response(f).local_force
    assert r.dtype == complex
    assert f[np.argmax(np.abs(r))] == pytest.approx(7e4, rel=1e-3)
    contact = c.elastic_response(f, k1=50.0, k2=10.0, H=1e-5)
    assert np.all(np.isfinite(contact.vertical))


@pytest.mark.parametrize("row", [f for f in families.FAMILIES if f.method], ids=lambda f: f.method)
def test_cantilever_methods_follow_the_registry(row):
    """Each registry row with a ``method`` is a Cantilever method: the wrapper at c.beta(f) when lossless."""
    c = Cantilever(2.0, 7e4, 1.5e-4)
    extra = [p for p in row.parameters if p not in ("k", "L")]
    method = getattr(c, row.method)
    keywords = [p.name for p in inspect.signature(method).parameters.values() if p.default is p.empty
                and p.kind is p.KEYWORD_ONLY]
    assert keywords == extra
    f = np.array([3e3, 7.1e4, 9e5])
    values = {p: P[p] for p in extra}
    wrapper = getattr(pfmdyn, row.function)(c.beta(f).real, **{"k": 2.0, "L": 1.5e-4, **values}
                                            if "L" in row.parameters else {"k": 2.0, **values})
    np.testing.assert_allclose(np.array(method(f, **values)), np.array(wrapper), rtol=1e-12)


def test_cantilever_losses_are_the_derived_complex_modulus():
    """E -> E (1 + i/Q): beta**4 / (1 + i/Q) and k (1 + i/Q), typed here independently; the maps
    (pfmdyn.maps.beam) apply the same model by dividing the contact springs by 1 + i/Q instead."""
    from pfmdyn.maps.beam import BeamMapModel

    q, k_, f1, length = 40.0, 3.0, 7e4, 2e-4
    c = Cantilever(k_, f1, length, quality_factor=q)
    f = np.linspace(2e5, 6e5, 7)
    beta_q = BETA1_FREE * np.sqrt(f / f1) * (1 + 1j / q) ** -0.25
    expected = pfmdyn.transfer.evaluate("elastic_contact", beta_q,
                                        dict(k=k_ * (1 + 1j / q), k1=300.0, k2=60.0, H=1e-5, L=length))
    got = c.elastic_response(f, k1=300.0, k2=60.0, H=1e-5)
    np.testing.assert_allclose(np.array(got), np.array(expected), rtol=1e-12)
    maps = BeamMapModel(Cantilever(k_, f1, length, tip_height=1e-5), f)
    np.testing.assert_allclose(maps.shape_functions(np.array([300.0]), np.array([q]), np.array([60.0]))[0],
                               got.vertical, rtol=1e-10)
    # The free mode's half-power width is f1/Q (to O(1/Q**2)): the loss factor is the mode's 1/Q.
    fine = np.linspace(0.9 * f1, 1.1 * f1, 20001)
    amp = np.abs(Cantilever(k_, f1, length, quality_factor=q).free_response(fine).local_force)
    band = fine[amp >= amp.max() / np.sqrt(2)]
    assert (band[-1] - band[0]) == pytest.approx(f1 / q, rel=0.02)
