"""One error type a Python user can catch; the library names quantities and the command line adds
their flags (issue 31): no flag is spelled in library code."""
from __future__ import annotations

import argparse
import ast
import importlib
import re
from pathlib import Path

import pytest

import pfmdyn
from pfmdyn import Cantilever, Contact, cli
from pfmdyn.errors import MissingExtraError, UserError
from pfmdyn.io.record import MissingFieldError

PACKAGE = Path(pfmdyn.__file__).resolve().parent

def cli_flags() -> set[str]:
    """Every long flag of every command, from the parsers the command line builds."""
    flags = set()
    for module, _ in cli.COMMANDS.values():
        parser = argparse.ArgumentParser()
        importlib.import_module(module).add_arguments(parser)
        flags.update(option for action in parser._actions for option in action.option_strings
                     if option.startswith("--") and option != "--help")
    return flags


def library_strings(path: Path):
    """``(line, text)`` of the string constants of a module; names.py's docstrings state the
    name -> flag mapping itself and are left out (its quantities' meanings are not)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped = set()
    if path.name == "names.py" and path.parent == PACKAGE:
        for node in [tree, *ast.walk(tree)]:
            if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef)) and ast.get_docstring(node) is not None:
                skipped.add(id(node.body[0].value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skipped:
            yield node.lineno, node.value


def test_no_flag_is_spelled_outside_the_command_line():
    flags = cli_flags()
    assert {"--tip-height", "--width", "--temperature", "--out"} <= flags
    spelled = re.compile(r"(?<![\w-])(" + "|".join(map(re.escape, sorted(flags, key=len, reverse=True)))
                         + r")(?![\w-])")
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE).as_posix()
        if relative.startswith("commands/") or relative == "cli.py":
            continue
        for line, text in library_strings(path):
            found += [f"pfmdyn/{relative}:{line}: {flag}" for flag in spelled.findall(text)]
    assert not found, "flags spelled in library code (name the quantity instead):\n" + "\n".join(found)


def test_a_python_user_catches_bad_input_as_a_value_error():
    assert issubclass(UserError, ValueError) and issubclass(MissingExtraError, ValueError)
    for make in (lambda: Cantilever(-1.0, 7e4, 2e-4),
                 lambda: Cantilever(2.0, 7e4, 2e-4, tip_height="tall"),
                 lambda: Cantilever.from_geometry(length=-225e-6, width=40e-6, thickness=3e-6,
                                                  youngs_modulus=169e9, density=2330.0),
                 lambda: Contact(k1=100.0, k2=30.0, poisson=0.3)):
        with pytest.raises(ValueError) as caught:
            make()
        assert type(caught.value) is UserError and "\n" not in str(caught.value)


def test_errors_name_the_quantity_not_the_flag():
    with pytest.raises(UserError) as caught:
        Cantilever(2.0, 7e4, 2e-4).response([1e5], Contact())
    assert caught.value.quantity == "k1" and "--" not in str(caught.value)
    missing = MissingFieldError("tip height not in a.ibw", "tip_height")
    assert missing.field == missing.quantity == "tip_height"


@pytest.mark.parametrize("argv, flag", [
    # a quantity missing from the lever
    (["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--tip-height", "1e-5", "--k1", "100",
      "--frequency", "1e4"], "--length"),
    # a bad value found by the analysis, not by the flag's check
    (["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4", "--tip-height", "1e-5",
      "--k1", "0", "--frequency", "1e4"], "--k1"),
    # a bad value found by the analysis, the flag named from the quantity's name (drive_frequency)
    (["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4", "--tip-height", "1e-5",
      "--k1", "100", "--drive-frequency", "1e10"], "--drive-frequency"),
    (["stiffness", "--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--tip-position",
      "fit"], "--contact"),
    (["stiffness", "--free-resonance", "60e3", "--contact", "2e5", "--spring-constant", "2", "--tilt", "12"],
     "--length"),
])
def test_the_command_line_names_the_flag_in_one_line(argv, flag, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pfmdyn {argv[0]}: error: ") and err.count("\n") == 1
    assert err.rstrip().endswith(f": give {flag}"), err
