"""The package's layering, read from the source with ``ast`` (issue 10).

* no import cycles between modules of ``pfmdyn``;
* the library never imports ``pfmdyn.commands`` or ``pfmdyn.cli`` (commands call the library,
  not the other way round), and never imports the plots (plots import results);
* numeric code never imports SymPy or ``pfmdyn.derivations`` at module level.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "pfmdyn"


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> list[tuple[str, bool]]:
    """Absolute names imported by ``path`` with whether the import is at module level."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    top = {id(node) for node in tree.body}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, id(node) in top) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            found.append((module, id(node) in top))
            # ``from . import x`` imports the submodule ``x``
            found += [(f"{module}.{alias.name}", id(node) in top) for alias in node.names]
    return found


MODULES = {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _graph(module_level_only: bool) -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        # a parent package is imported before its modules anyway: not an edge
        graph[name] = {target for target, top in _imports(path)
                       if target in MODULES and not name.startswith(target + ".") and target != name
                       and (top or not module_level_only)}
    return graph


def test_modules_found():
    assert {"pfmdyn.cli", "pfmdyn.commands.discrepancy", "pfmdyn.io.tables"} <= set(MODULES)


def test_no_import_cycles():
    graph = _graph(module_level_only=False)
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt):] + [nxt]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)


@pytest.mark.parametrize("name", sorted(n for n in MODULES if not n.startswith(("pfmdyn.commands", "pfmdyn.cli"))))
def test_library_never_imports_commands_or_plots(name):
    targets = {t for t, _ in _imports(MODULES[name])}
    bad = sorted(t for t in targets if t.startswith(("pfmdyn.commands", "pfmdyn.cli")))
    assert not bad, f"{name} imports {bad}"
    if not name.startswith("pfmdyn.plots") and name not in ("pfmdyn.book",):
        plots = sorted(t for t in targets if t.startswith("pfmdyn.plots"))
        assert not plots, f"{name} imports {plots}"


@pytest.mark.parametrize("name", sorted(n for n in MODULES if not n.startswith(("pfmdyn.derivations", "pfmdyn.generated"))
                                        and n not in ("pfmdyn.verify", "pfmdyn.book")))
def test_numeric_code_needs_no_sympy_at_import(name):
    top = {t for t, at_top in _imports(MODULES[name]) if at_top}
    bad = sorted(t for t in top if t.split(".")[0] == "sympy" or t.startswith("pfmdyn.derivations"))
    assert not bad, f"{name} imports {bad} at module level"
