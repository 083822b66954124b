"""Every subcommand's ``--help`` formats (issue 41, item 8; issue 39, item 3).

The subcommands are those the parser holds (:func:`pfmdyn.cli.parser`), not a list typed here:
a new command is tested the day it is added.
"""
from __future__ import annotations

import argparse

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


def test_top_level_help_lists_every_command(capsys):
    with pytest.raises(SystemExit) as stopped:
        cli.main(["--help"])
    assert stopped.value.code == 0
    text = capsys.readouterr().out
    assert all(command in text for command in COMMANDS)
