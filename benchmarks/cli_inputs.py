"""Benchmark: every command on bad and extreme command-line values, output paths and probes.

Not a pytest module: a wide sweep that writes one row per case and its pass count to
``benchmarks/results/cli_inputs.md`` (:mod:`recording`); ``tests/test_cli_inputs.py`` keeps a
representative set.  ``benchmarks/malformed_inputs.py`` does the same for malformed files.

    python benchmarks/cli_inputs.py

Three parts:

1. *Values.*  Every flag of every command that takes a number (the probe's quantities of
   :mod:`pfmdyn.names` and each command's own: ``--modes``, ``--frequency``, ``--n``,
   ``--points``, ``--fmin``, ``--contact``, ...) set in turn to zero, negative numbers (``-1``,
   ``-2.25e-4``, ``-inf``: argparse took the last two for options), NaN, infinity, text, an empty
   string and 1e30, on an otherwise valid command line.  A quantity's
   value outside what :func:`pfmdyn.names.checked` allows must be refused; any other value may
   be refused or succeed.
2. *Outputs.*  Every path a command writes (``--json``, ``--plot``, ``--out``, ``--csv``) set to
   a directory, to a path under a regular file, under a missing folder and (not as root) under
   a folder without write permission: refused, nothing written.
3. *Files.*  Frequency-bias CSVs (``deconvolve``, ``discrepancy``) and resonance tables
   (``discrepancy``, ``stiffness FILE``) empty, header only, with one row or one bias, a NaN,
   an infinity, text, a negative frequency, identical repeated rows (kept once) and repeated
   rows that disagree.  (``benchmarks/malformed_inputs.py`` does map and instrument files.)
4. *Probes over the real ranges* (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4, Q 5-500, tilt,
   set-back tip, viscous drag up to overdamping): ``pfmdyn resonances --json`` succeeds and
   every null in its report (a number JSON cannot hold) is an undamped Q or is explained in
   ``*_undetermined``.

Outcome of a case: ``pass`` when a refusal is exit 2 with one line ``pfmdyn COMMAND: error:``
naming an option or ``cannot write`` and nothing was written, or when an accepted input exits
0 (or 1: a proof that failed, stated); ``FAIL`` for a traceback, several lines, something
written despite the error, an invalid value accepted, or a run over 120 s.
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import shutil
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from malformed_inputs import _h5, _run, _Timeout, sweep  # noqa: E402  (the same in-process runner)
from recording import recorded  # noqa: E402

from pfmdyn import cli  # noqa: E402
from pfmdyn.cantilever import Cantilever  # noqa: E402
from pfmdyn.errors import UserError  # noqa: E402
from pfmdyn.names import NAMES, checked  # noqa: E402

VALUES = ("0", "-1", "-2.25e-4", "-inf", "nan", "inf", "abc", "", "1e30")
BAD = ("nan", "inf", "abc", "")
"""Values no number flag may take."""
LEVER = ["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4"]
PROBE = LEVER + ["--tip-height", "1e-5", "--k1", "100"]
CSV = "frequency_hz,bias_v,x,y\n" + "".join(f"{f},{v},{1 + 0.1 * v},{0.1 * v}\n"
                                          for f in (1e5, 2e5, 3e5) for v in (-1, 0, 1))
OWN = {   # each command's own number flags (besides the probe's quantities)
    "resonances": ("--modes",), "spot": ("--drive-frequency",),
    "stiffness": ("--contact", "--mode", "--free-resonance-uncertainty", "--spring-constant-uncertainty"),
    "diagram": ("--d-eff", "--local-force", "--surface-potential", "--fmin", "--fmax", "--vmin", "--vmax",
                "--frequency-points", "--bias-points"),
    "deconvolve": ("--surface-potential",), "roots": ("--modes", "--digits", "--k1-over-k"),
    "branches": ("--points", "--modes"), "discrepancy": (),
    "map": ("--block", "--workers", "--max-blocks", "--gap-threshold", "--surface-potential"),
}


def base_lines(tmp: Path) -> dict:
    """A valid command line of each command, its outputs under ``tmp / 'out'``."""
    out = tmp / "out"
    data = tmp / "data.csv"
    data.write_text(CSV)
    table = tmp / "table.csv"
    table.write_text("# spring_constant: 2\n# length: 2.25e-4\n# tip_height: 1e-5\n# free_resonance: 7e4\n"
                     "mode,condition,frequency_hz\n1,free,70000\n1,contact,300000\n")
    if not (tmp / "map.h5").exists():
        _h5(tmp / "map.h5")
    return {
        "resonances": ["resonances", *PROBE, "--json", f"{out}/r.json"],
        "spot": ["spot", *PROBE, "--drive-frequency", "1e5", "--json", f"{out}/s.json", "--plot", f"{out}/s.png"],
        "stiffness": ["stiffness", "--spring-constant", "2", "--free-resonance", "7e4", "--contact", "3e5",
                      "--length", "2e-4", "--json", f"{out}/k.json"],
        "diagram": ["diagram", "--plot", f"{out}/d.png", "--csv", f"{out}/d.csv", "--frequency-points", "20",
                    "--bias-points", "5"],
        "deconvolve": ["deconvolve", str(data), "--surface-potential", "0", "--out", f"{out}/dec", *PROBE],
        "roots": ["roots", "elastic", "--modes", "2", "--k1-over-k", "10", "--k2-ratio", "0.1", "--k2t-hl", "0",
                  "--json", f"{out}/r.json"],
        "branches": ["branches", "elastic", "--plot", f"{out}/b.png", "--csv", f"{out}/b.csv", "--points", "20",
                     "--modes", "1", "--k1-over-k", "1"],
        "discrepancy": ["discrepancy", str(table), "--json", f"{out}/q.json", "--plot", f"{out}/q.png"],
        "inspect": ["inspect", str(table), "--json", f"{out}/i.json"],
        "map": ["map", str(tmp / "map.h5"), "--out", f"{out}/map", "--model", "elastic", "--scheduler", "sync",
                "--no-progress"],
    }


def _flags(command: str) -> list[str]:
    """The number flags ``command`` takes: the quantities its parser has, then its own."""
    parser = argparse.ArgumentParser()
    importlib.import_module(cli.COMMANDS[command][0]).add_arguments(parser)
    options = {o for action in parser._actions for o in action.option_strings}
    return [q.flag for q in NAMES.values() if q.flag in options] + [f for f in OWN.get(command, ()) if f in options]


def _set(argv: list, flag: str, value: str) -> list:
    """``argv`` with ``flag`` set to ``value`` (replacing its value, or appended)."""
    argv = list(argv)
    if flag in argv:
        argv[argv.index(flag) + 1] = value
    else:
        argv += [flag, value]
    return argv


def _expected(flag: str, value: str) -> str:
    """'error' when no valid command line can hold this value, else 'any'."""
    if value in BAD:
        return "error"
    name = flag[2:].replace("-", "_")
    if name in NAMES:
        try:
            checked(name, value)
        except UserError:
            return "error"
    return "any"


def judge(command: str, argv: list, expect: str, out: Path) -> tuple[str, str]:
    """Outcome (pass/FAIL) and a short detail of one command line."""
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    start = time.perf_counter()
    status, _, stderr, escaped = _run(argv)
    elapsed = time.perf_counter() - start
    written = sorted(p.name for p in out.iterdir())
    if isinstance(escaped, _Timeout):
        return "FAIL", "over the time limit"
    if escaped is not None:
        return "FAIL", f"traceback: {type(escaped).__name__}: {' '.join(str(escaped).split())[:150]}"
    lines = [line for line in stderr.strip().splitlines() if "fit/s]" not in line and "Warning" not in line]
    if status == 2:
        if len(lines) != 1 or not lines[0].startswith(f"pfmdyn {command}: error: "):
            return "FAIL", f"error over {len(lines)} lines: {' | '.join(lines)[:160]}"
        if "--" not in lines[0] and "cannot write" not in lines[0] and ".csv" not in lines[0]:
            return "FAIL", f"error names no option or file: {lines[0][:160]}"
        if written:
            return "FAIL", f"written despite the error: {written}"
        return "pass", lines[0][len(f"pfmdyn {command}: error: "):][:150]
    if status not in (0, 1):
        return "FAIL", f"exit status {status}: {' | '.join(lines)[-160:]}"
    if expect == "error":
        return "FAIL", f"invalid value accepted ({elapsed:.1f} s)"
    return "pass", f"exit {status} ({elapsed:.1f} s)"


def value_cases(tmp: Path):
    """(name, command, argv, expected) of part 1."""
    base = base_lines(tmp)
    for command, argv in base.items():
        for flag in _flags(command):
            for value in VALUES:
                if command == "map" and value not in BAD and _expected(flag, value) == "any":
                    continue        # a valid value starts a full map fit: covered by malformed_inputs
                yield f"{flag}={value or '(empty)'}", command, _set(argv, flag, value), _expected(flag, value)


def output_cases(tmp: Path):
    """(name, command, argv, expected) of part 2: each written path made unwritable."""
    blocker = tmp / "a_file"
    blocker.write_text("x")
    locked = tmp / "locked"
    locked.mkdir(exist_ok=True)
    locked.chmod(0o500)
    faults = {"a_directory": lambda p: str(tmp), "under_a_file": lambda p: f"{blocker}/{Path(p).name}",
              "missing_folder": lambda p: f"{tmp}/missing/{Path(p).name}"}
    if os.geteuid() != 0:      # root writes anywhere: no permission fault to make
        faults["no_permission"] = lambda p: f"{locked}/{Path(p).name}"
    for command, argv in base_lines(tmp).items():
        for option in ("--json", "--plot", "--out", "--csv"):
            if option not in argv:
                continue
            for fault, path in faults.items():
                if option == "--out" and command in ("deconvolve", "map") and fault == "missing_folder":
                    continue        # an output folder is created with its parents
                if option == "--out" and command in ("deconvolve", "map") and fault == "a_directory":
                    continue        # a folder to write into: that is what --out names
                target = path(argv[argv.index(option) + 1])
                yield f"{option} {fault}", command, _set(argv, option, target), "error"


META = "# spring_constant: 2\n# length: 2.25e-4\n# tip_height: 1e-5\n# free_resonance: 7e4\n# width: 4e-5\n"
TABLE = META + "mode,condition,frequency_hz\n1,free,70000\n1,contact,300000\n2,contact,900000\n"
SPECTRUM = META + CSV
FILES = {   # name -> (text, expected: 'error' or 'any')
    "spectrum/empty": ("", "error"), "spectrum/header_only": (META + CSV.splitlines()[0] + "\n", "error"),
    "spectrum/one_bias": (META + "frequency_hz,bias_v,x,y\n100000,0,1,0\n200000,0,1,0\n", "error"),
    "spectrum/nan": (SPECTRUM.replace("1.1,", "nan,", 1), "error"),
    "spectrum/inf": (SPECTRUM.replace("1.1,", "inf,", 1), "error"),
    "spectrum/text": (SPECTRUM.replace("1.1,", "abc,", 1), "error"),
    "spectrum/negative_frequency": (SPECTRUM.replace("100000.0,", "-100000.0,"), "error"),
    "spectrum/identical_repeat": (SPECTRUM + CSV.splitlines()[1] + "\n", "any"),
    "spectrum/clashing_repeat": (SPECTRUM + "100000.0,-1,5,5\n", "error"),
    "table/one_row": (META + "mode,condition,frequency_hz\n1,contact,300000\n", "any"),
    "table/free_only": (META + "mode,condition,frequency_hz\n1,free,70000\n", "any"),
    "table/nan": (TABLE.replace("300000", "nan"), "error"), "table/text": (TABLE.replace("300000", "abc"), "error"),
    "table/negative_frequency": (TABLE.replace("300000", "-300000"), "error"),
    "table/identical_repeat": (TABLE + "1,contact,300000\n", "any"),
    "table/clashing_repeat": (TABLE + "1,contact,310000\n", "error"),
    "table/mode_zero": (TABLE.replace("1,contact", "0,contact"), "error"),
    "table/negative_spring_constant": (TABLE.replace("spring_constant: 2", "spring_constant: -2"), "error"),
    "table/no_header": (META, "error"),
}


def file_cases(tmp: Path):
    """(name, command, argv, expected) of part 3."""
    out = tmp / "out"
    for name, (text, expect) in FILES.items():
        path = tmp / (name.replace("/", "_") + ".csv")
        path.write_text(text)
        commands = {"discrepancy": ["discrepancy", str(path), "--json", f"{out}/q.json"]}
        if name.startswith("spectrum/"):
            commands["deconvolve"] = ["deconvolve", str(path), "--surface-potential", "0", "--out", f"{out}/dec"]
        else:
            commands["stiffness"] = ["stiffness", str(path), "--json", f"{out}/k.json"]
        for command, argv in commands.items():
            # a table of free modes only has no contact resonance for stiffness to invert
            wanted = "error" if (command, name) == ("stiffness", "table/free_only") else expect
            yield name, command, argv, wanted


def probe_cases():
    """Part 3: probes over the real ranges (silicon levers 40 um wide), for ``resonances``."""
    for k in (0.05, 0.5, 5.0, 50.0):
        for length in (100e-6, 250e-6, 500e-6):
            thickness = (4 * k * length ** 3 / (169e9 * 40e-6)) ** (1 / 3)
            f1 = Cantilever.from_geometry(length=length, width=40e-6, thickness=thickness, youngs_modulus=169e9,
                                          density=2330.0).free_resonance
            for ratio in (1.0, 100.0, 1e4):
                for damping in (["--quality-factor", "5"], ["--quality-factor", "500"], ["--viscous-loss", "3"]):
                    argv = ["resonances", "--spring-constant", f"{k:g}", "--free-resonance", f"{f1:.6g}",
                            "--length", f"{length:g}", "--tip-height", "1e-5", "--k1", f"{k * ratio:g}",
                            "--k2-over-k1", "0.8", "--tilt", "12", "--tip-position", "0.9", *damping]
                    yield f"k={k:g} L={length * 1e6:g}um k1/k={ratio:g} {' '.join(damping)}", argv


def _unexplained_nulls(document: dict) -> list[str]:
    """Records holding null where a number is promised and no reason is given (a mode's is a note)."""
    results = document.get("results", {})
    missing = [f"{c}.resonance" for c in ("free", "contact") if None in results.get(c, {}).get("resonance", {})
               .get("value", [None])]
    for condition in ("free", "contact"):
        for key in ("damped_resonance", "amplitude_peak", "predicted_quality_factor"):
            for i, value in enumerate(results.get(condition, {}).get(key, {}).get("value", [])):
                if value is None and not any(n.startswith(f"{condition} mode {i + 1}: ") for n in document["notes"]):
                    missing.append(f"{condition}.{key}[{i}]")
    return missing


def _judged(tmp: Path, report) -> str:
    """The values, outputs and files of every command, then the probes over the real ranges."""
    out = tmp / "out"
    for part, cases in (("values", value_cases(tmp)), ("outputs", output_cases(tmp)), ("files", file_cases(tmp))):
        counts = {}
        for name, command, line, expect in cases:
            outcome, detail = judge(command, line, expect, out)
            report(outcome, f"{part:<8} {command:<12} {name:<36} {detail.replace(str(tmp), 'TMP')[:100]}")
            counts.setdefault(command, []).append(outcome)
        print("  " + "; ".join(f"{c} {v.count('pass')}/{len(v)}" for c, v in counts.items()))
    for name, line in probe_cases():
        target = out / "r.json"
        outcome, detail = judge("resonances", line + ["--json", str(target)], "any", out)
        if outcome == "pass" and target.exists():
            nulls = _unexplained_nulls(json.loads(target.read_text()))
            if nulls:
                outcome, detail = "FAIL", f"null without a reason: {', '.join(nulls)[:100]}"
            else:
                document = json.loads(target.read_text())
                said = sum(bool(w) for p in ("free", "contact") for w in document.get(f"{p}_undetermined", []))
                detail += f"; {said} mode(s) stated undetermined" if said else ""
        report(outcome, f"probes   resonances   {name:<36} {detail[:100]}")
    return (f"commands {', '.join(base_lines(tmp))}; values {', '.join(map(repr, VALUES))}; "
            f"permission faults {'skipped (run as root)' if os.geteuid() == 0 else 'included'}")


if __name__ == "__main__":
    sys.exit(sweep(recorded("cli_inputs"), __doc__, _judged))
