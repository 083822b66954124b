"""Every subcommand's ``--help`` formats (issue 41, item 8; issue 39, item 3).

The subcommands are those the parser holds (:func:`pfmdyn.cli.parser`), not a list typed here:
a new command is tested the day it is added.
"""
from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from pfmdyn import cli

COMMANDS = sorted(cli.parser()[1])


def test_the_parser_holds_every_command():
    assert COMMANDS == sorted(cli.COMMANDS) and len(COMMANDS) >= 14


@pytest.mark.parametrize("command", COMMANDS)
def test_help_formats(command, capsys):
    """Exit status 0 and a usage line, the description and every option's help; before, a "%" in a
    quantity's meaning (``2 % of it``) made ``calibrate --help`` raise TypeError."""
    with pytest.raises(SystemExit) as stopped:
        cli.main([command, "--help"])
    assert stopped.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith(f"usage: pfmdyn {command}") and cli.COMMANDS[command][1].split()[0] in text
    shown = [a for a in cli.parser(command)[1][command]._actions if a.help != argparse.SUPPRESS]
    assert all(option in text for action in shown for option in action.option_strings)


def test_json_help_says_the_document_is_alone_on_standard_output(capsys):
    """What ``--json -`` does (README): the document alone on standard output, the report on standard
    error; the help said 'after the summary', as before that change."""
    helps = [action.help for command in COMMANDS for action in cli.parser(command)[1][command]._actions
             if action.dest in ("json", "errata")]
    assert len(helps) >= len(COMMANDS) - 2
    assert all("alone on standard output" in text and "after the summary" not in text for text in helps), helps
    assert cli.main(["roots", "free", "--modes", "1", "--digits", "5", "--json", "-"]) == 0
    captured = capsys.readouterr()
    assert captured.out.lstrip().startswith("{") and captured.out.rstrip().endswith("}") and captured.err


def test_top_level_help_lists_every_command(capsys):
    with pytest.raises(SystemExit) as stopped:
        cli.main(["--help"])
    assert stopped.value.code == 0
    text = capsys.readouterr().out
    assert all(command in text for command in COMMANDS)


HEAVY = ("scipy", "matplotlib", "sympy", "numba", "dask", "distributed", "zarr", "h5py", "xarray", "tqdm",
         "threadpoolctl", "flint", "mpmath", "yaml")
"""What no ``--help`` needs: each costs 30 ms to 2 s to import (the analyses, figures, certified
arithmetic, stores, progress bars); a command imports them when it runs."""

_HELP = f"""\
import contextlib, io, sys
from pfmdyn import cli
with contextlib.redirect_stdout(io.StringIO()) as text, contextlib.suppress(SystemExit):
    cli.main(sys.argv[1:])
assert text.getvalue().startswith("usage:")
print(" ".join(sorted({{name.split(".")[0] for name in sys.modules}} & {set(HEAVY)!r})) or "-")
"""


def _help_in_a_new_process(command: str) -> tuple[float, str]:
    """CPU time of ``--help`` in a fresh interpreter (start-up included; unlike wall time, not lengthened by
    the other tests running beside it) and the heavy modules it imported."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([sys.executable, "-W", "error", "-c", _HELP, command, "--help"], capture_output=True,
                          text=True, timeout=60)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert done.returncode == 0, done.stderr
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, done.stdout.strip()


def test_help_is_fast_and_imports_only_the_parser():
    """Each command's parser imports only names, flags and small constants; its library modules are
    imported by its run function.  Before, ``discrepancy --help`` took 2.5 s (SciPy, matplotlib and
    the fitting stack imported before argparse ran).  The time limit is generous for a loaded CI
    machine (about 0.3 s here); the modules are the exact check."""
    seconds = {}
    for command in COMMANDS:
        seconds[command], heavy = _help_in_a_new_process(command)
        assert heavy == "-", f"pfmdyn {command} --help imports {heavy}"
    slowest = max(seconds, key=seconds.get)
    if seconds[slowest] > 1.0:      # a busy moment of the machine, or slow: once more
        seconds[slowest] = min(seconds[slowest], _help_in_a_new_process(slowest)[0])
    assert seconds[slowest] < 1.0, f"pfmdyn {slowest} --help took {seconds[slowest]:.2f} s of CPU"
