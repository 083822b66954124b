"""Benchmark: ``pfmdyn discrepancy`` on inputs written the ways researchers and other
simulators write them.  Not a pytest module: a wide sweep that prints a pass table and rate.

Run ``python benchmarks/discrepancy_inputs.py [--seed N] [--physics] [--all-through-cli]``.

Each variant is a file: the same data as a canonical file (finite-element spectrum of
:func:`fe_beam.random_case` with a hidden damping and tip mass, and a
:func:`fe_beam.random_table` with a tip mass) written another way, or an input that must be
refused.  Spectrum variants: column order, header spellings and units (``freq``,
``Frequency (kHz)``, ``bias_mv``, ``real, imag``, ``R, Phase (rad)``), separators (tab,
semicolon, spaces, decimal commas), Windows and old Mac line ends, byte-order mark,
``%``/``##`` comments, ``key = value`` metadata, metadata with units, trailing separators,
row orders, duplicated rows, one or two biases, frequencies written with rounding noise,
biases read back with jitter, a single frequency, NaN cells, non-positive frequencies,
empty files, missing metadata, wrong units (kHz in a Hz column, length in um, f1 in kHz),
zero and constant responses.  Table variants: the same kinds, plus Q columns, free-only
and contact-only rows, condition words.
The paper's Section VI.1 resonances (tip 1, tip 2) are run in kHz, in both row orders.
``--physics`` adds random levers with each hidden effect and special spectra (noise-free,
interleaved sweeps, 6000 x 7 rows, 60 frequencies, a band without a peak).

Outcome of a variant:

* ``pass``: an equivalent file reads as the canonical one (so its report is the same) or,
  run through the CLI, names the canonical file's effects; an invalid file is refused in
  one line ``pfmdyn discrepancy: error: ...``;
* ``reject``: a valid file refused (one clear line, but a researcher has to edit the file);
* ``FAIL``: a traceback, a run over 60 s, an invalid file accepted, or a different named
  set than the canonical file's (a silently wrong answer).

Files that read as the canonical file are not re-analysed unless ``--all-through-cli``.

Results: ``benchmarks/results/discrepancy_inputs.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from fe_beam import FEBeam, random_case, random_table, spectrum  # noqa: E402

from pfmdyn.generated import paper_inputs  # noqa: E402
from pfmdyn.errors import UserError  # noqa: E402
from pfmdyn.io.tables import read  # noqa: E402
from recording import recorded  # noqa: E402

TIMEOUT_S, SLOW_S = 120, 60.0
SAME, EFFECTS, ERROR, ANY = "same", "effects", "error", "any"
"""Expectations: the canonical data; the canonical file's named effects; a one-line error; a
report or a one-line error."""


def _parse(text: str):
    """Metadata lines, header names and the numeric rows of a CSV written by ``fe_beam``."""
    meta = [line for line in text.splitlines() if line.startswith("#")]
    body = [line for line in text.splitlines() if line and not line.startswith("#")]
    return meta, body[0].split(","), np.array([[float(c) for c in line.split(",")] for line in body[1:]])


def _write(meta, header, columns, sep=",", newline="\n", bom=False, comment="#") -> str:
    lines = [m.replace("#", comment, 1) for m in meta] + [sep.join(header)]
    lines += [sep.join(repr(float(v)) for v in row) for row in np.column_stack(columns)]
    return ("\ufeff" if bom else "") + newline.join(lines) + newline


def _edit_metadata(text: str, key: str, fn) -> str:
    return "".join((f"# {key}: {fn(float(line.split(': ')[1]))}" if line.startswith(f"# {key}:") else line) + "\n"
                   for line in text.splitlines())


def spectrum_variants(text: str) -> dict[str, tuple[str, str]]:
    """Name -> (file text, expectation) for a canonical spectrum."""
    meta, header, rows = _parse(text)
    f, V = rows[:, 0], rows[:, 1]
    if "x" in header:
        z = rows[:, 2] + 1j * rows[:, 3]
    else:
        z = rows[:, 2] * np.exp(1j * np.deg2rad(rows[:, 3]))
    x, y, A, P = z.real, z.imag, np.abs(z), np.angle(z)
    base, cols = ["frequency_hz", "bias_v", "x", "y"], [f, V, x, y]
    canonical = _write(meta, base, cols)
    W = lambda h, c, **kw: _write(meta, h, c, **kw)  # noqa: E731
    rng = np.random.default_rng(0)
    order = rng.permutation(len(f))
    v = {"canonical": (canonical, SAME), "columns reordered": (W(["bias_v", "y", "frequency_hz", "x"], [V, y, f, x]), SAME)}
    for h in (["freq", "bias", "x", "y"], ["frequency", "bias", "X", "Y"], ["f_hz", "V_dc", "x", "y"],
              ["Frequency (Hz)", "Bias (V)", "X", "Y"], ["frequency_hz", "dc", "real", "imag"],
              ["frequency_hz", "bias_v", "re", "im"], ["Frequency [Hz]", "Bias [V]", "x", "y"], ["f", "V", "x", "y"],
              ["frequency_hz", "bias_v", "X (pm)", "Y (pm)"], ["frequency_hz", "bias_v", "x_pm", "y_pm"],
              ['"frequency_hz"', '"bias_v"', '"x"', '"y"'], ["Frequency_Hz", "Bias_V", "X", "Y"]):
        v["header " + "|".join(h)] = (W(h, cols), SAME)
    deg = np.degrees(P)
    v.update({
        "frequency_khz": (W(["frequency_khz", "bias_v", "x", "y"], [f / 1e3, V, x, y]), SAME),
        "Frequency (kHz)": (W(["Frequency (kHz)", "Bias (V)", "x", "y"], [f / 1e3, V, x, y]), SAME),
        "frequency_mhz": (W(["frequency_mhz", "bias_v", "x", "y"], [f / 1e6, V, x, y]), SAME),
        "bias_mv": (W(["frequency_hz", "bias_mv", "x", "y"], [f, 1e3 * V, x, y]), SAME),
        "Bias (mV)": (W(["frequency_hz", "Bias (mV)", "x", "y"], [f, 1e3 * V, x, y]), SAME),
        "amplitude, phase_deg": (W(["frequency_hz", "bias_v", "amplitude", "phase_deg"], [f, V, A, deg]), SAME),
        "amplitude, phase_rad": (W(["frequency_hz", "bias_v", "amplitude", "phase_rad"], [f, V, A, P]), SAME),
        "R, theta_rad": (W(["frequency_hz", "bias_v", "R", "theta_rad"], [f, V, A, P]), SAME),
        "Amplitude (pm), Phase (deg)": (W(["Frequency (Hz)", "Bias (V)", "Amplitude (pm)", "Phase (deg)"],
                                          [f, V, A, deg]), SAME),
        "phase without unit": (W(["frequency_hz", "bias_v", "amplitude", "phase"], [f, V, A, deg]), ERROR),
        "X, Y, R, Theta (deg)": (W(["f", "V", "X", "Y", "R", "Theta (deg)"], cols + [A, deg]), SAME),
        "x, y and a phase of opposite sign": (W(base + ["amplitude", "phase_deg"], cols + [A, -deg]), ERROR),
        "tab": (W(base, cols, sep="\t"), SAME),
        "semicolon": (W(base, cols, sep=";"), SAME),
        "semicolon, decimal comma": (W(base, cols, sep=";").replace(".", ","), SAME),
        "spaces": (W(base, cols, sep="  "), SAME),
        "comma and space": (W(base, cols, sep=", "), SAME),
        "CRLF": (W(base, cols, newline="\r\n"), SAME),
        "CR only": (W(base, cols, newline="\r"), SAME),
        "BOM": (W(base, cols, bom=True), SAME),
        "BOM, CRLF, tab": (W(base, cols, bom=True, newline="\r\n", sep="\t"), SAME),
        "% comments": (W(base, cols, comment="%"), SAME),
        "## comments": (W(base, cols, comment="##"), SAME),
        "key = value": (canonical.replace(": ", " = "), SAME),
        "#key:value": (canonical.replace("# ", "#"), SAME),
        "metadata with units": (_edit_metadata(_edit_metadata(canonical, "length_m", lambda q: f"{q * 1e6!r} um"),
                                               "free_resonance_hz", lambda q: f"{q / 1e3!r} kHz"), SAME),
        "metadata key case": (canonical.replace("spring_constant_n_per_m", "Spring_Constant_N_per_m"), SAME),
        "blank lines": (canonical.replace("\nfrequency_hz", "\n\nfrequency_hz") + "\n\n", SAME),
        "trailing separator": ("".join(line + ("\n" if line.startswith("#") else ",\n")
                                       for line in canonical.splitlines()), SAME),
        "trailing spaces": (canonical.replace("\n", "  \n"), SAME),
        "shuffled": (W(base, [c[order] for c in cols]), SAME),
        "descending": (W(base, [c[np.lexsort((V, f))[::-1]] for c in cols]), SAME),
        "duplicated rows": (W(base, [np.concatenate([c, c[:50]]) for c in cols]), SAME),
        "rounding noise on f": (W(base, [f * (1 + 1e-13 * rng.standard_normal(len(f))), V, x, y]), SAME),
        "jitter 1e-7 on f": (W(base, [f * (1 + 1e-7 * rng.standard_normal(len(f))), V, x, y]), SAME),
        "bias read back, 1 mV jitter": (W(base, [f, V + 1e-3 * rng.standard_normal(len(V)), x, y]), EFFECTS),
        "one frequency": (W(base, [c[f == f.min()] for c in cols]) + "".join(
            f"{float(f.min())!r},{float(b)!r},1.0,0.0\n" for b in np.arange(10.0, 40.0)), ERROR),
        "conflicting duplicate": (W(base, [np.concatenate([f, f[:5]]), np.concatenate([V, V[:5]]),
                                           np.concatenate([x, 1.01 * x[:5]]), np.concatenate([y, y[:5]])]), ERROR),
        "NaN cell": (canonical.replace(f",{float(x[10])!r},", ",NaN,", 1), ERROR),
        "empty cell": (canonical.replace(f",{float(x[10])!r},", ",,", 1), ERROR),
        "negative frequency": (canonical.replace(f"\n{float(f[3])!r},", f"\n{-float(f[3])!r},", 1), ERROR),
        "empty file": ("", ERROR),
        "header only": ("\n".join(meta + [",".join(base)]) + "\n", ERROR),
        "metadata only": ("\n".join(meta) + "\n", ERROR),
        "no metadata": ("\n".join(line for line in canonical.splitlines() if not line.startswith("#")) + "\n", ERROR),
        "kHz in a Hz column": (W(base, [f / 1e3, V, x, y]), ERROR),
        "length in um, no unit": (_edit_metadata(canonical, "length_m", lambda q: repr(q * 1e6)), ERROR),
        "f1 in kHz, no unit": (_edit_metadata(canonical, "free_resonance_hz", lambda q: repr(q / 1e3)), ERROR),
        "zero response": (W(base, [f, V, 0 * x, 0 * y]), ERROR),
        "constant response": (W(base, [f, V, 0 * x + 1, 0 * y]), ANY),
        "one bias": (W(base, [c[V == V.min()] for c in cols]), ANY),
        "two biases": (W(base, [c[V <= np.unique(V)[1]] for c in cols]), ANY),
        "responses x 1e-12 (in m)": (W(base, [f, V, 1e-12 * x, 1e-12 * y]), EFFECTS),
        "25 rows": (W(base, [c[:25] for c in cols]), ANY),
    })
    return v


def table_variants(text: str) -> dict[str, tuple[str, str]]:
    """Name -> (file text, expectation) for a canonical resonances table."""
    meta = [line for line in text.splitlines() if line.startswith("#")]
    rows = [line.split(",") for line in text.splitlines() if line and not line.startswith("#")][1:]
    head = ["mode", "condition", "frequency_hz"]

    def T(header, body, sep=",", newline="\n"):
        return newline.join(meta + [sep.join(header)] + [sep.join(r) for r in body]) + newline

    khz = [[m, c, repr(float(fr) / 1e3)] for m, c, fr in rows]
    free = [r for r in rows if r[1] == "free"]
    contact = [r for r in rows if r[1] == "contact"]
    return {
        "canonical": (T(head, rows), SAME),
        "frequency_khz": (T(["mode", "condition", "frequency_khz"], khz), SAME),
        "Frequency (kHz), capitals": (T(["Mode", "Condition", "Frequency (kHz)"], khz), SAME),
        "f_hz": (T(["mode", "condition", "f_hz"], rows), SAME),
        "freq": (T(["mode", "condition", "freq"], rows), SAME),
        "Frequency [Hz]": (T(["mode", "condition", "Frequency [Hz]"], rows), SAME),
        "columns reversed": (T(head[::-1], [r[::-1] for r in rows]), SAME),
        "Q column": (T(head + ["Q"], [r + ["100"] for r in rows]), ANY),
        "Q factor, blank": (T(head + ["Q factor"], [r + [""] for r in rows]), SAME),
        "quality_factor inf": (T(head + ["quality_factor"], [r + ["inf"] for r in rows]), SAME),
        "free rows only": (T(head, free), ANY),
        "contact rows only": (T(head, contact), ANY),
        "one row": (T(head, contact[:1]), ANY),
        "FREE/CONTACT": (T(head, [[m, c.upper(), fr] for m, c, fr in rows]), SAME),
        "air / in contact": (T(head, [[m, {"free": "air", "contact": "in contact"}[c], fr] for m, c, fr in rows]), SAME),
        "mode as 1.0": (T(head, [[m + ".0", c, fr] for m, c, fr in rows]), SAME),
        "tab": (T(head, rows, sep="\t"), SAME),
        "semicolon": (T(head, rows, sep=";"), SAME),
        "spaces": (T(head, rows, sep="   "), SAME),
        "BOM, CRLF": ("\ufeff" + T(head, rows, newline="\r\n"), SAME),
        "CR only": (T(head, rows, newline="\r"), SAME),
        "trailing separator": (T(head + [""], [r + [""] for r in rows]), SAME),
        "quoted": (T(['"mode"', '"condition"', '"frequency_hz"'], [[m, f'"{c}"', fr] for m, c, fr in rows]), SAME),
        "duplicated rows": (T(head, rows + rows[:2]), SAME),
        "conflicting duplicate": (T(head, rows + [[rows[0][0], rows[0][1], repr(1.1 * float(rows[0][2]))]]), ERROR),
        "mode 2 missing": (T(head, [r for r in rows if r[:2] != ["2", "free"]]), ANY),
        "negative frequency": (T(head, [[m, c, "-" + fr] for m, c, fr in rows]), ERROR),
        "NaN frequency": (T(head, rows[:-1] + [rows[-1][:2] + ["nan"]]), ERROR),
        "mode 0": (T(head, [[str(int(m) - 1), c, fr] for m, c, fr in rows]), ERROR),
        "kHz in a Hz column": (T(head, khz), ERROR),
        "comment after the header": (T(head, rows[:2] + [["# note"]] + rows[2:]), ERROR),
        "metadata with units": (T(head, rows).replace("\n# length_m", " N/m\n# length_m"), SAME),
        "no metadata": (",".join(head) + "\n" + "\n".join(",".join(r) for r in rows) + "\n", ERROR),
        "empty file": ("", ERROR),
        "header only": (T(head, []), ERROR),
    }


def paper_variants() -> dict[str, tuple[str, str]]:
    """The paper's Section VI.1 resonances, as a researcher would type them (kHz)."""
    head = ("# spring_constant_n_per_m: 2.4\n# length_m: 223e-6\n# width_m: 24e-6\n# tip_height_m: 1e-5\n"
            "# free_resonance_hz: {f1}\nmode,condition,frequency_khz\n")
    free1, contact1 = list(paper_inputs.TIP1_FREE_KHZ), list(paper_inputs.TIP1_CONTACT_KHZ)
    rows = [f"{i + 1},free,{v}" for i, v in enumerate(free1)] + [f"{i + 1},contact,{v}" for i, v in enumerate(contact1)]
    free2 = [f"{i + 1},free,{v}" for i, v in enumerate(paper_inputs.TIP2_FREE_KHZ)]
    return {"paper tip 1": (head.format(f1=free1[0] * 1e3) + "\n".join(rows) + "\n", ANY),
            "paper tip 1, rows reversed": (head.format(f1=free1[0] * 1e3) + "\n".join(rows[::-1]) + "\n", ANY),
            "paper tip 2": (head.format(f1=paper_inputs.TIP2_FREE_KHZ[0] * 1e3) + "\n".join(free2) + "\n", ANY)}


def physics_variants(seed: int) -> dict[str, tuple[str, tuple | None]]:
    """Name -> (spectrum or table text, hidden effects or None) over levers and effects."""
    out = {}
    classes = [(), ("damping",), ("tip_mass",), ("tip_setback",), ("tilt",), ("background",),
               ("lateral_stiffness",), ("damping", "tilt")]
    for i, hidden in enumerate(classes):
        label = "+".join(hidden) or "none"
        out[f"spectrum {label}"] = (random_case(100 * seed + i, hidden, n_freq=300, n_elements=60)[0], hidden)
        if "background" not in hidden:
            table_hidden = tuple(h for h in hidden if h != "damping")
            out[f"table {label}"] = (random_table(100 * seed + i, hidden)[0], table_hidden)
    beam = FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, n_elements=60, Q=100.0)
    f = np.linspace(150e3, 1300e3, 400)
    out["noise-free"] = (spectrum(beam, f, noise=0.0, order="instrument"), ("damping",))
    both = np.sort(np.concatenate([f, f + (f[1] - f[0]) / 2]))
    meta, header, rows = _parse(spectrum(beam, both, noise=0.005))
    f_index, v_index = np.searchsorted(both, rows[:, 0]), np.searchsorted(np.unique(rows[:, 1]), rows[:, 1])
    keep = rows[f_index % 2 == v_index % 2]                 # odd biases at the half steps
    out["interleaved sweeps"] = (_write(meta, header, keep.T), ("damping",))
    out["6000 x 7 rows"] = (spectrum(beam, np.linspace(150e3, 1300e3, 6000), tuple(np.linspace(-3, 3, 7)),
                                     noise=0.005, order="instrument"), ("damping",))
    out["60 frequencies"] = (spectrum(beam, np.linspace(150e3, 1300e3, 60), noise=0.005), ("damping",))
    out["band without a peak"] = (spectrum(beam, np.linspace(300e3, 330e3, 200), noise=0.005), None)
    return out


def run_cli(path: Path, extra=()) -> dict:
    """``pfmdyn discrepancy`` in a subprocess: exit status, last stderr line, named effects, seconds."""
    start = time.perf_counter()
    command = [sys.executable, "-m", "pfmdyn.cli", "discrepancy", str(path), "--json", f"{path}.json", *extra]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return {"status": "timeout", "err": "", "lines": 0, "named": None, "seconds": time.perf_counter() - start}
    err = [line for line in done.stderr.replace("\r", "\n").splitlines() if line.strip() and "fit" not in line]
    named = json.loads(Path(f"{path}.json").read_text())["missing_effects"] if done.returncode == 0 else None
    return {"status": done.returncode, "err": err[-1] if err else "", "lines": len(err), "named": named,
            "seconds": time.perf_counter() - start}


def _same(a, b) -> bool:
    if type(a) is not type(b) or a.frequency_hz.shape != b.frequency_hz.shape or a.metadata != b.metadata:
        return False
    if hasattr(a, "response"):
        scale = np.abs(b.response).max()
        return (np.allclose(a.frequency_hz, b.frequency_hz, rtol=1e-6) and np.allclose(a.bias_v, b.bias_v, atol=1e-9)
                and np.allclose(a.response / scale, b.response / scale, atol=1e-9))
    return (a.mode.tolist() == b.mode.tolist() and a.condition.tolist() == b.condition.tolist()
            and np.allclose(a.frequency_hz, b.frequency_hz, rtol=1e-9))


def judge(path: Path, expect: str, canonical, named, through_cli: bool) -> tuple[str, str]:
    """Outcome (pass / reject / FAIL) of one file and a note."""
    try:
        data, problem = read(path), None
    except UserError as exc:
        data, problem = None, str(exc)
    except Exception as exc:                                # noqa: BLE001 - a traceback is the finding
        return "FAIL", f"traceback in read: {type(exc).__name__}: {exc}"
    if problem is not None:
        return ("pass" if expect in (ERROR, ANY) else "reject"), problem.split(": ", 1)[-1]
    if expect == SAME and canonical is not None and not through_cli:
        return ("pass", "reads as the canonical file") if _same(data, canonical) else ("FAIL", "reads differently")
    r = run_cli(path)
    if r["status"] not in (0, 2) or (r["status"] == 2 and r["lines"] != 1):
        return "FAIL", f"exit {r['status']}: {r['err']}"
    if r["seconds"] > SLOW_S:
        return "FAIL", f"{r['seconds']:.0f} s"
    if r["status"] == 2:
        return ("pass" if expect in (ERROR, ANY) else "reject"), r["err"]
    if expect == ERROR:
        return "FAIL", f"accepted; named {r['named']}"
    if expect in (SAME, EFFECTS) and named is not None and sorted(r["named"]) != sorted(named):
        return "FAIL", f"named {r['named']}, canonical file {named}"
    return "pass", f"named {r['named'] or 'nothing'}, {r['seconds']:.0f} s"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--physics", action="store_true", help="also random levers and special spectra (slow)")
    parser.add_argument("--all-through-cli", action="store_true", help="analyse equivalent files too")
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        spectrum_text = random_case(args.seed, ("damping", "tip_mass"), n_freq=200, n_elements=60)[0]
        table_text = random_table(args.seed, ("tip_mass",))[0]
        groups = [("spectrum", spectrum_text, spectrum_variants), ("table", table_text, table_variants),
                  ("paper", None, lambda _: paper_variants())]
        for kind, text, variants in groups:
            canonical = named = None
            if text is not None:
                (tmp / f"{kind}.csv").write_text(text)
                canonical, named = read(tmp / f"{kind}.csv"), run_cli(tmp / f"{kind}.csv")["named"]
                print(f"canonical {kind}: named {named}", flush=True)
            for i, (name, (body, expect)) in enumerate(variants(text).items()):
                path = tmp / f"{kind}{i}.csv"
                path.write_bytes(body.encode("utf-8"))
                outcome, note = judge(path, expect, canonical, named, args.all_through_cli)
                results.append(outcome)
                print(f"{outcome:6s} {kind:8s} {name:34s} {note[:110]}", flush=True)
        if args.physics:
            for i, (name, (body, hidden)) in enumerate(physics_variants(args.seed).items()):
                path = tmp / f"physics{i}.csv"
                path.write_text(body)
                r = run_cli(path, ("--vertical-only",) if hidden and "lateral_stiffness" in hidden else ())
                crashed = r["status"] not in (0, 2) or (r["status"] == 2 and r["lines"] != 1) or r["seconds"] > SLOW_S
                outcome = "FAIL" if crashed else "reject" if r["status"] == 2 else (
                    "pass" if hidden is None or sorted(r["named"]) == sorted(hidden) else "miss")
                results.append(outcome)
                print(f"{outcome:6s} physics  {name:34s} named {r['named']}, hidden {hidden}, "
                      f"{r['seconds']:.0f} s {r['err'][:80]}", flush=True)
    counts = {k: results.count(k) for k in ("pass", "reject", "miss", "FAIL")}
    print(" ".join(f"{k} {v}" for k, v in counts.items()), f"of {len(results)}:",
          f"{100 * counts['pass'] / len(results):.0f} % pass")
    return 0 if counts["FAIL"] == 0 else 1


if __name__ == "__main__":
    with recorded("discrepancy_inputs"):
        status = main()
    sys.exit(status)
