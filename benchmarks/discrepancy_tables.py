"""Benchmark: ``pfmdyn discrepancy`` on independent random resonance tables, through the CLI.

Run ``python benchmarks/discrepancy_tables.py [--tables N] [--damped N]``.

Every case goes through ``pfmdyn discrepancy`` as a user would (``pfmdyn.cli.main``), so a
traceback is a failure, as is a run over 70 s.  Two sets:

* :func:`fe_beam.random_table` for each class of ``benchmarks/discrepancy.py``
  ``TABLE_CLASSES`` (no Q column): passes when the named set is the hidden one and
  ``gap_after <= 1.5``;
* :func:`fe_quality.damped_table` (Q per mode from the FE beam's complex eigenvalues, 3 %
  noise on Q) for each damping mechanism, alone and with a hidden tip mass or set-back,
  half of them with columns reordered, in kHz and Q named ``Q``: passes when the hidden
  set is named, ``damping`` with the hidden mechanism alone, and ``gap_after <= 1.5``.

Results: ``benchmarks/results/discrepancy_tables.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from discrepancy import TABLE_CLASSES  # noqa: E402
from fe_beam import random_table  # noqa: E402
from fe_quality import MECHANISMS, damped_table  # noqa: E402

from pfmdyn import cli  # noqa: E402
from recording import recorded  # noqa: E402

LIMIT_S, GAP_PASS = 70.0, 1.5
DAMPED_WITH = [(), ("tip_mass",), ("tip_setback",)]


def run_cli(text: str, vertical_only: bool) -> tuple[int, dict | str, float]:
    """Exit status, report (or stderr) and seconds of ``pfmdyn discrepancy`` on ``text``."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "table.csv"
        path.write_text(text)
        args = ["discrepancy", str(path), "--json", str(path.with_suffix(".json"))]
        err = io.StringIO()
        start = time.perf_counter()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            status = cli.main(args + (["--vertical-only"] if vertical_only else []))
        elapsed = time.perf_counter() - start
        out = json.loads(path.with_suffix(".json").read_text()) if status == 0 else err.getvalue().strip()
    return status, out, elapsed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", type=int, default=6, help="random tables per class (default 6)")
    parser.add_argument("--damped", type=int, default=6, help="damped tables per mechanism (default 6)")
    args = parser.parse_args()
    cases = [("table", hidden, None, seed) for hidden in TABLE_CLASSES for seed in range(args.tables)]
    cases += [("damped", hidden, mech, seed) for hidden in DAMPED_WITH for mech in MECHANISMS
              for seed in range(args.damped)]
    passed = 0
    for kind, hidden, mech, seed in cases:
        if kind == "table":
            text, _ = random_table(7000 + 97 * seed + len("+".join(hidden)), hidden)
            want = sorted(hidden)
        else:
            text, _ = damped_table(8000 + 31 * seed + len(hidden[0] if hidden else ""), mech, hidden, q_noise=0.03,
                                   columns="other" if seed % 2 else "plain")
            want = sorted(("damping",) + hidden)
        status, out, elapsed = run_cli(text, "lateral_stiffness" in hidden)
        if status != 0:
            ok, line = False, f"exit {status}: {str(out)[-200:]}"
        else:
            gaps = {key: out["fit"][key]["value"] for key in ("gap_before", "gap_after")}
            mechanisms = out["results"]["damping_mechanisms"]["value"]
            ok = sorted(out["missing_effects"]) == want and gaps["gap_after"] <= GAP_PASS and elapsed <= LIMIT_S
            if mech:
                ok = ok and mechanisms == [mech]
            line = (f"named {'+'.join(out['missing_effects']) or 'none'} {mechanisms or ''}, "
                    f"gap {gaps['gap_before']:.3g} -> {gaps['gap_after']:.2f}")
        passed += ok
        label = "+".join(((mech,) if mech else ()) + hidden) or "none"
        print(f"{kind} {label} seed {seed}: {line}, {elapsed:.1f} s {'ok' if ok else 'FAIL'}", flush=True)
    print(f"overall: {passed}/{len(cases)} pass ({100 * passed / len(cases):.0f} %)")
    return 0 if passed == len(cases) else 1


if __name__ == "__main__":
    with recorded("discrepancy_tables"):
        status = main()
    sys.exit(status)
