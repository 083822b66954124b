"""Packaging: what a user installs is what the tests test.

An editable install (the README's, CI's) sees the source tree and cannot show a package or a data
file that a built wheel leaves out.  Here the wheel of this checkout is built and installed, without
its dependencies, into a fresh virtual environment that sees the installed ones (no source tree on
the path): every module is imported from it and each subcommand runs once on small inputs.  That
the wheel declares what it needs is read from the source: every third-party import is a declared
dependency (a module-level one, of the core), so a fresh install from the index resolves them.
"""
from __future__ import annotations

import ast
import importlib.metadata
import json
import os
import re
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
TREES = {"pfmdyn": "pfmdyn", "derivations": "pfmdyn.derivations", "generated": "pfmdyn.generated",
         "audit": "pfmdyn.audit"}
LEVER = ["--spring-constant", "2", "--free-resonance", "6e4", "--length", "2e-4"]
PROBE = LEVER + ["--tip-height", "1e-5", "--k1", "200"]


def _packages_in_tree() -> set[str]:
    """Every folder with an ``__init__.py`` in the four trees, as the package it installs as."""
    found = set()
    for folder, package in TREES.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT / folder).parts
            found.add(".".join((package, *parts)))
    return found


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                    "-w", str(out), str(ROOT)], check=True, cwd=out)
    (path,) = out.glob("pfmdyn-*.whl")
    return path


def test_wheel_holds_every_package_and_data_file(wheel):
    """Each package of the trees ships, and so does each data file the code reads."""
    names = zipfile.ZipFile(wheel).namelist()
    shipped = {n.rsplit("/", 1)[0].replace("/", ".") for n in names if n.endswith("/__init__.py")}
    assert _packages_in_tree() <= shipped, sorted(_packages_in_tree() - shipped)
    data = [p for folder in TREES for p in (ROOT / folder).rglob("*")
            if p.suffix in {".yaml", ".json", ".jinja", ".md"} and "__pycache__" not in p.parts]
    for path in data:
        folder = path.relative_to(ROOT).parts[0]
        inside = "/".join((*TREES[folder].split("."), *path.relative_to(ROOT / folder).parts))
        assert inside in names, f"{path.relative_to(ROOT)} is not in the wheel"


def _distribution(requirement: str) -> str:
    return re.split(r"[<>=!~\[; ]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def _imports_by_module() -> dict[str, set[bool]]:
    """Top-level names of the third-party modules the four trees import, each with whether some
    import of it is at module level."""
    found: dict[str, set[bool]] = {}
    for folder in TREES:
        for path in (ROOT / folder).rglob("*.py"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            top = {id(node) for node in tree.body}
            for node in ast.walk(tree):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                    [node.module] if isinstance(node, ast.ImportFrom) and not node.level else []
                for name in names:
                    module = name.split(".")[0]
                    if module not in sys.stdlib_module_names and module not in ("pfmdyn", "__future__"):
                        found.setdefault(module, set()).add(id(node) in top)
    return found


def test_every_third_party_import_is_a_declared_dependency():
    """What the wheel's metadata must carry for an install from the index to work: a module-level
    import is a core dependency; any other, a dependency of an extra (or one they bring)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = {_distribution(r) for r in project["dependencies"]}
    # the library's extras (not the tests', nor the peers' that only benchmarks/ import)
    extras = {_distribution(r) for name, reqs in project["optional-dependencies"].items()
              if name not in ("test", "peers") for r in reqs}

    def requires(dist):
        try:
            return importlib.metadata.requires(dist) or ()
        except importlib.metadata.PackageNotFoundError:
            return ()
    brought = {_distribution(r) for d in core | extras for r in requires(d) if "extra ==" not in r}
    owners = importlib.metadata.packages_distributions()
    found = _imports_by_module()
    assert {"numpy", "sympy", "numba", "zarr", "igor2"} <= set(found)
    for module, levels in found.items():
        dists = {_distribution(d) for d in owners.get(module, [module])}
        allowed = core if True in levels else core | extras | brought
        assert dists & allowed, f"{module} ({sorted(dists)}) is imported but not a declared dependency"


@pytest.fixture(scope="module")
def fresh(wheel, tmp_path_factory) -> dict:
    """A fresh venv holding the wheel, seeing the installed dependencies (declared: the test above)."""
    home = tmp_path_factory.mktemp("venv")
    venv.create(home / "env", with_pip=True, system_site_packages=True)
    python = home / "env" / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", "--ignore-installed", str(wheel)],
                   check=True, cwd=home)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    shared = ROOT.parent / "shared"
    if (shared / "claims.yaml").exists():
        env["PFMDYN_CLAIMS"] = str(shared / "claims.yaml")
    return {"python": python, "pfmdyn": home / "env" / "bin" / "pfmdyn", "cwd": home, "env": env}


def _run(fresh, *argv, compiled: bool = False) -> subprocess.CompletedProcess:
    """A command from the wheel; its numba kernels run as Python unless ``compiled`` (a fresh install
    compiles them on first use, 10-20 s: one command, a fit, shows that they compile from the wheel)."""
    env = fresh["env"] if compiled else {**fresh["env"], "NUMBA_DISABLE_JIT": "1"}
    return subprocess.run([str(fresh["pfmdyn"]), *argv], cwd=fresh["cwd"], env=env,
                          capture_output=True, text=True, timeout=900)


def test_every_module_imports_from_the_wheel(fresh):
    """No module needs the source tree: each imports from the installed wheel alone."""
    code = ("import importlib, pkgutil, pfmdyn, sys\n"
            f"assert pfmdyn.__file__.startswith({str(fresh['cwd'])!r}), pfmdyn.__file__\n"
            "bad = []\n"
            "for m in pkgutil.walk_packages(pfmdyn.__path__, 'pfmdyn.'):\n"
            "    try: importlib.import_module(m.name)\n"
            "    except Exception as e: bad.append(f'{m.name}: {e!r}')\n"
            "print(len(bad)); print('\\n'.join(bad))\n")
    done = subprocess.run([str(fresh["python"]), "-c", code], cwd=fresh["cwd"], env=fresh["env"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.splitlines()[0] == "0", done.stdout + done.stderr


def test_each_subcommand_runs_from_the_wheel(fresh):
    """resonances, discrepancy on a resonance table made from them, stiffness, spot, roots, verify on two claims."""
    cwd = fresh["cwd"]
    done = _run(fresh, "resonances", *PROBE, "--json", "r.json")
    assert done.returncode == 0, done.stderr
    found = json.loads((cwd / "r.json").read_text())
    free, contact_hz = (found["results"][c]["resonance"]["value"] for c in ("free", "contact"))
    rows = [f"free,{i + 1},{f}" for i, f in enumerate(free[:3])]
    rows += [f"contact,{i + 1},{f}" for i, f in enumerate(contact_hz[:3])]
    (cwd / "table.csv").write_text("# spring_constant_n_per_m: 2\n# length_m: 2e-4\n# tip_height_m: 1e-5\n"
                                   "# free_resonance_hz: 6e4\n"
                                   "condition,mode,frequency_hz\n" + "\n".join(rows) + "\n")
    done = _run(fresh, "discrepancy", "table.csv", "--json", "d.json", compiled=True)
    assert done.returncode == 0, done.stderr
    report = json.loads((cwd / "d.json").read_text())
    assert report["missing_effects"] == [] and report["results"]["k1"]["value"] == pytest.approx(200, rel=1e-3)
    contact = contact_hz[0]
    # no k2 policy given to either: both tie k2 to k1 alike (Mindlin), so k1 comes back
    done = _run(fresh, "stiffness", *LEVER, "--tip-height", "1e-5", "--contact", str(contact),
                "--json", "s.json")
    assert done.returncode == 0, done.stderr
    assert json.loads((cwd / "s.json").read_text())["results"]["k1"]["value"] == pytest.approx(200, rel=1e-9)
    for argv in (["spot", *PROBE, "--frequency", "1e5"], ["roots", "free", "--modes", "2", "--digits", "20"],
                 ["verify", "--only", "eq6.Av", "--only", "eq23.frictionless"]):    # the whole of verify: test_verify
        done = _run(fresh, *argv)
        assert done.returncode == 0, (argv, done.stdout[-2000:], done.stderr[-2000:])
