"""Every command on bad and edge-case command-line input (issue 23, item 2).

A bad value, a missing or conflicting option, a malformed file or an output path that cannot
be written ends in exit status 2 and one line ``pfmdyn COMMAND: error: ...`` naming the option
or the file, with nothing written; a valid but extreme input succeeds and states what it
cannot determine.  The wide sweep is ``benchmarks/cli_inputs.py``; here the failures it found
(now fixed) and a representative set of the rest, each run in-process.
"""
from __future__ import annotations

import argparse
import cmath
import json
import math
import re
from pathlib import Path

import pytest

from pfmdyn import cli
from pfmdyn.analysis.resonances import resonances
from pfmdyn.cantilever import Cantilever
from pfmdyn.names import NAMES

LEVER = ["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4"]
PROBE = LEVER + ["--tip-height", "1e-5", "--k1", "100"]
CSV = "frequency_hz,bias_v,x,y\n" + "".join(f"{f},{v},{1 + 0.1 * v},{0.1 * v}\n"
                                          for f in (1e5, 2e5, 3e5) for v in (-1, 0, 1))


def _run(argv) -> int:
    """Exit status of the command in-process (argparse's refusals raise SystemExit)."""
    try:
        return cli.main(argv)
    except SystemExit as exc:
        return exc.code


def _argv(tmp: Path, command: str) -> dict:
    """Base command lines (their outputs all under ``tmp``) and the outputs they may write."""
    data = tmp / "data.csv"
    data.write_text(CSV)
    json_out, png = str(tmp / "out.json"), str(tmp / "out.png")
    return {
        "resonances": ["resonances", *LEVER, "--json", json_out],
        "spot": ["spot", *PROBE, "--drive-frequency", "1e5", "--json", json_out, "--plot", png],
        "stiffness": ["stiffness", "--spring-constant", "2", "--free-resonance", "7e4", "--contact", "3e5",
                      "--json", json_out],
        "diagram": ["diagram", "--plot", png, "--frequency-points", "20", "--bias-points", "5", "--json", json_out],
        "deconvolve": ["deconvolve", str(data), "--surface-potential", "0", "--out", str(tmp / "dec"), "--json", json_out],
        "roots": ["roots", "free", "--modes", "2", "--json", json_out],
        "branches": ["branches", "indentation", "--plot", png, "--points", "20", "--modes", "1", "--json", json_out],
        "inspect": ["inspect", str(data), "--json", json_out],
        "discrepancy": ["discrepancy", str(data), "--json", json_out],
        "calibrate": ["calibrate", str(tmp / "tune.csv"), "--json", json_out],   # the flags are checked first
        "map": ["map", str(tmp / "map.h5"), "--out", str(tmp / "sub")],
    }[command]


def _outputs(tmp: Path) -> list[Path]:
    return [p for p in (tmp / "out.json", tmp / "out.png", tmp / "dec", tmp / "out.csv", tmp / "sub") if p.exists()]


def _override(argv: list, extra: list) -> list:
    """``argv`` with each flag of ``extra`` replacing its earlier value (or appended)."""
    argv = list(argv)
    i = 0
    while i < len(extra):
        flag = extra[i]
        value = extra[i + 1] if i + 1 < len(extra) and not extra[i + 1].startswith("--") else None
        if flag in argv and value is not None:
            argv[argv.index(flag) + 1] = value
        else:
            argv += [flag] + ([value] if value is not None else [])
        i += 2 if value is not None else 1
    return argv


REFUSED = [
    # (command, extra arguments, words the one line must hold)
    ("resonances", ["--k1", "nan"], "--k1"),
    ("resonances", ["--k1", "abc"], "--k1"),
    ("resonances", ["--tip-position", "1.5"], "--tip-position"),
    ("resonances", ["--tip-position", "0"], "--tip-position"),
    ("resonances", ["--spot-position", "0"], "--spot-position"),
    ("resonances", ["--tilt", "91"], "--tilt"),
    ("resonances", ["--poisson", "0.7", "--k1", "100"], "--poisson"),
    ("resonances", ["--poisson", "-1", "--k1", "100"], "--poisson"),
    ("resonances", ["--k1", "100", "--k2", "5", "--k2-over-k1", "0.5"], "not several"),
    ("resonances", ["--modes", "0"], "--modes"),
    ("resonances", ["--modes", "51"], "--modes"),
    ("resonances", ["--length", "-2e-4"], "--length"),
    ("resonances", ["--quality-factor", "inf"], "--quality-factor"),
    ("resonances", ["--k2", "5"], "--k1"),
    ("resonances", ["--json", "{tmp}"], "cannot write"),                       # a directory
    ("resonances", ["--json", "{tmp}/data.csv/out.json"], "cannot write"),     # a file among its parents
    ("spot", ["--drive-frequency", "0"], "--drive-frequency"),
    ("spot", ["--frequency", "x"], "--drive-frequency"),                            # argparse: one line too
    ("spot", ["--drive-frequency", "1e9"], "beyond what the beam model"),          # was a 40 s run
    ("spot", ["--k1", "0"], "needs a contact"),                                 # was inf and NaN numbers
    ("spot", ["--spot-position", "1.5"], "--spot-position"),
    ("spot", ["--plot", "{tmp}/out.xyz"], "cannot write"),                      # was a ValueError traceback
    ("spot", ["--plot", "{tmp}/data.csv/out.png"], "cannot write"),            # was written: the JSON
    ("spot", ["--plot", "-"], "cannot write -"),                                 # '-' is for documents; was '-.png'
    ("stiffness", ["--contact", "0"], "--contact"),
    ("stiffness", ["--contact", "nan"], "--contact"),
    ("stiffness", ["--mode", "0"], "--mode"),
    ("stiffness", ["--tip-position", "1.5"], "--tip-position"),
    ("stiffness", ["--k2", "5", "--poisson", "0.3"], "not several"),
    ("stiffness", ["--contact", "6e4"], "free limit"),
    ("stiffness", ["--json", "{tmp}"], "cannot write"),
    ("diagram", ["--spot-position", "0"], "--spot-position"),
    ("diagram", ["--spot-position", "1.01"], "--spot-position"),
    ("diagram", ["--d-eff", "nan"], "--d-eff"),
    ("diagram", ["--k1", "0"], "--k1"),
    ("stiffness", ["--tip-radius", "-1"], "--tip-radius"),               # was accepted, unused
    ("stiffness", ["--mode", "1e30"], "--mode"),                         # was a ValueError traceback
    ("spot", ["--drive-frequency", "nan"], "--drive-frequency"),
    ("diagram", ["--fmin", "0"], "--fmin"),
    ("diagram", ["--frequency-points", "100000000"], "--frequency-points"),   # was a MemoryError or a swap
    ("diagram", ["--plot", "{tmp}/dir.png"], "cannot write"),                   # was an IsADirectoryError
    ("diagram", ["--csv", "{tmp}/data.csv/out.csv"], "cannot write"),
    ("deconvolve", ["--out", "{tmp}/data.csv/sub"], "not a directory"),        # was a NotADirectoryError
    ("deconvolve", ["--surface-potential", "nan"], "--surface-potential"),
    ("deconvolve", [*PROBE, "--spot-position", "0"], "--spot-position"),
    ("deconvolve", ["--spring-constant", "2"], "--free-resonance"),
    ("roots", ["--digits", "5000"], "--digits"),                                 # was a ValueError traceback
    ("roots", ["--modes", "0"], "--modes"),
    ("roots", ["--modes", "100000"], "--modes"),                                         # was a run of hours
    ("branches", ["--points", "1"], "--points"),
    ("branches", ["--modes", "51"], "--modes"),
    ("branches", ["--plot", "{tmp}/out.xyz"], "cannot write"),
    ("inspect", ["--json", "{tmp}"], "cannot write"),
    ("resonances", ["--temperature", "abc"], "--temperature"),                  # was ignored in vacuum
    ("stiffness", ["--temperature", "0"], "--temperature"),
    ("diagram", ["--medium="], "--medium"),                                    # was vacuum, silently
    ("discrepancy", ["--added-mass-position", "0.5"], "--added-mass-position"),  # was ignored for a spectrum
    ("discrepancy", ["--added-mass-position", "nan"], "--added-mass-position"),
    # a temperature where the medium is not that phase; Celsius-looking values named so (was 25 K, accepted)
    ("resonances", ["--medium", "air", "--width", "4e-5", "--temperature", "25"], "did you mean 298.15 K (25 C)?"),
    ("spot", ["--temperature", "60"], "--temperature: air is a gas"),                # air: the default medium
    ("diagram", ["--medium", "water", "--temperature", "0"], "did you mean 273.15 K (0 C)?"),
    ("diagram", ["--medium", "water", "--temperature", "400"], "--temperature: water is liquid"),
    ("stiffness", ["--temperature", "120"], "did you mean 393.15 K"),
    # an output over an input or another output (the data were overwritten by the report, one output by the other)
    ("deconvolve", ["--json", "{tmp}/data.csv"], "--json would overwrite INPUT"),
    ("inspect", ["--json", "{tmp}/data.csv"], "--json would overwrite INPUT"),
    ("spot", ["--json", "{tmp}/out.png"], "--json and --plot name the same file"),
    ("diagram", ["--csv", "{tmp}/out.png"], "--plot and --csv name the same file"),
    ("branches", ["--json", "{tmp}/./out.png"], "--json and --plot name the same file"),
]


@pytest.mark.parametrize("command, extra, words", REFUSED, ids=[f"{c}{' '.join(e)}" for c, e, _ in REFUSED])
def test_bad_input_is_one_line_and_writes_nothing(command, extra, words, tmp_path, capsys):
    (tmp_path / "dir.png").mkdir()
    extra = [e.replace("{tmp}", str(tmp_path)) for e in extra]
    code = _run(_override(_argv(tmp_path, command), extra))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and err[0].startswith(f"pfmdyn {command}: error: "), err
    assert words in err[0], err
    assert _outputs(tmp_path) == []


@pytest.mark.parametrize("command, missing", [("resonances", "--length"), ("spot", "--drive-frequency"),
                                              ("deconvolve", "--out"), ("branches", "--plot")])
def test_missing_required_option_is_one_line(command, missing, tmp_path, capsys):
    argv = _argv(tmp_path, command)
    i = argv.index(missing)
    assert _run(argv[:i] + argv[i + 2:]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"pfmdyn {command}: error: ") and missing in err[0], err


@pytest.mark.parametrize("argv, flags_named", [
    (["spot", "--k1", "100", "--drive-frequency", "1e5", "--spring-constant", "2"],     # the tip height: assumed
     ["--free-resonance", "--length"]),
    (["stiffness", "--contact", "3e5"], ["--free-resonance", "--spring-constant"]),
    (["roots", "elastic"], ["--k1-over-k", "--k2-ratio"]),
])
def test_every_missing_lever_flag_is_named_in_one_run(argv, flags_named, capsys):
    """A user gives what is missing in one run, not one flag per run."""
    assert _run(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(flag in err[0] for flag in flags_named), err


def test_every_lever_field_missing_from_an_instrument_file_is_named():
    from pfmdyn.commands.flags import option_hint
    from pfmdyn.io.instruments import resonance_table
    from pfmdyn.io.record import MissingFieldError, make_record
    record = make_record("scan.h5", "image", "test", (), {"free_resonance": 6e4, "spring_constant": 1.0})
    with pytest.raises(MissingFieldError, match="^lever length and tip height not in scan.h5$") as caught:
        resonance_table(record)
    assert option_hint(caught.value) == ": give --length and --tip-height"


@pytest.mark.parametrize("name, text, words", [
    ("empty", "", "empty"),
    ("one_bias", "frequency_hz,bias_v,x,y\n100000,0,1,0\n200000,0,1,0\n", "one bias"),
    ("nan", CSV.replace("1.1,", "nan,", 1), "'x'"),
    ("text", CSV.replace("1.1,", "abc,", 1), "'x'"),
    ("clashing_duplicate", CSV + "100000,1,9,9\n", "duplicate"),
])
def test_deconvolve_malformed_csv(name, text, words, tmp_path, capsys):
    data = tmp_path / f"{name}.csv"
    data.write_text(text)
    out = tmp_path / "dec"
    assert _run(["deconvolve", str(data), "--surface-potential", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and data.name in err[0] and words in err[0], err
    assert not out.exists()


def test_valid_extremes_succeed(tmp_path, capsys):
    """Spot exactly at the free end, k1/k = 1e4 and a lever at the ends of the real ranges."""
    out = tmp_path / "r.json"
    assert _run(["spot", *PROBE, "--drive-frequency", "1e5", "--spot-position", "1", "--k1", "2e4"]) == 0
    assert _run(["resonances", "--spring-constant", "0.05", "--free-resonance", "1.3e4", "--length", "5e-4",
                 "--k1", "500", "--tip-height", "1e-5", "--tilt", "15", "--poisson", "0.3", "--json", str(out)]) == 0
    modes = json.loads(out.read_text())["results"]
    assert all(f is not None and f > 0 for f in modes["free"]["resonance"]["value"] + modes["contact"]["resonance"]["value"])
    capsys.readouterr()


def _numbers(document) -> list:
    if isinstance(document, dict):
        return [x for value in document.values() for x in _numbers(value)]
    if isinstance(document, list):
        return [x for value in document for x in _numbers(value)]
    return [document]


@pytest.mark.parametrize("k, length, f1", [(0.05, 5e-4, 1.3e4), (0.05, 1e-4, 3e5), (50.0, 5e-4, 4e4),
                                           (50.0, 1e-4, 1e6)])
@pytest.mark.parametrize("k1_over_k", [1.0, 1e4])
def test_resonances_json_over_real_ranges(k, length, f1, k1_over_k, tmp_path, capsys):
    """No null in the report where a number is promised (the lever is undamped, Q lossless aside)."""
    out = tmp_path / "r.json"
    assert _run(["resonances", "--spring-constant", str(k), "--free-resonance", str(f1), "--length", str(length),
                 "--k1", str(k * k1_over_k), "--tip-height", "1e-5", "--k2-over-k1", "0.8", "--tilt", "12",
                 "--tip-position", "0.9", "--json", str(out)]) == 0
    modes = json.loads(out.read_text())["results"]
    for condition in ("free", "contact"):
        for key in ("resonance", "complete_below"):
            assert None not in _numbers(modes[condition][key]["value"]), (condition, key)
    # contact modes lie above the free ones of the same order (k1 only stiffens)
    assert all(c > f for c, f in zip(modes["contact"]["resonance"]["value"], modes["free"]["resonance"]["value"]))
    capsys.readouterr()


@pytest.mark.parametrize("quality_factor", [0.3, 1.0, 5.0])
def test_heavy_internal_friction_keeps_each_mode(quality_factor):
    """E (1 + i/Q) makes omega**2 complex by the same factor: r_c = r_n sqrt(1 + i/Q) for each free
    mode.  Before, at Q <= 1 the secant run from the undamped root landed on the next mode's root
    (mode 2 reported mode 1's Q and frequency) or failed."""
    lever = Cantilever(2.0, 7e4, 2e-4, quality_factor=quality_factor)
    result = resonances(lever, None, modes=3)
    for hz, damped_hz, q in zip(result.free.hz, result.free.damped_hz, result.free.q):
        exact = (hz / 7e4) * cmath.sqrt(1 + 1j / quality_factor)
        assert damped_hz == pytest.approx(7e4 * exact.real, rel=1e-8)
        assert q == pytest.approx(abs(exact) / (2 * exact.imag), rel=1e-8)


@pytest.mark.parametrize("g", [0.5, 1.0, 3.0, 10.0])
def test_viscous_drag_overdamped_modes_are_undetermined(g, tmp_path, capsys):
    """Drag on a free lever: r (r - i g) = r_n**2, so r_c = (i g + sqrt(4 r_n**2 - g**2)) / 2 while
    g < 2 r_n, and the mode is overdamped (no resonance) beyond.  Before, g = 1 ended in a traceback."""
    out = tmp_path / "r.json"
    assert _run(["resonances", *LEVER, "--viscous-loss", str(g), "--json", str(out)]) == 0
    document = json.loads(out.read_text())
    free = {key: record["value"] for key, record in document["results"]["free"].items()}
    for n, (hz, damped_hz, q) in enumerate(zip(free["resonance"], free["damped_resonance"],
                                               free["predicted_quality_factor"]), 1):
        why = " ".join(note for note in document["notes"] if note.startswith(f"free mode {n}: "))
        rn = hz / 7e4
        if g < 1.9 * rn:
            exact = (1j * g + cmath.sqrt(4 * rn ** 2 - g ** 2)) / 2
            assert damped_hz == pytest.approx(7e4 * exact.real, rel=1e-8)
            assert q == pytest.approx(abs(exact) / (2 * exact.imag), rel=1e-8)
        elif g >= 2 * rn:
            assert damped_hz is None and q is None and "overdamped" in why
    assert not re.search(r"\bnan\b", capsys.readouterr().out, re.IGNORECASE)


def test_argparse_refusal_is_one_line_in_every_command(capsys):
    for command in cli.COMMANDS:
        assert _run([command, "--no-such-option"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"pfmdyn {command}: error: "), (command, err)


def test_error_is_not_a_catch_all(monkeypatch):
    """A programming error still surfaces as an exception (only UserError becomes one line)."""
    from pfmdyn.analysis import resonances as analysis

    monkeypatch.setattr(analysis, "resonances", lambda *a, **k: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        cli.main(["resonances", *LEVER])


def test_no_nan_printed_for_spot_at_free_end_in_stiff_contact(capsys):
    assert _run(["spot", *LEVER, "--tip-height", "1e-5", "--k1", "2e4", "--drive-frequency", "2e5"]) == 0
    assert not re.search(r"\bnan\b", capsys.readouterr().out, re.IGNORECASE)


def test_auxetic_sample_is_a_valid_poisson_ratio():
    """-1 < nu <= 1/2 for an isotropic solid; Mindlin's k2/k1 = 2 (1 - nu) / (2 - nu) = 1.2 at nu = -1/2."""
    import argparse

    from pfmdyn.commands import flags

    contact = flags.contact(argparse.Namespace(k1="100", poisson="-0.5"))
    assert contact.k2_of(100.0) == pytest.approx(120.0, rel=1e-12)


def test_a_mode_without_an_amplitude_peak_says_so():
    """Contact mode 3 of a stiff, tilted, damped lever (Q 5) is a shoulder on mode 4's flank: no local
    maximum of |slope| within its width (dense evaluation), so no peak frequency, with the reason;
    its Q and damped frequency stand.  Before, the window's largest value (its edge) was reported."""
    import numpy as np

    from pfmdyn.cantilever import Contact

    lever = Cantilever(50.0, 4e4, 5e-4, tip_height=1e-5, tilt=12.0, tip_position=0.9, quality_factor=5.0)
    contact = Contact(k1=5e5, k2_over_k1=0.8)
    modes = resonances(lever, contact, modes=3).in_contact
    centre, q = modes.damped_hz[2], modes.q[2]
    f = np.linspace(centre * (1 - 1 / q), centre * (1 + 1 / q), 2001)
    a = np.abs(lever.response(f, contact).vertical)
    assert not np.any((a[1:-1] > a[:-2]) & (a[1:-1] > a[2:]))
    assert math.isnan(modes.peak_hz[2]) and "no amplitude peak" in modes.undetermined[2]
    assert math.isfinite(q) and 4 < q < 8
    assert all(math.isfinite(p) for p in modes.peak_hz[:2])


def _takes_a_value(action) -> bool:
    return bool(action.option_strings) and action.nargs is None and action.help != argparse.SUPPRESS


def _required(parser) -> list[str]:
    """Placeholder values for a parser's required arguments (positionals and required options)."""
    argv = []
    for action in parser._actions:
        if not action.option_strings and action.nargs in (None, "?") and action.dest != "help":
            argv.append("x" if action.choices is None else str(next(iter(action.choices))))
        elif action.required:
            argv += [action.option_strings[0], "1"]
    return argv


@pytest.mark.parametrize("value", ["-225e-6", "-0.5", "-.5", "-3", "-inf", "-1E+3"])
def test_a_negative_value_is_a_value_of_every_flag(value, capsys):
    """argparse takes ``-225e-6`` or ``-inf`` for an option (its rule knows only ``-3`` and ``-0.5``)
    and refused ``--length -225e-6`` with "expected one argument"; every flag that takes a value, in
    every command the parser holds, now receives it (a flag of a count or a choice may refuse it)."""
    for command, parser in cli.parser(None)[1].items():
        for action in filter(_takes_a_value, parser._actions):
            flag = action.option_strings[-1]
            try:
                args = parser.parse_args([*_required(parser), flag, value])
            except SystemExit:
                err = capsys.readouterr().err
                assert "expected one argument" not in err and (action.type or action.choices), (command, flag, err)
                continue
            got = getattr(args, action.dest)
            assert got == [value] or str(got) == value or float(got) == float(value), (command, flag, got)


def test_negative_values_reach_the_range_check(tmp_path, capsys):
    """Every flag of a quantity that cannot be negative, in every command with a base command line
    above: a one-line error naming the flag and the range (before: "expected one argument")."""
    checked = 0
    for command in ("resonances", "spot", "stiffness", "diagram", "deconvolve", "discrepancy", "calibrate", "map"):
        base = _argv(tmp_path, command)
        for action in filter(_takes_a_value, cli.parser(command)[1][command]._actions):
            quantity = NAMES.get(action.dest)
            if quantity is None or quantity.low < 0 or action.dest == "medium":
                continue
            flag = action.option_strings[-1]
            assert _run(_override(base, [flag, "-225e-6"])) == 2, (command, flag)
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and flag in err[0] and re.search(r"got -(225e-6|0\.000225)\b", err[0]), \
                (command, flag, err)
            checked += 1
    assert checked > 50


@pytest.mark.parametrize("extra, words", [
    (["--temperature", "300"], "medium: air at 26.85 C; temperature 300 K (given)"),
    ([], "medium: air at 20 C; temperature 293.15 K (assumed: give --temperature)"),
])
def test_the_temperature_used_is_printed(extra, words, capsys):
    """Before, resonances printed "air at -248.15 C" for --temperature 25 and never the kelvin."""
    assert _run(["resonances", *LEVER, "--width", "4e-5", "--medium", "air", *extra]) == 0
    assert capsys.readouterr().out.splitlines()[0] == words


def test_a_resonance_table_without_metadata_takes_the_flags_and_its_free_row(tmp_path, capsys):
    """stiffness refused a table whose lever came in flags ('missing metadata key(s) spring_constant, length, ...'),
    and both commands asked for the free resonance the table's free mode 1 row holds."""
    table = tmp_path / "table.csv"
    table.write_text("mode,condition,frequency_hz,quality_factor\n1,contact,368990,213.46\n1,free,72969,138.63\n")
    lever = ["--spring-constant", "0.46538", "--length", "240e-6", "--tip-height", "13e-6"]
    assert _run(["stiffness", str(table), *lever, "--json", str(tmp_path / "file.json")]) == 0
    assert _run(["stiffness", "--free-resonance", "72969", "--contact", "368990", *lever,
                 "--json", str(tmp_path / "flags.json")]) == 0
    k1 = [json.loads((tmp_path / f"{name}.json").read_text())["results"]["k1"] for name in ("file", "flags")]
    assert k1[0]["value"] == pytest.approx(k1[1]["value"], rel=1e-12) and k1[0]["stderr"] > 0
    assert _run(["discrepancy", str(table), *lever, "--json", str(tmp_path / "d.json")]) == 0
    assert json.loads((tmp_path / "d.json").read_text())["lever"]["free_resonance"]["value"] == 72969.0
    capsys.readouterr()
    table.write_text("mode,condition,frequency_hz\n1,contact,368990\n")
    assert _run(["discrepancy", str(table), *lever]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "table.csv" in err[0] and "--free-resonance" in err[0], err


def test_spot_takes_the_drive_frequency_its_file_records(tmp_path, capsys, monkeypatch):
    """spot FILE required --frequency though the image's note records the drive (DriveFrequency); its 'from the
    file' line named the drive alone, not the lever it read there."""
    import numpy as np
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    from igor_files import asylum_note, igor_wave

    image = igor_wave(tmp_path / "scan.ibw", np.ones((8, 8, 2), "f4"), "scan", [(0.0, 1e-8, "m")] * 2, "m",
                      {2: ["HeightRetrace", "AmplitudeRetrace"]},
                      asylum_note({"SpringConstant": 2.0, "ThermalFrequency": 7e4, "CustomLeverLength": 2e-4,
                                   "DriveFrequency": 3.1e5}))
    out = tmp_path / "spot.json"
    assert _run(["spot", str(image), "--k1", "100", "--json", str(out)]) == 0
    frequency = json.loads(out.read_text())["results"]["drive_frequency"]
    assert frequency["value"] == 3.1e5 and frequency["status"] == "file"
    assert ("from the file: drive_frequency 310000 Hz, free_resonance 70000 Hz, length 0.0002 m, spring_constant 2 N/m"
            in capsys.readouterr().out.splitlines())
    assert _run(["spot", str(image), "--k1", "100", "--drive-frequency", "2e5", "--spring-constant", "3", "--json",
                 str(out)]) == 0
    assert "from the file: free_resonance 70000 Hz, length 0.0002 m" in capsys.readouterr().out.splitlines()
    assert json.loads(out.read_text())["results"]["drive_frequency"] == {"value": 2e5, "stderr": None, "unit": "Hz",
                                                                   "status": "given"}


@pytest.mark.parametrize("rows", [1, 30])
def test_calibrate_names_the_file_of_a_spectrum_too_short(rows, tmp_path, capsys):
    """The line named no file ('a thermal spectrum needs ... at least 50 points')."""
    tune = tmp_path / "short tune.csv"
    tune.write_text("frequency_hz,asd_m_per_sqrthz\n" + "".join(f"{1e3 * (i + 1)},1e-12\n" for i in range(rows)))
    assert _run(["calibrate", str(tune), "--json", str(tmp_path / "out.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"pfmdyn calibrate: error: {tune}: {rows} ASD values"), err
    assert _outputs(tmp_path) == []


def test_deconvolve_reads_the_unit_its_columns_name(tmp_path, capsys):
    """diagram's own CSV (amplitude_m_per_v) was deconvolved in 'a.u.'; a column '(pm)' too."""
    table = tmp_path / "diagram.csv"
    assert _run(["diagram", "--plot", str(tmp_path / "d.png"), "--csv", str(table), "--frequency-points", "5",
                 "--bias-points", "3"]) == 0
    capsys.readouterr()
    assert _run(["deconvolve", str(table), "--out", str(tmp_path / "dec"), "--json", str(tmp_path / "d.json")]) == 0
    out = capsys.readouterr().out
    assert " m/V (V_surf" in out and "a.u." not in out
    assert "data in m/V" in json.loads((tmp_path / "d.json").read_text())["notes"]
    pm = tmp_path / "pm.csv"
    pm.write_text(CSV.replace("x,y", "X (pm),Y (pm)"))
    assert _run(["deconvolve", str(pm), "--out", str(tmp_path / "dec2")]) == 0
    out = capsys.readouterr().out
    assert " pm " in out and "a.u." not in out


def test_stiffness_states_the_uncertainty_of_k1_over_k(tmp_path, capsys):
    """k1/k was printed and written with no uncertainty; it has k1's from every input but the spring constant,
    which k1 scales with."""
    from pfmdyn.digits import rounded
    out = tmp_path / "k1.json"
    base = ["stiffness", "--free-resonance", "7e4", "--contact", "3e5", "--spring-constant", "2", "--k2", "0",
            "--json", str(out)]
    assert _run([*base, "--contact-uncertainty", "300"]) == 0
    results = json.loads(out.read_text())["results"]
    k1, ratio = results["k1"], results["k1_over_k"]
    assert k1["stderr"] > 0 and ratio["stderr"] == pytest.approx(k1["stderr"] / 2.0, rel=1e-12)
    assert f"(k1/k = {rounded(ratio['value'], ratio['stderr'])} +- {ratio['stderr']:.2g})" in capsys.readouterr().out
    assert _run([*base, "--spring-constant-uncertainty", "0.2", "--contact-uncertainty", "0",
                 "--free-resonance-uncertainty", "0"]) == 0
    results = json.loads(out.read_text())["results"]
    assert results["k1"]["stderr"] == pytest.approx(0.1 * results["k1"]["value"], rel=1e-6)
    assert results["k1_over_k"]["stderr"] == 0.0


def test_discrepancy_prints_a_tables_rows_beside_the_model(tmp_path, capsys):
    """The text gave the fitted parameters alone: the measured resonances and Qs (an instrument's fits) stood
    beside the model's only in the JSON."""
    table = tmp_path / "table.csv"
    table.write_text("mode,condition,frequency_hz,quality_factor\n1,contact,368990,213.46\n1,free,72969,138.63\n")
    assert _run(["discrepancy", str(table), "--spring-constant", "0.46538", "--length", "240e-6", "--tip-height",
                 "13e-6", "--json", str(tmp_path / "d.json")]) == 0
    out = capsys.readouterr().out.splitlines()
    results = json.loads((tmp_path / "d.json").read_text())["results"]
    head = out.index(next(line for line in out if line.startswith("condition  mode")))
    for line, c, f, p, q, qp in zip(out[head + 1:], results["condition"]["value"],
                                     results["measured_resonance"]["value"], results["predicted_resonance"]["value"],
                                     results["measured_quality_factor"]["value"],
                                     results["predicted_quality_factor"]["value"]):
        words = line.split()
        assert words[0] == c and float(words[2]) == f and float(words[5]) == pytest.approx(p, rel=1e-5)
        assert float(words[6]) == pytest.approx(q, rel=1e-3) and float(words[7]) == pytest.approx(qp, rel=1e-3)


@pytest.mark.parametrize("tip_mass_ratio", [0.3, 1.0])
def test_a_heavy_tip_in_water_keeps_its_measured_resonance(tip_mass_ratio, tmp_path):
    """Sader's relation took the fluid's mass ratio over the beam alone, as though the fluid loaded the tip's mass
    too: a heavy tip in water was refused ('the medium's load exceeds the lever's inertia'), a light one placed
    the resonance in water 1 % off (tests/test_sweeps_fit.py: the exact massed beam)."""
    lever = ["--spring-constant", "2", "--free-resonance", "2e4", "--length", "225e-6", "--width", "40e-6",
             "--medium", "water", "--modes", "1", "--tip-height", "13e-6"]
    damped = []
    for extra in ([], ["--tip-mass-ratio", str(tip_mass_ratio)]):
        out = tmp_path / "r.json"
        assert _run(["resonances", *lever, *extra, "--json", str(out)]) == 0
        damped.append(json.loads(out.read_text())["results"]["free"]["damped_resonance"]["value"][0])
    assert damped[1] == pytest.approx(damped[0], rel=0.005) and damped[0] == pytest.approx(2e4, rel=0.03)


def test_inspect_shows_the_resonances_a_tables_rows_hold(tmp_path):
    """inspect said 'cantilever fields found: none' of a resonance table whose rows stiffness and discrepancy read."""
    table = tmp_path / "table.csv"
    table.write_text("# spring_constant: 0.46538\nmode,condition,frequency_hz,quality_factor\n"
                     "2,free,457000,\n1,contact,368990,213.46\n1,free,72969,138.63\n")
    out = tmp_path / "i.json"
    assert _run(["inspect", str(table), "--json", str(out)]) == 0
    results = json.loads(out.read_text())["results"]
    assert {name: r["value"] for name, r in results.items()} == {
        "spring_constant": 0.46538, "free_resonance": 72969.0, "free_quality_factor": 138.63,
        "contact_resonance": 368990.0, "contact_quality_factor": 213.46}
    assert {r["status"] for r in results.values()} == {"file"}


def test_resonances_json_says_which_frequency_is_in_vacuum(tmp_path, capsys):
    """In a medium the certified 'resonance' is the lever's in vacuum (above the measured one it was given); the text
    said so, the JSON's results.free.resonance stood unexplained."""
    out = tmp_path / "r.json"
    assert _run(["resonances", *LEVER, "--medium", "air", "--width", "3e-5", "--modes", "1", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    line = next(line for line in capsys.readouterr().out.splitlines() if "undamped lever's in vacuum" in line)
    assert line in doc["notes"] and doc["results"]["free"]["resonance"]["value"][0] > 7e4
    assert doc["results"]["free"]["damped_resonance"]["value"][0] == pytest.approx(7e4, rel=1e-3)


def test_discrepancy_prints_values_to_the_digits_their_uncertainty_leaves(tmp_path, capsys):
    """discrepancy printed 'k1 = 258.49 +- 85 N/m' where stiffness (and README) state 258 +- 85."""
    table = tmp_path / "table.csv"
    table.write_text("mode,condition,frequency_hz,quality_factor\n1,contact,368990,213.46\n1,free,72969,138.63\n")
    assert _run(["discrepancy", str(table), "--spring-constant", "0.46538", "--length", "240e-6", "--tip-height",
                 "13e-6"]) == 0
    printed = re.findall(r"^  (\w+) = ([-\d.e+]+) \+- ([\d.e+-]+)", capsys.readouterr().out, re.MULTILINE)
    assert {name for name, _, _ in printed} >= {"k1", "quality_factor"}, printed
    for name, value, sigma in printed:
        decimals = len(value.partition(".")[2])
        assert 10 ** -decimals >= float(sigma) / 100, (name, value, sigma)     # no digit below u's second


def test_a_contact_map_says_why_some_pixels_have_no_k1(tmp_path, capsys):
    """stiffness FILE --out on a contact-frequency map said 'k1 at 35.0 % of pixels' and nothing of the rest (it
    said why only when no pixel had a k1)."""
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = [[3.0e5, 3.05e5], [3.1e5, 3.2e5]]      # f1 70 kHz: the pinned limit 4.385 f1
        h.attrs.update(spring_constant=2.0, free_resonance=7e4)
    assert _run(["stiffness", str(path), "--out", str(tmp_path / "o"), "--json", str(tmp_path / "s.json")]) == 0
    line = "k1 undetermined at 2 of 4 pixels: their contact/free ratio (4.429 to 4.571) lies outside mode 1's limits"
    assert line in capsys.readouterr().out
    assert any(note.startswith(line) for note in json.loads((tmp_path / "s.json").read_text())["notes"])


def test_diagram_json_writes_no_negative_zero(tmp_path):
    """diagram --json wrote -0.0 in the electrostatic responses (the imaginary part of a real response)."""
    out = tmp_path / "d.json"
    assert _run(["diagram", "--plot", str(tmp_path / "d.png"), "--json", str(out), "--frequency-points", "12",
                 "--bias-points", "5"]) == 0
    text = out.read_text()
    assert "-0.0," not in text and "-0.0]" not in text and json.loads(text)["results"]


def test_spot_states_how_far_its_results_move_with_the_assumed_tip_height_and_tie(tmp_path, capsys):
    """spot printed the blind spot, the contact sensitivity and the calibration factor to six figures with no
    uncertainty, though they rest on a tip height and a k2 tie it assumed (the BTFO image's calibration factor is 14,
    31 and 1669 at a tip height of 10.5, 13 and 15.5 um).  Each now carries its spread over the assumed inputs, and
    the value at a tip height one standard uncertainty off lies within about it."""
    lever = ["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2.25e-4", "--width", "3e-5", "--k1", "200",
             "--drive-frequency", "2e5", "--spot-position", "0.8"]
    out = tmp_path / "s.json"
    assert _run(["spot", *lever, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "uncertainties from the assumed inputs, each moved by its own: tip height, k2 policy" in text
    assert re.search(r"blind spot x_s/L: [\d.]+ \+- [\d.e+-]+ ", text) and re.search(r"in contact [\d.]+ \+- ", text)
    assumed = json.loads(out.read_text())["results"]
    assert _run(["spot", *lever, "--tip-height", "10.5e-6", "--poisson", "0.3", "--json", str(out)]) == 0
    moved = json.loads(out.read_text())["results"]
    for name in ("blind_spot", "contact_sensitivity", "calibration_factor"):
        value, stderr = assumed[name]["value"], assumed[name]["stderr"]
        value, stderr, other = (value[0], stderr[0], moved[name]["value"][0]) if name == "blind_spot" else (
            (value["real"], stderr, moved[name]["value"]["real"]) if isinstance(value, dict) else
            (value, stderr, moved[name]["value"]))
        assert 0 < abs(other - value) < 1.5 * stderr, (name, value, stderr, other)


def test_resonances_state_how_far_the_contact_resonances_move_with_the_assumed_inputs(tmp_path, capsys):
    """resonances printed each contact resonance to 0.1 Hz with no uncertainty, though it rests on a tip height
    and a k2 tie it assumed (the BTFO lever's first moves by 12 kHz over the tip height's spread).  Each contact
    resonance now has its standard uncertainty over them; with k2 = 0 and no tilt the tip height does not act and
    none is stated."""
    lever = ["--spring-constant", "0.46538", "--free-resonance", "72969", "--length", "2.4e-4", "--k1", "258.48"]
    out = tmp_path / "r.json"
    assert _run(["resonances", *lever, "--json", str(out)]) == 0
    assert "each moved by its own: tip height, k2 policy" in capsys.readouterr().out
    assumed = json.loads(out.read_text())["results"]["contact"]["resonance"]
    assert _run(["resonances", *lever, "--tip-height", "10.5e-6", "--poisson", "0.3", "--json", str(out)]) == 0
    moved = json.loads(out.read_text())["results"]["contact"]["resonance"]["value"]
    for value, stderr, other in zip(assumed["value"], assumed["stderr"], moved):
        assert 0 < abs(other - value) < 1.5 * stderr, (value, stderr, other)
    capsys.readouterr()
    assert _run(["resonances", *lever, "--k2", "0", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["results"]["contact"]["resonance"]["stderr"] is None
    assert " +- " not in capsys.readouterr().out


def test_discrepancy_on_a_resonance_table_assumes_the_tip_height_as_stiffness_does(tmp_path, capsys):
    """stiffness TABLE took the typical PFM probe's tip height; discrepancy on the same table refused ('missing
    metadata key(s) tip_height'), though it assumes it for an instrument file holding the same two rows."""
    table = tmp_path / "table.csv"
    table.write_text("# spring_constant: 0.46538\n# length: 240e-6\nmode,condition,frequency_hz,quality_factor\n"
                     "1,contact,368990,213.46\n1,free,72969,138.63\n")
    _discrepancy_beside_stiffness(table, tmp_path, capsys, "tip_height", "assumed: tip height 1.3e-05 m")


def _discrepancy_beside_stiffness(path, tmp_path, capsys, name: str, line: str) -> None:
    """discrepancy on ``path`` assumes ``name`` (printing ``line``, its record marked so) and finds the k1 of
    stiffness on the same file, with its uncertainty (discrepancy fits the damped lever: 0.1 % apart)."""
    out = tmp_path / "d.json"
    assert _run(["discrepancy", str(path), "--json", str(out)]) == 0
    assert line in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["lever"][name]["status"] == "assumed"
    assert _run(["stiffness", str(path), "--json", str(out)]) == 0
    k1 = json.loads(out.read_text())["results"]["k1"]
    assert doc["results"]["k1"]["value"] == pytest.approx(k1["value"], rel=5e-3)
    assert doc["results"]["k1"]["stderr"] == pytest.approx(k1["stderr"], rel=0.05)


def test_a_tables_extra_column_is_left_out_and_said(tmp_path, capsys):
    """A resonance table or spectrum with a column of its own (a note, the instrument's fit) was refused ('unknown
    column(s)'); its columns are read, the extra one left out with a note, the result that of the table without it."""
    rows = "1,contact,368990,213.46,{}\n1,free,72969,138.63,{}\n"
    plain, extra = tmp_path / "plain.csv", tmp_path / "extra.csv"
    plain.write_text("# spring_constant: 0.46538\nmode,condition,frequency_hz,quality_factor\n"
                     + rows.replace(",{}", ""))
    extra.write_text("# spring_constant: 0.46538\nmode,condition,frequency_hz,quality_factor,operator\n"
                     + rows.format("A", "B"))
    out = tmp_path / "s.json"
    k1 = []
    for path in (plain, extra):
        assert _run(["stiffness", str(path), "--json", str(out)]) == 0
        k1.append(json.loads(out.read_text())["results"]["k1"]["value"])
    assert k1[0] == k1[1]
    assert f"note: {extra}: column 'operator' not read" in capsys.readouterr().out
    spectrum = tmp_path / "spectrum.csv"
    spectrum.write_text("# spring_constant: 2\n# length: 2e-4\n# tip_height: 1e-5\n# free_resonance: 7e4\n"
                        "frequency_hz,bias_v,x,y,comment\n" + "".join(
                            f"{1e5 + 8e3 * i:g},{v},{1 + 0.1 * v},{0.1 * v},ok\n" for i in range(25) for v in (-1, 0, 1)))
    assert _run(["discrepancy", str(spectrum), "--json", str(out)]) in (0, 1)
    assert f"note: {spectrum}: column 'comment' not read" in capsys.readouterr().out


def test_discrepancy_on_a_file_without_length_assumes_it_as_stiffness_does(tmp_path, capsys, monkeypatch):
    """stiffness on an image without the lever length (as the shared PMN28 file) takes a typical PFM lever's, since
    only the assumed tip height over it acts; discrepancy refused it ('lever length not in ...: give --length')."""
    import numpy as np
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    from igor_files import asylum_note, igor_wave

    image = igor_wave(tmp_path / "scan.ibw", np.ones((8, 8, 2), "f4"), "scan", [(0.0, 1e-8, "m")] * 2, "m",
                      {2: ["HeightRetrace", "AmplitudeRetrace"]},
                      asylum_note({"SpringConstant": 1.0, "ThermalFrequency": 74369, "ThermalQ": 20,
                                   "TuneFreqResult": 348400, "TuneQResult": 218.47}))
    _discrepancy_beside_stiffness(image, tmp_path, capsys, "length", "assumed: lever length 0.000225 m (a typical")


def test_discrepancy_on_a_table_says_what_it_took_from_the_file(tmp_path, capsys):
    """discrepancy on a resonance table or an image's resonances said what it assumed but not what it took from
    the file (its sweeps and tunes did): the rows and the lever values no flag replaced, the free resonance once."""
    table = tmp_path / "table.csv"
    table.write_text("# spring_constant: 0.46538\n# length: 240e-6\n# tip_height: 13e-6\n"
                     "mode,condition,frequency_hz,quality_factor\n1,contact,368990,213.46\n1,free,72969,\n")
    assert _run(["discrepancy", str(table), "--length", "2.3e-4"]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("from the file: "))
    assert line == ("from the file: free mode 1 72969 Hz, contact mode 1 368990 Hz (Q 213.46), spring_constant 0.46538 "
                    "N/m, tip_height 1.3e-05 m")
