"""Benchmark: ``pfmdyn discrepancy`` on band-limited spectra against the design of 478d53d.

Issue 38's goal: one band-limited spectrum (200-600 points) at least 6x faster than at
:data:`BASELINE`, every report unchanged.  The cases are fixed-seed spectra of
:func:`fe_beam.acquisition_case` (:data:`CASES`: viscous damping, a set-back tip, the laser spot
away from the end and at it).  The baseline is checked out into a temporary git worktree
(:func:`compose._baseline_tree`); each case runs in a fresh interpreter per design, the designs
alternating, the best of :data:`REPEAT` runs kept (spectrum generation and imports excluded,
one BLAS thread per process as the command runs); beside it the whole command (:func:`command_seconds`: start-up,
imports, reading, report and exit included), the best of as many runs.  Three designs: the baseline; the current code as
the command runs it (a step's candidate fits in worker processes, one per core: the wall clock is what
a user waits); and the current code in one process, whose CPU seconds (which a shared machine's load
changes less than the wall clock) give the speed-up per core.  CPU seconds count the worker processes'.
The wall clock needs a quiet machine: under load the workers wait for a core (the column ``cores free``,
:func:`free_cores`, is what two CPU-bound processes found just before the kept run).  Every report's JSON is
compared with the baseline's: the
named effects, mechanisms and verdicts identical, every number within :data:`RTOL` (the fits' tolerance,
:data:`FIT_TOLERANCE`, times a hundred), or equal to the bit; and by the scientist's rule (:func:`judged`):
a value with a stated standard error within a tenth of it (the standard error within
:data:`STDERR_RTOL` of itself), the BIC and gap of the candidates a step did
not select (unconverged trials) free to move, listed.

Run ``python benchmarks/discrepancy_speed.py [--repeat N] [--cases a,b]``; results:
``benchmarks/results/discrepancy_speed.md``.  Ratios are baseline / current (above 1: faster
now); the machine's load is printed beside them (the cores may be shared).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from compose import _baseline_tree
from recording import recorded

ROOT = Path(__file__).resolve().parent.parent
BASELINE = "478d53d"
REPEAT = 3
FIT_TOLERANCE = 1e-8
"""The fits' own tolerance: ``scipy.optimize.least_squares`` stops when a step changes the cost by less
than this fraction (its ``ftol``, and ``xtol`` for the parameters), so two runs of one design that
differ in rounding may stop a step apart."""
RTOL, ATOL = 100 * FIT_TOLERANCE, 1e-12
"""Tolerances of the reports' numbers: relative, a hundred times :data:`FIT_TOLERANCE` (the fits converge to
the same point within it, not to the same bits; a number derived from several fits, a gap or a BIC
difference, adds theirs), and absolute for a value at zero (a tip mass at its null bound: 1e-14 or 1e-13
of rounding).  Strings (the effects named, the candidate selected at each step, verdicts) and the
reports' structure are compared exactly."""
CASES = {
    "band_viscous 2": ("band_viscous", 2, None),
    "band_air_setback 0": ("band_air_setback", 0, None),
    "band_spot 0": ("band_spot", 0, None),
    "band_spot 0 (spot at the end)": ("band_spot", 0, 1.0),
}
"""Name -> (class, seed, spot) of :func:`fe_beam.acquisition_case`."""

CASE_DATA = """
import sys, tempfile
from pathlib import Path
sys.path.insert(0, {tests!r})
from fe_beam import acquisition_case
from threadpoolctl import threadpool_limits
from pfmdyn.discrepancy.select import TIME_BUDGET_S
from pfmdyn.io.tables import read
text, _ = acquisition_case({seed}, {kind!r}, spot={spot!r})
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "s.csv"
    path.write_text(text)
    data = read(path)
"""
"""The start of a case's worker (a template for ``str.format``: ``tests``, ``seed``, ``kind``, ``spot``): the
spectrum of :func:`fe_beam.acquisition_case` read as ``data``, and ``threadpool_limits``, ``TIME_BUDGET_S``."""

# Run in a fresh interpreter in either tree: prints the seconds of the analysis (wall, and the CPU of the
# process and of the worker processes it ran), writes the report.
WORKER = CASE_DATA + """
import json, os, time
from pfmdyn.discrepancy.spectrum import analyse

def cpu():
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system

started, cpu_started = time.perf_counter(), cpu()
with threadpool_limits(1, user_api="blas"):
    report = analyse(data, time_budget_s=TIME_BUDGET_S{workers})
seconds, cpu = time.perf_counter() - started, cpu() - cpu_started
Path({out!r}).write_text(json.dumps(report.to_dict(), default=str))
print(seconds, cpu, len(data.frequency_hz))
"""


SPIN = "import time\nt = time.perf_counter()\nx = 0\nfor i in range(3_000_000):\n    x += i\nprint(time.perf_counter() - t)"
"""A CPU-bound loop of a fraction of a second (:func:`free_cores`)."""


def free_cores() -> float:
    """How many cores two CPU-bound processes found just now: twice one loop's time alone (the faster of two) over
    the mean time of two run side by side (2.0: two whole cores; 1.0: a shared one).  This machine's two cores are
    shared with others: side by side, two such loops have taken 1.7 times as long as one alone, and a minute later
    the same."""
    def spin(count: int) -> list[float]:
        runs = [subprocess.Popen([sys.executable, "-c", SPIN], stdout=subprocess.PIPE, text=True) for _ in range(count)]
        return [float(run.communicate()[0]) for run in runs]

    return 2 * min(spin(1)[0], spin(1)[0]) / statistics.mean(spin(2))


def run_case(case: str, cwd: Path, env: dict, out: Path, workers: int | None = None) -> tuple[float, float, int]:
    """Seconds (wall clock, and the CPU of the process and its workers) of one case's analysis in a fresh
    interpreter (its report written to ``out``; ``workers`` processes, else the design's default) and its rows."""
    kind, seed, spot = CASES[case]
    code = WORKER.format(tests=str(ROOT / "tests"), seed=seed, kind=kind, spot=spot, out=str(out),
                         workers="" if workers is None else f", workers={workers}")
    done = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{case} in {cwd} failed: {done.stderr[-2000:]}")
    seconds, cpu, rows = done.stdout.split()[-3:]
    return float(seconds), float(cpu), int(rows)


def command_seconds(case: str, cwd: Path, env: dict, tmp: Path) -> float:
    """Seconds of the whole command, ``python -m pfmdyn.cli discrepancy <case>.csv``, as a user waits for it: the
    interpreter's start, the imports, reading the file, the analysis, the report and the exit."""
    kind, seed, spot = CASES[case]
    path = tmp / f"{kind}_{seed}_{spot}.csv"
    if not path.exists():
        code = (CASE_DATA.format(tests=str(ROOT / "tests"), seed=seed, kind=kind, spot=spot)
                + f"Path({str(path)!r}).write_text(text)")
        subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True, capture_output=True)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pfmdyn.cli", "discrepancy", str(path)], cwd=cwd, env=env,
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"discrepancy {case} in {cwd} failed: {done.stderr[-2000:]}")
    return time.perf_counter() - started


def differences(new, old, where: str = "", rtol: float = RTOL) -> list[str]:
    """Where two reports (parsed JSON) differ: strings and structure exactly, numbers beyond ``rtol``
    (or :data:`ATOL` near zero); a field only the new report has is an addition (:func:`additions`),
    not a difference.

    >>> differences({"a": [1.0, "x"], "b": 2.0, "c": 1}, {"a": [1.0 + 1e-9, "x"], "b": 2.1})
    ['b: 2.0 != 2.1']
    >>> differences({"a": 1.0}, {"a": 1.0, "b": 2.0})
    [": keys ['b'] missing"]
    """
    if isinstance(new, dict) and isinstance(old, dict):
        if old.keys() - new.keys():
            return [f"{where}: keys {sorted(old.keys() - new.keys())} missing"]
        return [d for k in old for d in differences(new[k], old[k], f"{where}.{k}".lstrip("."), rtol)]
    if isinstance(new, list) and isinstance(old, list):
        if len(new) != len(old):
            return [f"{where}: {len(new)} != {len(old)} items"]
        return [d for i, (a, b) in enumerate(zip(new, old)) for d in differences(a, b, f"{where}[{i}]", rtol)]
    numbers = (int, float)
    if isinstance(new, numbers) and isinstance(old, numbers) and not isinstance(new, bool):
        same = (math.isnan(new) and math.isnan(old)) or math.isclose(new, old, rel_tol=rtol, abs_tol=ATOL)
        return [] if same else [f"{where}: {new!r} != {old!r}"]
    return [] if new == old else [f"{where}: {new!r} != {old!r}"]


STDERR_SHARE = 0.1
"""The scientist's rule (issue 38): a reported value with a stated standard error may move by this share of
the baseline's standard error; every other number by :data:`RTOL`; names, mechanisms, verdicts and the
effect selected at each step exactly."""
STDERR_RTOL = 1e-3
"""A standard error's own tolerance, relative: it is an estimate, uncertain by ``1 / sqrt(2 dof)`` (above 1 %
for spectra of a few thousand values), and moves with the fitted point (a few 1e-6 of itself where an
undetermined parameter's fit stops a step apart)."""


def judged(new, old, where: str = "") -> tuple[list[str], list[str], float]:
    """The scientist's rule on two reports (parsed JSON): the differences that break it, the numbers it lets
    move more (the BIC and gap of a candidate a step did not select: a trial stopped after a few evaluations
    to rank it, never converged), and the largest move of a value with a standard error, in its standard
    errors.

    >>> p = lambda v, e: {"value": v, "stderr": e, "unit": "N/m"}
    >>> broken, _, worst = judged({"k1": p(10.005, 0.1), "gap": 1.0}, {"k1": p(10.0, 0.1), "gap": 1.0})
    >>> broken, round(worst, 3)
    ([], 0.05)
    >>> judged({"k1": p(10.02, 0.1), "gap": 1.1}, {"k1": p(10.0, 0.1), "gap": 1.0})[0]
    ['k1.value: 10.02 != 10.0 (0.2 stderr)', 'gap: 1.1 != 1.0']
    >>> step = lambda bic: {"effect": "damping", "candidates": [{"effect": "tilt", "bic": bic}]}
    >>> judged(step(5.0), step(4.0))
    ([], ['candidates[0].bic: 5.0 != 4.0'], 0.0)
    """
    if isinstance(new, dict) and isinstance(old, dict):
        if old.get("stderr", 0) is None and isinstance(new.get("stderr"), float) and "value" in old:
            # an uncertainty stated since, where the baseline gave none: an addition, listed
            broken, free, worst = judged({**new, "stderr": None}, old, where)
            return broken, free + [f"{where}.stderr: stated now ({new['stderr']:.3g}), none before"], worst
        if {"value", "stderr"} <= old.keys() and {"value", "stderr"} <= new.keys():
            value, err = old["value"], old["stderr"]
            if isinstance(value, float) and isinstance(new["value"], float) and isinstance(err, float) and err > 0:
                moved = abs(new["value"] - value) / err
                rest = judged({k: v for k, v in new.items() if k not in ("value", "stderr")},
                              {k: v for k, v in old.items() if k not in ("value", "stderr")}, where)
                broken = [f"{where}.value: {new['value']!r} != {value!r} ({moved:.2g} stderr)"] \
                    if moved > STDERR_SHARE else []
                broken += differences(new["stderr"], err, f"{where}.stderr", STDERR_RTOL)
                return broken + rest[0], rest[1], max(rest[2], moved)
        if old.keys() - new.keys():
            return [f"{where}: keys {sorted(old.keys() - new.keys())} missing"], [], 0.0
        if "candidates" in old and "effect" in old:
            # a step: the candidates it did not select may move (their trials are not converged)
            out = judged({k: v for k, v in new.items() if k != "candidates"},
                         {k: v for k, v in old.items() if k != "candidates"}, where)
            free = []
            for i, (a, b) in enumerate(zip(new["candidates"], old["candidates"])):
                at = f"{where}.candidates[{i}]".lstrip(".")
                fixed = {k: v for k, v in b.items() if b.get("effect") == old["effect"] or k not in ("bic", "delta_bic", "gap")}
                out[0].extend(differences({k: a.get(k) for k in fixed}, fixed, at))
                free += differences({k: a.get(k) for k in b if k not in fixed}, {k: b[k] for k in b if k not in fixed}, at)
            if len(new["candidates"]) != len(old["candidates"]):
                out[0].append(f"{where}.candidates: {len(new['candidates'])} != {len(old['candidates'])} items")
            return out[0], out[1] + free, out[2]
        parts = [judged(*(_numbers_only(new[k]), _numbers_only(old[k])) if k == "fit_report" else (new[k], old[k]),
                        f"{where}.{k}".lstrip(".")) for k in old]
    elif isinstance(new, list) and isinstance(old, list) and len(new) == len(old):
        parts = [judged(a, b, f"{where}[{i}]") for i, (a, b) in enumerate(zip(new, old))]
    else:
        return differences(new, old, where), [], 0.0
    return ([d for p in parts for d in p[0]], [d for p in parts for d in p[1]], max([p[2] for p in parts], default=0.0))


def _numbers_only(text):
    r"""A fit report's text without its ``+/- error`` parts: the values it renders are judged in their records,
    where an error stated since the baseline is an addition.

    >>> print(_numbers_only("k1: 10.3 +/- 2.1e-05 N/m, width: 1449.09 +/- 0.12 Hz"))
    k1: 10.3 N/m, width: 1449.09 Hz
    """
    return re.sub(r" \+/- \S+", "", text) if isinstance(text, str) else text


def additions(new, old) -> set[str]:
    """The names of the fields the new report has and the old one has not (anywhere in it).

    >>> sorted(additions({"a": [{"x": 1, "y": 2}], "b": 1}, {"a": [{"x": 1}]}))
    ['b', 'y']
    """
    if isinstance(new, dict) and isinstance(old, dict):
        return set(new.keys() - old.keys()).union(*(additions(new[k], old[k]) for k in new.keys() & old.keys()))
    if isinstance(new, list) and isinstance(old, list):
        return set().union(*(additions(a, b) for a, b in zip(new, old)))
    return set()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="commit of the previous design")
    parser.add_argument("--repeat", type=int, default=REPEAT, help="runs per case and design (the best kept)")
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated names of CASES")
    args = parser.parse_args()
    print(f"machine load at start: {os.getloadavg()[0]:.2f} (2 cores; shared)")
    print(f"reports compared: names, selections and structure exactly; numbers within {RTOL:g} relative "
          f"({RTOL / FIT_TOLERANCE:g} x the fits' tolerance {FIT_TOLERANCE:g}) or {ATOL:g} absolute; "
          "'to the bit' when every number is equal (or within 1e-12 at zero); fields the baseline's reports lack "
          "are listed, not compared")
    print(f"scientist's rule (issue 38): names, mechanisms, verdicts and each step's selection exactly; a value "
          f"with a stated standard error within {STDERR_SHARE:g} of it, that standard error within {STDERR_RTOL:g} of "
          f"itself, other numbers within {RTOL:g}; the BIC and "
          "gap of a step's unselected candidates (unconverged trials) may move, listed")
    with tempfile.TemporaryDirectory() as tmp:
        base, base_env = _baseline_tree(args.baseline, Path(tmp))
        now_env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        # The command's design (a step's candidates in worker processes, one per core), the same in one
        # process (CPU per core), and the baseline's.
        designs = {"current": (ROOT, now_env, None), "one worker": (ROOT, now_env, 1),
                   "baseline": (base, base_env, None)}
        try:
            print(f"\ncurrent: worker processes, one per core ({os.cpu_count()}); one worker: the same code in one process"
                  "\n\n| case | rows | baseline CPU s (wall) | current wall s (CPU) | one worker CPU s (wall) | "
                  "speed-up, wall (current) | speed-up, CPU (one worker) | whole command s, baseline / current (speed-up) "
                  "| load | cores free | report |"
                  "\n|---|---|---|---|---|---|---|---|---|---|---|")
            walls, cpus, commands = [], [], []
            for case in args.cases.split(","):
                times = {name: [math.inf, math.inf] for name in designs}
                reports, cores, whole = {}, math.nan, {"baseline": math.inf, "current": math.inf}
                for _ in range(args.repeat):
                    for name, (cwd, env, workers) in designs.items():
                        out = Path(tmp) / f"{name}.json"
                        probe = free_cores() if name == "current" else math.nan
                        seconds, cpu, rows = run_case(case, cwd, env, out, workers)
                        if name == "current" and seconds < times[name][1]:
                            cores = probe      # what the workers found before the run kept (the fastest)
                        times[name] = [min(times[name][0], cpu), min(times[name][1], seconds)]
                        reports[name] = json.loads(out.read_text())
                    for name in ("baseline", "current"):
                        whole[name] = min(whole[name], command_seconds(case, *designs[name][:2], Path(tmp)))
                diff = differences(reports["current"], reports["baseline"])
                added = additions(reports["current"], reports["baseline"])
                exact = not differences(reports["current"], reports["baseline"], rtol=0.0)
                broken, free, worst = judged(reports["current"], reports["baseline"])
                (old, old_wall), (new, new_wall), (one, one_wall) = (times[n] for n in ("baseline", "current", "one worker"))
                walls.append(old_wall / new_wall)
                cpus.append(old / one)
                commands.append(whole["baseline"] / whole["current"])
                verdict = ("unchanged to the bit" if exact else f"unchanged within {RTOL:g}" if not diff
                           else f"CHANGED beyond {RTOL:g}: {'; '.join(diff[:4])}")
                verdict += (f"; scientist's rule: {'FAILS: ' + '; '.join(broken[:4]) if broken else 'passes'} "
                            f"(values within {worst:.2g} of their stderr; unselected candidates moved: "
                            f"{'; '.join(free) if free else 'none'})")
                verdict += f" (fields added since: {', '.join(sorted(added))})" if added else ""
                same = reports["one worker"] == reports["current"]
                verdict += "; one worker: the same report to the bit" if same else "; one worker: ANOTHER REPORT"
                print(f"| {case} | {rows} | {old:.1f} ({old_wall:.1f}) | {new_wall:.1f} ({new:.1f}) | {one:.1f} "
                      f"({one_wall:.1f}) | {old_wall / new_wall:.2f} | {old / one:.2f} | {whole['baseline']:.1f} / "
                      f"{whole['current']:.1f} ({commands[-1]:.2f}) | {os.getloadavg()[0]:.1f} | {cores:.2f} | {verdict} |")
            print(f"\nmedian speed-up: wall, as the command runs {statistics.median(walls):.2f} (target >= 6); "
                  f"CPU in one process {statistics.median(cpus):.2f}; the whole command (start-up, imports, reading, "
                  f"report and exit included) {statistics.median(commands):.2f}")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, check=False)


if __name__ == "__main__":
    with recorded("discrepancy_speed"):
        main()
