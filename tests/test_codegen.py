"""Generated code against the SymPy source: accuracy, staleness check, and why it is needed."""
from __future__ import annotations

import importlib
import math
import shutil
import subprocess
import sys
from functools import lru_cache

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from pfmdyn import cli
from pfmdyn.commands.codegen import compare, stale_files
from pfmdyn.derivations import codegen
from pfmdyn.derivations.beam import H, L, beta, k, k1, k2
from pfmdyn.derivations.tilt import kll, kvl, kvv
from pfmdyn.derivations.tip_mass import mu
from pfmdyn.derivations.torsion import k2t
from pfmdyn.generated import characteristic

TOL = 1e-12

CASES = [(fam, fn) for fam in codegen.families() for fn in fam.functions]
IDS = [f"{fam.module}.{fn.name}" for fam, fn in CASES]


@lru_cache(maxsize=None)
def _reference(module: str, function: str):
    """mpmath callables for the denominator, each numerator, and their term magnitudes."""
    fam = next(f for f in codegen.families() if f.module == module)
    fn = next(f for f in fam.functions if f.name == function)
    args = (fam.variable, *fam.parameters)

    def compile_(expr):
        value = sp.lambdify(args, expr, "mpmath")
        parts = [(sp.lambdify(args, coeff, "mpmath"),
                  sp.lambdify(args, codegen.from_atoms(h, fam.variable), "mpmath"),
                  [sp.lambdify(args, codegen.from_atoms(t, fam.variable), "mpmath")
                   for t in sp.Add.make_args(h)])
                 for coeff, h in codegen.split(expr, fam.variable, fam.parameters)]

        def magnitude(*a):
            # Sum over parameter groups of |coefficient| * |h|; where the closed form is used
            # (|var| >= 1) the terms inside h count too: zeros of h are rounded relative to them.
            total = mp.mpf(0)
            for coeff, h, terms in parts:
                size = abs(h(*a))
                if abs(a[0]) >= 1:
                    size += sum(abs(t(*a)) for t in terms)
                total += abs(coeff(*a)) * size
            return total

        return value, magnitude

    return fam, compile_(fam.denominator), [compile_(e) for _, e in fn.outputs]


def check_against_mpmath(module, function, var_values, params):
    fam, (den, den_mag), outputs = _reference(module, function)
    generated = getattr(importlib.import_module(f"pfmdyn.generated.{module}"), function)
    with np.errstate(all="raise"):
        values = generated(np.asarray(var_values), *params)
    for i, v in enumerate(var_values):
        # Guard digits: the raw form cancels like beta**6 at small beta and grows like e**beta.
        with mp.workdps(60 + int(abs(v.real) / math.log(10))):
            a = (mp.mpc(v.real, v.imag), *[mp.mpf(p) for p in params])
            d = den(*a)
            for (num, num_mag), got in zip(outputs, values):
                ref = num(*a) / d
                bound = TOL * (num_mag(*a) + abs(ref) * den_mag(*a)) / abs(d)
                err = abs(mp.mpc(complex(np.broadcast_to(got, np.shape(var_values))[i])) - ref)
                assert err <= bound, (module, function, v, params, float(err), float(bound))


def _params(fam, draw_or_rng):
    """Physical parameters in SI: k [0.01, 100] N/m, stiffness ratios 1e-3..1e3, H, L in um."""
    u = draw_or_rng
    kk = 10 ** u(-2, 2)
    values = {k: kk, k1: kk * 10 ** u(-3, 3), H: 10 ** u(-6, -4.5), L: 10 ** u(-5, -3.3)}
    values[k2] = kk * values[L] ** 2 / values[H] ** 2 * 10 ** u(-3, 3)
    values[k2t] = 10 ** u(-3, 3) / (values[H] * values[L])
    values.update({mu: 10 ** u(-3, 0), kvv: values[k1], kll: values[k2],
                   kvl: 0.3 * (values[k1] * values[k2]) ** 0.5})
    return tuple(values[p] for p in fam.parameters)


@pytest.mark.parametrize("fam,fn", CASES, ids=IDS)
def test_grid_real(fam, fn):
    """Log-spaced real grid over [1e-6, 1e3], including the switch point and 710 (cosh overflow)."""
    rng = np.random.default_rng(0)
    grid = np.concatenate([np.logspace(-6, 3, 40), [codegen_switch(fam), 710.5, 1e3]])
    params = _params(fam, lambda a, b: rng.uniform(a, b))
    check_against_mpmath(fam.module, fn.name, grid, params)


def codegen_switch(fam):
    return importlib.import_module(f"pfmdyn.generated.{fam.module}").SWITCH or 1.0


@pytest.mark.parametrize("fam,fn", CASES, ids=IDS)
@settings(max_examples=40, deadline=None, derandomize=True)
@given(data=st.data())
def test_property_against_mpmath(fam, fn, data):
    """Random beta in [1e-6, 1e3] (real or with a small imaginary part), random parameters."""
    u = lambda a, b: data.draw(st.floats(a, b))  # noqa: E731
    logs = data.draw(st.lists(st.floats(-6, 3), min_size=1, max_size=6))
    damping = data.draw(st.sampled_from([0.0, 1e-3, -1e-2]))
    values = np.array([10**x * complex(1, damping) for x in logs])
    if damping == 0.0:
        values = values.real
    check_against_mpmath(fam.module, fn.name, values, _params(fam, u))


def test_broadcasting_over_parameters():
    from pfmdyn.generated import elastic_contact
    b = np.logspace(-3, 2, 7)
    k1s = np.array([[1.0], [10.0], [100.0]])
    out = elastic_contact.slope(b, 1.0, k1s, 2.0, 1e-5, 1e-4)
    assert all(o.shape == (3, 7) for o in out)
    single = elastic_contact.slope(b, 1.0, 10.0, 2.0, 1e-5, 1e-4)
    np.testing.assert_array_equal(out[0][1], single[0])


def test_headers_and_gitattributes():
    for path in sorted(codegen.GENERATED.glob("*.py")):
        if path.name == "__init__.py":
            continue
        head = path.read_text(encoding="utf-8").splitlines()[:3]
        assert head[0] == "# generated — do not edit."
        assert "pfmdyn codegen" in head[1] and "derivations/" in head[1]
        assert f"SymPy {sp.__version__}" in head[2] and "sha256" in head[2]
    attrs = (codegen.GENERATED.parent / ".gitattributes").read_text()
    assert "generated/** linguist-generated=true" in attrs


@pytest.fixture(scope="module")
def fresh():
    """One fresh generation shared by the tests below (rendering takes most of a minute)."""
    return codegen.render_all()


def test_check_passes(fresh, monkeypatch, capsys):
    result = compare(codegen.GENERATED, fresh)
    assert result.ok, (sorted(result.diffs), result.orphans)
    monkeypatch.setattr(codegen, "render_all", lambda: fresh)
    assert cli.main(["codegen", "--check"]) == 0
    assert "up to date" in capsys.readouterr().out


def test_check_fails_on_hand_edit_with_the_diff(fresh, tmp_path, capsys, monkeypatch):
    copy = tmp_path / "generated"
    shutil.copytree(codegen.GENERATED, copy)
    path = copy / "pinned.py"
    path.write_text(path.read_text().replace("_r = 1.0 /", "_r = 1.0001 /"))
    monkeypatch.setattr(codegen, "render_all", lambda: fresh)
    assert cli.main(["codegen", "--check", "--output", str(copy)]) == 1
    out = capsys.readouterr().out
    assert "--- pinned.py (committed)\n+++ pinned.py (fresh)" in out
    assert "\n-    _r = 1.0001 / (" in out and "\n+    _r = 1.0 / (" in out
    assert "pinned.py; run `pfmdyn codegen`" in out and "orphan" not in out
    assert stale_files(copy) == ["pinned.py"]


def test_check_fails_on_orphan(fresh, tmp_path, capsys, monkeypatch):
    copy = tmp_path / "generated"
    shutil.copytree(codegen.GENERATED, copy)
    # A module left behind when its family was renamed: nothing writes it any more.
    shutil.copy(copy / "pinned.py", copy / "pinned_old.py")
    monkeypatch.setattr(codegen, "render_all", lambda: fresh)
    assert cli.main(["codegen", "--check", "--output", str(copy)]) == 1
    out = capsys.readouterr().out
    assert "orphan file(s)" in out and "pinned_old.py" in out
    assert "---" not in out and "stale" not in out
    assert compare(copy, fresh).orphans == ["pinned_old.py"]


def test_generation_is_deterministic(fresh, tmp_path):
    codegen.write(tmp_path, fresh)
    assert codegen.write(tmp_path) == []


def test_examples_match_the_sympy_expression():
    """Each transfer module's doctest values agree with the mpmath reference of this file."""
    import ast
    import doctest
    for fam, fn in CASES:
        function = getattr(importlib.import_module(f"pfmdyn.generated.{fam.module}"), fn.name)
        first = doctest.DocTestParser().get_examples(function.__doc__)[0]
        call = first.source[first.source.index(f" {fn.name}(") + len(fn.name) + 1:first.source.rindex("]")]
        args = ast.literal_eval(call)
        shown = [float(v) for v in ast.literal_eval(first.want)]
        _, (den, _), outputs = _reference(fam.module, fn.name)
        with mp.workdps(30):
            a = [mp.mpf(x) for x in args]
            values = [num(*a) / den(*a) for num, _ in outputs]
        assert shown == pytest.approx([float(v) for v in values], rel=1e-6), (fam.module, fn.name)


def test_naive_lambdify_fails_where_generated_holds():
    """Why codegen: the raw expression cancels at small beta and overflows at large beta."""
    fam, fn = next((f, fn) for f, fn in CASES if f.module == "elastic_contact")
    expr = dict(fn.outputs)["q0"] / fam.denominator      # elastic contact, per unit q0
    args = (beta, k, k1, k2, H, L)
    naive = sp.lambdify(args, expr, "numpy")
    params = (1.0, 10.0, 1e3, 1e-5, 1e-4)
    from pfmdyn.generated import elastic_contact
    for b, dps in [(1e-5, 80), (800.0, 400)]:
        with mp.workdps(dps):
            ref = complex(sp.lambdify(args, expr, "mpmath")(mp.mpf(b), *map(mp.mpf, params)))
        with np.errstate(all="ignore"):
            bad = complex(naive(b, *params))
        with np.errstate(all="raise"):
            good = complex(elastic_contact.slope(b, *params)[3])
        assert not (abs(bad - ref) <= 1e-3 * abs(ref)), (b, bad, ref)
        assert abs(good - ref) <= 1e-13 * abs(ref), (b, good, ref)


def test_characteristic_matches_denominator():
    """Scaled dimensionless characteristic function vs the SymPy denominator, in mpmath."""
    for name, _, den, var in codegen.characteristic_families():
        expr = codegen.dimensionless(den, var)
        params = {p: sp.Rational(3, 7) for p in expr.free_symbols - {var}}
        f = characteristic.FAMILIES[name]
        assert sorted(map(str, params)) == sorted(characteristic.PARAMETERS[name])
        scale = sp.cosh(var) if expr.has(sp.cosh, sp.sinh) else 1
        for zv in ["0.3", "2.5", "40"]:
            with mp.workdps(50):
                kwargs = {str(p): mp.mpf(3) / 7 for p in params}
                ref = sp.N((expr / scale).subs(params).subs(var, sp.Rational(zv)), 50)
                got = f(mp.mpf(zv), mp, **kwargs)
                assert abs(got - mp.mpf(str(ref))) <= mp.mpf(10) ** -40 * (1 + abs(got))


def test_characteristic_backends_and_certified_roots():
    """The same code runs in NumPy, mpmath and python-flint; arb_series isolates the free roots."""
    import flint
    z = np.array([1.0, 5.0, 900.0])
    # exp(-900) underflows to 0, harmlessly (it only feeds sech); anything else must not occur.
    with np.errstate(all="raise", under="ignore"):
        as_numpy = characteristic.elastic(z, np, k1_over_k=2.0, k2_ratio=0.5)
    as_mp = [characteristic.elastic(mp.mpf(v), mp, k1_over_k=2, k2_ratio=mp.mpf("0.5")) for v in z]
    np.testing.assert_allclose(as_numpy, [float(v) for v in as_mp], rtol=1e-13)
    flint.ctx.prec = 128
    roots = flint.arb_series.find_roots(lambda s: characteristic.free(s, characteristic.FLINT), 1, 12)
    assert len(roots) == 4
    a, b = roots[0]
    assert float(a) < characteristic.BETA1_FREE < float(b)
    assert mp.mpf(characteristic.BETA1_FREE_STR) == pytest.approx(1.875104068711961166, rel=1e-17)


def test_numeric_path_does_not_import_sympy():
    code = ("import sys, pfmdyn, pfmdyn.cantilever, pfmdyn.generated.characteristic;"
            "pfmdyn.tip_slope_transfer(1.0, k=1, k1=1, k2=1, H=1e-5, L=1e-4);"
            "sys.exit('sympy' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_check_on_missing_folder_is_a_user_error(tmp_path, capsys):
    assert cli.main(["codegen", "--check", "--output", str(tmp_path / "nowhere")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
