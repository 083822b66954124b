"""The package's layering, read from the source with ``ast`` (issues 10 and 24).

The four source trees installed as one package -- ``pfmdyn/``, ``derivations/``
(``pfmdyn.derivations``), ``audit/`` (``pfmdyn.audit``) and ``generated/`` (``pfmdyn.generated``):

* no import cycles anywhere, counting imports inside functions too;
* a rank order: ``generated`` imports nothing of ours but ``generated``; ``derivations`` never
  imports ``generated``, ``audit`` or the rest of ``pfmdyn``; ``audit`` imports only
  ``derivations`` (and itself); within ``pfmdyn``, ``io`` and ``fitting`` lie below ``analysis``,
  which lies below ``discrepancy``, below ``maps``, below ``plots``, below ``commands``;
* inside ``analysis``, ``discrepancy``, ``maps`` and ``book``, a rank order of their own (:data:`INNER_RANKS`:
  a module imports only modules of a lower layer; a new module must be placed in one);
* the library never imports ``pfmdyn.commands`` or ``pfmdyn.cli`` (commands call the library,
  not the other way round), and never imports the plots (plots import results);
* numeric code never imports SymPy at module level, nor a ``pfmdyn.derivations`` module that
  loads it (the flint-only root certifier, ``derivations/certify.py``, it may).
"""
from __future__ import annotations

import ast
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "pfmdyn"
TREES = {"pfmdyn": PACKAGE, "pfmdyn.derivations": ROOT / "derivations", "pfmdyn.audit": ROOT / "audit",
         "pfmdyn.generated": ROOT / "generated"}
"""Installed package name -> source tree (``pyproject.toml``'s package-dir)."""


def _module_name(path: Path) -> str:
    package, tree = next((name, tree) for name, tree in TREES.items() if name != "pfmdyn" and tree in path.parents) \
        if PACKAGE not in path.parents else ("pfmdyn", PACKAGE)
    parts = (*package.split("."), *path.relative_to(tree).with_suffix("").parts)
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


MODULES = {_module_name(p): p for tree in TREES.values() for p in tree.rglob("*.py") if "__pycache__" not in p.parts}


@lru_cache(maxsize=2)
def _graph(module_level_only: bool) -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        # a parent package is imported before its modules anyway: not an edge
        graph[name] = {target for target, top in _imports(path)
                       if target in MODULES and not name.startswith(target + ".") and target != name
                       and (top or not module_level_only)}
    return graph


def test_modules_found():
    assert {"pfmdyn.cli", "pfmdyn.commands.discrepancy", "pfmdyn.io.tables", "pfmdyn.derivations.beam",
            "pfmdyn.derivations.checks.core", "pfmdyn.audit.xref", "pfmdyn.audit.text",
            "pfmdyn.generated.families"} <= set(MODULES)


def _tree(name: str) -> str:
    """Which of the four trees a module belongs to."""
    return next((t for t in ("pfmdyn.derivations", "pfmdyn.audit", "pfmdyn.generated")
                 if name == t or name.startswith(t + ".")), "pfmdyn")


# What each tree may import of ours (itself always).
MAY_IMPORT = {"pfmdyn.generated": set(), "pfmdyn.derivations": set(), "pfmdyn.audit": {"pfmdyn.derivations"},
              "pfmdyn": {"pfmdyn.derivations", "pfmdyn.audit", "pfmdyn.generated"}}

# Within pfmdyn: a module may import its own rank or lower ones.
# pfmdyn.fitting (the fitting core of discrepancy and maps) is a compute layer below them; the paper's
# analyses lie below the two engines that use them; maps take the discrepancy workflow's selection rule,
# so they lie above it (no sideways import between the engines).
RANKS = {"pfmdyn.io": 1, "pfmdyn.fitting": 1, "pfmdyn.analysis": 2, "pfmdyn.discrepancy": 3, "pfmdyn.maps": 4,
         "pfmdyn.plots": 5, "pfmdyn.commands": 6, "pfmdyn.cli": 6}

# Known edges against the rank order, each with the change that removes it (then delete the entry).
KNOWN: dict[tuple[str, str], str] = {}


def _rank(name: str) -> int | None:
    return next((r for prefix, r in RANKS.items() if name == prefix or name.startswith(prefix + ".")), None)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_rank_order(name):
    graph = _graph(module_level_only=False)
    own = _tree(name)
    bad = sorted(t for t in graph[name] if _tree(t) != own and _tree(t) not in MAY_IMPORT[own] and (name, t) not in KNOWN)
    assert not bad, f"{name} ({own}) imports {bad}"
    if own == "pfmdyn" and _rank(name) is not None:
        above = sorted(t for t in graph[name] if (_rank(t) or 0) > _rank(name) and (name, t) not in KNOWN)
        assert not above, f"{name} imports {above}, which lie above it"


def test_known_exceptions_still_exist():
    """An exception to the rank order that no longer occurs is removed from KNOWN."""
    graph = _graph(module_level_only=False)
    gone = [edge for edge in KNOWN if edge[1] not in graph.get(edge[0], set())]
    assert not gone, f"fixed, delete from KNOWN: {gone}"


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


@pytest.mark.parametrize("name", sorted(n for n in MODULES
                                        if not n.startswith(("pfmdyn.derivations", "pfmdyn.generated", "pfmdyn.audit"))
                                        and n not in ("pfmdyn.verify", "pfmdyn.book", "pfmdyn.typeset")))
def test_numeric_code_needs_no_sympy_at_import(name):
    """Nor through a derivations module: of derivations/ numeric code imports at module level only
    what itself imports no SymPy (the root certifier, flint only), counting everything that loads."""
    top = {t for t, at_top in _imports(MODULES[name]) if at_top}
    bad = sorted(t for t in top if t.split(".")[0] == "sympy"
                  or (t.startswith("pfmdyn.derivations") and _loads_sympy(t)))
    assert not bad, f"{name} imports {bad} at module level"


def _loads_sympy(name: str) -> bool:
    """Whether importing module ``name`` loads SymPy: it, a parent package or a module it imports at
    module level (transitively) imports SymPy at module level."""
    graph, seen = _graph(module_level_only=True), set()
    todo = [name] + [".".join(name.split(".")[:i]) for i in range(2, name.count(".") + 1)]
    while todo:
        module = todo.pop()
        if module in seen or module not in MODULES:
            continue
        seen.add(module)
        if any(t.split(".")[0] == "sympy" for t, at_top in _imports(MODULES[module]) if at_top):
            return True
        todo += graph[module]
    return False


INNER_RANKS = {
    "analysis": (("contact_resonance", "diagram", "domains", "resonances", "spot", "thermal"),
                 ("calibrate", "deconvolve", "stiffness", "tip_position"),
                 ("stiffness_report",)),
    "discrepancy": (("regions", "fit_kernel", "peak_kernel"),                         # where a misfit sits; a fit's and a peak fit's compiled evaluation
                    ("effects", "inputs", "sweep"),                        # the model's pieces, the inputs
                    ("model", "plausible", "reference", "thermal"),          # a model; the free lever's fits
                    ("quality", "select", "undamped_modes"),
                    ("peaks", "report", "resonance_fit"),
                    ("resonances", "spectrum")),                             # the two analyses
    "maps": (("bias", "spec", "sho_kernel"), ("outputs", "sho"), ("beam", "resonance_start"), ("fit", "readers"), ("select", "store"),
             ("contact", "dart", "result", "usid"), ("driver",)),
    "book": (("records",), ("build", "display")),                            # the verdicts; their build, their display
}
"""Layers of each package's modules, lowest first."""


@pytest.mark.parametrize("package", sorted(INNER_RANKS))
def test_rank_order_inside_packages(package):
    layer = {module: i for i, names in enumerate(INNER_RANKS[package]) for module in names}
    present = {p.stem for p in (PACKAGE / package).glob("*.py") if p.stem != "__init__"}
    assert present == set(layer), f"place in INNER_RANKS: {sorted(present - set(layer))}; gone: {sorted(set(layer) - present)}"
    prefix = f"pfmdyn.{package}."
    for module in present:
        for target, _ in _imports(PACKAGE / package / f"{module}.py"):
            other = target[len(prefix):].split(".")[0] if target.startswith(prefix) else None
            if other in layer and other != module:
                assert layer[other] < layer[module], f"{package}.{module} imports {other}, not below it"

