"""The ``pfmdyn`` command line: one console script, one module per subcommand in pfmdyn.commands.

Each subcommand module ``pfmdyn.commands.<name>`` (listed in :data:`COMMANDS`) defines
``add_arguments(parser)`` and ``run(args) -> int``.  Modules are imported lazily so that
``pfmdyn --help`` stays fast and numeric commands never import SymPy (a command's parser
imports only names and flags; its ``run`` imports the library).  User errors are raised as
:class:`UserError` and printed as one line, never as a traceback; so is Ctrl-C (exit status 130).
"""
from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import io
import os
import re
import signal
import sys
import threading

from .errors import UserError

# subcommand -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "verify": ("pfmdyn.commands.verify", "derive every result and give each claim of the paper a verdict"),
    "codegen": ("pfmdyn.commands.codegen", "write generated/ from derivations/ (--check: fail if stale)"),
    "deconvolve": ("pfmdyn.commands.deconvolve", "separate electrostatic and electromechanical response in frequency-bias data"),
    "book": ("pfmdyn.commands.book", "build the verified book"),
    "discrepancy": ("pfmdyn.commands.discrepancy", "find where model and measurement disagree and name the missing effect"),
    "roots": ("pfmdyn.commands.roots", "certified resonance roots of a family to any number of digits"),
    "branches": ("pfmdyn.commands.branches", "resonance branches against contact stiffness (CSV + PNG)"),
    "diagram": ("pfmdyn.commands.diagram", "frequency-bias response diagrams of vertical PFM (Figs. 6-7)"),
    "inspect": ("pfmdyn.commands.inspect", "what pfmdyn reads from an instrument file (.ibw, .h5, .nid, sweeps)"),
    "stiffness": ("pfmdyn.commands.stiffness", "contact stiffness k1 (with k2 or the tip position) from contact resonances"),
    "map": ("pfmdyn.commands.map", "fit the beam model at every pixel of a band-excitation map (Dask, Zarr)"),
    "resonances": ("pfmdyn.commands.resonances", "certified free and contact resonances of a probe (and Q, damped and peak frequencies)"),
    "calibrate": ("pfmdyn.commands.calibrate", "spring constant of the free lever from its thermal tune (thermal and Sader)"),
    "spot": ("pfmdyn.commands.spot", "electrostatic blind spots, calibration and d_eff error at the laser spot"),
}


class _Parser(argparse.ArgumentParser):
    """argparse with its refusals as one line ``pfmdyn COMMAND: error: ...`` (no usage block):
    a missing or malformed option is a user error like any other (``--help`` shows the usage)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # A value that starts with a minus and a digit is a (negative) number, never an option, so that
        # ``--length -225e-6`` reaches the range check (argparse's own rule misses exponents and -inf).
        self._negative_number_matcher = re.compile(r"^-\.?\d|^-(inf|infinity|nan)$", re.IGNORECASE)

    def error(self, message):
        print(f"{self.prog}: error: {message} (see {self.prog} --help)", file=sys.stderr)
        raise SystemExit(2)


def parser(only: str | None = "") -> tuple[_Parser, dict[str, _Parser]]:
    """The ``pfmdyn`` parser and its subcommands' parsers, with the arguments of the subcommand
    ``only`` (all of them when None; none when ``""``: ``pfmdyn --help`` imports no command).

    >>> top, commands = parser("roots")
    >>> sorted(commands)[:3], commands["roots"].prog, any(a.dest == "digits" for a in commands["roots"]._actions)
    (['book', 'branches', 'calibrate'], 'pfmdyn roots', True)
    """
    top = _Parser(prog="pfmdyn", description="Cantilever dynamics in PFM, derived and verified.")
    sub = top.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parsers = {}
    for name, (module, help_text) in COMMANDS.items():
        p = parsers[name] = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(_module=module)
        if only is None or only == name:
            importlib.import_module(module).add_arguments(p)
            if "--quiet" not in p._option_string_actions:
                p.add_argument("--quiet", action="store_true", help="print nothing but errors (a document asked "
                               "with --json - still goes to standard output)")
    return top, parsers


def main(argv: list[str] | None = None) -> int:
    """Run one command; its exit status (2: a user error, printed as one line; 130: interrupted)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, _ctrl_c(os.getpid())) if main_thread else None
    try:
        return _run(argv)
    except KeyboardInterrupt:
        return _interrupted(argv[0] if argv and argv[0] in COMMANDS else None)
    finally:        # for a caller in Python (after an interruption the default stays: see _interrupted)
        if previous is not None and signal.getsignal(signal.SIGINT) is not signal.SIG_DFL:
            signal.signal(signal.SIGINT, previous)


def _ctrl_c(command: int):
    """The SIGINT handler of the command's process ``command``: KeyboardInterrupt there; nothing in
    the worker processes it forks (they inherit the handler, and a terminal's Ctrl-C reaches the
    whole process group): the command reports the interruption once and its workers end with it.

    >>> _ctrl_c(-1)(signal.SIGINT, None)       # as in a forked worker: ignored
    """
    def handler(signum, frame):
        if os.getpid() == command:
            raise KeyboardInterrupt
    return handler


def _run(argv: list[str]) -> int:
    top, parsers = parser(argv[0] if argv else "")
    args, extra = top.parse_known_args(argv)
    if extra:       # refused by the command's parser, so that the line names the command
        parsers[args.command].error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        from .commands import flags
        flags.check_medium(args)
        flags.check_distinct_paths(args)
        module = importlib.import_module(args._module)
        with flags.lever_forms(getattr(module, "ONE_LEVER", False)):
            quiet = getattr(args, "quiet", False) and args.command != "verify"
            if not quiet and getattr(args, "json", None) != "-":
                return int(module.run(args) or 0)
            # The document alone on standard output (a pipe into jq reads JSON only); the report goes
            # to standard error, or nowhere with --quiet.
            flags.DOCUMENTS.append(sys.stdout)
            try:
                with contextlib.redirect_stdout(io.StringIO() if quiet else sys.stderr):
                    return int(module.run(args) or 0)
            finally:
                flags.DOCUMENTS.pop()
    except UserError as exc:
        from .commands.flags import option_hint
        print(f"pfmdyn {args.command}: error: {exc}{option_hint(exc, parsers[args.command])}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # Output piped into `head` and closed early: not an error of ours or the user's.
        sys.stderr.close()
        return 0


def _interrupted(command: str | None) -> int:
    """Ctrl-C: one line and the shell's status for SIGINT (128 + 2), no traceback.  The work done
    is kept where a command keeps it (``map`` resumes); a second Ctrl-C while Python shuts down
    (joining threads, closing files) ends the process at once, also without a traceback."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    print(f"pfmdyn{' ' + command if command else ''}: interrupted", file=sys.stderr)
    return 130


def console() -> int:
    """The console script ``pfmdyn``: :func:`main`, then the objects it leaves frozen (:func:`gc.freeze`), since
    the process ends now and Python's exit would otherwise run a full collection over all of them: 0.2 s
    after a ``discrepancy``, whose imports (numba, SciPy) leave hundreds of thousands."""
    status = main()
    gc.freeze()
    return status


if __name__ == "__main__":
    sys.exit(console())
