"""Resonance tables in ``pfmdyn discrepancy``: any column layout, Q values, short tables.

Data come from the independent finite-element beam (``tests/fe_beam.py``; Q values from its
complex eigenvalues, ``tests/fe_quality.py``), never from the fitted model.  Wide sweeps with
pass rates: ``benchmarks/discrepancy_tables.py``.
"""
from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam  # noqa: E402
from fe_quality import damped_table, quality_factors  # noqa: E402
from test_instruments import ASYLUM  # noqa: E402

from pfmdyn import cli  # noqa: E402
from pfmdyn.discrepancy.resonance_fit import K2_OVER_K1  # noqa: E402
from pfmdyn.discrepancy.resonances import analyse_resonances  # noqa: E402
from pfmdyn.errors import UserError  # noqa: E402
from pfmdyn.discrepancy.inputs import read as read_input  # noqa: E402
from pfmdyn.io.tables import ResonanceData, read  # noqa: E402

HEAD = ("# spring_constant_n_per_m: 2\n# length_m: 2e-4\n# width_m: 3e-5\n# tip_height_m: 1e-5\n"
        "# free_resonance_hz: 6e4\n")


def _read(tmp_path, text, name="t.csv"):
    path = tmp_path / name
    path.write_text(text)
    return read(path)


def test_column_layouts_read_alike(tmp_path):
    """Columns reordered, frequency in kHz, Q named 'Q', a unit in parentheses: the same table."""
    plain, _ = damped_table(2, "viscous", columns="plain", n_elements=30)
    other, _ = damped_table(2, "viscous", columns="other", n_elements=30)
    a, b = _read(tmp_path, plain, "a.csv"), _read(tmp_path, other, "b.csv")
    assert a.condition.tolist() == b.condition.tolist() and a.mode.tolist() == b.mode.tolist()
    np.testing.assert_allclose(a.frequency_hz, b.frequency_hz, rtol=1e-12)
    np.testing.assert_allclose(a.quality_factor, b.quality_factor, rtol=1e-12)
    c = _read(tmp_path, HEAD + "Frequency (kHz),Mode,Condition\n60,1,free\n370,2,free\n300,1,contact\n")
    assert c.frequency_hz.tolist() == [6e4, 3.7e5, 3e5] and c.quality_factor is None
    d = _read(tmp_path, HEAD + "mode,condition,frequency_hz,quality_factor\n1,free,6e4,inf\n1,contact,3e5,80\n")
    assert math.isinf(d.quality_factor[0]) and d.quality_factor[1] == 80


@pytest.mark.parametrize("header, rows, message", [
    ("mode,condition,frequency_hz,frequency_khz", "1,free,6e4,60", "frequency_khz given more than once"),
    ("mode,condition,quality_factor", "1,free,100", "lacks the column(s) frequency_hz"),
    ("mode,condition,frequency_hz,quality_factor", "1,free,6e4,-3", "quality_factor must be"),
    ("mode,condition,frequency_hz,q", "1,free,6e4,abc", "quality_factor numbers"),
    ("frequency_ghz,bias_v,x,y", "60,0,1,0", "'frequency_ghz'; give frequencies as 'frequency_hz'"),
])
def test_bad_columns_are_one_line_naming_the_column(tmp_path, capsys, header, rows, message):
    text = HEAD + header + "\n" + "\n".join([rows] * 3) + "\n"
    with pytest.raises(UserError, match=message.replace("(", r"\(").replace(")", r"\)")):
        _read(tmp_path, text)
    path = tmp_path / "t.csv"
    assert cli.main(["discrepancy", str(path), "--json", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pfmdyn discrepancy: error: ")


@pytest.mark.parametrize("mechanism", ["internal", "viscous", "contact"])
def test_damping_mechanism_from_quality_factors(tmp_path, mechanism):
    """Q per mode from the FE beam's complex eigenvalues: the mechanism is told apart by how
    the width scales with the mode and the contact, and the Q values are reproduced."""
    text, truth = damped_table(2, mechanism, columns="other")
    report = analyse_resonances(_read(tmp_path, text), progress=False)
    assert report["missing_effects"] == ["damping"] and report["damping_mechanisms"] == [mechanism]
    assert report["gap_after"] < 1.5 and report["unexplained"] is None
    measured, predicted = np.array(report["measured_quality_factor"]), np.array(report["predicted_quality_factor"])
    assert np.max(np.abs(predicted / measured - 1)) < 0.05
    if mechanism == "internal":
        q = report["parameters"]["quality_factor"]
        assert abs(q["value"] - truth["Q"]) < 3 * q["stderr"] + 0.02 * truth["Q"]


def test_one_contact_mode_determines_k1(tmp_path):
    """A two-row table (free 1, contact 1, each with Q), as from an image's metadata: k1 with
    its uncertainty (k2 tied at the Mindlin ratio, said so), and the truth within it."""
    k1 = 2.0 * 60
    beam = FEBeam(2.0, 2e-4, 6e4, 1e-5, k1=k1, k2=K2_OVER_K1 * k1, Q=150.0, n_elements=60)
    f_free, f_contact = float(beam.free_resonances(1)[0]), float(beam.contact_resonances(1)[0])
    q_free, q_contact = float(quality_factors(beam, 1, False)[0]), float(quality_factors(beam, 1, True)[0])
    text = HEAD.replace("6e4", repr(float(f_free))) + (
        f"mode,condition,frequency_hz,quality_factor\n1,contact,{f_contact!r},{q_contact!r}\n"
        f"1,free,{f_free!r},{q_free!r}\n")
    report = analyse_resonances(_read(tmp_path, text), progress=False)
    k1_fit, k2_fit = report["parameters"]["k1"], report["parameters"]["k2"]
    assert k1_fit["determined"] and math.isfinite(k1_fit["stderr"]) and k1_fit["stderr"] < 0.1 * k1_fit["value"]
    assert abs(k1_fit["value"] - k1) < 3 * k1_fit["stderr"]
    assert k2_fit["value"] is None and "Mindlin" in k2_fit["note"] and "k2" in report["spring_rule"]
    assert report["missing_effects"] == ["damping"] and "tilt" in report["untestable_effects"]


@pytest.mark.skipif(not ASYLUM.is_dir(), reason="real data absent")
def test_asylum_image_through_read_and_cli(tmp_path, capsys):
    """An instrument file goes through the one entry point (discrepancy.inputs.read) and ends in a
    report with k1 determined from the one contact mode."""
    path = ASYLUM / "IgorIBWReader_ImageStack_BTFO_DSO.ibw"
    data = read_input(path, {"tip_height_m": 1e-5})
    assert isinstance(data, ResonanceData) and data.condition.tolist() == ["free", "contact"]
    out = tmp_path / "o.json"
    assert cli.main(["discrepancy", str(path), "--json", str(out), "--tip-height", "1e-5"]) == 0
    report = json.loads(out.read_text())
    assert report["results"]["k1"]["status"] == "fitted" and report["results"]["k2"]["value"] is None
    assert report["results"]["k2"]["why"].startswith("tied to k1")
    summary = capsys.readouterr().out
    assert "k2 not determined by these data: tied to k1" in summary
    # Without --json the summary alone; with '--json -' the report alone on stdout, the summary on stderr.
    assert cli.main(["discrepancy", str(path), "--tip-height", "1e-5"]) == 0
    assert capsys.readouterr().out == summary
    assert cli.main(["discrepancy", str(path), "--json", "-", "--tip-height", "1e-5"]) == 0
    printed = capsys.readouterr()
    assert json.loads(printed.out) == report and printed.err.startswith(summary)


def test_the_first_free_resonance_alone_is_nothing_to_compare(tmp_path, capsys):
    """It sets the lever's scale: the report said 'gap 0.00 -> 0.00, missing effects: none' from 0 data values
    (a one-row table, or a map file read as the resonance its attributes give)."""
    path = tmp_path / "one.csv"
    path.write_text(HEAD + "mode,condition,frequency_hz\n1,free,60000\n")
    assert cli.main(["discrepancy", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "one.csv: only the first free resonance" in err
    path.write_text(HEAD + "mode,condition,frequency_hz,quality_factor\n1,free,60000,300\n")
    assert cli.main(["discrepancy", str(path)]) == 0       # its Q is a value to compare


def test_the_viscous_width_carries_the_uncertainty_of_the_loss_it_is_made_of(tmp_path, capsys):
    """The half-power width of viscous drag was printed bare ('viscous_width_hz = 1924.8 Hz') beside its loss
    0.02588 +- 0.00099 (the shared PMN28 image's two rows): the width is f1 times the loss, so is its uncertainty."""
    path = tmp_path / "t.csv"
    path.write_text("# spring_constant: 1\n# length: 225e-6\n# tip_height: 13e-6\n"
                    "mode,condition,frequency_hz,quality_factor\n1,free,74369,20\n1,contact,348400,218.47\n")
    out = tmp_path / "d.json"
    assert cli.main(["discrepancy", str(path), "--json", str(out)]) == 0
    results = json.loads(out.read_text())["results"]
    loss, width = results["viscous_loss"], results["viscous_width"]
    assert width["stderr"] == pytest.approx(74369 * loss["stderr"], rel=1e-9) and width["stderr"] > 0
    assert re.search(r"viscous_width_hz = \d+ \+- \d+ Hz", capsys.readouterr().out)
