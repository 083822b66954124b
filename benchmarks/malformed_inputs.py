"""Benchmark: every file-reading command on malformed map and instrument files.

Not a pytest module: a wide sweep that writes one row per case and its pass count to
``benchmarks/results/malformed_inputs.md`` (:mod:`recording`).

    python benchmarks/malformed_inputs.py

Each variant is a file (or a command-line override) written from a valid one: a 4 x 4
band-excitation map of the finite-element beam (``tests/fe_beam.py``) as HDF5, Zarr and
pycroscopy USID; a contact-frequency map; Asylum ``.ibw`` images written by igorwriter (when
installed); and copies of the real instrument files of ``shared/realdata`` (when present:
``.ibw``, NSID ``.h5``, Nanosurf ``.nid``, drive sweeps).  Map variants: empty, short, 2-D,
text, NaN, negative and repeated frequency axes; shapes that disagree with the axes; empty
grids; text data; missing datasets; metadata missing, zero, negative, NaN, inf, text or
arrays (in the file and on the command line); tip geometry out of range; bias axes with one
value, NaN or the wrong length; NaN, inf and all-zero pixels; damaged Zarr stores (missing or
corrupt metadata, a truncated chunk) and USID layouts (no Frequency row, a partial grid);
an output path that cannot be written.  File variants of every format: empty, truncated,
a few bytes, random bytes, bytes overwritten in the middle.  Every variant goes through every
command that reads files: ``map``, ``stiffness FILE``, ``inspect`` (and ``resonances``,
``spot`` when the command table has them).

Outcome of a (variant, command):

* ``pass``: an invalid input ends in one line ``pfmdyn COMMAND: error: ...`` (exit 2) that
  names the file (or the option) and nothing is written; a valid one ends in exit 0 (for maps
  with bad pixels: those pixels NaN with ``explained`` 0, the others fitted); where either is
  acceptable (a damaged byte the format cannot detect, an instrument file a command does not
  use), exit 0 or such a line;
* ``FAIL``: a traceback, a message over several lines or not naming the file, something
  written despite the error, masked pixels reported as fitted, or a run over 120 s.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np
import zarr

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
from fe_beam import FEBeam  # noqa: E402
from recording import recorded  # noqa: E402

from pfmdyn import cli  # noqa: E402

K, L, F1, H = 2.0, 225e-6, 75e3, 10e-6
META = {"spring_constant_n_per_m": K, "length_m": L, "tip_height_m": H, "free_resonance_hz": F1}
TIMEOUT_S = 120
OK, ERROR, ANY = "ok", "error", "any"
REALDATA = next((p for p in (Path(os.environ.get("PFMDYN_REALDATA", "/nonexistent")),
                             HERE.parents[1] / "shared" / "realdata", HERE.parents[2] / "shared" / "realdata")
                 if p.is_dir()), None)


def _spectra(n_freq=32, grid=(4, 4)):
    beam = FEBeam(K, L, F1, H, k1=200.0, Q=60.0, n_elements=40)
    f = beam.contact_resonances(1)[0] * np.linspace(0.85, 1.15, n_freq)
    y = np.broadcast_to(2e-3 * beam.slope(f)[:, 0], (*grid, n_freq)).copy()
    y += 2e-3 * np.abs(y).max() * np.random.default_rng(1).standard_normal(y.shape)
    return f, y


F, Y = _spectra()


def _h5(path, response=Y, frequency_hz=F, attrs=None, **datasets):
    with h5py.File(path, "w") as h:
        for name, value in {"response": response, "frequency_hz": frequency_hz, **datasets}.items():
            if value is not None:
                h[name] = value
        h.attrs.update({k: v for k, v in {**META, **(attrs or {})}.items() if v is not None})
    return path


def _zarr(path, response=Y, frequency_hz=F, attrs=None):
    group = zarr.open_group(str(path), mode="w")
    group["response"], group["frequency_hz"] = response, frequency_hz
    group.attrs.update({**META, **(attrs or {})})
    return path


def _usid(path, labels=("Frequency",), units=("Hz",), positions=None, values=None):
    """Band-excitation data as BGlib writes it (positions x spectral values, X fastest)."""
    ny, nx, nf = Y.shape
    with h5py.File(path, "w") as h:
        chan = h.create_group("Measurement_000").create_group("Channel_000")
        raw = chan.create_dataset("Raw_Data", data=Y.reshape(ny * nx, nf))
        yy, xx = np.divmod(np.arange(ny * nx), nx)
        pos = chan.create_dataset("Position_Indices", data=np.stack([xx, yy], 1)[:positions].astype(np.uint32))
        pos.attrs["labels"] = ["X", "Y"]
        spec = chan.create_dataset("Spectroscopic_Values", data=F[None, :] if values is None else values)
        spec.attrs["labels"], spec.attrs["units"] = list(labels), list(units)
        raw.attrs["Position_Indices"], raw.attrs["Spectroscopic_Values"] = pos.ref, spec.ref
        h.attrs.update(META)
    return path


def _contact(path, fc=None, attrs=None):
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((3, 4), 300e3) if fc is None else fc
        h.attrs.update({k: v for k, v in {"spring_constant_n_per_m": K, "free_resonance_hz": F1,
                                          **(attrs or {})}.items() if v is not None})
    return path


def _damage(source: Path, path: Path, how: str) -> Path:
    """A copy of ``source`` emptied, truncated, cut to 16 bytes, replaced by random bytes or
    with 64 bytes overwritten in the middle."""
    data = source.read_bytes()
    rng = np.random.default_rng(len(data))
    noise = rng.integers(0, 256, max(len(data), 64), dtype=np.uint8).tobytes()
    middle = len(data) // 2
    path.write_bytes({"empty": b"", "truncated": data[:middle], "16_bytes": data[:16], "random": noise[:len(data)],
                      "overwritten": data[:middle] + noise[:64] + data[middle + 64:]}[how])
    return path


def _ibw(path, note: dict):
    """An Asylum image written by igorwriter with a ``Key: value`` note, or None without it."""
    try:
        import igorwriter
    except ImportError:
        return None
    wave = igorwriter.IgorWave(np.zeros((8, 8, 2), np.float32), name="scan")
    values = {"SpringConstant": "2.7", "ThermalFrequency": "71324", "TuneFreqResult": "331250",
              "CustomLeverLength": "2.25e-4", "CustomLeverWidth": "4e-5", **note}
    wave.set_note("\r".join(f"{k}: {v}" for k, v in values.items()))
    wave.save(str(path))
    return path


def variants(tmp: Path):
    """(name, path, extra arguments, expected outcome per command) of every case."""
    map_only = {"map": ERROR, "stiffness": ANY, "inspect": ANY}
    cases = []

    def add(name, path, expect=None, extra=()):
        if path is not None:
            cases.append((name, Path(path), list(extra), {**map_only, **(expect or {})}))

    add("map/valid", _h5(tmp / "valid.h5"), {"map": OK})
    add("map/valid_zarr", _zarr(tmp / "valid.zarr"), {"map": OK})
    add("map/valid_usid", _usid(tmp / "usid.h5"), {"map": OK})
    add("map/valid_default_scheduler", tmp / "valid.h5", {"map": OK}, ["--scheduler", "processes"])
    n = F.size
    axes = {"empty_axis": (Y[..., :0], F[:0]), "one_frequency": (Y[..., :1], F[:1]), "two_frequencies": (Y[..., :2], F[:2]),
            "nan_frequency": (Y, np.where(np.arange(n) == 3, np.nan, F)), "negative_frequency": (Y, -F),
            "repeated_frequency": (Y, np.r_[F[:1], F[:-1]]), "2d_axis": (Y, F[None, :]),
            "text_axis": (Y, np.full(n, b"x")), "fewer_spectral_points": (Y[..., :-1], F),
            "flat_response": (Y.reshape(16, n), F), "4d_without_bias": (Y[:, :, None, :], F),
            "empty_grid": (Y[:0], F), "text_response": (np.full(Y.shape, b"x"), F),
            "missing_response": (None, F), "missing_frequency": (Y, None)}
    for name, (response, frequency) in axes.items():
        add(f"map/{name}", _h5(tmp / f"{name}.h5", response, frequency))
    with h5py.File(_h5(tmp / "response_group.h5", None), "a") as h:
        h.create_group("response")
    add("map/response_is_a_group", tmp / "response_group.h5")
    bad_meta = {"negative_spring_constant": ("spring_constant_n_per_m", -2.0),
                "zero_spring_constant": ("spring_constant_n_per_m", 0.0), "zero_length": ("length_m", 0.0),
                "nan_free_resonance": ("free_resonance_hz", np.nan), "inf_tip_height": ("tip_height_m", np.inf),
                "text_tip_height": ("tip_height_m", "10 um"), "array_spring_constant": ("spring_constant_n_per_m", [1.0, 2.0]),
                "missing_length": ("length_m", None), "tip_position_1.5": ("tip_position", 1.5),
                "negative_tip_mass": ("tip_mass_ratio", -1.0)}
    for name, (key, value) in bad_meta.items():
        add(f"map/{name}", _h5(tmp / f"{name}.h5", attrs={key: value}))
    for name, args in {"override_negative_k": ["--spring-constant", "-1"], "override_zero_length": ["--length", "0"],
                       "override_nan_f1": ["--free-resonance", "nan"], "override_tip_mass": ["--tip-mass", "-1"]}.items():
        add(f"map/{name}", tmp / "valid.h5", {"map": ERROR, "stiffness": None, "inspect": None}, args)
    for name, bias in {"one_bias": [1.0], "nan_bias": [0.0, np.nan, 1.0], "bias_length_mismatch": [0.0, 1.0, 2.0]}.items():
        response = np.broadcast_to(Y[:, :, None, :], (4, 4, 2, n)) if name == "bias_length_mismatch" else \
            np.broadcast_to(Y[:, :, None, :], (4, 4, len(bias), n))
        add(f"map/{name}", _h5(tmp / f"{name}.h5", response, F, bias_v=np.array(bias)))
    for name, pixels in {"few_nan_pixels": "nan", "inf_pixels": "inf", "zero_pixels": "zero"}.items():
        y = Y.copy()
        y[1, 2, 5:9] = y[3, 0] = {"nan": np.nan, "inf": np.inf, "zero": 0.0}[pixels]
        add(f"map/{name}", _h5(tmp / f"{name}.h5", y), {"map": OK})
        add(f"map/{name}_auto_model", tmp / f"{name}.h5", {"map": OK}, ["--model", "auto"])
    add("map/all_nan_pixels", _h5(tmp / "all_nan.h5", np.full(Y.shape, np.nan + 0j)), {"map": ANY})
    add("map/all_nan_pixels_auto_model", tmp / "all_nan.h5", {"map": ERROR}, ["--model", "auto"])
    # damaged Zarr stores
    for name in ("zarr_missing_array_metadata", "zarr_corrupt_array_metadata", "zarr_corrupt_group_attrs",
                 "zarr_truncated_chunk", "zarr_missing_chunk"):
        store = _zarr(tmp / f"{name}.zarr")
        response = store / "response"
        # Zarr 2 keeps metadata in .zarray/.zattrs beside flat chunks, Zarr 3 in zarr.json with chunks under c/
        metadata = ("zarr.json", ".zarray", ".zattrs", ".zgroup")
        chunk = next(p for p in sorted(response.rglob("*")) if p.is_file() and p.name not in metadata)
        array_meta = next(response / m for m in (".zarray", "zarr.json") if (response / m).exists())
        if name == "zarr_missing_array_metadata":
            array_meta.unlink()
        elif name == "zarr_corrupt_array_metadata":
            array_meta.write_text("{not json")
        elif name == "zarr_corrupt_group_attrs":
            next(store / m for m in (".zattrs", "zarr.json") if (store / m).exists()).write_text("{not json")
        elif name == "zarr_truncated_chunk":
            chunk.write_bytes(chunk.read_bytes()[:20])
        else:
            chunk.unlink()      # reads as the fill value: all-zero pixels, masked
        add(f"map/{name}", store, {"map": OK if name == "zarr_missing_chunk" else ERROR})
    add("map/usid_no_frequency_row", _usid(tmp / "usid_nofreq.h5", labels=("Time",), units=("s",)))
    add("map/usid_frequency_in_volts", _usid(tmp / "usid_volts.h5", units=("V",)))
    add("map/usid_partial_grid", _usid(tmp / "usid_partial.h5", positions=10))
    add("map/usid_text_values", _usid(tmp / "usid_text.h5", values=np.full((1, n), b"x")))
    for how in ("empty", "truncated", "16_bytes", "random", "overwritten"):
        add(f"map/hdf5_{how}", _damage(tmp / "valid.h5", tmp / f"damaged_{how}.h5", how),
            {"map": ANY if how == "overwritten" else ERROR})
    add("map/out_is_a_file", tmp / "valid.h5", {"map": ERROR, "stiffness": None, "inspect": None},
        ["--out-override", str(tmp / "valid.h5")])
    for name, (entry, text) in {"out_maps_zarr_is_a_file": ("", "x"), "out_corrupt_zgroup": (".zgroup", "{bad"),
                                "out_corrupt_zattrs": (".zattrs", "{bad")}.items():
        store = tmp / name / "maps.zarr"
        if entry:
            store.mkdir(parents=True)
            (store / ".zgroup").write_text('{"zarr_format": 2}')
        else:
            store.parent.mkdir()
        (store / entry if entry else store).write_text(text)
        for model in ("elastic", "auto"):
            add(f"map/{name}_{model}", tmp / "valid.h5", {"map": ERROR, "stiffness": None, "inspect": None},
                ["--out-override", str(tmp / name), "--model", model])
        # a contact map is written anew each time: a damaged store in the way is replaced
        wanted = ERROR if name == "out_maps_zarr_is_a_file" else OK
        add(f"contact/{name}", tmp / "cr.h5", {"map": wanted, "stiffness": wanted, "inspect": None},
            ["--out-override", str(tmp / name)])
    # contact-frequency maps (map and stiffness FILE take them)
    contact = {"stiffness": ERROR, "inspect": ANY, "map": ERROR}
    fc_nan = np.full((3, 4), 300e3)
    fc_nan[1, 1], fc_nan[2, 3] = np.nan, -5.0
    add("contact/valid", _contact(tmp / "cr.h5"), {"map": OK, "stiffness": OK})
    add("contact/nan_pixels", _contact(tmp / "cr_nan.h5", fc_nan), {"map": OK, "stiffness": OK})
    for name, (fc, attrs) in {"negative_spring_constant": (None, {"spring_constant_n_per_m": -2.0}),
                              "zero_free_resonance": (None, {"free_resonance_hz": 0.0}),
                              "text_spring_constant": (None, {"spring_constant_n_per_m": "2 N/m"}),
                              "missing_free_resonance": (None, {"free_resonance_hz": None}),
                              "mode_2.5": (None, {"contact_mode": 2.5}), "mode_0": (None, {"contact_mode": 0}),
                              "negative_uncertainty": (None, {"contact_uncertainty_hz": -1.0}),
                              "1d_map": (np.full(4, 3e5), None), "empty_map": (np.zeros((0, 4)), None),
                              "text_map": (np.full((2, 2), b"x"), None)}.items():
        add(f"contact/{name}", _contact(tmp / f"cr_{name}.h5", fc, attrs), contact)
    # instrument files: each command reads them (map refuses them in one line)
    instruments = {"stiffness": ANY, "inspect": ANY, "map": ERROR}
    sources = {}
    for name, note in {"valid": {}, "negative_spring_constant": {"SpringConstant": "-2"},
                       "zero_length": {"CustomLeverLength": "0"}, "nan_free_resonance": {"ThermalFrequency": "NaN"},
                       "text_spring_constant": {"SpringConstant": "two"}}.items():
        path = _ibw(tmp / f"asylum_{name}.ibw", note)
        add(f"ibw/{name}", path, instruments)
        sources.setdefault("written.ibw", path)
    if REALDATA is not None:
        for path in sorted(REALDATA.rglob("*")):
            if path.suffix.lower() in (".ibw", ".h5", ".nid", ".txt", ".dat") and path.stat().st_size < 50e6:
                sources.setdefault(path.suffix.lower(), path)
    for source in sources.values():
        if source is None:
            continue
        text = source.suffix.lower() in (".txt", ".dat")
        for how in ("empty", "truncated", "16_bytes", "random", "overwritten"):
            add(f"instrument/{source.name}/{how}", _damage(source, tmp / f"{how}_{source.name}", how),
                # a cut text sweep is a shorter sweep; overwritten bytes may sit where nothing checks them
                {**instruments, "inspect": ANY if how == "overwritten" or (how == "truncated" and text) else ERROR})
    return cases


def _commands():
    """Commands that read a file, as far as the command table has them."""
    extra = [name for name in ("resonances", "spot") if name in cli.COMMANDS]
    return ["map", "stiffness", "inspect", *extra]


def _argv(command, path: Path, extra: list, out: Path) -> list[str]:
    """The command line of ``command`` on ``path``; ``extra`` may start with ``--out-override DIR``
    (an output path that is itself the fault)."""
    target, rest = (extra[1], extra[2:]) if extra[:1] == ["--out-override"] else (str(out), extra)
    if command == "map":
        base = ["map", str(path), "--out", target, "--no-progress"]
        if "--model" not in rest:
            base += ["--model", "elastic"]
        if "--scheduler" not in rest:
            base += ["--scheduler", "sync"]
        return base + rest
    if command == "stiffness":     # --out: a contact-frequency map's k1 map (refused for other files)
        contact = path.suffix == ".h5" and path.name.startswith("cr")
        return ["stiffness", str(path), "--json", str(out.with_suffix(".json"))] + (["--out", target] if contact else [])
    if command == "inspect":
        return [command, str(path), "--json", str(out.with_suffix(".json"))]
    return [command, str(path)]


class _Timeout(Exception):
    pass


def _run(argv):
    """Exit status, stdout, stderr and the exception that escaped (a traceback), if any."""
    out, err = io.StringIO(), io.StringIO()
    signal.signal(signal.SIGALRM, lambda *_: (_ for _ in ()).throw(_Timeout()))
    signal.alarm(TIMEOUT_S)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = cli.main(argv)
        escaped = None
    except SystemExit as exc:           # argparse refusing the arguments: its usage lines are counted
        status, escaped = exc.code, None
    except BaseException as exc:        # noqa: BLE001  (a traceback is what is measured)
        status, escaped = None, exc
    finally:
        signal.alarm(0)
    return status, out.getvalue(), err.getvalue(), escaped


def _masked_ok(path: Path, out: Path) -> str | None:
    """For a map of spectra that ran: masked pixels NaN and not explained, every other pixel fitted."""
    group = zarr.open_group(str(out / "maps.zarr"), mode="r")
    if "explained" not in group:        # a contact-frequency map's k1: no spectra fitted
        return None
    k1, explained = np.asarray(group["k1"][...]), np.asarray(group["explained"][...])
    with contextlib.ExitStack() as stack:
        root = zarr.open_group(str(path), mode="r") if path.is_dir() else stack.enter_context(h5py.File(path, "r"))
        data = root["response"] if "response" in root else root["Measurement_000/Channel_000/Raw_Data"]
        y = np.asarray(data[...]).reshape(k1.size, -1)     # USID: positions x spectra, X fastest
    masked = (~np.all(np.isfinite(y), axis=1) | np.all(y == 0, axis=1)).reshape(k1.shape)
    if not (np.all(np.isnan(k1[masked])) and np.all(explained[masked] == 0)):
        return "masked pixels reported as fitted"
    if not np.all(np.isfinite(k1[~masked])):
        return "a fittable pixel left unfitted"
    return None


def judge(command, expect, path, argv, out: Path) -> tuple[str, str]:
    """Outcome (pass/FAIL) and a short detail of one command on one variant."""
    json_path = out.with_suffix(".json")
    start = time.perf_counter()
    status, stdout, stderr, escaped = _run(argv)
    elapsed = time.perf_counter() - start
    if isinstance(escaped, _Timeout):
        return "FAIL", f"over {TIMEOUT_S} s"
    if escaped is not None:
        return "FAIL", f"traceback: {type(escaped).__name__}: {' '.join(str(escaped).split())[:160]}"
    lines = stderr.strip().splitlines()
    if status == 2:
        message = lines[-1] if lines else ""
        written = [str(p) for p in (out, json_path) if p.exists()]
        if len(lines) != 1 or not message.startswith(f"pfmdyn {command}: error: "):
            return "FAIL", f"error over {len(lines)} lines: {' | '.join(lines)[:200]}"
        names_input = path.name in message or "--" in message or "cannot write" in message
        if not names_input:
            return "FAIL", f"error does not name the file: {message[:200]}"
        if written:
            return "FAIL", f"written despite the error: {written}; {message[:120]}"
        if expect == OK:
            return "FAIL", f"valid input refused: {message[:200]}"
        return "pass", message[len(f"pfmdyn {command}: error: "):][:200]
    if status != 0:
        return "FAIL", f"exit status {status}: {stderr.strip()[-200:]}"
    if expect == ERROR:
        return "FAIL", f"invalid input accepted ({elapsed:.1f} s): {stdout.strip().splitlines()[-1:]}"
    if command == "map" and (out / "maps.zarr").exists():
        problem = _masked_ok(path, out)
        if problem:
            return "FAIL", problem
    return "pass", (stdout.strip().splitlines() or [""])[-1][:200]


def sweep(record, doc: str, judged) -> int:
    """A sweep's command line: ``judged(tmp, report)`` runs every case in a scratch folder ``tmp``,
    reporting each (its outcome and the rest of its row), and returns what the sweep covered; the
    output goes to ``record`` (the script's :func:`recording.recorded`).  Exit status 0 when every
    case passed."""
    argparse.ArgumentParser(description=doc.splitlines()[0]).parse_args()
    rows = []

    def report(outcome: str, row: str) -> None:
        rows.append(outcome)
        print(f"{outcome:<5} {row}", flush=True)

    with record, tempfile.TemporaryDirectory() as tmp:
        covered = judged(Path(tmp), report)
        passed = rows.count("pass")
        print(f"\n{passed}/{len(rows)} pass ({covered})")
    return 0 if passed == len(rows) else 1


def _judged(tmp: Path, report) -> str:
    """Every variant through every command that reads it."""
    cases = variants(tmp)
    for name, path, extra, expect in cases:
        for command in _commands():
            wanted = expect.get(command, ANY)
            if wanted is None:          # a command-line option of another command
                continue
            out = tmp / "out" / f"{name.replace('/', '_').replace('.', '_')}_{command}"
            outcome, detail = judge(command, wanted, path, _argv(command, path, extra, out), out)
            report(outcome, f"{name:<44} {command:<10} {detail.replace(str(tmp), 'TMP')[:110]}")
    return (f"{len(cases)} variants x commands {', '.join(_commands())}; "
            f"real files {'included' if REALDATA is not None else 'absent'}")


if __name__ == "__main__":
    sys.exit(sweep(recorded("malformed_inputs"), __doc__, _judged))
