"""``pfmdyn discrepancy`` honest on little data: degrees of freedom stated, nothing named that
the data cannot test, absurd effects not findings, the noise read right on band-limited data.

Spectra come from the independent finite-element beam (``tests/fe_beam.py``:
:func:`fe_beam.acquisition_case`, band-limited sampling, air damping, gain drift), never from
the fitted model; real files from ``../shared/realdata``.  Sweeps with pass rates per class:
``benchmarks/discrepancy_acquisition.py``.
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam, acquisition_case, silicon_lever, spectrum  # noqa: E402
from schema_check import validate  # noqa: E402
from test_instruments import ASYLUM, THERMAL  # noqa: E402

from pfmdyn import cli  # noqa: E402
from pfmdyn.discrepancy.model import Model  # noqa: E402
from pfmdyn.discrepancy.plausible import implausible  # noqa: E402
from pfmdyn.discrepancy.effects import EFFECTS  # noqa: E402
from pfmdyn.discrepancy.spectrum import SpectrumProblem, analyse, noise_sigma  # noqa: E402
from pfmdyn.io.tables import read  # noqa: E402

REAL = [ASYLUM / name for name in ("PTO_Funakubo0001.h5", "PMN28Pt0000.h5", "IgorIBWReader_ImageStack_BTFO_DSO.ibw",
                                   "IgorIBWReader_P0089OP0027.ibw")]


def _run(tmp_path, path, *flags) -> dict:
    out = tmp_path / "r.json"
    assert cli.main(["discrepancy", str(path), "--json", str(out), *flags]) == 0
    document = json.loads(out.read_text())
    validate(document)
    return document


@pytest.mark.skipif(not ASYLUM.is_dir(), reason="real data absent")
@pytest.mark.parametrize("path", REAL, ids=lambda p: p.name)
def test_real_files_state_dof_and_name_no_untestable_mechanism(tmp_path, capsys, path):
    """Every real resonance file: the JSON and the summary state data values, fitted
    parameters and dof; no file gets more damping mechanisms (or effects) than its values
    can test (PTO_Funakubo0001 got two mechanisms from two Q values, gap 4.89 -> 0.00).
    PMN28Pt0000 records no width, and none is asked for."""
    report = _run(tmp_path, path, "--tip-height", "1e-5", "--length", "2.4e-4")
    summary = capsys.readouterr().out
    results, fit = report["results"], {k: v["value"] for k, v in report["fit"].items() if "value" in v}
    n_q = sum(q is not None for q in results.get("measured_quality_factor", {}).get("value", []))
    assert fit["degrees_of_freedom"] == fit["points"] - fit["fitted_parameters"] >= 0
    assert f"{fit['points']} data values, {fit['fitted_parameters']} fitted parameters" in summary
    # One mechanism is tested by the undamped baseline (1/Q = 0); a second needs a Q left over.
    assert len(results["damping_mechanisms"]["value"]) <= max(n_q - 1, 1)
    named = report["missing_effects"]
    assert fit["degrees_of_freedom"] >= 1 or named in ([], ["damping"]), (named, fit["degrees_of_freedom"])
    if n_q == 2:
        assert any(n.startswith("damping: ") and "a second damping mechanism" in n for n in report["notes"])


@pytest.mark.skipif(not ASYLUM.is_dir(), reason="real data absent")
def test_a_file_without_length_asks_for_it_only_with_a_given_tip_height(capsys):
    """The tip height has its default in every command: a file that records neither it nor the length takes a
    typical PFM lever's length too, as stiffness does (only their ratio acts); a tip height given needs the length."""
    assert cli.main(["discrepancy", str(ASYLUM / "PMN28Pt0000.h5")]) == 0
    assert "assumed: lever length 0.000225 m" in capsys.readouterr().out
    assert cli.main(["discrepancy", str(ASYLUM / "PMN28Pt0000.h5"), "--tip-height", "13e-6"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith("lever length not in PMN28Pt0000.h5: give --length"), err


def test_second_mechanism_untestable_from_two_q_values(tmp_path):
    """A two-row table (free 1, contact 1, each with Q) whose Q values no single mechanism
    explains: the second mechanism is not named (two parameters on two Q values test
    nothing), the misfit is unexplained, and the reason is stated."""
    text = ("# spring_constant_n_per_m: 1.17\n# length_m: 2.4e-4\n# tip_height_m: 1e-5\n"
            "# free_resonance_hz: 59758\nmode,condition,frequency_hz,quality_factor\n"
            "1,free,59758,138\n1,contact,371710,312.72\n")
    path = tmp_path / "t.csv"
    path.write_text(text)        # no width: not needed
    report = _run(tmp_path, path)
    assert report["fit"]["points"]["value"] == 3 and len(report["results"]["damping_mechanisms"]["value"]) == 1
    assert report["missing_effects"] == ["damping"] and "unexplained" in report["fit"]
    assert any(n.startswith("damping: not testable with these data") for n in report["notes"])
    assert any(n.startswith("tip_setback: ") for n in report["notes"])


def test_implausible_effects_are_not_findings():
    """A tip heavier than twice the beam, k2 five decades below k1, a set-back at the bound:
    each flagged with why; a plausible tip mass and set-back pass."""
    meta = SimpleNamespace(spring_constant=0.5, length=1.6e-4, tip_height=1e-5, free_resonance=2e4)
    heavy = SimpleNamespace(model=Model(meta, ("tip_mass",)), internal=np.array([2.0, 1.0, 2.2]), fitted=None)
    assert "times the beam mass" in implausible(heavy)["tip_mass"]
    loose = SimpleNamespace(model=Model(meta, ("tip_mass",)), internal=np.array([3.6, -2.0, 0.3]), fitted=None)
    assert "k2 = 2.5e-06 k1" in implausible(loose)["tip_mass"]
    bound = SimpleNamespace(model=Model(meta, ("tip_setback",)), internal=np.array([2.0, 1.5, 0.5]), fitted=None)
    assert "lower bound" in implausible(bound)["tip_setback"]
    fine = SimpleNamespace(model=Model(meta, ("tip_mass", "tip_setback")), internal=np.array([2.0, 1.8, 0.3, 0.87]),
                           fitted=None)
    assert implausible(fine) == {}


@pytest.mark.parametrize("kind, seed", [("band_viscous", 1), ("band_air", 2)])
def test_noise_estimate_holds_on_band_limited_data(tmp_path, kind, seed):
    """2-4 bands of 64-256 bins around the contact resonances: the noise estimate within
    10 % of the noise the generator added (second differences alone read it 17-32 % high on
    these two)."""
    text, truth = acquisition_case(seed, kind)
    path = tmp_path / "s.csv"
    path.write_text(text)
    data = read(path)
    ratio = noise_sigma(data.frequency_hz, data.bias_v, data.response) / truth["noise_sigma"]
    assert 0.9 < ratio < 1.1, ratio


def test_band_limited_spectrum_finds_every_band_peak_and_names_damping(tmp_path):
    """Three bands of 64-256 bins around the contact resonances, viscous damping hidden:
    every band's peak is found (the median of all bands hid two of the three, and the
    spring start then missed: gap 339, nothing named) and damping alone is named."""
    from pfmdyn.discrepancy.peaks import data_peaks
    text, truth = acquisition_case(2, "band_viscous")
    path = tmp_path / "s.csv"
    path.write_text(text)
    data = read(path)
    np.testing.assert_allclose(data_peaks(data), truth["contact_hz"], rtol=1e-3)
    report = analyse(data, progress=False)
    assert report["missing_effects"] == ["damping"] and report["gap_after"] < 1.5
    assert report["dof"] == report["data_values"] - report["fitted_parameters"] > 0


@pytest.mark.skipif(not THERMAL.is_file(), reason="real data absent")
def test_one_q_value_rejects_the_undamped_model_but_does_not_test_damping():
    """The thermal tune reduced to its one free mode and Q (``pfmdyn discrepancy`` fits the tune's whole
    spectrum instead, tests/test_thermal_fit.py): the undamped baseline (Q infinite) is rejected, so
    damping is named, but its one parameter reproduces the one Q by construction (dof 0): the report
    says the damping model is not testable with these data, and the mechanisms fit alike."""
    from pfmdyn.analysis.thermal import instrument_resonances
    from pfmdyn.discrepancy.resonances import analyse_resonances

    data = instrument_resonances(THERMAL, {"tip_height": 1.2e-5, "length": 2.25e-4})
    with threadpool_limits(1, user_api="blas"):
        report = analyse_resonances(data, progress=False).to_dict()
    assert (report["data_values"], report["fitted_parameters"], report["dof"]) == (1, 1, 0)
    assert report["missing_effects"] == ["damping"] and len(report["damping_mechanisms"]) == 1
    assert report["gap_before"] > 5 and report["unexplained"] is None
    why = report["untestable_effects"]["damping"]
    assert why.startswith("not testable with these data: 1 Q value(s) and 1 damping parameter(s) "
                          "(0 degree(s) of freedom left)"), why
    assert report["damping_mechanisms_indistinguishable_from"]


def _read_text(tmp_path, text):
    path = tmp_path / "s.csv"
    path.write_text(text)
    return read(path)


def _analyse(data) -> dict:
    with threadpool_limits(1, user_api="blas"):        # as the command runs it
        return analyse(data, progress=False)


def _honest_or_exact(report: dict, hidden: list[str]) -> str:
    """``exact`` (the hidden set, gap within the unexplained threshold) or ``honest``
    (unexplained, with where); fails on a false effect or a miss without ``unexplained``."""
    named = report["missing_effects"]
    assert set(named) <= set(hidden), f"false effect: {named} (hidden {hidden})"
    if sorted(named) == sorted(hidden) and report["gap_after"] <= 2:
        return "exact"
    assert report["unexplained"] is not None, (named, report["gap_after"])
    assert len(report["unexplained"]["where"]) == 2, report["unexplained"]
    return "honest"


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0], ids=["soft-tip-0.71L"])      # the class's sweep: benchmarks/discrepancy_acquisition.py
def test_large_setback_named_exactly(tmp_path, seed):
    """Soft (k 0.62 N/m, tip at 0.711 L) and stiff (k 14.5 N/m, tip at 0.739 L) levers with
    viscous damping, three biases, 1-2 % noise, instrument order: damping and the set-back are
    named, the tip position within 0.01 L, the gap at the noise.  Seed 0 named a false tip
    mass and tilt (gap 6) and seed 1 nothing but damping (gap 614): the set-back tip puts
    contact mode 2 near a node of the slope, where its peak stands only 2-3 times above the
    median (beside its antiresonance) though hundreds of noise levels, and the peak search
    (5 x the median) missed it; the spring starts then matched the other two peaks with that
    mode elsewhere."""
    text, truth = acquisition_case(seed, "large_setback")
    data = _read_text(tmp_path, text)
    report = _analyse(data)
    assert _honest_or_exact(report, truth["hidden"]) == "exact", report["missing_effects"]
    assert report["damping_mechanisms"] == ["viscous"] and report["gap_after"] < 1.2
    assert abs(report["parameters"]["tip_position"]["value"] - truth["gamma"]) < 0.01
    assert abs(math.log10(report["parameters"]["k1"]["value"] / truth["k1"])) < 0.02


@pytest.mark.parametrize("kind, seed", [("gain_drift", 1), ("band_air", 1)])
def test_air_damping_is_the_fluid_not_a_background(tmp_path, kind, seed):
    """A detector gain drifting by 0.4 % between bias sweeps (with air damping), and air damping
    alone (width ~ sqrt f) sampled in bands.  Before the fluid's law was in the library, the
    damping named left a misfit that a background lowered by reshaping the peaks (refused, and
    reported as unexplained); with it, the damping is the fluid's and the gap is at the noise."""
    text, truth = acquisition_case(seed, kind)
    report = _analyse(_read_text(tmp_path, text))
    assert _honest_or_exact(report, truth["hidden"]) == "exact", report["missing_effects"]
    assert report["missing_effects"] == ["damping"] and report["damping_mechanisms"] == ["fluid"]
    assert report["gap_after"] <= 1.5 and report["unexplained"] is None


def _damped_lever(seed: int, law: str, gamma: float = 1.0) -> tuple[str, dict]:
    """One lever (k 0.2-40 N/m, L 120-450 um, k1/k 10-1000) with free mode-1 Q 20-63 under each
    damping law: ``viscous`` (constant width), ``air`` (width ~ sqrt f), ``internal`` (width ~ f);
    400 frequencies over the first two contact modes, three biases, 1 % noise."""
    rng = np.random.default_rng(seed)
    k, L, w, H, f1 = silicon_lever(rng)
    k1 = k * 10 ** rng.uniform(1, 3)
    k2 = k1 * rng.uniform(0.5, 1.0)
    q1 = 10 ** rng.uniform(1.3, 1.8)
    damping = {"viscous": dict(viscous_hz=f1 / q1), "air": dict(viscous_hz=f1 / q1, air_exponent=0.5),
               "internal": dict(Q=q1)}[law]
    beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, gamma=gamma, n_elements=60, **damping)
    contact = FEBeam(k, L, f1, H, k1=k1, k2=k2, gamma=gamma, n_elements=60).contact_resonances(3)
    freq = np.linspace(0.5 * contact[0], 0.5 * (contact[1] + contact[2]), 400)
    return spectrum(beam, freq, (-2.0, 0.0, 2.0), noise=0.01, seed=seed, order="instrument"), {"k1": k1}


@pytest.mark.parametrize("seed, gamma", [(0, 1.0), (1, 1.0), (2, 1.0), (0, 0.85), (1, 0.85)])
def test_spring_starts_do_not_depend_on_the_damping_law(tmp_path, seed, gamma):
    """The same lever with viscous, air (sqrt f) and internal damping: the springs matched to
    the peaks (the start of every fit) agree within 2 % whatever the law.  Tip at the end: the
    baseline's start, within 3 % of the truth.  Tip set back to 0.85 L: the set-back's start as
    the loop makes it once damping is in the model (viscous, from the peak widths, over the
    set-back's profile), k1 within 20 % and the tip within 0.03 L of the truth, the same
    basin for all three laws.  (Ranked by the undamped misfit instead, the internal-friction
    lever's start moved to 0.92 L: the peak shapes, not the positions, decided.)"""
    k1, tip = {}, {}
    for law in ("viscous", "air", "internal"):
        text, truth = _damped_lever(seed, law, gamma)
        problem = SpectrumProblem(_read_text(tmp_path, text))
        meta = problem.data.metadata
        if gamma == 1.0:
            start = problem.resonance_starts(Model(meta), [np.array([])], count=1)[0]
        else:
            g = problem.damping_seeds()["viscous"]
            seeds = [np.array([g, gamma_seed]) for gamma_seed in EFFECTS["tip_setback"].seeds]
            start = problem.resonance_starts(Model(meta, ("damping_viscous", "tip_setback")), seeds, count=1)[0]
            tip[law] = start[-1]
        k1[law] = 10 ** start[0]
    assert max(k1.values()) / min(k1.values()) < 1.02, k1
    tolerance = 0.03 if gamma == 1.0 else 0.2
    assert all(abs(v / truth["k1"] - 1) < tolerance for v in k1.values()), (k1, truth["k1"])
    assert all(abs(v - gamma) < 0.03 for v in tip.values()), tip


@pytest.mark.slow
def test_same_named_set_under_every_damping_law(tmp_path):
    """The set-back lever (tip at 0.85 L) under air (sqrt f) and internal damping:
    damping and the set-back are named for each, nothing else, the gap within the unexplained
    threshold (air damping named a false background before: its smooth remainder, 0.4 % of
    the response, below the noise)."""
    for law in ("air", "internal"):         # (viscous: test_hidden_effect_is_named and the spring starts above)
        text, _ = _damped_lever(0, law, 0.85)
        report = _analyse(_read_text(tmp_path, text))
        assert sorted(report["missing_effects"]) == ["damping", "tip_setback"], (law, report["missing_effects"])
        assert report["gap_after"] <= 2 and report["unexplained"] is None, (law, report["gap_after"])
        assert abs(report["parameters"]["tip_position"]["value"] - 0.85) < 0.02, law


@pytest.mark.slow
def test_band_air_setback_is_explained_by_the_fluid(tmp_path):
    """Bands around three contact modes, air damping (width ~ sqrt f) and the tip at 0.82 L: damping
    and the set-back are named and nothing else, the mechanism is the fluid's (its law with
    frequency; before it was in the library the gap stopped at 6.6) and the gap is at the noise."""
    text, truth = acquisition_case(1, "band_air_setback")
    report = _analyse(_read_text(tmp_path, text))
    assert sorted(report["missing_effects"]) == truth["hidden"], report["missing_effects"]
    assert report["damping_mechanisms"] == ["fluid"], report["damping_mechanisms"]
    assert report["gap_after"] <= 1.5 and report["unexplained"] is None, report["gap_after"]
