"""Benchmark: ``pfmdyn discrepancy`` on independent random data: pass rates and speed.

Run ``python benchmarks/discrepancy.py [--cases N] [--tables N] [--classes a,b]``.

Data: the finite-element beam of ``tests/fe_beam.py`` (it shares no code with the fitted
model), cantilevers, contacts, damping mechanism, noise, bias count, response columns and
row order (instrument order: one sweep per bias) drawn at random over realistic ranges
(:func:`fe_beam.random_case`, :func:`fe_beam.random_table`).  Classes: nothing hidden,
each effect alone, damping with each other effect.  ``lateral_stiffness`` is analysed
``--vertical-only`` (the baseline otherwise has k2).  A case passes when the named set is
exactly the hidden set and ``gap_after <= 1.5`` (spectra; tables: ``<= 1.5`` too).

Speed targets (one core; BLAS limited to one thread as in the command): a spectrum of 1000 frequencies x 5 biases with two hidden
effects in <= 10 s with the Jacobian from the generated partials (``model.JACOBIAN =
"analytic"``), printed beside the same analysis with finite differences of the design matrix
(``"projection"``) and of the whole residual (``"finite-difference"``); a resonance table in <= 2 s.

Results: ``benchmarks/results/discrepancy.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

# The FE generator and the paper's tables are test support, not part of the package: import it from tests/.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from fe_beam import FEBeam, random_case, random_table, spectrum  # noqa: E402
from paper_resonances import paper_tables  # noqa: E402

from pfmdyn.discrepancy import model as model_module  # noqa: E402
from pfmdyn.discrepancy.resonances import analyse_resonances  # noqa: E402
from pfmdyn.discrepancy.spectrum import analyse  # noqa: E402
from pfmdyn.io.tables import read  # noqa: E402
from recording import recorded  # noqa: E402

SINGLE = ("damping", "tip_mass", "tip_setback", "tilt", "background", "lateral_stiffness")
CLASSES = [()] + [(e,) for e in SINGLE] + [("damping", e) for e in SINGLE[1:]]
TABLE_CLASSES = [(), ("tip_mass",), ("tip_setback",), ("tilt",), ("lateral_stiffness",)]
SPECTRUM_TARGET_S, TABLE_TARGET_S, GAP_PASS = 10.0, 2.0, 1.5


def _read(text: str):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "data.csv"
        path.write_text(text)
        return read(path)


def run_case(kind: str, hidden: tuple, seed: int) -> dict:
    """Analyse one random case; return what was hidden, what was named, gap and time."""
    if kind == "spectrum":
        text, truth = random_case(seed, hidden)
    else:
        text, truth = random_table(seed, hidden)
    data = _read(text)
    vertical = "lateral_stiffness" in hidden
    start = time.perf_counter()
    report = (analyse(data, vertical_only=vertical, progress=False) if kind == "spectrum"
              else analyse_resonances(data, vertical_only=vertical, progress=False))
    elapsed = time.perf_counter() - start
    named = report["missing_effects"]
    ok = sorted(named) == sorted(hidden) and report["gap_after"] <= GAP_PASS
    return {"hidden": hidden, "named": named, "mechanism": truth.get("damping_mechanism"),
            "found_mechanisms": report["damping_mechanisms"], "gap_after": report["gap_after"],
            "seconds": elapsed, "pass": ok}


def speed() -> bool:
    """The issue's timing case with each Jacobian (same data, same run), and a resonance table."""
    beam = FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, n_elements=150, Q=100.0, mu=0.2)
    data = _read(spectrum(beam, np.linspace(150e3, 1300e3, 1000), seed=11, order="instrument"))
    times = {}
    for how in ("analytic", "projection", "finite-difference"):
        model_module.JACOBIAN = how
        (report,), times[how] = _timed(analyse, data, progress=False)
        print(f"spectrum 1000 x 5, hidden damping + tip_mass, {how} Jacobian: {times[how][0]:.1f} s wall, "
              f"{times[how][1]:.1f} s CPU; named {report['missing_effects']} ({report['damping_mechanisms']}), "
              f"gap {report['gap_after']:.2f}")
    model_module.JACOBIAN = "analytic"
    for other in ("finite-difference", "projection"):
        print(f"  ratio {other} / analytic: {times[other][0] / times['analytic'][0]:.2f} wall, "
              f"{times[other][1] / times['analytic'][1]:.2f} CPU")
    (tip1,), table = _timed(analyse_resonances, paper_tables()["tip 1"], progress=False)
    print(f"resonance table (paper tip 1): {table[0]:.2f} s wall, {table[1]:.2f} s CPU (target <= "
          f"{TABLE_TARGET_S:g} s); named {tip1['missing_effects'] or 'nothing'}, unexplained {tip1['unexplained'] is not None}")
    # One core: CPU time is the one-core time when other processes share the machine.
    return times["analytic"][1] <= SPECTRUM_TARGET_S and table[1] <= TABLE_TARGET_S


def _timed(fn, *args, **kwargs):
    """``((result,), (wall seconds, CPU seconds of this process))``."""
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn(*args, **kwargs)
    return (out,), (time.perf_counter() - wall, time.process_time() - cpu)


def main() -> int:
    """Run the sweep; print per-case lines and pass rates; 1 if a target is missed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=10, help="spectra per class (default 10)")
    parser.add_argument("--tables", type=int, default=10, help="resonance tables per class (default 10)")
    parser.add_argument("--classes", help="comma-separated hidden sets to run, e.g. 'damping+tilt,none'")
    parser.add_argument("--no-speed", action="store_true", help="skip the timing case")
    args = parser.parse_args()
    fast = True if args.no_speed else speed()
    wanted = None if not args.classes else {c for c in args.classes.split(",")}
    total = passed = 0
    for kind, classes, count in (("table", TABLE_CLASSES, args.tables), ("spectrum", CLASSES, args.cases)):
        for hidden in classes:
            label = "+".join(hidden) or "none"
            if wanted and label not in wanted:
                continue
            results = [run_case(kind, hidden, 1000 * len(label) + seed) for seed in range(count)]
            for r in results:
                mech = f" [{r['mechanism']} -> {','.join(r['found_mechanisms']) or '-'}]" if r["mechanism"] else ""
                print(f"  {kind} {label}: named {'+'.join(r['named']) or 'none'}{mech}, gap {r['gap_after']:.2f}, "
                      f"{r['seconds']:.1f} s {'ok' if r['pass'] else 'FAIL'}", flush=True)
            ok = sum(r["pass"] for r in results)
            if results:
                print(f"{kind} {label}: {ok}/{len(results)} pass, max {max(r['seconds'] for r in results):.1f} s",
                      flush=True)
            total, passed = total + len(results), passed + ok
    if total:
        print(f"overall: {passed}/{total} pass ({100 * passed / total:.0f} %)")
    return 0 if fast and passed == total else 1


if __name__ == "__main__":
    with threadpool_limits(1, user_api="blas"), recorded("discrepancy"):   # one core, as the command runs
        status = main()
    sys.exit(status)
