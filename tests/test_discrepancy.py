"""Discrepancy loop on independent finite-element data (tests/fe_beam.py) with hidden effects."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

# The independent FE generator lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam, resonances, spectrum  # noqa: E402
from pfmdyn import cli
from pfmdyn.discrepancy.spectrum import analyse
from pfmdyn.plots.discrepancy import spectrum_figure
from pfmdyn.io.tables import read
from pfmdyn.discrepancy.model import Model
from pfmdyn.discrepancy.resonances import analyse_resonances, paper_tables
from pfmdyn.generated import elastic_contact, tip_setback

FREQ = np.linspace(150e3, 1300e3, 240)


def _beam(**hidden):
    return FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, n_elements=150, **hidden)


def _run(tmp_path, text):
    path = tmp_path / "data.csv"
    path.write_text(text)
    return analyse(read(path), progress=False)


def test_generated_composite_against_finite_elements():
    """Set-back, tip mass, tilt and damping together: generated code vs the FE beam."""
    beam = FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, Q=80, mu=0.15, gamma=0.9,
                  alpha=0.2, n_elements=200)
    f = np.array([30e3, 200e3, 500e3, 900e3])
    meta = type("M", (), {"k": 2.4, "H": 1e-5, "L": 223e-6, "f1": 63.2e3})
    model = Model(meta, ("damping", "tip_mass", "tip_setback", "tilt"))
    internal = [math.log10(120.0), 2.0, 1 / 80, 0.15, 0.9, 0.2]
    # The bare-beam f1 sets the frequency scale of the FE beam: undo the tip-mass rescaling.
    v = model.values(internal)
    beta = 1.8751040687119611 * np.sqrt(f / 63.2e3) * (1 - 1j / 80) ** 0.25
    got = np.array(tip_setback.slope(beta, 2.4, *model.springs(v), 1e-5, 223e-6, 0.15, 0.9)).T
    ratio = got / beam.slope(f)
    # Complex modulus K/(1 - i/Q) in FE vs beta**4 (1 - i/Q): a constant factor (1 - i/Q).
    np.testing.assert_allclose(ratio, 1 / (1 - 1j / 80), rtol=2e-5)


def test_composite_reduces_to_eq5():
    b = np.array([0.5, 2.0, 7.0, 30.0])
    e = elastic_contact.slope(b, 2.4, 120.0, 100.0, 1e-5, 223e-6)
    s = tip_setback.slope(b, 2.4, 120.0, 100.0, 0.0, 1e-5, 223e-6, 0.0, 1.0)
    np.testing.assert_allclose(np.array(s), np.array(e), rtol=1e-10)


def test_baseline_exact_names_nothing(tmp_path):
    report = _run(tmp_path, spectrum(_beam(), FREQ))
    assert report["missing_effects"] == []
    assert report["gap_after"] < 1.3
    assert abs(report["parameters"]["k1"]["value"] - 120.0) < 1.0


@pytest.mark.parametrize("hidden,name,polar", [
    ({"Q": 100.0}, "damping", False),
    ({"mu": 0.2}, "tip_mass", True),
    ({"gamma": 0.9}, "tip_setback", False),
    ({"alpha": 0.3}, "tilt", True),
])
def test_hidden_effect_is_named(tmp_path, hidden, name, polar):
    text = spectrum(_beam(**hidden), FREQ, polar=polar, seed=3)
    report = _run(tmp_path, text)
    assert report["missing_effects"][:1] == [name]
    assert report["gap_before"] > 5
    assert report["gap_after"] < 1.3
    step = report["steps"][0]
    assert step["criterion_gain"] > 10 and step["parameters"]


def test_cli_hidden_background(tmp_path):
    """Cross-talk hidden in polar data, through the command line: JSON report and plot."""
    data = tmp_path / "d.csv"
    data.write_text(spectrum(_beam(), FREQ, background=0.5, polar=True, seed=5))
    out, png = tmp_path / "o.json", tmp_path / "o.png"
    assert cli.main(["discrepancy", str(data), "--json", str(out), "--plot", str(png)]) == 0
    report = json.loads(out.read_text())
    assert report["missing_effects"] == ["background"]
    assert report["gap_before"] > 5 and report["gap_after"] < 1.3
    step = report["steps"][0]
    assert step["criterion_gain"] > 10 and set(step["parameters"]) == {"k1", "k2"}
    assert png.stat().st_size > 1000


def test_plot_axis_follows_data(tmp_path):
    """A baseline collapsed to ~0 (undamped model on damped data) must not set the log axis."""
    f = np.repeat(np.linspace(1e5, 2e5, 50), 2)
    data = SimpleNamespace(frequency_hz=f, bias_v=np.tile([0.0, 1.0], 50),
                           response=(1 + f / 1e5) * np.exp(1j * f / 1e4))
    collapsed = SimpleNamespace(prediction=1e-12 * data.response, residual=data.response)
    exact = SimpleNamespace(prediction=data.response, residual=0 * data.response)
    fig = spectrum_figure(data, {"_fits": (collapsed, exact)})
    low, high = fig.axes[0].get_ylim()
    fig.clear()
    assert 0.5 < low < 2 and 3 < high < 10


def test_vertical_only_start_finds_lateral_stiffness(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text(spectrum(_beam(), FREQ, seed=7))
    report = analyse(read(path), vertical_only=True, progress=False)
    assert report["missing_effects"] == ["lateral_stiffness"]
    assert abs(report["parameters"]["k2"]["value"] - 100.0) < 2.0


@pytest.mark.parametrize("edit,message", [
    (lambda t: t.replace("# length_m: 0.000223\n", ""), "missing metadata"),
    (lambda t: t.replace("frequency_hz,bias_v,x,y", "frequency_hz,bias_v,x,y,z").replace("\n1", ",0\n1"),
     "unknown column"),
    (lambda t: "\n".join(t.splitlines()[:12]) + "\n", "at least"),
])
def test_bad_input_is_one_line(tmp_path, capsys, edit, message):
    data = tmp_path / "d.csv"
    data.write_text(edit(spectrum(_beam(), FREQ[:10])))
    assert cli.main(["discrepancy", str(data), "--json", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_resonances_table_is_read(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text(resonances(_beam(mu=0.1)))
    data = read(path)
    assert data.kind == "resonances" and list(data.condition).count("contact") == 2


def test_resonances_hidden_tip_mass(tmp_path):
    """FE eigenfrequencies with a tip mass: the free mode ratios call for tip_mass."""
    path = tmp_path / "r.csv"
    text = resonances(_beam(mu=0.15), n_free=3, n_contact=2)
    path.write_text(text.replace("# description", "# frequency_uncertainty_hz: 50\n# description"))
    report = analyse_resonances(read(path), progress=False)
    assert report["missing_effects"] == ["tip_mass"]
    assert report["gap_after"] < 1.0 < report["gap_before"]
    assert abs(report["parameters"]["mu"]["value"] - 0.15) < 0.01


def _noisy_resonances(beam, n_contact, sigma=50.0, seed=1):
    """FE resonances (3 free modes) plus Gaussian noise of ``sigma`` Hz, declared as the uncertainty."""
    rng = np.random.default_rng(seed)
    lines = []
    for line in resonances(beam, n_free=3, n_contact=n_contact).splitlines():
        cells = line.split(",")
        if line.startswith("# description"):
            lines.append(f"# frequency_uncertainty_hz: {sigma}")
        elif len(cells) == 3 and cells[0].isdigit():
            line = f"{cells[0]},{cells[1]},{float(cells[2]) + sigma * rng.standard_normal()!r}"
        lines.append(line)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("hidden,n_contact,vertical_only,named,check", [
    # Exact baseline beam: only noise is left, nothing may be added.
    ({}, 2, False, [], ("k1", 120.0, 1.0)),
    # Set-back moves contact modes only: with 3 free + 4 contact modes tilt (also a
    # contact-only effect) cannot mimic it.
    ({"gamma": 0.9}, 4, False, ["tip_setback"], ("gamma", 0.9, 0.002)),
    # A vertical-only start misses k2, which the contact modes call for.
    ({}, 3, True, ["lateral_stiffness"], ("k2", 100.0, 2.0)),
])
def test_resonances_hidden_effect(tmp_path, hidden, n_contact, vertical_only, named, check):
    path = tmp_path / "r.csv"
    path.write_text(_noisy_resonances(_beam(**hidden), n_contact))
    report = analyse_resonances(read(path), vertical_only=vertical_only, progress=False)
    assert report["missing_effects"] == named
    assert report["gap_after"] < 1.0
    if named:
        assert report["gap_before"] > 5 and report["steps"][0]["criterion_gain"] > 10
    name, value, tol = check
    assert abs(report["parameters"][name]["value"] - value) < tol


def test_cli_free_modes_only(tmp_path, capsys):
    """Paper tip 2 (free modes only) through the command line: tip mass, springs undetermined."""
    tip2 = paper_tables()["tip 2"]
    m = tip2.metadata
    rows = "".join(f"{n},{c},{float(f)!r}\n" for n, c, f in zip(tip2.mode, tip2.condition, tip2.frequency_hz))
    data = tmp_path / "tip2.csv"
    data.write_text(f"# spring_constant_n_per_m: {m.k}\n# length_m: {m.L}\n# width_m: {m.width}\n"
                    f"# tip_height_m: {m.H}\n# free_resonance_hz: {m.f1}\n"
                    f"# frequency_uncertainty_hz: {m.frequency_uncertainty_hz}\n"
                    f"mode,condition,frequency_hz\n{rows}")
    out, png = tmp_path / "o.json", tmp_path / "o.png"
    assert cli.main(["discrepancy", str(data), "--json", str(out), "--plot", str(png)]) == 0
    report = json.loads(out.read_text())
    assert report["missing_effects"] == ["tip_mass"] and report["gap_after"] < 1.0
    for spring in ("k1", "k2"):
        assert report["parameters"][spring] == {"value": None, "stderr": None, "unit": "N/m",
                                                "determined": False}
    assert 0.02 < report["parameters"]["mu"]["value"] < 0.1
    assert "k1 not determined" in capsys.readouterr().out and png.stat().st_size > 1000


def test_paper_resonances():
    """Section VI.1: tip 2's free modes (ratios above 6.27:1) are explained by a tip mass."""
    tables = paper_tables()
    tip2 = analyse_resonances(tables["tip 2"], progress=False)
    assert tip2["missing_effects"] == ["tip_mass"] and tip2["gap_after"] < 1.0
    assert 0.02 < tip2["parameters"]["mu"]["value"] < 0.1
