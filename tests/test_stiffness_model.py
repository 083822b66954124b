"""``pfmdyn stiffness`` on the whole lever model: set-back, heavy and tilted tips, the k2 policy.

Held-out data: contact resonances from an independent exact beam solution
(``tests/exact_beam.py``: an 8 x 8 two-segment determinant in mpmath at 30 digits, springs
from the tip's energy on a tilted lever), never from ``generated/``.  Levers over the real
ranges (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4, tip at 0.7-1 L, tip mass ratio 0-0.5, tilt
0-15 deg) with fixed seeds.
"""
import json
import re
import shlex
import sys
from pathlib import Path

import numpy as np
import pytest

# The independent exact beam lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from exact_beam import ExactLever, random_lever  # noqa: E402
from pfmdyn import cli
from pfmdyn.analysis import contact_resonance as cr
from pfmdyn.analysis.stiffness_report import analyse
from pfmdyn.cantilever import Cantilever, Contact
from pfmdyn.errors import UserError

# The issue's example: two contact modes of a lever whose tip sits at 0.93 L, k2 = 0, k1 = 300 N/m.
EXAMPLE = ExactLever(spring_constant=3.0, free_resonance=70e3, length=225e-6, tip_height=15e-6, k1=300.0,
                     tip_position=0.93)


def lever_of(e: ExactLever, **changes) -> Cantilever:
    """What the user states about the exact lever (tip position at the end unless changed)."""
    values = dict(spring_constant=e.spring_constant, free_resonance=e.free_resonance, length=e.length,
                  tip_height=e.tip_height, tip_mass_ratio=e.tip_mass_ratio, tilt=e.tilt)
    values.update(changes)
    return Cantilever(**values)


@pytest.fixture(scope="module")
def example_hz():
    return EXAMPLE.contact_resonances(2)


def test_exact_beam_matches_the_composed_model_and_the_tilt_sign():
    """The two routes agree for a heavy, set-back, tilted tip; the opposite tilt is percent-level off."""
    e = ExactLever(3.0, 70e3, 225e-6, 15e-6, k1=300.0, k2=50.0, tip_position=0.93, tip_mass_ratio=0.2, tilt=12.0)
    exact = np.array(e.contact_resonances(2))
    for tilt, close in ((12.0, True), (-12.0, False)):
        lever = lever_of(e, tip_position=0.93, tilt=tilt)
        modes = cr.mode_numbers(cr.betas(lever, exact), lever, 300.0, 50.0, 0.93)
        k1 = [float(cr.k1_at(b, m, lever, Contact(k2=50.0), 0.93))
              for b, m in zip(cr.betas(lever, exact), (1, 2))]
        assert (np.allclose(k1, 300.0, rtol=1e-9) and modes.tolist() == [1, 2]) == close


def test_issue_example_two_modes_alone_are_not_unique(example_hz, tmp_path, capsys):
    out = tmp_path / "k.json"
    base = ["stiffness", "--free-resonance", "70e3", "--spring-constant", "3", "--length", "225e-6",
            "--tip-height", "15e-6"] + [a for f in example_hz for a in ("--contact", repr(f))]
    assert cli.main(base + ["--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert not doc["results"]["unique"]["value"] and doc["results"]["k1"]["value"] is None
    assert "not unique" in capsys.readouterr().out
    readings = {"k2" if s["k2"]["status"] == "derived" else "tip_position": {k: v["value"] for k, v in s.items()}
                for s in doc["fit"]["solutions"]}
    assert abs(readings["k2"]["k1"] / 300 - 1) > 0.1            # the old answer, k1 = 253
    tip = readings["tip_position"]
    assert abs(tip["k1"] / 300 - 1) < 1e-6 and abs(tip["tip_position"] - 0.93) < 1e-6
    # --tip-position fit: the L1/L method, unique in the searched box, with uncertainties.
    assert cli.main(base + ["--tip-position", "fit", "--contact-uncertainty", "20", "--json", str(out)]) == 0
    notes = json.loads(out.read_text())["notes"]
    doc = json.loads(out.read_text())["results"]
    assert doc["unique"]["value"] and abs(doc["k1"]["value"] / 300 - 1) < 1e-6
    assert abs(doc["tip_position"]["value"] - 0.93) < 1e-6
    assert doc["k2"]["value"] == 0.0 and doc["k1"]["stderr"] > 0 and doc["tip_position"]["stderr"] > 0
    assert "L1/L" in notes[0] and "cross 1 time" in notes[1]
    # the printed resonances command carries the L1/L method's k2 = 0 (resonances alone would tie k2 to k1)
    command = next(line.partition("): ")[2] for line in capsys.readouterr().out.splitlines()
                   if line.startswith("the same lever in resonances"))
    argv = shlex.split(command)
    assert argv[argv.index("--k2") + 1] == "0" and float(argv[argv.index("--tip-position") + 1]) == pytest.approx(0.93)
    assert cli.main([*argv[1:], "--modes", "2", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["results"]["contact"]["resonance"]["value"] == pytest.approx(example_hz, rel=1e-6)


def test_k1_and_tip_position_from_two_exact_modes_over_real_levers():
    """Held-out check of the issue: k1 and the tip position to 1e-4 (k2 = 0 or a stated ratio)."""
    rng = np.random.default_rng(2026)
    worst, unique = 0.0, 0
    for i in range(6):
        ratio = 0.0 if i % 2 else round(float(rng.uniform(0.3, 1.0)), 3)
        e = random_lever(rng, k2_over_k1=ratio)
        fc = e.contact_resonances(2)
        contact = Contact(k2_over_k1=ratio) if ratio else Contact()
        r = analyse(lever_of(e), contact, fc, fit_tip_position=True)
        truth = [s for s in r.solutions if abs(s.tip_position - e.tip_position) < 1e-3]
        assert len(truth) == 1, (e, r.solutions)
        s = truth[0]
        worst = max(worst, abs(s.k1 / e.k1 - 1), abs(s.tip_position - e.tip_position))
        unique += r.unique
        if not r.unique:           # two (k1, tip position) in the box: a third mode decides
            assert "a third contact mode decides" in " ".join(r.proof)
            three = analyse(lever_of(e), contact, e.contact_resonances(3), fit_tip_position=True)
            assert three.unique and abs(three.solution.tip_position - e.tip_position) < 1e-4
            worst = max(worst, abs(three.solution.k1 / e.k1 - 1))
    assert worst < 1e-4, worst
    assert unique == 5             # this seed draws one lever whose two modes allow two solutions


def test_one_mode_ties_k2_by_mindlin_unless_told(example_hz):
    """One mode of a heavy, tilted, set-back tip: k1 exact when the policy is the truth's, and said."""
    rng = np.random.default_rng(7)
    for policy in (Contact(), Contact(poisson=0.25), Contact(k2=0.0)):
        e = random_lever(rng, k2_over_k1=policy.tie() if policy.k2 is None else 0.0)
        fc = e.contact_resonances(1)
        r = analyse(lever_of(e, tip_position=e.tip_position), policy, fc)
        assert r.unique and abs(r.solution.k1 / e.k1 - 1) < 1e-7
        assert ("Mindlin" in r.k2_policy) == (policy.k2 is None)
        if policy.k2 is None and policy.poisson is None:
            assert "assumed" in r.k2_policy


def test_k1_and_k2_from_two_modes_at_a_stated_tip_position():
    """Two modes: every (k1, k2) solution (the truth among them); a third mode decides when two exist."""
    rng = np.random.default_rng(11)
    ambiguous = 0
    for _ in range(3):
        e = random_lever(rng, k2_over_k1=float(rng.uniform(0.2, 1.2)))
        fc = e.contact_resonances(3)
        lever = lever_of(e, tip_position=e.tip_position)
        r = analyse(lever, Contact(), fc[:2])
        assert all(s.unknowns == ("k1", "k2") for s in r.solutions)
        assert sum(abs(s.k1 / e.k1 - 1) < 1e-6 and abs(s.k2 / e.k2 - 1) < 1e-6 for s in r.solutions) == 1
        assert r.unique == (len(r.solutions) == 1) and (r.unique or "a third contact mode decides" in r.proof[0])
        ambiguous += not r.unique
        three = analyse(lever, Contact(), fc)
        assert three.unique and abs(three.solution.k1 / e.k1 - 1) < 1e-6 and abs(three.solution.k2 / e.k2 - 1) < 1e-6
    assert ambiguous >= 1          # this seed draws levers where two modes allow two (k1, k2)


def test_a_stated_policy_makes_two_modes_a_least_squares_k1():
    e = random_lever(np.random.default_rng(5), k2_over_k1=0.5)
    fc = e.contact_resonances(2)
    r = analyse(lever_of(e, tip_position=e.tip_position), Contact(k2_over_k1=0.5), fc)
    assert r.unique and np.allclose(r.solution.k1_by_mode, e.k1, rtol=1e-7)
    assert abs(r.solution.k1 / e.k1 - 1) < 1e-7 and r.solution.residual < 1e-10
    # A wrong tip position: the modes disagree, and the report shows it.
    wrong = analyse(lever_of(e, tip_position=max(0.7, e.tip_position - 0.05)), Contact(k2_over_k1=0.5), fc)
    spread = np.ptp(np.log(wrong.solution.k1_by_mode))
    assert spread > 1e-3 and wrong.solution.residual > 1e-6


def test_propagated_uncertainty_of_k1_and_tip_position_matches_the_scatter(example_hz):
    """Gaussian noise on both contact frequencies: the scatter of the refit equals the propagated sigma."""
    lever, sigma = lever_of(EXAMPLE), 30.0
    truth = {"k1": 300.0, "tip_position": 0.93}
    cov = cr.covariance(lever, Contact(), example_hz, truth, sigma)
    rng = np.random.default_rng(3)
    draws = np.array([list(cr.fit(lever, Contact(), np.array(example_hz) + sigma * rng.standard_normal(2),
                                  truth)[0].values()) for _ in range(150)])
    ratio = draws.std(axis=0) / np.sqrt(np.diag(cov))
    assert np.all(np.abs(ratio - 1) < 0.2), ratio          # 150 draws: about 6 % scatter of a std


def test_frequencies_outside_the_model_name_the_effect():
    lever = Cantilever(2.0, 60e3, 2e-4, tip_height=1e-5, tip_mass_ratio=0.3, tip_position=0.95)
    with pytest.raises(UserError, match="no contact stiffness lowers a resonance"):
        analyse(lever, Contact(k2=0.0), [0.9 * 60e3])
    with pytest.raises(UserError, match="stiff limit"):
        analyse(lever, Contact(k2=0.0), [9 * 60e3])


def test_k1s_uncertainty_covers_an_assumed_tip_height_and_k2_policy():
    """The user states a datasheet's tip height (the true one within 10 %) and no k2 policy (Mindlin at 0.3
    assumed, the sample's Poisson ratio drawn in 0.2-0.4): the stated 2-sigma interval of k1 holds the
    exact beam's k1, each assumed input named with its share (benchmarks/stiffness_coverage.py: 40/40;
    without the two shares, 7/40)."""
    rng = np.random.default_rng(23)
    for _ in range(4):
        nu = rng.uniform(0.2, 0.4)
        e = random_lever(rng, k2_over_k1=2 * (1 - nu) / (2 - nu))
        fc = e.contact_resonances(1)
        stated = lever_of(e, tip_position=e.tip_position, tip_height=e.tip_height * (1 + 0.1 * rng.standard_normal()))
        s = analyse(stated, Contact(), fc, contact_uncertainty=1e-4 * fc[0]).solution
        assert abs(s.k1 - e.k1) <= 2 * s.stderr["k1"], (e, s)
        assert {"tip_height_uncertainty", "k2_policy_uncertainty"} <= set(s.sources)
    stated_policy = analyse(stated, Contact(poisson=0.3), fc).solution
    assert "k2_policy_uncertainty" not in stated_policy.sources and "tip_height_uncertainty" in stated_policy.sources
    held = analyse(stated, Contact(), fc, tip_height_uncertainty=0.0).solution
    assert "tip_height_uncertainty" not in held.sources and held.stderr["k1"] < s.stderr["k1"]


REAL_IMAGES = Path("/work/shared/realdata/asylum_pfm_images")


@pytest.mark.skipif(not REAL_IMAGES.is_dir(), reason="shared real data absent")
@pytest.mark.parametrize("name", ["IgorIBWReader_ImageStack_BTFO_DSO.ibw", "IgorIBWReader_P0089OP0027.ibw",
                                  "PMN28Pt0000.h5", "PTO_Funakubo0001.h5"])
@pytest.mark.parametrize("tip_height", [None, "12e-6"])
def test_stiffness_then_resonances_gives_back_the_files_contact_resonance(tmp_path, capsys, name, tip_height):
    """One k2 policy and one tip height for every command: the k1 that ``stiffness`` finds in a file (no
    policy: Mindlin assumed by both; the tip height given, or with default flags the typical PFM probe's
    both assume), fed to ``resonances`` with the same lever, puts the first contact resonance where the
    file says, to 1e-6; an assumed tip height is said, marked assumed and has its share of k1's uncertainty."""
    from pfmdyn.constants import LEVER_LENGTH
    from pfmdyn.io.instruments import read_instrument

    path = REAL_IMAGES / name
    fields = read_instrument(path).fields
    height = [] if tip_height is None else ["--tip-height", tip_height]
    # a file without the length: a tip height given needs it; the assumed one stands on a typical lever, and says so
    length = ["--length", repr(fields.get("length", LEVER_LENGTH))]
    out = tmp_path / "s.json"
    assert cli.main(["stiffness", str(path), *height, *(length if height else []), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    k1 = doc["results"]["k1"]["value"]
    text = capsys.readouterr().out
    if tip_height is None:
        assert doc["lever"]["tip_height"]["status"] == "assumed" and "PFM probe" in doc["lever"]["tip_height"]["why"]
        budget = doc["fit"]["budget"]
        share = dict(zip(budget["uncertainty_source"]["value"], budget["relative_uncertainty"]["value"]))
        assert share["tip_height_uncertainty"] > 0.1 and doc["results"]["k1"]["stderr"] >= share[
            "tip_height_uncertainty"] * k1
        # what came from the file, with the contact resonance the k1 rests on (stiffness printed neither)
        assert "assumed: tip height" in text and \
            f"from the file: contact_resonance {fields['contact_resonance']:.6g} Hz (mode 1), " in text
    # what stiffness prints is enough (its k1 line is rounded to the uncertainty): the resonances command it names
    command = next(line.partition("): ")[2] for line in text.splitlines()
                   if line.startswith("the same lever in resonances"))
    argv = shlex.split(command)
    assert argv[:2] == ["pfmdyn", "resonances"] and float(argv[argv.index("--k1") + 1]) == pytest.approx(k1, rel=1e-9)
    assert cli.main([*argv[1:], "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["results"]["contact"]["resonance"]["value"][0] == pytest.approx(fields["contact_resonance"], rel=1e-6)
    assert doc["lever"]["k2"]["status"] == "tied" and "Mindlin" in doc["lever"]["k2"]["why"]
    assert doc["lever"]["tip_height"]["status"] == ("assumed" if tip_height is None else "given")
    assert "k2 policy: k2 tied to k1 by Mindlin" in capsys.readouterr().out


@pytest.mark.skipif(not REAL_IMAGES.is_dir(), reason="shared real data absent")
def test_discrepancy_states_every_assumed_input_of_k1_as_stiffness_does(tmp_path, capsys):
    """``discrepancy`` on the shared BTFO image with default flags: the tip height assumed as by every command,
    k1's uncertainty input by input (the tip height, the k2 policy, the table's frequency and Q uncertainties it
    assumed, marked assumed) and the same k1 and uncertainty as ``stiffness`` (within 5 %)."""
    path = REAL_IMAGES / "IgorIBWReader_ImageStack_BTFO_DSO.ibw"
    out = tmp_path / "d.json"
    assert cli.main(["discrepancy", str(path), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "assumed: tip height" in text and "k1's uncertainty, input by input: tip height" in text
    doc = json.loads(out.read_text())
    assert doc["lever"]["tip_height"]["status"] == "assumed"
    assert doc["results"]["resonance_uncertainty"]["status"] == "assumed"
    assert doc["results"]["quality_factor_uncertainty"]["status"] == "assumed"
    budget = doc["fit"]["budget"]
    assert set(budget["uncertainty_source"]["value"]) == {"resonance_frequencies", "quality_factors", "tip_height",
                                                        "k2_policy"}
    k1 = doc["results"]["k1"]
    assert cli.main(["stiffness", str(path), "--json", str(out)]) == 0
    reference = json.loads(out.read_text())["results"]["k1"]
    assert k1["value"] == pytest.approx(reference["value"], rel=1e-3)
    assert k1["stderr"] == pytest.approx(reference["stderr"], rel=0.05)


def test_modes_that_disagree_widen_k1s_uncertainty_by_their_spread(capsys):
    """Two modes of a lever whose tip sits at 0.95 L (k1 = 100 N/m) read with the tip stated at the end: each mode's
    own k1 is 171 and 71 N/m, yet k1 was stated +- 0.5 % (the frequencies' uncertainty alone).  The modes'
    disagreement is now in k1's uncertainty, named, and the truth within two of it."""
    exact = ExactLever(spring_constant=3.0, free_resonance=70e3, length=225e-6, tip_height=15e-6, k1=100.0,
                       tip_position=0.95)
    argv = ["stiffness", "--free-resonance", "70e3", "--spring-constant", "3", "--length", "225e-6", "--tip-height",
            "15e-6", "--k2", "0", *[a for f in exact.contact_resonances(2) for a in ("--contact", repr(f))]]
    assert cli.main(argv) == 0
    text = capsys.readouterr().out
    k1, sigma = (float(x) for x in re.search(r"^k1 = ([\d.]+) \+- ([\d.e+]+) N/m", text, re.MULTILINE).groups())
    by_mode = [float(x) for x in re.search(r"k1 from each mode alone: ([\d.]+), ([\d.]+)", text).groups()]
    assert sigma >= abs(by_mode[0] - by_mode[1]) / 2 * 0.99 and abs(k1 - 100) < 2 * sigma
    assert "the modes' disagreement" in text
