"""The audit of the paper's text: extraction from the transcription and checks against targets.

Skipped when the transcription (shared/paper/ beside the source tree, or $PFMDYN_PAPER) is absent.
Each check is shown to fail on a wrong target and to pass on the right one.
"""
from __future__ import annotations

import re

import pytest

from pfmdyn import audit
from pfmdyn.audit import statements, wording, xref_equations, xref_figures, xref_sections, xref_symbols, xref_tables
from pfmdyn.audit import text as T
from pfmdyn.derivations.checks import core
from pfmdyn.derivations.evidence import text

pytestmark = pytest.mark.skipif(not T.sections(), reason="paper transcription not found")
audit.register()


def _ref(kind, section, sentence, ref_text, targets):
    start = sentence.index(ref_text)
    r = T.Reference(kind, section, sentence, ref_text, targets, start, start + len(ref_text))
    return T.Reference(kind, section, sentence, ref_text, targets, start, start + len(ref_text),
                       T._context(sentence, [r], r) if kind == "figure" else sentence)


def test_every_reference_and_statement_has_an_id_and_a_verdict():
    refs, stmts = T.references(), statements.statements()
    assert len(refs) >= 100 and len(stmts) >= 90 and len(T.symbols()) >= 50
    ids = [i for i in core.REGISTRY if i.startswith(("xref.", "text.", "symbol.", "structure."))]
    assert len(ids) == len(set(ids)) == len(refs) + len(stmts) + len(T.symbols()) + 4 + len(T.captions())
    kinds = {r.kind for r in refs}
    assert kinds == {"equation", "figure", "section", "table"}


def test_captions_are_parsed_into_panels_with_properties():
    fig10 = T.captions()[10]
    assert fig10.panels == tuple("abcdefghijkl")
    assert fig10.described["e"]["regime"] == {"contact"} and fig10.described["c"]["direction"] == {"lateral"}
    assert T.captions()[2].panels == ("a", "b")


@pytest.mark.parametrize("sentence, ref_text, targets, verdict", [
    ("For comparison, Fig. 8 c,d are the response diagrams from the LiNbO$_3$ surface.", "Fig. 8 c,d",
     ((8, ("c", "d")),), core.ERRATUM),
    ("For comparison, Fig. 8 e,f are the response diagrams from the LiNbO$_3$ surface.", "Fig. 8 e,f",
     ((8, ("e", "f")),), core.HOLDS),
    ("This mechanism is illustrated in Fig. 2d.", "Fig. 2d", ((2, ("d",)),), core.ERRATUM),
    ("This mechanism is illustrated in Fig. 2b.", "Fig. 2b", ((2, ("b",)),), core.HOLDS),
])
def test_panel_references_are_checked_against_the_caption(sentence, ref_text, targets, verdict):
    assert xref_figures.check_figure(_ref("figure", "VI1", sentence, ref_text, targets)).verdict == verdict


def test_section_references_are_checked_against_the_section():
    wrong = "Tip wear effect of force-bias response spectrum is illustrated in Section IV.3."
    right = wrong.replace("IV.3", "VI.3")
    assert xref_sections.check_section(_ref("section", "VI", wrong, "Section IV.3", ("IV.3",))).verdict == core.ERRATUM
    assert xref_sections.check_section(_ref("section", "VI", right, "Section VI.3", ("VI.3",))).verdict == core.HOLDS
    missing = wrong.replace("IV.3", "IX.3")
    assert xref_sections.check_section(_ref("section", "VI", missing, "Section IX.3", ("IX.3",))).verdict == core.ERRATUM


def test_equation_references_need_the_right_tip_conditions():
    s = "The resonances are similar to that of a free cantilever under the electrostatic forces given in Eq. (20)."
    assert xref_equations.check_equation(_ref("equation", "III4", s, "Eq. (20)", ("20",))).verdict == core.ERRATUM
    s22 = s.replace("(20)", "(22)")
    assert xref_equations.check_equation(_ref("equation", "III4", s22, "Eq. (22)", ("22",))).verdict == core.HOLDS
    s99 = s.replace("(20)", "(99)")
    assert xref_equations.check_equation(_ref("equation", "III4", s99, "Eq. (99)", ("99",))).verdict == core.ERRATUM


def test_symbol_misprints_are_found_and_defined_symbols_pass():
    assert xref_symbols.check_symbol("d_{elf}").verdict == core.ERRATUM
    assert "d_{el}" in text(xref_symbols.check_symbol("d_{elf}").sentence)
    assert xref_symbols.check_symbol("d_{eff}").verdict == core.HOLDS
    assert xref_symbols.check_symbol("A_{el}").verdict == core.ERRATUM       # defined with G_loc and with G_nl


def test_a_statement_decider_follows_the_derivation():
    evidence = statements._torsion_crossover()
    assert evidence.verdict == core.ERRATUM and "K_n = pi*(n - 1/4)" in evidence.correct_text()
    assert wording.limiting_cases_order().verdict == core.ERRATUM
    assert statements._scaling_order("nonlocal_fastest")().verdict == core.HOLDS


def test_a_roman_numeral_names_the_same_table():
    s = "Cantilever parameters are summarized in Table I."
    assert xref_tables.check_table(_ref("table", "captions", s, "Table I", ("I",))).verdict == core.HOLDS
    s2 = s.replace("Table I", "Table II")
    assert xref_tables.check_table(_ref("table", "captions", s2, "Table II", ("II",))).verdict == core.ERRATUM


def test_loose_names_are_decided_by_the_physics_they_point_to(monkeypatch):
    # "8 times ... than that for the clamped cantilever": the number decides, not the name.
    assert wording.eight_times().verdict == core.HOLDS
    monkeypatch.setattr(wording.P, "nonlocal_free_to_supported", 4)
    core.clear_results()
    try:
        assert wording.eight_times().verdict == core.ERRATUM
    finally:
        core.clear_results()
    # "a cantilever with a high spring constant (k1 -> oo)": k1 grows with k through the load.
    evidence = wording.stiff_cantilever_vs_k1()
    assert evidence.verdict == core.HOLDS and "d ln k1/d ln k = 1/3" in evidence.evidence_text()
    assert wording.tip1_null_consistency().verdict == core.HOLDS
    assert wording.nominal_resonance().verdict == core.UNDECIDABLE     # a catalogue value, no tolerance


def test_a_sentence_that_says_where_a_result_is_follows_its_reference():
    wrong = wording.where_it_is("IV2", r"is given in Section II\b")()
    assert wrong.verdict == core.ERRATUM and wrong.correct_text() == "Section III.2"
    assert wording.where_it_is("IV", r"analyzed in Section IV\.2")().verdict == core.HOLDS
    # several references in one sentence: the worst decides
    evidence = wording.where_it_is("VI4", r"Shown in Fig\. 14 are the bias")()
    assert evidence.verdict == core.HOLDS and "Fig. 14 (c)" in evidence.evidence_text()
    assert wording.where_it_is("VI1", r"Fig\. 8 c,d are the response")().verdict == core.ERRATUM


def test_the_order_of_limiting_cases_is_read_from_the_sentence(monkeypatch):
    printed = next(t for t in wording.sentences_of("III2") if "providing purely" in t)
    assert wording.limiting_cases_order().verdict == core.ERRATUM
    swapped = printed.replace("purely electromechanical and purely electrostatic",
                              "purely electrostatic and purely electromechanical")
    monkeypatch.setattr(wording, "sentences_of", lambda tag: [swapped])
    assert wording.limiting_cases_order().verdict == core.HOLDS


def test_sentences_about_superposition_and_the_nulling_bias_are_decided():
    ids = {sentence[:60]: core.run_check(core.REGISTRY[cid]).verdict
           for cid, _, sentence, _ in statements.statements()
           if re.search(r"A = A_\{el\} \+ A_\{piezo\}|nulling bias provides information", sentence)}
    assert len(ids) == 2 and set(ids.values()) == {core.HOLDS}
