"""The family registry (derivations/families.py) is the one list of families."""
from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

from pfmdyn import transfer
from pfmdyn.derivations import codegen, families
from pfmdyn.generated import characteristic, families as generated_families
from pfmdyn.roots import branches, core

PACKAGE = Path(__file__).resolve().parent.parent / "pfmdyn"
WRAPPED = [f for f in families.FAMILIES if f.function]


def test_generated_copy_is_the_registry():
    assert [tuple(f) for f in generated_families.FAMILIES] == [
        tuple(getattr(f, n) for n in generated_families.Family._fields) for f in families.FAMILIES]
    assert generated_families.PARAMETER_HELP == families.PARAMETER_HELP


def test_codegen_roots_and_branches_follow_the_registry():
    assert [f.module for f in codegen.families()] == [
        f.module for f in families.FAMILIES]
    assert list(characteristic.FAMILIES) == [f.roots for f in families.FAMILIES if f.roots]
    assert list(core.FAMILIES) == list(characteristic.FAMILIES)
    assert branches.SWEPT == {f.roots: f.branch for f in families.FAMILIES if f.branch}
    assert set(branches.SWEPT.values()) <= set(core.PARAMETER_HELP)


@pytest.mark.parametrize("row", WRAPPED, ids=lambda f: f.module)
def test_transfer_wrapper_matches_its_row(row):
    """Each wrapper takes the row's parameters and returns one field per drive."""
    fn, result = getattr(transfer, row.function), getattr(transfer, row.result)
    keywords = [p.name for p in inspect.signature(fn).parameters.values()
                if p.kind is p.KEYWORD_ONLY and p.default is p.empty]
    assert keywords == list(row.parameters)
    assert len(result._fields) == len(row.drives)
    assert sorted(transfer.__all__) == sorted({n for f in WRAPPED for n in (f.function, f.result)})


def _family_names():
    return {f.module for f in families.FAMILIES} | {f.roots for f in families.FAMILIES if f.roots}


def test_no_other_list_of_families():
    """No literal list, tuple, set or dict under pfmdyn/ names two or more families.

    pfmdyn/discrepancy/ is left out: its effects (tilt, tip_mass, tip_setback) are named
    after their derivations, and the effect list is that subpackage's own registry.
    """
    names = _family_names()
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if "discrepancy" in path.relative_to(PACKAGE).parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            items = (node.keys if isinstance(node, ast.Dict)
                     else node.elts if isinstance(node, (ast.List, ast.Tuple, ast.Set)) else [])
            hits = {i.value for i in items if isinstance(i, ast.Constant) and i.value in names}
            if len(hits) >= 2:
                offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno}: {sorted(hits)}")
    assert not offenders, offenders


def test_package_exports_every_registry_wrapper():
    import pfmdyn

    assert set(pfmdyn.__all__) == {"Cantilever", "Contact"} | {f.function for f in WRAPPED}
    assert all(hasattr(pfmdyn, name) for name in pfmdyn.__all__)


def test_book_family_chapters_follow_the_registry():
    """Every family chapter of the book derives registry rows and shows them with book.family_table."""
    import yaml

    book_dir = PACKAGE.parent / "book"
    toc = yaml.safe_load((book_dir / "_toc.yml").read_text())
    part = next(p for p in toc["parts"] if p["caption"] == "Boundary-condition families")
    pages = {c["file"] for c in part["chapters"]} - {"numeric"}   # numeric: the generated code itself
    assert pages == {f.chapter for f in families.FAMILIES if f.chapter}
    for page in pages:
        assert "book.family_table(" in (book_dir / f"{page}.md").read_text(), page


def test_cantilever_methods_are_the_registry_rows():
    from pfmdyn import Cantilever

    made = {name for name, value in vars(Cantilever).items() if name.endswith("_response") and callable(value)}
    assert made == {f.method for f in families.FAMILIES if f.method}
