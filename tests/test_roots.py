"""Certified roots (pfmdyn.roots, pfmdyn roots): accuracy, asymptotics, limits, cross-checks, CLI."""
from __future__ import annotations

import json

import mpmath as mp
import pytest
import sympy as sp

from pfmdyn import cli
from pfmdyn.derivations import free_end, pinned, torsion
from pfmdyn.derivations.beam import L, beta, k
from pfmdyn.derivations.roots import certified_roots
from pfmdyn.generated import characteristic
from pfmdyn.roots.core import FAMILIES, family_roots

PARAMS = {"elastic": {"k1_over_k": "3.5", "k2_ratio": "0.25"}, "frictionless": {"k1_over_k": "2"},
          "indentation": {"k1_over_k": "1e6"}, "torsion-elastic": {"k2t_HL": "0.1"}}


def _residual(family, root, params, dps):
    with mp.workdps(dps + 20):
        z = mp.mpf(root)
        kw = {n: mp.mpf(v) for n, v in params.items()}
        f = (lambda z, m: m.cos(z)) if family == "torsion-force" else characteristic.FAMILIES[family]
        slope = mp.diff(lambda t: f(t, mp, **kw), z)
        return abs(f(z, mp, **kw) / slope / z)        # relative error of the root


@pytest.mark.parametrize("family", list(FAMILIES))
def test_roots_satisfy_their_equation(family):
    params = PARAMS.get(family, {})
    result = family_roots(family, 4, 40, **params)
    assert result.certified, result.reason
    for root, (lo, hi) in zip(result.roots, result.intervals):
        assert len(root.replace(".", "").lstrip("0")) == 40
        ulp = mp.mpf(root) * mp.mpf(10) ** -39
        assert mp.mpf(lo) <= mp.mpf(hi) and abs(mp.mpf(lo) - mp.mpf(root)) <= ulp
        assert _residual(family, root, params, 40) < mp.mpf(10) ** -39


def test_hundred_digits_and_interval_holds_the_root():
    result = family_roots("free", 2, 100)
    with mp.workdps(130):
        exact = mp.findroot(lambda b: mp.cos(b) + mp.sech(b), mp.mpf(result.roots[1]))
        lo, hi = map(mp.mpf, result.intervals[1])
        assert lo <= exact <= hi
        assert abs(mp.mpf(result.roots[1]) - exact) <= exact * mp.mpf(10) ** -99


@pytest.mark.parametrize("family, asymptote", [("free", lambda n: (2 * n - 1) * mp.pi / 2),
                                               ("pinned", lambda n: (4 * n + 1) * mp.pi / 4)])
def test_roots_approach_asymptotes_exponentially(family, asymptote):
    roots = family_roots(family, 8, 30).roots
    with mp.workdps(30):
        errors = [abs(mp.mpf(r) - asymptote(n)) for n, r in enumerate(roots, 1)]
        for n in range(3, 8):          # error * exp(z) stays bounded: decay like exp(-z) or faster
            assert errors[n] * mp.exp(mp.mpf(roots[n])) < 3
            assert errors[n] < errors[n - 1]


def test_torsion_force_roots_are_odd_multiples_of_half_pi():
    roots = family_roots("torsion-force", 5, 25).roots
    with mp.workdps(30):
        for n, r in enumerate(roots, 1):
            assert abs(mp.mpf(r) - (2 * n - 1) * mp.pi / 2) < mp.mpf(10) ** -23


@pytest.mark.parametrize("family, key", [("indentation", "k1_over_k"), ("frictionless", "k1_over_k")])
def test_contact_families_reach_free_and_pinned_limits(family, key):
    free, sup = (list(map(mp.mpf, family_roots(f, 3, 20).roots)) for f in ("free", "pinned"))
    soft = list(map(mp.mpf, family_roots(family, 3, 20, **{key: "1e-9"}).roots))
    stiff = list(map(mp.mpf, family_roots(family, 3, 20, **{key: "1e12"}).roots))
    assert all(abs(s - f) < 1e-8 for s, f in zip(soft, free))
    assert all(abs(s - p) < 1e-7 for s, p in zip(stiff, sup))
    assert all(f < s < p for s, f, p in zip(family_roots(family, 3, 10, **{key: 10}).roots, free, sup)
               for s in [mp.mpf(s)])


def test_elastic_with_k2_zero_is_indentation():
    a = family_roots("elastic", 3, 25, k1_over_k="7", k2_ratio="0").roots
    assert a == family_roots("indentation", 3, 25, k1_over_k="7").roots


def test_engine_matches_sympy_denominators():
    """Independent path: SymPy denominators through derivations.roots vs generated functions."""
    ours = family_roots("free", 3, 20).roots
    theirs = certified_roots(free_end.solve().denominator, beta, 3, 20, {k: 1, L: 1})
    assert all(abs(mp.mpf(a) - t.value) < 1e-15 for a, t in zip(ours, theirs))
    ours = family_roots("pinned", 3, 20).roots
    theirs = certified_roots(pinned.solve().denominator, beta, 3, 20, {k: 1, L: 1})
    assert all(abs(mp.mpf(a) - t.value) < 1e-15 for a, t in zip(ours, theirs))
    z = sp.Symbol("z", positive=True)
    char = sp.expand(torsion.solve_force().denominator.subs(torsion.xi, z / L) * L)
    theirs = certified_roots(char, z, 3, 15)
    ours = family_roots("torsion-force", 3, 15).roots
    assert all(abs(mp.mpf(a) - t.value) < 1e-13 for a, t in zip(ours, theirs))


def test_uncertified_result_has_reason_and_no_numbers():
    # A function with a double root: isolation cannot prove simplicity and must say so.
    from pfmdyn.roots.core import CertificationError, certify
    with pytest.raises(CertificationError, match="isolation failed"):
        certify(lambda s: (s - 2) ** 2 * (s + 1), 1, 10, lower="0.5")


@pytest.mark.parametrize("argv, text", [
    (["roots", "nosuch"], "unknown family"), (["roots", "free", "--modes", "0"], "--modes"),
    (["roots", "free", "--digits", "0"], "--digits"), (["roots", "elastic", "--k1-over-k", "1"], "needs --k2-ratio"),
    (["roots", "indentation", "--k1-over-k", "-2"], "non-negative"), (["roots", "free", "--modes", "two"], "integer"),
    (["roots", "free", "--k2t-hl", "1"], "takes no")])
def test_cli_errors_are_one_line(argv, text, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and text in err


def test_cli_json_schema(tmp_path, capsys):
    path = tmp_path / "r.json"
    assert cli.main(["roots", "elastic", "--modes", "3", "--digits", "12", "--k1-over-k", "1e3",
                     "--k2-ratio", "0.5", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    assert set(doc["results"]) == {"root", "root_interval", "certified"}
    assert "family: elastic" in doc["notes"] and doc["results"]["certified"]["value"] is True
    assert {"parameter k1_over_k = 1e3", "parameter k2_ratio = 0.5"} <= set(doc["notes"])
    roots = doc["results"]["root"]["value"]
    assert len(roots) == 3 and all(len(r.replace(".", "")) == 12 for r in roots)
    # the 12-digit strings are the correctly rounded values of the 15-digit interval ends
    assert all(len(i) == 2 and abs(mp.mpf(i[0]) - mp.mpf(r)) < 1e-10 and mp.mpf(i[0]) <= mp.mpf(i[1])
               for i, r in zip(doc["results"]["root_interval"]["value"], roots))
    assert "certified" in capsys.readouterr().out
