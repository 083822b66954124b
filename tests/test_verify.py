"""The claim checks and the verdict gate of ``pfmdyn verify``."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
import sympy as sp
import yaml

from pfmdyn import cli, typeset, verify
from pfmdyn.audit import text
from pfmdyn.derivations.checks import core
from pfmdyn.derivations.evidence import Evidence, Math, Tex, say
from pfmdyn.derivations.evidence import text as plain
from pfmdyn.derivations.paper import printed as P

SHARED = verify.shared_claims_path() or Path("/nonexistent/claims.yaml")
# The text audit reads the paper's transcription beside the source tree; without it only the
# registry's claims are computed.
PAPER = text.paper_path()


def _verdict(claim_id):
    return core.run_check(core.REGISTRY[claim_id]).verdict


def test_every_registered_claim_has_a_recorded_verdict_equal_to_the_computed_one(all_verdicts):
    recorded = verify.load_recorded()
    if PAPER is None:
        recorded = {i: v for i, v in recorded.items() if i in core.REGISTRY}
    assert {v.id: v.verdict for v in all_verdicts} == recorded


@pytest.mark.skipif(not SHARED.exists(), reason="shared claims file not present")
def test_every_shared_claim_id_is_checked():
    ids = [e["id"] for e in yaml.safe_load(SHARED.read_text())]
    assert set(ids) <= set(core.REGISTRY)


@pytest.mark.skipif(PAPER is None, reason="the errata list holds the text audit's, which needs the paper")
def test_committed_errata_list_is_up_to_date(all_verdicts):
    from pfmdyn import generated
    path = Path(generated.__file__).parent / "errata.md"
    assert path.read_text() == verify.render_errata(all_verdicts)


def test_every_erratum_carries_a_correction_and_evidence(all_verdicts):
    for v in all_verdicts:
        assert v.evidence, v.id
        if v.verdict == core.ERRATUM:
            assert v.correct, v.id


# --- the gate can fail ---------------------------------------------------------------------------

def test_flipping_the_sign_of_a_printed_equation_changes_its_verdict(monkeypatch):
    assert _verdict("eq6.Av") == core.HOLDS
    monkeypatch.setitem(P.ELASTIC, P.d1, -P.ELASTIC[P.d1])
    # No other printed equation pins the sign of A_v, so the flip reads as a convention.
    assert _verdict("eq6.Av") == core.SIGN
    monkeypatch.setitem(P.ELASTIC, P.d1, 2 * P.ELASTIC[P.d1])
    assert _verdict("eq6.Av") == core.ERRATUM


def test_changing_a_factor_in_a_printed_equation_changes_its_verdict(monkeypatch):
    assert _verdict("eq20.pinned_response") == core.HOLDS
    monkeypatch.setattr(P, "theta_nlc", 2 * P.theta_nlc)
    assert _verdict("eq20.pinned_response") == core.ERRATUM


def test_correcting_a_printed_erratum_makes_it_hold(monkeypatch):
    assert _verdict("eq35.roots") == core.ERRATUM
    monkeypatch.setattr(P, "torsion_force_roots", (2 * P.n - 1) * sp.pi / (2 * P.L))
    assert _verdict("eq35.roots") == core.HOLDS
    assert _verdict("eq20.roots") == core.ERRATUM
    monkeypatch.setattr(P, "pinned_roots", ("3.927", "7.069", "10.21"))
    assert _verdict("eq20.roots") == core.HOLDS


def test_a_sign_flip_without_contradicting_anchor_is_a_convention():
    verdict, why = core.sign_flip_verdict({"other equation": False}, "f0 towards the surface")
    assert verdict == core.SIGN and "f0 towards the surface" in plain(why)
    assert core.sign_flip_verdict({"other equation": True}, "")[0] == core.ERRATUM


def test_gate_exits_nonzero_when_a_verdict_differs_from_the_record(tmp_path, monkeypatch, capsys):
    record = {**verify.load_recorded(), "eq6.Av": str(core.ERRATUM)}
    path = tmp_path / "recorded.yaml"
    path.write_text(yaml.safe_dump(record))
    monkeypatch.setattr(verify, "recorded_path", lambda: path)
    assert cli.main(["verify", "--only", "eq6.Av", "--quiet"]) == 1
    assert "eq6.Av: computed holds, recorded erratum" in capsys.readouterr().err


def test_gate_exits_nonzero_when_a_claim_has_no_verdict(tmp_path, monkeypatch, capsys):
    path = tmp_path / "recorded.yaml"
    path.write_text(yaml.safe_dump({}))
    monkeypatch.setattr(verify, "recorded_path", lambda: path)
    assert cli.main(["verify", "--only", "k.from_beam", "--quiet"]) == 1
    assert "no recorded verdict" in capsys.readouterr().err


def test_json_output_and_unknown_id(tmp_path, capsys):
    out = tmp_path / "v.json"
    assert cli.main(["verify", "--only", "eq6.Av", "--only", "eq35.roots", "--json", str(out), "--quiet"]) == 0
    data = json.loads(out.read_text())
    assert [c["id"] for c in data["claims"]] == ["eq6.Av", "eq35.roots"]
    assert set(data["claims"][1]) >= {"id", "verdict", "correct", "evidence"}
    assert cli.main(["verify", "--only", "no.such.claim", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown claim id" in err[0]


# --- library: no files unless asked; summary; LaTeX errata ---------------------------------------

def test_verify_writes_no_file_unless_asked(tmp_path, monkeypatch):
    from pfmdyn import generated
    errata = Path(generated.__file__).parent / "errata.md"
    before = (errata.stat().st_mtime_ns, verify.recorded_path().stat().st_mtime_ns)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["verify", "--only", "eq6.Av", "--quiet"]) == 0
    assert (errata.stat().st_mtime_ns, verify.recorded_path().stat().st_mtime_ns) == before
    assert list(tmp_path.iterdir()) == []
    assert cli.main(["verify", "--only", "eq22.free_response", "--quiet", "--errata", str(tmp_path / "e.md")]) == 0
    assert "\\theta_f" in (tmp_path / "e.md").read_text()


def test_summary_line_counts_each_kind(all_verdicts):
    line = verify.summary(all_verdicts)
    n = verify.counts(all_verdicts)["n"]
    assert line.startswith(f"{len(all_verdicts)} claims: ")
    assert f"registry {n['claim']}" in line
    if n["cross-reference"]:
        assert f"{n['cross-reference']} references" in line and f"{n['statement']} statements" in line


def test_long_expressions_are_broken_to_the_line_width():
    x = sp.Symbol("x")
    long = sum(sp.cos(i * x) * x**i for i in range(1, 25)) / (1 + sum(sp.sinh(i * x) for i in range(1, 20)))
    tex = typeset.display_latex(r"\theta", long)
    assert tex.startswith(r"\begin{aligned}")
    rows = tex.splitlines()[1:-1]
    assert len(rows) > 4 and all(typeset.visible(r) <= typeset.LINE_WIDTH + 8 for r in rows)
    assert typeset.display_latex("y", x + 1) == "y = x + 1"


def test_evidence_is_rendered_from_its_parts_not_parsed():
    x = sp.Symbol("x")
    sentence = say("the slope is ", Math(3 * x**2, "y'"), " for ", Tex(r"x \to \infty", "x -> oo"))
    assert plain(sentence) == "the slope is y' = 3*x**2 for x -> oo"
    assert typeset.markdown(sentence) == r"the slope is $y' = 3 x^{2}$ for $x \to \infty$"
    assert typeset.html(sentence).count('class="math notranslate nohighlight"') == 2 and "**" not in typeset.html(sentence)
    long = Math(sum(sp.cos(i * x) * x**i for i in range(1, 12)), "y")
    assert "pfm-display" in typeset.html(say("so ", long)) and r"\begin{aligned}" in typeset.html(say("so ", long))
    with pytest.raises(TypeError):
        say("a", 1.5)                              # a bare number is not a part: format it as words


def test_every_erratum_is_typeset(all_verdicts):
    """The words of every erratum (printed, proof, correction) hold no formula written as text
    (SymPy's ``**``, ``*``, ``sqrt(``, a power ``^``): formulas are parts that go through LaTeX."""
    for v in all_verdicts:
        if v.verdict not in (core.ERRATUM, core.SIGN):
            continue
        for sentence in (v.printed, v.proof.proof, typeset.correction(v)):
            words = " ".join(p for p in sentence if isinstance(p, str))
            for bad in ("**", "*", "sqrt(", "^"):
                assert bad not in words, (v.id, bad, words)


def test_the_book_orders_the_one_set_of_verdict_names():
    from pfmdyn import book
    assert book.VERDICT_ORDER == tuple(o.value for o in core.Outcome)
    assert core.Outcome("erratum") == "erratum" and str(core.Outcome.SIGN) == "holds_up_to_sign_convention"


def test_measured_ratios_are_judged_within_their_printed_uncertainties():
    from pfmdyn.derivations.checks import numbers
    value, interval = 2.6351759, (2.63287, 2.63748)
    assert numbers._digits_verdict([("2.63", value, interval)], "ratio").verdict == core.HOLDS
    assert numbers._digits_verdict([("2.63", value)], "ratio").verdict == core.ERRATUM       # no uncertainty
    assert numbers._digits_verdict([("2.62", value, interval)], "ratio").verdict == core.ERRATUM
    assert _verdict("exp.tip1_contact_ratio") == core.HOLDS
    tip2 = core.run_check(core.REGISTRY["exp.tip2_noncontact_ratios"])
    assert tip2.verdict == core.ERRATUM and tip2.correct == "6.23 should read 6.27"    # theory, exact
    assert [n.rounded for n in tip2.proof.numbers if not n.ok] == ["6.27"]


def test_a_check_must_return_evidence(monkeypatch):
    check = core.Check("x.prose", ("somewhere",), ("as printed",), lambda: ("holds", "prose", ""))
    with pytest.raises(TypeError, match="Evidence"):
        core.run_check(check)
    good = core.Check("x.data", ("somewhere",), ("as printed",), lambda: Evidence(core.HOLDS, "fine"))
    assert core.run_check(good).evidence == "fine"
