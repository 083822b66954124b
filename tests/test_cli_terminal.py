"""What a user sees in the terminal (issue 41, item 8): Ctrl-C ends a command with one line and the
exit status 130, and the interrupted map's workers end with it and the map resumes; no command
prints a warning, a library's progress bar or ``nan``; ``--json -`` writes to standard output.

Ctrl-C is sent as a terminal sends it: SIGINT to the command's whole process group (its own session
here), workers included.
"""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import cli

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam  # noqa: E402

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")


def _start(argv, cwd) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-W", "error", "-m", "pfmdyn.cli", *argv], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _ctrl_c(process: subprocess.Popen) -> tuple[str, str]:
    """Ctrl-C to the command's process group; its output once it has ended."""
    os.killpg(process.pid, signal.SIGINT)
    out, err = process.communicate(timeout=60)
    return out, err


def _alive(session: int) -> list[str]:
    """Processes of the session still running (an exited worker may linger as a zombie: not running)."""
    listed = subprocess.run(["ps", "-e", "-o", "sid=,stat=,pid=,args="], capture_output=True, text=True).stdout
    return [line for line in listed.splitlines() if line.split()[0] == str(session) and not line.split()[1].startswith("Z")]


def test_ctrl_c_is_one_line_and_status_130(tmp_path):
    """``verify`` (11-25 s) interrupted a few seconds in: before, a 24-line traceback and status -2."""
    process = _start(["verify", "--quiet"], tmp_path)
    time.sleep(4.0)
    assert process.poll() is None, "verify ended before it could be interrupted"
    out, err = _ctrl_c(process)
    assert process.returncode == 130
    assert err == "pfmdyn verify: interrupted\n", err


def _small_map(path: Path, n: int = 16) -> None:
    """A map of two contact stiffnesses (an FE beam, independent of pfmdyn's model), 2 % noise."""
    k, length, f1, tip_height = 2.0, 225e-6, 75e3, 10e-6
    beams = {k1: FEBeam(k, length, f1, tip_height, k1=k1, Q=60.0, n_elements=40) for k1 in (150.0, 400.0)}
    first = [beam.contact_resonances(1)[0] for beam in beams.values()]
    f = np.linspace(0.85 * min(first), 1.15 * max(first), 48)
    shapes = {k1: beam.slope(f)[:, 0] for k1, beam in beams.items()}
    columns = np.arange(n) < n // 2
    clean = np.stack([2e-3 * shapes[150.0 if columns[j] else 400.0] for _ in range(n) for j in range(n)])
    rng = np.random.default_rng(3)
    noisy = clean * (1 + 0.02 * (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)))
    with h5py.File(path, "w") as h:
        h["response"] = noisy.reshape(n, n, -1)
        h["frequency_hz"] = f
        h.attrs.update(spring_constant=k, length=length, width=40e-6, tip_height=tip_height, free_resonance=f1,
                       k2=0.0)


def test_ctrl_c_ends_the_map_and_its_workers_and_the_map_resumes(tmp_path, monkeypatch, capsys):
    """Interrupted while its worker processes start (where a worker importing pfmdyn printed a
    traceback) or fit: one line, status 130, no process left; the same command then finishes the map."""
    _small_map(tmp_path / "be.h5")
    argv = ["map", "be.h5", "--out", "out", "--model", "elastic", "--block", "4", "--no-progress"]
    process = _start([*argv, "--workers", "2"], tmp_path)
    assert process.stdout.readline().startswith("fitting:")
    time.sleep(0.5)
    out, err = _ctrl_c(process)
    assert process.returncode == 130, out + err
    assert err == "pfmdyn map: interrupted\n", err
    for _ in range(50):     # the workers end with their parent (SIGKILL from the kernel, or their watch)
        if not _alive(process.pid):
            break
        time.sleep(0.1)
    assert not _alive(process.pid)
    monkeypatch.chdir(tmp_path)
    assert cli.main([*argv, "--scheduler", "sync"]) == 0        # in one process: quicker
    assert "16/16 done" in capsys.readouterr().out
    k1 = np.asarray(zarr.open_group(str(tmp_path / "out" / "maps.zarr"), mode="r")["k1"][...])
    assert np.allclose(k1[:, :8], 150.0, rtol=0.05) and np.allclose(k1[:, 8:], 400.0, rtol=0.05)


def test_an_interrupt_while_the_workers_start_is_not_lost():
    """Ctrl-C in the instant the pool's workers are started (when SIGINT was ignored there, the map
    ran on and exited 0, in 2 of 5 fresh-clone CI runs): the parent still gets its KeyboardInterrupt."""
    code = ("import os, signal, concurrent.futures as f; from pfmdyn.fitting import workers\n"
            "start = f.ProcessPoolExecutor.__init__\n"
            "def interrupted(self, *a, **k):\n"
            "    os.kill(os.getpid(), signal.SIGINT); start(self, *a, **k)\n"
            "f.ProcessPoolExecutor.__init__ = interrupted\n"
            "try:\n    workers.pool(1)\nexcept KeyboardInterrupt:\n    print('interrupted')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.stdout == "interrupted\n" and not run.stderr, run.stdout + run.stderr


# --- a clean terminal: no warning, no library progress bar, no nan --------------------------------

LEVER = ["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4"]
PROBE = LEVER + ["--tip-height", "1e-5", "--k1", "100"]


def _inputs(folder: Path) -> None:
    """Small inputs of every kind a command reads, each drawn by a route of its own."""
    from fe_beam import resonances

    from pfmdyn import Cantilever
    from pfmdyn.medium import Medium

    (folder / "bias.csv").write_text("frequency_hz,bias_v,x,y\n" + "".join(
        f"{f},{v},{1 + 0.1 * v},{0.1 * v}\n" for f in (1e5, 2e5, 3e5) for v in (-1, 0, 1)))
    beam = FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, n_elements=60, Q=80.0)
    (folder / "modes.csv").write_text(resonances(beam))
    # thermal tunes: a stiff lever in air (Q near 1000, the peak 5 bins wide, where an uncertainty was nan)
    # as a bare oscillator over a floor, and a soft one from the beam in air
    f = np.arange(1, 8192) * 38.147
    rng = np.random.default_rng(1)
    oscillator = 1e-15 / np.sqrt((1 - (f / 1.8e5) ** 2) ** 2 + (f / 1.8e8) ** 2)
    asd = np.sqrt(oscillator ** 2 + 3e-14 ** 2) * np.sqrt(rng.chisquare(1000, f.size) / 1000)
    (folder / "stiff_tune.csv").write_text("frequency_hz,deflection_m_per_sqrthz\n" + "".join(
        f"{a:.8g},{b:.8g}\n" for a, b in zip(f, asd)))
    f = np.linspace(2e4, 1.2e5, 2000)
    asd = np.sqrt(1e-8 * Cantilever(2.0, 7e4, 2e-4, width=3e-5, medium=Medium.air()).thermal_noise(f, 300.0).slope)
    (folder / "soft_tune.csv").write_text("frequency_hz,deflection_m_per_sqrthz\n" + "".join(
        f"{a:.8g},{b:.8g}\n" for a, b in zip(f, asd)))
    # drive sweeps in water before and after the resonance fell by 2 % (Cytomass layout)
    f = np.linspace(3e4, 1.2e5, 160)
    for name, resonance in (("before", 7.2e4), ("after", 7.05e4)):
        lever = Cantilever(8.0, resonance, 1e-4, width=4e-5, medium=Medium.water())
        y = (0.3 - 2j) * lever.base_driven(f).slope + 0.5
        y = y + 1e-3 * np.abs(y).max() * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
        (folder / f"{name}.txt").write_text("Cytomass frequency sweep file\n\nSweep data\nFrequency (Hz)\tAmplitude (V)\t"
                                           "Phase (deg)\n" + "".join(f"{a:.6f}\t{abs(b):.9g}\t{np.angle(b, deg=True):.9g}\n"
                                                                     for a, b in zip(f, y)))
    _small_map(folder / "be.h5", 8)


MAIN_PATHS = {
    "resonances": ["resonances", *PROBE[:-2], "--width", "4e-5", "--medium", "air", "--k1", "300", "--poisson", "0.3",
                   "--quality-factor", "50", "--json", "r.json"],
    "resonances overdamped": ["resonances", *LEVER, "--viscous-loss", "3"],
    "spot": ["spot", *PROBE, "--drive-frequency", "1e5", "--plot", "s.png"],
    "stiffness": ["stiffness", "--spring-constant", "2", "--free-resonance", "7e4", "--contact", "3e5", "--contact",
                  "9e5", "--mode", "1", "--mode", "2", "--tip-position", "fit", "--contact-uncertainty", "100"],
    "diagram": ["diagram", "--plot", "d.png", "--frequency-points", "40", "--bias-points", "9", "--csv", "d.csv"],
    "deconvolve": ["deconvolve", "bias.csv", "--surface-potential", "0", "--out", "dec", *PROBE],
    "roots": ["roots", "elastic", "--modes", "3", "--k1-over-k", "10", "--k2-ratio", "0.1"],
    "branches 50 modes": ["branches", "indentation", "--plot", "b.png", "--points", "20", "--modes", "50"],
    "inspect": ["inspect", "before.txt"],
    "discrepancy resonances": ["discrepancy", "modes.csv"],
    "discrepancy thermal tune": ["discrepancy", "soft_tune.csv", *LEVER[:2], "--length", "2e-4", "--width", "3e-5"],
    "discrepancy sweeps": ["discrepancy", "after.txt", "--reference", "before.txt", "--spring-constant", "8",
                           "--length", "1e-4", "--width", "4e-5", "--plot", "sw.png"],
    "calibrate stiff lever": ["calibrate", "stiff_tune.csv", "--length", "225e-6", "--width", "40e-6",
                              "--temperature", "300", "--plot", "c.png"],
    "calibrate soft lever": ["calibrate", "soft_tune.csv", "--length", "2e-4", "--width", "3e-5"],
    "map": ["map", "be.h5", "--out", "beam", "--scheduler", "sync", "--no-progress", "--plot", "beam"],
    "map sho": ["map", "be.h5", "--out", "sho", "--model", "sho", "--scheduler", "sync", "--no-progress"],
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("inputs")
    _inputs(folder)
    return folder


@pytest.mark.parametrize("case", sorted(MAIN_PATHS))
def test_a_command_prints_no_warning_progress_bar_or_nan(case, inputs, monkeypatch, capsys):
    """Each command on a small input of its main path, every warning recorded (as errors they would
    change what the command does): none, nothing on stderr (no library progress bar on a pipe), no
    ``nan`` in what it prints.  Before, ``branches --modes 50`` gave matplotlib's UserWarning and
    ``discrepancy`` printed its fits' progress bar into a log."""
    monkeypatch.chdir(inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = cli.main(MAIN_PATHS[case])
    out, err = capsys.readouterr()
    assert status in (0, 1) and not err, err       # 1: roots/resonances not certified (a verdict, no error)
    assert not caught, [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in caught]
    assert not re.search(r"\bnan\b", out, re.IGNORECASE), out


@pytest.mark.parametrize("argv", [["map", "be.h5", "--out", "bar", "--scheduler", "sync", "--model", "elastic"],
                                  ["verify", "--only", "eq6.Av"]])
def test_no_progress_bar_off_a_terminal(argv, inputs, monkeypatch, capsys):
    """Without ``--no-progress`` or ``--quiet``: on a pipe or in a log, no bar (``map`` and ``verify`` drew
    tqdm's into it, as ``discrepancy`` did before); on a terminal, one."""
    monkeypatch.chdir(inputs)
    assert cli.main(argv) == 0
    assert not capsys.readouterr().err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert cli.main([a if a != "bar" else "bar again" for a in argv]) == 0
    assert "%|" in capsys.readouterr().err


def _without_json(argv: list) -> list:
    argv = list(argv)
    if "--json" in argv:
        del argv[argv.index("--json"):argv.index("--json") + 2]
    return argv


JSON_COMMANDS = sorted(command for command, parser in cli.parser(None)[1].items()
                       if any(action.dest == "json" for action in parser._actions))


@pytest.mark.parametrize("command", JSON_COMMANDS)
def test_json_dash_is_standard_output(command, inputs, monkeypatch, capsys):
    """``--json -`` in every command that has ``--json`` (the parser says which): the document alone on
    standard output (the same as in a file), the summary on standard error, and no file named ``-``
    (calibrate wrote one)."""
    monkeypatch.chdir(inputs)
    argv = ["verify", "--only", "eq6.Av", "--quiet"] if command == "verify" else \
        _without_json(next(MAIN_PATHS[case] for case in sorted(MAIN_PATHS) if MAIN_PATHS[case][0] == command))
    assert cli.main([*argv, "--json", "file.json"]) in (0, 1)
    summary = capsys.readouterr().out
    if command == "map":        # a second run into the same folder resumes it: another folder, another summary
        argv = [a if a != "beam" else "beam again" for a in argv]
    assert cli.main([*argv, "--json", "-"]) in (0, 1)
    printed = capsys.readouterr()
    document, written = json.loads(printed.out), json.loads(Path("file.json").read_text())
    if command == "map":
        assert document.keys() == written.keys() and document["results"].keys() == written["results"].keys()
    else:
        assert document == written and printed.err.startswith(summary)
    assert not Path("-").exists()


def test_errata_dash_is_standard_output(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["verify", "--only", "eq6.Av", "--quiet", "--errata", "-"]) == 0
    assert "\n# Errata of " in capsys.readouterr().out and not Path("-").exists()


def test_the_console_script_exits_without_a_full_collection():
    """``pfmdyn`` is :func:`pfmdyn.cli.console`: the command, then its objects frozen, so that Python's exit skips
    a full collection over them (0.2 s after a ``discrepancy``); ``main`` itself, which a caller in Python
    uses, freezes nothing."""
    from importlib.metadata import entry_points

    assert [e.value for e in entry_points(group="console_scripts") if e.name == "pfmdyn"] == ["pfmdyn.cli:console"]
    code = ("import gc, sys; from pfmdyn import cli; sys.argv = ['pfmdyn', 'roots', 'free', '--modes', '1'];"
            " cli.main(); frozen = gc.get_freeze_count(); cli.console(); print(frozen, gc.get_freeze_count() > 1000)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split()[-2:] == ["0", "True"]
