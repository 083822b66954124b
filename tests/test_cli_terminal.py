"""What a user sees in the terminal (issue 41, item 8): Ctrl-C ends a command with one line and the
exit status 130, and the interrupted map's workers end with it and the map resumes.

Ctrl-C is sent as a terminal sends it: SIGINT to the command's whole process group (its own session
here), workers included.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import cli

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam  # noqa: E402

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")


def _start(argv, cwd) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "pfmdyn.cli", *argv], cwd=cwd, stdout=subprocess.PIPE,
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
