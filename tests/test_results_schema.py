"""Every command's JSON document on small inputs, validated against its kind's schema (issue 39, item 1).

Each document is one envelope (``pfmdyn.io.results``) with one record per number; its schema is the
package's ``pfmdyn/schemas/COMMAND.KIND.json``, every key outside the envelope and the record a name
of ``pfmdyn.names`` (``tests/schema_check.py``), and ``to_dataset`` reads it as an xarray Dataset.
The inputs are the smallest that give each kind (a few seconds in all); the physics of each command
is tested in its own file.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from schema_check import SCHEMAS, validate  # noqa: E402

from pfmdyn import cli  # noqa: E402
from pfmdyn.io.results import quantity, to_dataset  # noqa: E402

LEVER = ["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4"]
PROBE = LEVER + ["--tip-height", "1e-5", "--k1", "100"]
TABLE = ("# spring_constant: 2\n# length: 2e-4\n# tip_height: 1e-5\n# free_resonance: 7e4\n"
         "mode,condition,frequency_hz\n1,free,70000\n2,free,438683\n1,contact,277474\n")


FREQUENCY_BIAS = "frequency_hz,bias_v,x,y\n" + "".join(f"{f},{v},{1 + 0.1 * v},{0.1 * v}\n"
                                                     for f in (1e5, 2e5, 3e5) for v in (-1, 0, 1))
"""Frequency-bias data: at each of three frequencies a line 1 + (0.1 + 0.1i) V."""


def _tune_csv(path: Path) -> Path:
    """A thermal tune: a lever's first mode (180 kHz, Q 300) over a white floor, as CSV in m/sqrt(Hz)."""
    from pfmdyn.generated.formulas import oscillator_asd

    f = np.linspace(1e3, 4e5, 1000)
    asd = oscillator_asd(f, 1.8e5, 300.0, 1.03e-15, 3e-14)
    path.write_text("frequency_hz,asd_m_per_sqrthz\n" + "".join(f"{a:.9g},{b:.9g}\n" for a, b in zip(f, asd)))
    return path


def _contact_map(path: Path) -> Path:
    h5py = pytest.importorskip("h5py")
    pytest.importorskip("zarr")
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((2, 3), 3e5)
        h.attrs.update(spring_constant=2.0, free_resonance=7e4)
    return path


CASES = {
    "resonances": lambda tmp: ["resonances", *PROBE, "--quality-factor", "50", "--modes", "2"],
    "spot": lambda tmp: ["spot", *PROBE, "--drive-frequency", "1e5"],
    "roots": lambda tmp: ["roots", "elastic", "--modes", "2", "--k1-over-k", "50", "--k2-ratio", "0.5"],
    "stiffness": lambda tmp: ["stiffness", *LEVER[:4], "--contact", "3e5", "--contact-uncertainty", "100"],
    "inspect": lambda tmp: ["inspect", str(_write(tmp / "t.csv", TABLE))],
    "calibrate": lambda tmp: ["calibrate", str(_tune_csv(tmp / "tune.csv")), "--medium", "air", "--length",
                              "225e-6", "--width", "40e-6"],
    "discrepancy": lambda tmp: ["discrepancy", str(_write(tmp / "t.csv", TABLE))],
    "map": lambda tmp: ["map", str(_contact_map(tmp / "cr.h5")), "--out", str(tmp / "out")],
    "branches": lambda tmp: ["branches", "elastic", "--plot", str(tmp / "b.png"), "--points", "5", "--modes", "2"],
    "diagram": lambda tmp: ["diagram", "--plot", str(tmp / "d.png"), "--frequency-points", "6", "--bias-points", "3",
                            "--quality-factor", "30"],
    "deconvolve": lambda tmp: ["deconvolve", str(_write(tmp / "fv.csv", FREQUENCY_BIAS)), "--surface-potential",
                               "0.2", "--out", str(tmp / "out"), *PROBE],
}
"""Command -> its argument list on small inputs (``--json`` added)."""


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize("command", sorted(CASES))
def test_every_command_writes_its_kind(command, tmp_path, capsys):
    """The document validates, has only names for keys, reads as a Dataset, and ``--json -`` prints the same."""
    out = tmp_path / "o.json"
    assert cli.main([*CASES[command](tmp_path), "--json", str(out)]) in (0, 1)
    doc = json.loads(out.read_text())
    assert doc["command"] == command
    validate(doc)
    dataset = to_dataset(doc)
    for name, variable in dataset.data_vars.items():
        assert variable.attrs.get("units") and variable.attrs.get("status") or name.endswith("_stderr"), name
    capsys.readouterr()


def test_the_discrepancy_kinds_and_the_map_summary_validate(tmp_path):
    """The kinds the walk above does not reach in seconds (a spectrum, a sweep, two sweeps, a tune, a beam
    map) are tested where their commands are (test_discrepancy*, test_sweeps_fit, test_thermal_fit): here
    each has a schema, and a schema rejects a record that breaks the rules."""
    kinds = {p.stem for p in SCHEMAS.glob("*.*.json")}
    assert {"discrepancy.spectrum", "discrepancy.resonances", "discrepancy.sweep", "discrepancy.comparison",
            "discrepancy.thermal", "calibrate.thermal_tune", "stiffness.contact_resonance", "map.map"} <= kinds
    from pfmdyn.io.results import document

    good = document("stiffness", "contact_resonance", {"path": None}, None,
                    {name: quantity(name, 1.0, status="derived") for name in ("k1", "k2", "tip_position")}
                    | {"unique": quantity("unique", True, status="derived"),
                       "contact_resonance": quantity("contact_resonance", [3e5], status="given", dims=["mode"]),
                       "mode": quantity("mode", [1], status="given", dims=["mode"])}, {"solutions": []})
    validate(good)
    for broken in ({"value": None, "stderr": None, "unit": "N/m", "status": "fitted"},     # null, not undetermined
                   {"value": 1.0, "stderr": None, "unit": "N/m", "status": "assumed"},    # no why
                   {"value": 1.0, "stderr": None, "unit": "N/m", "status": "guessed"}):   # not a status
        with pytest.raises(Exception):
            validate({**good, "results": {**good["results"], "k1": broken}})
    with pytest.raises(AssertionError, match="not a name"):
        validate({**good, "results": {**good["results"], "k1_hz": quantity("k1", 1.0)}})


def test_quiet_prints_only_a_document_asked_on_standard_output(capsys):
    """``--quiet`` (every command): nothing but errors; ``--json -`` still prints the document, alone."""
    assert cli.main(["roots", "free", "--modes", "1", "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    assert cli.main(["roots", "free", "--modes", "1", "--digits", "5", "--quiet", "--json", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["results"]["root"]["value"] == ["1.8751"]


def test_the_walk_covers_every_command_with_a_result():
    """Every command of ``pfmdyn --help`` writes its document in the walk above, but those with no result
    of their own: ``codegen`` and ``book`` write files, ``verify --json`` the claims' verdicts (their own
    format, read by the book)."""
    from pfmdyn.cli import COMMANDS

    assert set(COMMANDS) - {"codegen", "book", "verify"} == set(CASES)


def test_the_new_documents_hold_their_results(tmp_path, capsys):
    """diagram: the map follows from the parts per frequency; deconvolve: the line 1 + (0.1 + 0.1i) V of
    the data at V_surf 0.2; branches: each crossover between the roots swept around it."""
    from pfmdyn.analysis.diagram import response_map, table1_cantilever

    docs = {}
    for command in ("diagram", "deconvolve", "branches"):
        out = tmp_path / f"{command}.json"
        assert cli.main([*CASES[command](tmp_path), "--json", str(out), "--quiet"]) == 0
        docs[command] = to_dataset(json.loads(out.read_text()))
    d = docs["diagram"]
    lever = table1_cantilever("A", quality_factor=30.0)
    expected = response_map(lever, d["frequency"].values, d["tip_bias"].values, width=float(d["width"]),
                            k1=float(d["k1"]), H=float(d["tip_height"]), d_eff=float(d["d_eff"]))
    total = d["piezo_response"] + (d["local_electrostatic_response"] + d["nonlocal_electrostatic_response"]) * (
        d["tip_bias"] - float(d["surface_potential"]))
    np.testing.assert_allclose(total.values, expected.total, rtol=1e-12)
    v = docs["deconvolve"]
    np.testing.assert_allclose(v["measured_d_eff"].values, 1 + (0.1 + 0.1j) * 0.2, rtol=1e-12)
    np.testing.assert_allclose(v["electrostatic_slope"].values, 0.1 + 0.1j, rtol=1e-12)
    assert v["calibration_factor"].attrs["status"] == "derived"
    b = docs["branches"]
    for n in (0, 1):
        root = b["root"].isel(mode=n).values
        assert root.min() < float(b["crossover_root"][n]) < root.max()
        assert b["frequency_ratio"].isel(mode=n).values == pytest.approx((root / 1.8751040687)**2, rel=1e-9)
