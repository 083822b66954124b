"""Resonance branches against contact stiffness (pfmdyn.branches, pfmdyn branches)."""
from __future__ import annotations

import csv

import mpmath as mp
import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.roots import branches
from pfmdyn.roots.core import family_roots


@pytest.mark.parametrize("family, fixed", [("indentation", {}), ("elastic", {"k1_over_k": "0"}),
                                           ("torsion-elastic", {})])
def test_sweep_matches_certified_roots(family, fixed):
    stiffness = np.array([1e-3, 0.7, 30.0, 1e6])
    z = branches.sweep(family, stiffness, 3, **fixed)
    name = branches.SWEPT[family]
    for s, row in zip(stiffness, z):
        exact = family_roots(family, 3, 17, **fixed, **{name: repr(float(s))}).roots
        np.testing.assert_allclose(row, [float(v) for v in exact], rtol=2e-15)


def test_branches_rise_between_their_limits():
    stiffness = np.logspace(-3, 6, 200)
    z = branches.sweep("indentation", stiffness, 5)
    soft, stiff = branches.branch_limits("indentation", 5)
    assert np.all(np.diff(z, axis=0) >= 0)
    assert np.all((z >= soft - 1e-12) & (z <= stiff + 1e-12))
    assert np.all(stiff[:-1] < soft[1:])             # the frequency gaps of the paper
    free, pinned = (np.array([float(r) for r in family_roots(f, 5, 17).roots]) for f in ("free", "pinned"))
    np.testing.assert_allclose(soft, free, rtol=1e-15)
    np.testing.assert_allclose(stiff, pinned, rtol=1e-15)


def test_guided_limit_of_longitudinal_coupling():
    """k1 = 0, k2 -> oo holds the tip slope: tan z = -tanh z."""
    _, stiff = branches.branch_limits("elastic", 3, k1_over_k="0")
    with mp.workdps(30):
        exact = [mp.findroot(lambda z: mp.tan(z) + mp.tanh(z), (4 * n - 1) * mp.pi / 4) for n in (1, 2, 3)]
    np.testing.assert_allclose(stiff, [float(v) for v in exact], rtol=1e-15)


def test_crossover_is_midway_and_moves_up_with_mode():
    s, mid = branches.crossovers("indentation", 4)
    z = branches.sweep("indentation", s, 4)
    np.testing.assert_allclose(np.diag(z), mid, rtol=1e-13)
    assert np.all(np.diff(s) > 0)


def test_cli_writes_png_and_csv(tmp_path, capsys):
    png, table = tmp_path / "b.png", tmp_path / "b.csv"
    assert cli.main(["branches", "torsion-elastic", "--plot", str(png), "--csv", str(table), "--points", "40"]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = list(csv.reader(table.open()))
    assert rows[0][0] == "k2t_HL" and len(rows) == 41 and len(rows[0]) == 11
    assert float(rows[1][0]) == pytest.approx(1e-3) and float(rows[-1][0]) == pytest.approx(1e6)
    assert "crossover of mode 5" in capsys.readouterr().out


@pytest.mark.parametrize("argv, text", [
    (["branches", "free", "--out", "x.png"], "no branches"),
    (["branches", "indentation", "--out", "x.png", "--points", "1"], "at least 2"),
    (["branches", "indentation", "--out", "x.png", "--k1-over-k", "1"], "fixed only"),
    (["branches", "elastic", "--out", "x.png", "--k1-over-k", "-1"], "non-negative")])
def test_cli_errors_are_one_line(argv, text, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and text in err
