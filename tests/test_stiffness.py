"""Contact stiffness of the paper's lever (vectorised, maps) and the CLI: recovery, uncertainty, range.

Test data come from an independent route: the certified roots of the elastic-contact family
(:func:`pfmdyn.roots.core.family_roots`, ball arithmetic) at known k1/k, never from the
closed-form inversion under test.  Levers are drawn over real ranges with fixed seeds.  The
whole lever model (set-back, heavy, tilted tips) is ``tests/test_stiffness_model.py``'s.
"""
import json
import math
import re

import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.analysis.stiffness import branch_proof, contact_stiffness, k1_over_k_from_z, reduced_modulus
from pfmdyn.errors import UserError
from pfmdyn.generated.characteristic import BETA1_FREE
from pfmdyn.roots.core import family_roots


def draw_levers(seed, n):
    """k (N/m), L (m), f1 (Hz) and k1/k as exact decimal strings, over the real ranges."""
    rng = np.random.default_rng(seed)
    k = 10 ** rng.uniform(np.log10(0.05), np.log10(50), n)
    length = rng.uniform(100e-6, 500e-6, n)
    # f1 of a silicon lever of that length and stiffness is 10-500 kHz; any value tests the scaling.
    f1 = 10 ** rng.uniform(4, np.log10(5e5), n)
    ratio = [f"{10 ** x:.6e}" for x in rng.uniform(0, 4, n)]
    return k, length, f1, ratio


def certified_contact_hz(f1, mode, digits=25, **params):
    z = float(family_roots("elastic", mode, digits, **params).roots[mode - 1])
    return f1 * (z / BETA1_FREE) ** 2


def test_k1_recovered_to_1e9_from_certified_roots_over_real_levers():
    k, _, f1, ratio = draw_levers(12, 10)
    modes = [1, 2, 3, 1, 2, 1, 1, 3, 2, 1]
    worst = 0.0
    for ki, fi, ri, mode in zip(k, f1, ratio, modes):
        fc = certified_contact_hz(fi, mode, k1_over_k=ri, k2_ratio=0)
        got = contact_stiffness(fc, fi, ki, mode=mode).k1
        worst = max(worst, abs(float(got) / (float(ri) * ki) - 1))
    assert worst < 1e-9, worst


def test_k1_recovered_with_a_fixed_longitudinal_spring():
    k, _, f1, ratio = draw_levers(7, 6)
    b = np.random.default_rng(8).uniform(0, 2, 6)
    for ki, fi, ri, bi in zip(k, f1, ratio, b):
        b_text = f"{bi:.4f}"
        fc = certified_contact_hz(fi, 1, k1_over_k=ri, k2_ratio=b_text)
        got = contact_stiffness(fc, fi, ki, k2_ratio=float(b_text)).k1
        assert abs(float(got) / (float(ri) * ki) - 1) < 1e-9


def test_vectorised_map_matches_scalar_and_marks_impossible_pixels():
    f1, k = 60e3, 3.0
    fc = np.array([[certified_contact_hz(f1, 1, k1_over_k=r, k2_ratio=0) for r in ("1", "30", "3000")],
                   [f1 * 0.9, f1 * 5.0, certified_contact_hz(f1, 1, k1_over_k="10000", k2_ratio=0)]])
    r = contact_stiffness(fc, f1, k, out_of_range="nan")
    assert r.k1.shape == (2, 3)
    np.testing.assert_allclose(r.k1[0], [3.0, 90.0, 9000.0], rtol=1e-9)
    assert np.isnan(r.k1[1, :2]).all() and abs(r.k1[1, 2] / 30000 - 1) < 1e-9


def test_noise_scatter_matches_the_propagated_uncertainty():
    """Frequencies with Gaussian noise: k1 scatter equals the first-order propagated sigma."""
    rng = np.random.default_rng(3)
    f1, k, sig_c, sig_f = 70e3, 1.5, 30.0, 10.0
    fc_true = certified_contact_hz(f1, 1, k1_over_k="80", k2_ratio=0)
    n = 4000
    fc = fc_true + sig_c * rng.standard_normal(n)
    f1s = f1 + sig_f * rng.standard_normal(n)
    got = contact_stiffness(fc, f1s, k).k1
    sigma = float(contact_stiffness(fc_true, f1, k, contact_uncertainty=sig_c,
                                    free_resonance_uncertainty=sig_f).k1_stderr)
    assert abs(np.std(got) / sigma - 1) < 0.06
    assert abs(np.mean(got) - 120.0) < 4 * sigma / math.sqrt(n) + 1e-3 * sigma
    inside = np.abs(got - 120.0) < 2 * sigma
    assert 0.93 < inside.mean() < 0.97


def test_branch_limits_are_the_certified_free_and_pinned_roots_and_k1_is_monotonic():
    free = family_roots("free", 3, 17).roots
    pinned = family_roots("pinned", 3, 17).roots
    for mode in (1, 2, 3):
        p = branch_proof(mode)
        assert abs(p.soft_z - float(free[mode - 1])) < 1e-14 and abs(p.stiff_z - float(pinned[mode - 1])) < 1e-14
        z = np.linspace(p.soft_z, p.stiff_z, 2001)[1:-1]
        a = k1_over_k_from_z(z)
        assert np.all(a > 0) and np.all(np.diff(a) > 0)


@pytest.mark.parametrize("ratio, words", [(5.0, ("stiff limit", "k2", "higher mode")), (0.8, ("mass",))])
def test_ratios_outside_the_model_name_the_effect(ratio, words):
    with pytest.raises(UserError) as err:
        contact_stiffness(ratio * 60e3, 60e3, 2.0)
    assert "\n" not in str(err.value) and all(w in str(err.value) for w in words)


def test_reduced_modulus_inverts_the_derived_hertz_stiffness():
    import sympy as sp
    from pfmdyn.derivations import contact_mechanics as cm
    k1 = float(cm.hertz_stiffness().subs({cm.E_star: 7e10, cm.R: 30e-9, cm.P: 2e-7}))
    assert abs(float(reduced_modulus(k1, 30e-9, 2e-7)) / 7e10 - 1) < 1e-12
    assert sp.simplify(cm.hertz_stiffness() ** 3 - 6 * cm.E_star**2 * cm.R * cm.P) == 0


def test_cli_numbers_json_and_reduced_modulus(tmp_path, capsys):
    fc = certified_contact_hz(75e3, 1, k1_over_k="40", k2_ratio=0)
    out = tmp_path / "k1.json"
    code = cli.main(["stiffness", "--free-resonance", "75e3", "--contact", repr(fc), "--spring-constant", "2",
                     "--contact-uncertainty", "50", "--reduced-modulus", "--tip-radius", "20e-9",
                     "--load", "1e-7", "--k2", "0", "--json", str(out)])
    assert code == 0
    doc = json.loads(out.read_text())
    k1, results = doc["results"]["k1"], doc["results"]
    assert abs(k1["value"] / 80 - 1) < 1e-9 and isinstance(k1["stderr"], float) and k1["stderr"] > 0
    assert results["reduced_modulus"]["value"] > 0 and results["unique"]["value"]
    assert "one k1" in [n for n in doc["notes"] if n.startswith("why: ")][0]
    # k2 = 0 stated: no lateral spring, so neither a tip height nor a length is needed or assumed
    assert "length" not in doc["lever"] and "tip_height" not in doc["lever"]
    assert doc["notes"][0].startswith("k2 policy: k2 = 0")
    assert "k1 = 80" in capsys.readouterr().out


def test_cli_two_modes_from_a_resonance_table(tmp_path):
    """No k2 policy, no tip position: (k1, k2) and (k1, tip position) both, not unique; a stated tip decides."""
    fc = [certified_contact_hz(60e3, m, k1_over_k="25", k2_ratio="0.04") for m in (1, 2)]
    table = tmp_path / "res.csv"
    table.write_text("# spring_constant_n_per_m: 4\n# length_m: 2e-4\n# width_m: 3e-5\n# tip_height_m: 1e-5\n"
                     f"# free_resonance_hz: 60000\nmode,condition,frequency_hz\n2,contact,{fc[1]!r}\n"
                     f"1,free,60000\n1,contact,{fc[0]!r}\n")
    out = tmp_path / "k.json"
    assert cli.main(["stiffness", str(table), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    k2_true = 0.04 * 4 * 4e-8 / 1e-10
    assert not doc["results"]["unique"]["value"] and doc["results"]["k1"]["value"] is None
    assert "three unknowns" in [n for n in doc["notes"] if n.startswith("why: ")][0]
    pair = [s for s in doc["fit"]["solutions"] if s["k2"]["status"] == "derived"][0]
    assert abs(pair["k1"]["value"] / 100 - 1) < 1e-8 and abs(pair["k2"]["value"] / k2_true - 1) < 1e-8
    assert cli.main(["stiffness", str(table), "--tip-position", "1", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())["results"]
    assert doc["unique"]["value"] and abs(doc["k1"]["value"] / 100 - 1) < 1e-8
    assert abs(doc["k2"]["value"] / k2_true - 1) < 1e-8
    # the same table under a .txt name: read as discrepancy reads it, not refused as "not a drive sweep"
    text = tmp_path / "res.txt"
    text.write_text(table.read_text())
    assert cli.main(["stiffness", str(text), "--tip-position", "1", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["results"] == doc


@pytest.mark.parametrize("argv, words", [
    (["--free-resonance", "60e3", "--contact", "400e3", "--spring-constant", "2"], "stiff limit"),
    (["--free-resonance", "60e3", "--contact", "2e5"], "--spring-constant"),
    (["--free", "-1", "--contact", "2e5", "--spring-constant", "2"], "--free-resonance"),
    (["--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--reduced-modulus"], "--tip-radius"),
    (["--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--tip-position", "fit"], "two or more"),
    (["--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--tilt", "12"], "--length"),
    (["--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--tip-position", "1.3"],
     "--tip-position"),
])
def test_cli_errors_are_one_line_and_write_nothing(tmp_path, capsys, argv, words):
    out = tmp_path / "k.json"
    assert cli.main(["stiffness", *argv, "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pfmdyn stiffness: error:") and err.count("\n") == 1 and words in err
    assert not out.exists()


def test_k1_recovered_when_k2_follows_k1_mindlin():
    from pfmdyn.analysis.stiffness import coupled_contact_stiffness, mindlin_k2_over_k1
    k, length, f1, ratio = draw_levers(31, 6)
    height = np.random.default_rng(32).uniform(5e-6, 20e-6, 6)
    c = mindlin_k2_over_k1(0.3)
    for ki, li, fi, ri, hi in zip(k, length, f1, ratio, height):
        b = float(float(ri) * c * (hi / li) ** 2)
        fc = certified_contact_hz(fi, 1, k1_over_k=ri, k2_ratio=repr(b))
        r = coupled_contact_stiffness(fc, fi, ki, k2_over_k1=c, length=li, tip_height=hi)
        assert abs(float(r.k1) / (float(ri) * ki) - 1) < 1e-9
    with pytest.raises(UserError, match="tip mass"):
        coupled_contact_stiffness(6.5 * 60e3, 60e3, 1.0, k2_over_k1=c, length=2e-4, tip_height=1e-5)


def test_cli_mindlin_coupling_assumes_a_typical_tip_height_unless_given(tmp_path, capsys):
    base = ["stiffness", "--free-resonance", "60e3", "--contact", "300e3", "--spring-constant", "1", "--poisson", "0.3"]
    out = tmp_path / "k.json"
    assert cli.main(base + ["--length", "2.4e-4", "--json", str(out)]) == 0
    assert "assumed: tip height 1.3e-05 m" in capsys.readouterr().out
    lever = json.loads(out.read_text())["lever"]
    assert lever["tip_height"]["status"] == "assumed" and lever["tip_height_uncertainty"]["value"] == 2.5e-6
    assert cli.main(base + ["--length", "2.4e-4", "--tip-height", "1.5e-5", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())["results"]
    assert doc["k1"]["value"] > 0 and doc["k2"]["value"] == pytest.approx(1.4 / 1.7 * doc["k1"]["value"])   # 2(1-nu)/(2-nu)
    assert doc["k2"]["status"] == "tied"


def test_cli_contact_frequency_map_takes_the_lever_flags_and_refuses_the_rest(tmp_path, capsys):
    h5py = pytest.importorskip("h5py")
    pytest.importorskip("zarr")
    fc = certified_contact_hz(75e3, 1, k1_over_k="40", k2_ratio=0)
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((2, 3), fc)
        h.attrs.update(spring_constant=2.0, free_resonance=75e3)
    assert cli.main(["stiffness", str(path), "--out", str(tmp_path / "a"), "--spring-constant", "4"]) == 0
    assert "median k1 160 N/m" in capsys.readouterr().out          # k1/k = 40 at the flag's k
    assert cli.main(["stiffness", str(path), "--out", str(tmp_path / "b"), "--tilt", "12"]) == 2
    assert "--tilt" in capsys.readouterr().err and not (tmp_path / "b").exists()


def test_contact_map_uncertainty_under_its_name_and_its_old_spelling(tmp_path, capsys):
    """The map attribute ``contact_uncertainty`` (Hz; ``contact_uncertainty_hz`` still read) and the flag
    ``--contact-uncertainty`` give the same k1 standard error, which grows with it."""
    h5py = pytest.importorskip("h5py")
    zarr = pytest.importorskip("zarr")
    fc = certified_contact_hz(75e3, 1, k1_over_k="40", k2_ratio=0)
    stderr = {}
    for name, attrs, extra in (("new", {"contact_uncertainty": 200.0}, []),
                               ("old", {"contact_uncertainty_hz": 200.0}, []),
                               ("flag", {}, ["--contact-uncertainty", "200"]),
                               ("double", {"contact_uncertainty": 200.0}, ["--contact-uncertainty", "400"])):
        path = tmp_path / f"{name}.h5"
        with h5py.File(path, "w") as h:
            h["contact_frequency_hz"] = np.full((2, 3), fc)
            h.attrs.update(spring_constant=2.0, free_resonance=75e3, free_resonance_uncertainty=0.0, **attrs)
        assert cli.main(["stiffness", str(path), "--out", str(tmp_path / name), *extra]) == 0
        stderr[name] = float(zarr.open_group(str(tmp_path / name / "maps.zarr"), mode="r")["k1_stderr"][0, 0])
    assert stderr["new"] > 0 and stderr["old"] == stderr["new"] == stderr["flag"]
    assert stderr["double"] == pytest.approx(2 * stderr["new"], rel=1e-9)
    assert cli.main(["stiffness", str(tmp_path / "new.h5"), "--out", str(tmp_path / "bad"),
                     "--contact-uncertainty", "-1"]) == 2
    assert "--contact-uncertainty" in capsys.readouterr().err


def test_reduced_modulus_takes_the_normal_load_and_its_old_flag(tmp_path):
    """``--normal-load`` (the name of the quantity) and the hidden old ``--load`` give the same E*."""
    base = ["stiffness", "--free-resonance", "75e3", "--contact", "300e3", "--spring-constant", "2",
            "--reduced-modulus", "--tip-radius", "20e-9"]
    docs = []
    for flag in ("--normal-load", "--load"):
        out = tmp_path / f"{flag}.json"
        assert cli.main(base + [flag, "1e-7", "--json", str(out)]) == 0
        docs.append({k: v["value"] for k, v in json.loads(out.read_text())["results"].items()})
    assert docs[0]["reduced_modulus"] == docs[1]["reduced_modulus"]
    assert docs[0]["reduced_modulus"] == pytest.approx(float(reduced_modulus(docs[0]["k1"], 20e-9, 1e-7)), rel=1e-12)


def test_uncertainty_is_written_as_the_other_commands_write_it(capsys):
    """'k1 = ... +- ... N/m', as calibrate and discrepancy print a value and its standard uncertainty."""
    assert cli.main(["stiffness", "--spring-constant", "2", "--free-resonance", "70e3", "--length", "225e-6",
                     "--tip-height", "10e-6", "--contact", "300e3"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^k1 = [\d.]+ \+- [\d.e+]+ N/m", out, re.M) and "+/-" not in out, out


def test_two_modes_without_a_k2_policy_give_each_reading_and_no_noise_as_uncertainty(capsys):
    """Two modes, k1 and k2 free: the (k1, k2) reading's k1 does not move with the tip height (which only rescales
    k2), so its uncertainty from it is none, not the differences' noise, and k1 is not printed to 12 digits."""
    from pfmdyn import Cantilever, Contact
    from pfmdyn.analysis.stiffness_report import analyse

    lever = Cantilever(2.0, 7e4, 225e-6, tip_height=13e-6)
    report = analyse(lever, Contact(), [3e5, 8e5], [1, 2], tip_position_stated=False)
    assert not report.unique and len(report.solutions) == 2
    for s in report.solutions:
        assert s.sources.get("tip_height_uncertainty", {}).get("k1", 0.0) == 0.0
    pair = next(s for s in report.solutions if "k2" in s.unknowns)
    assert pair.stderr["k2"] > 0.1 * pair.k2          # k2 = k2 H^2 / H^2: the tip height's share is real
    text = report.report()
    assert "reproduce the resonances (k1 from 180.442 to 180.594 N/m)" in text
    assert not re.search(r"k1 = \d+\.\d{7}", text)


def test_resonances_without_uncertainty_take_the_assumed_one_discrepancy_takes(tmp_path, capsys):
    """stiffness took resonances given without uncertainty as exact (0 Hz) where discrepancy assumes 0.1 % of each:
    both now take pfmdyn.constants.RESONANCE_RELATIVE_UNCERTAINTY, marked assumed, with its share of k1's; a table's
    stated uncertainty (or a flag) wins."""
    from pfmdyn.constants import RESONANCE_RELATIVE_UNCERTAINTY
    from pfmdyn.discrepancy.resonance_fit import frequency_sigma
    from pfmdyn.io.tables import read

    rows = "mode,condition,frequency_hz\n1,free,72969\n1,contact,290000\n"
    table = tmp_path / "t.csv"
    table.write_text(rows)
    assert frequency_sigma(read(str(table), required=())).tolist() == pytest.approx(
        [RESONANCE_RELATIVE_UNCERTAINTY * 72969, RESONANCE_RELATIVE_UNCERTAINTY * 290000], rel=1e-12)
    base = ["stiffness", "--spring-constant", "0.46538", "--k2", "0"]
    out = tmp_path / "k1.json"
    assert cli.main([*base, str(table), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "contact resonances (assumed)" in text and "free resonance (assumed)" in text
    doc = json.loads(out.read_text())
    lever, budget = doc["lever"], doc["fit"]["budget"]
    assert lever["contact_uncertainty"]["status"] == "assumed"
    assert lever["contact_uncertainty"]["value"] == pytest.approx([RESONANCE_RELATIVE_UNCERTAINTY * 290000])
    assert lever["free_resonance_uncertainty"]["value"] == pytest.approx(RESONANCE_RELATIVE_UNCERTAINTY * 72969)
    shares = dict(zip(budget["uncertainty_source"]["value"], budget["relative_uncertainty"]["value"]))
    assert shares["contact_uncertainty"] > 1e-3 and doc["results"]["k1"]["stderr"] > 0.01 * doc["results"]["k1"]["value"]
    table.write_text("# frequency_uncertainty_hz: 50\n" + rows)          # the table's own wins
    assert cli.main([*base, str(table), "--json", str(out)]) == 0
    lever = json.loads(out.read_text())["lever"]
    assert lever["contact_uncertainty"]["value"] == 50.0 and lever["contact_uncertainty"]["status"] == "file"
    assert "(assumed)" not in capsys.readouterr().out
    assert cli.main([*base, str(table), "--contact-uncertainty", "0", "--json", str(out)]) == 0     # a flag wins
    assert json.loads(out.read_text())["lever"]["contact_uncertainty"]["status"] == "given"


def test_contact_map_without_uncertainty_assumes_the_resonances_one(tmp_path, capsys):
    """A contact-frequency map without contact_uncertainty wrote k1_stderr 0 at every pixel (the frequencies taken
    as exact); it takes the assumed relative uncertainty, as stiffness on numbers does, and says so."""
    h5py = pytest.importorskip("h5py")
    zarr = pytest.importorskip("zarr")
    from pfmdyn.constants import RESONANCE_RELATIVE_UNCERTAINTY

    fc = certified_contact_hz(75e3, 1, k1_over_k="40", k2_ratio=0)
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((2, 3), fc)
        h.attrs.update(spring_constant=2.0, free_resonance=75e3)
    assert cli.main(["stiffness", str(path), "--out", str(tmp_path / "o"), "--json", str(tmp_path / "s.json")]) == 0
    assert "assumed: standard uncertainty 0.1% of each pixel's frequency and the free resonance" in capsys.readouterr().out
    stderr = float(zarr.open_group(str(tmp_path / "o" / "maps.zarr"), mode="r")["k1_stderr"][0, 0])
    expected = contact_stiffness(fc, 75e3, 2.0, contact_uncertainty=RESONANCE_RELATIVE_UNCERTAINTY * fc,
                                 free_resonance_uncertainty=RESONANCE_RELATIVE_UNCERTAINTY * 75e3).k1_stderr
    assert stderr == pytest.approx(float(expected), rel=1e-12) and stderr > 0
    assert any(n.startswith("assumed:") for n in json.loads((tmp_path / "s.json").read_text())["notes"])
