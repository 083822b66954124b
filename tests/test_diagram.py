"""Frequency-bias response diagrams (Section IV.2, Figs. 6-7) and the ``pfmdyn diagram`` command."""
import csv
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from pfmdyn import cli
from pfmdyn.cantilever import BETA1_FREE, Contact
from pfmdyn.analysis.diagram import (EPSILON_0, TABLE1, low_frequency_crossover_bias, nulling_bias,
                            response_map, table1_cantilever)
from pfmdyn.generated import characteristic

K1, H, D_EFF, F_LOC, WIDTH = 1000.0, 15e-6, 5e-12, 14e-9, 24e-6


def to_hz(lever, beta):
    """Invert ``beta = BETA1_FREE sqrt(f / f1)`` (Cantilever.beta without losses)."""
    return lever.free_resonance * (np.asarray(beta) / BETA1_FREE) ** 2


def contact_resonances_hz(lever, f_max):
    """Zeros of the frictionless characteristic function (Eq. 23's N), in Hz, below f_max."""
    ratio = K1 / lever.spring_constant
    z = np.linspace(0.5, np.sqrt(f_max / lever.free_resonance) * BETA1_FREE, 20000)
    g = characteristic.frictionless(z, np, k1_over_k=ratio)
    brackets = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
    roots = [brentq(lambda x: characteristic.frictionless(x, np, k1_over_k=ratio), z[i], z[i + 1],
                    xtol=1e-14) for i in brackets]
    return to_hz(lever, roots)


@pytest.mark.parametrize("name", ["A", "B", "C"])
def test_resonance_lines_sit_at_the_derived_roots_and_do_not_move_with_bias(name):
    lever = table1_cantilever(name)
    resonances = contact_resonances_hz(lever, 3e6)
    assert len(resonances) >= 2
    for f_n in resonances:
        frequency = np.linspace(0.99 * f_n, 1.01 * f_n, 2001)
        m = response_map(lever, frequency, [-10.0, 0.0, 3.0, 10.0], width=WIDTH, local_force=F_LOC)
        peaks = frequency[np.argmax(np.abs(m.total), axis=0)]
        step = frequency[1] - frequency[0]
        assert np.all(np.abs(peaks - f_n) <= step), (name, f_n, peaks)


@pytest.mark.parametrize("name", ["A", "B", "C"])
def test_low_frequency_crossover_bias(name):
    lever = table1_cantilever(name)
    k, length = lever.spring_constant, lever.length
    expected = 24 * k * D_EFF * H**2 / (EPSILON_0 * WIDTH * length) * K1 / abs(K1 - 8 * k)
    assert low_frequency_crossover_bias(lever, width=WIDTH) == pytest.approx(expected, rel=1e-12)
    m = response_map(lever, [10.0], [expected], width=WIDTH)   # 10 Hz: static limit
    assert abs(m.piezo_coefficient[0] / m.nonlocal_coefficient[0]) == pytest.approx(expected, rel=1e-6)
    assert m.dominance()[0, 0] == pytest.approx(0.5, rel=1e-6)


def test_bias_independent_band_and_linear_region_where_the_equations_say():
    lever = table1_cantilever("C")
    v_cross = low_frequency_crossover_bias(lever, width=WIDTH)
    frequency = np.geomspace(100.0, 20e3, 50)   # well below the first contact resonance
    bias = np.array([0.0, 0.01 * v_cross, -0.01 * v_cross, 100 * v_cross, 200 * v_cross, -200 * v_cross])
    amplitude = np.abs(response_map(lever, frequency, bias, width=WIDTH).total)
    np.testing.assert_allclose(amplitude[:, 1:3], amplitude[:, [0, 0]], rtol=0.02)   # flat band
    np.testing.assert_allclose(amplitude[:, 4] / amplitude[:, 3], 2.0, rtol=0.02)      # linear
    np.testing.assert_allclose(amplitude[:, 5] / amplitude[:, 4], 1.0, rtol=0.02)      # a V
    # A stiffer cantilever has a wider flat band: the crossover scales with k (Fig. 6 arrow).
    crossovers = [low_frequency_crossover_bias(table1_cantilever(n), width=WIDTH) for n in "ABC"]
    assert crossovers[0] > crossovers[1] > crossovers[2]


@pytest.mark.parametrize("name", ["A", "C"])
def test_dominance_is_one_at_zero_bias_and_vanishes_at_large_bias(name):
    frequency = np.linspace(1e3, 3e6, 3001)
    m = response_map(table1_cantilever(name), frequency, [0.0, 1.0, -10.0, 1e6], width=WIDTH)
    share = m.dominance()
    assert np.all(share[:, 0] == 1.0)
    assert np.all(share[:, 1] > share[:, 2]) and np.all(share[:, 2] > share[:, 3])
    # Except next to the zeros of the non-local transfer (A_q = 0: the buckling mode leaves
    # the tip slope unchanged), where the non-local part vanishes at every bias.
    nonlocal_ = m.nonlocal_coefficient.real   # real without losses
    zeros = frequency[np.nonzero(np.sign(nonlocal_[:-1]) != np.sign(nonlocal_[1:]))[0]]
    far = np.all(np.abs(frequency[:, None] - zeros[None, :]) > 0.01 * zeros, axis=1)
    assert zeros.size >= 1 and np.all(share[far, 3] < 1e-2)


@pytest.mark.parametrize("name", ["A", "B", "C"])
def test_nonlocal_share_is_enhanced_at_antiresonances_not_at_resonances(name):
    lever = table1_cantilever(name)
    anti = to_hz(lever, np.pi * np.arange(1, 5))   # zeros of A_v: sin(beta) = 0
    anti = anti[anti < 3e6]
    bias = [1.0]
    for f_a in anti:
        frequency = np.linspace(0.9 * f_a, 1.1 * f_a, 4001)
        share = response_map(lever, frequency, bias, width=WIDTH).dominance()[:, 0]
        assert abs(frequency[np.argmin(share)] - f_a) <= frequency[1] - frequency[0]
        assert share.min() < 0.05 * np.median(share)
    for f_n in contact_resonances_hz(lever, 3e6):
        share = response_map(lever, f_n * np.array([0.999, 1.001]), bias, width=WIDTH).dominance()
        assert share[0, 0] == pytest.approx(share[1, 0], abs=0.01)


@pytest.mark.parametrize("local_force", [F_LOC, 0.7e-9, -0.7e-9])
def test_local_versus_electromechanical_boundary_is_frequency_independent(local_force):
    boundary = D_EFF * K1 / abs(local_force)   # |d_eff| k1 = |F_loc| |dV|
    frequency = np.concatenate([np.geomspace(10.0, 3e6, 500),
                                contact_resonances_hz(table1_cantilever("B"), 3e6) * (1 + 1e-6)])
    m = response_map(table1_cantilever("B"), frequency, [-boundary, boundary], width=WIDTH,
                     local_force=local_force, surface_potential_v=0.0)
    shares = m.shares()
    np.testing.assert_allclose(shares[..., 0], shares[..., 2], rtol=1e-9)


def test_nulling_bias_nulls_the_signal_and_minimises_it_with_losses():
    lever = table1_cantilever("B")
    frequency = np.linspace(1e3, 3e6, 301)
    v_null = nulling_bias(lever, frequency, width=WIDTH, local_force=0.7e-9, surface_potential_v=0.3)
    m = response_map(lever, frequency, [0.0], width=WIDTH, local_force=0.7e-9, surface_potential_v=0.3)
    total = m.piezo_coefficient + (m.local_coefficient + m.nonlocal_coefficient) * (v_null - 0.3)
    assert np.all(np.abs(total) <= 1e-9 * np.abs(m.piezo_coefficient))
    lossy = table1_cantilever("B", quality_factor=30.0)
    for f in [5e4, 7e5, 2e6]:
        v0 = nulling_bias(lossy, [f], width=WIDTH)[0]
        amplitude = np.abs(response_map(lossy, [f], v0 + np.array([-1e-3, 0.0, 1e-3]), width=WIDTH).total[0])
        assert amplitude[1] < amplitude[0] and amplitude[1] < amplitude[2]


def test_validation():
    lever = table1_cantilever("A")
    with pytest.raises(ValueError, match="unknown cantilever"):
        table1_cantilever("D")
    with pytest.raises(ValueError, match="k1"):
        response_map(lever, [1e3], [0.0], width=WIDTH, k1=-1.0)
    with pytest.raises(ValueError, match="width"):
        response_map(lever, [1e3], [0.0], width=0.0)
    with pytest.raises(ValueError, match="frequency"):
        response_map(lever, [-1e3], [0.0], width=WIDTH)


def test_cli_writes_png_and_csv(tmp_path):
    png, table = tmp_path / "d.png", tmp_path / "d.csv"
    code = cli.main(["diagram", "--cantilever", "custom", "--spring-constant", "3", "--length", "225e-6",
                     "--width", "30e-6", "--thickness", "3e-6", "--kind", "rgb", "--local-force", "14e-9",
                     "--log-frequency",
                     "--frequency-points", "30", "--bias-points", "11", "--plot", str(png), "--csv", str(table)])
    assert code == 0 and png.stat().st_size > 0
    with open(table) as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 30 * 11
    assert list(rows[0]) == ["frequency_hz", "bias_v", "amplitude_m_per_v", "phase_deg",
                             "local_share", "nonlocal_share", "piezo_share"]
    for kind in ["amplitude", "phase", "dominance"]:
        assert cli.main(["diagram", "--kind", kind, "--frequency-points", "20", "--bias-points", "9",
                         "--plot", str(tmp_path / f"{kind}.png")]) == 0


@pytest.mark.parametrize("argv, message", [
    (["--cantilever", "D"], "unknown cantilever"),
    (["--cantilever", "custom", "--spring-constant", "-1", "--length", "2e-4", "--width", "3e-5", "--thickness",
      "2e-6"], "--spring-constant: spring_constant must be in"),
    (["--cantilever", "custom", "--spring-constant", "1", "--length", "2e-4", "--width", "3e-5",
      "--thickness=-2e-6"], "--thickness: thickness must be in"),
    (["--cantilever", "custom", "--spring-constant", "1", "--length", "200", "--width", "3e-5", "--thickness",
      "2e-6"], "--length: length must be in (1e-06, 0.01] m, got 200"),     # micrometres are not SI
    (["--quality-factor", "0"], "quality_factor"),
    (["--cantilever", "custom", "--spring-constant", "1"], "needs --length, --width and --thickness"),
    (["--cantilever", "B", "--spring-constant", "1"], "--spring-constant applies only to --cantilever custom"),
    (["--cantilever", "B", "--width", "3e-5", "--length", "2e-4"], "--length and --width apply only to"),
    (["--fmin", "2e6", "--fmax", "1e6"], "--fmin < --fmax"),
    (["--vmin", "1", "--vmax", "1"], "--vmin < --vmax"),
    (["--k1", "-5"], "k1"),
])
def test_cli_errors_are_one_line(tmp_path, capsys, argv, message):
    assert cli.main(["diagram", *argv, "--plot", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "x.png").exists()


def test_cli_writes_the_figure_formats_of_the_other_commands(tmp_path, capsys):
    """--plot takes .svg as calibrate's, spot's and branches' do; a format matplotlib lacks is one line."""
    small = ["--frequency-points", "3", "--bias-points", "2"]
    assert cli.main(["diagram", *small, "--plot", str(tmp_path / "x.svg")]) == 0
    assert (tmp_path / "x.svg").read_text().lstrip().startswith("<?xml")
    assert cli.main(["diagram", *small, "--plot", str(tmp_path / "x.txt")]) == 2
    assert ".txt" in capsys.readouterr().err and not (tmp_path / "x.txt").exists()


def test_table1_spring_constants_are_the_printed_ones():
    for name, (_, _, _, k) in TABLE1.items():
        assert table1_cantilever(name).spring_constant == pytest.approx(k, rel=1e-12)


def test_attractive_electrostatics_is_the_default_and_mirrors_the_nulling_bias():
    """The capacitive force is attractive (project convention): flipping its sign mirrors V_null about V_surf."""
    lever = table1_cantilever("B")
    frequency = np.array([2e3, 3e5, 9e5])
    attractive = nulling_bias(lever, frequency, width=WIDTH, local_force=0.7e-9, surface_potential_v=0.4)
    assert np.array_equal(attractive, nulling_bias(lever, frequency, width=WIDTH, local_force=0.7e-9,
                                                   surface_potential_v=0.4, electrostatic_sign=-1))
    printed = nulling_bias(lever, frequency, width=WIDTH, local_force=0.7e-9, surface_potential_v=0.4,
                           electrostatic_sign=1)
    np.testing.assert_allclose(attractive - 0.4, -(printed - 0.4), rtol=1e-12)
    with pytest.raises(ValueError, match="electrostatic_sign"):
        nulling_bias(lever, frequency, width=WIDTH, electrostatic_sign=2)


# --- the laser spot away from the free end (issue 21 item 5) --------------------------------------

sys.path.insert(0, str(Path(__file__).parent))   # the independent reference beside the tests
from segment_beam import spot_response  # noqa: E402


def _segment_beam_height(lever, f, bias, *, k1, quality_factor, local_force, surface_potential):
    """``A(f, V)`` per V_ac from the two-segment exact beam: ``(2L/3)`` times the slope at the spot
    under ``d1 = d_eff``, ``f0 = -F_loc dV`` and ``q0 = -eps0 w dV / H**2`` (attractive)."""
    loss = 1 + 1j / quality_factor                    # complex modulus E (1 + i/Q)
    beta = BETA1_FREE * np.sqrt(f / lever.free_resonance) * loss ** -0.25
    dv = bias - surface_potential
    slope = spot_response(beta, lever.spot_position, k=lever.spring_constant * loss, L=lever.length, H=H, kvv=k1,
                          d1=D_EFF, f0=-local_force * dv, q0=-EPSILON_0 * WIDTH * dv / H**2)[0]
    return 2 * lever.length / 3 * slope


@pytest.mark.parametrize("name, quality_factor", [("A", math.inf), ("B", math.inf), ("C", 40.0)])
def test_spot_away_from_the_end_matches_the_segment_beam(name, quality_factor):
    """Spot at 0.7 L: the diagram at (f, V) points below, between and above contact resonances."""
    lever = replace(table1_cantilever(name, quality_factor=quality_factor), spot_position=0.7)
    frequency = np.array([0.05, 1.3, 3.7, 9.0]) * lever.free_resonance
    bias = np.array([-7.0, 0.2, 0.5, 4.0])
    m = response_map(lever, frequency, bias, width=WIDTH, k1=K1, H=H, local_force=0.7e-9, surface_potential_v=0.2)
    for i, f in enumerate(frequency):
        for j, v in enumerate(bias):
            ref = _segment_beam_height(lever, f, v, k1=K1, quality_factor=quality_factor, local_force=0.7e-9,
                                       surface_potential=0.2)
            assert abs(m.total[i, j] - ref) <= 1e-8 * abs(ref), (f, v, m.total[i, j], ref)
    # the spot matters: the same points read at the end differ by more than 5 %
    end = response_map(replace(lever, spot_position=1.0), frequency, bias, width=WIDTH, k1=K1, H=H,
                       local_force=0.7e-9, surface_potential_v=0.2)
    assert np.max(np.abs(end.total / m.total - 1)) > 0.05


def test_spot_at_the_end_is_the_paper_diagram(tmp_path):
    """--spot-position 1 writes the old diagram byte for byte; a spot a hair before the end is continuous."""
    common = ["diagram", "--cantilever", "B", "--frequency-points", "12", "--bias-points", "5",
              "--local-force", "0.7e-9", "--log-frequency"]
    tables = []
    for extra in ([], ["--spot-position", "1"], ["--spot-position", "0.6"]):
        table = tmp_path / f"d{len(tables)}.csv"
        assert cli.main([*common, *extra, "--plot", str(tmp_path / "d.png"), "--csv", str(table)]) == 0
        tables.append(table.read_text())
    assert tables[0] == tables[1] and tables[0] != tables[2]
    lever = table1_cantilever("B")
    frequency = np.geomspace(2e3, 3e6, 40)
    paper = response_map(lever, frequency, [-3.0, 2.0], width=WIDTH, local_force=0.7e-9)
    near = response_map(replace(lever, spot_position=1 - 1e-9), frequency, [-3.0, 2.0], width=WIDTH,
                        local_force=0.7e-9)
    np.testing.assert_allclose(near.total, paper.total, rtol=1e-6)


def test_spot_at_quasi_static_frequencies_matches_the_static_beam(tmp_path, capsys):
    """Read at a spot the composed lever holds down to quasi-static frequencies (no lowest
    frequency any more): at 10 Hz its slopes are the static segment beam's to 1e-9."""
    lever = replace(table1_cantilever("A"), spot_position=0.7, tip_height=H)
    assert response_map(lever, [10.0, 1e4], [0.0], width=WIDTH).total.shape == (2, 1)
    t = lever.response(np.array([10.0]), Contact(k1=K1))
    for drive, got in (("d1", t.vertical), ("q0", t.distributed_load)):
        ref = spot_response(0.0, 0.7, k=lever.spring_constant, L=lever.length, H=H, kvv=K1, **{drive: 1.0})[0]
        assert abs(got[0] / ref - 1) < 1e-9, (drive, got[0], ref)
    with pytest.raises(ValueError, match="paper's probe"):
        low_frequency_crossover_bias(lever, width=WIDTH)
    assert cli.main(["diagram", "--spot-position", "0.7", "--fmin", "10", "--plot", str(tmp_path / "x.png")]) == 0
    assert cli.main(["diagram", "--spot-position", "1.5", "--plot", str(tmp_path / "x.png")]) == 2
    assert "--spot-position: spot_position must be in" in capsys.readouterr().err


def test_at_the_blind_spot_the_nonlocal_part_vanishes():
    """The spot where the segment beam's distributed-load slope is zero (brentq) nulls the diagram's
    non-local coefficient at that frequency, and only there (1e-6 of its value at the end)."""
    lever = table1_cantilever("B")
    f = 0.3 * lever.free_resonance
    beta = BETA1_FREE * np.sqrt(0.3)
    slope = lambda s: spot_response(beta, s, k=lever.spring_constant, L=lever.length, H=H, kvv=K1, q0=1.0)[0].real  # noqa: E731
    grid = np.linspace(0.3, 1.0, 141)
    values = [slope(s) for s in grid]
    i = next(i for i in range(len(grid) - 1) if values[i] * values[i + 1] < 0)
    blind = brentq(slope, grid[i], grid[i + 1], xtol=1e-14)
    end = response_map(lever, [f], [1.0], width=WIDTH).nonlocal_coefficient[0]
    at = response_map(replace(lever, spot_position=blind), [f], [1.0], width=WIDTH).nonlocal_coefficient[0]
    beside = response_map(replace(lever, spot_position=blind + 0.02), [f], [1.0], width=WIDTH).nonlocal_coefficient[0]
    assert abs(at) < 1e-6 * abs(end) and abs(beside) > 1e-3 * abs(end)
