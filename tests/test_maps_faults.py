"""``pfmdyn map`` under faults: a killed worker, a killed run, and nothing left behind.

The map is small (16 x 16 pixels of two finite-element levers, tests/fe_beam.py, in 4 x 4
blocks) so that each run takes seconds; every faulted run is compared pixel by pixel with a
clean run of the same blocks.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")
psutil = pytest.importorskip("psutil")
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn.cli import main  # noqa: E402
from pfmdyn.maps import open_result  # noqa: E402
from pfmdyn.maps.driver import open_map, run_map  # noqa: E402

K, L, F1, H, Q = 2.0, 225e-6, 75e3, 10e-6, 60.0
N, BLOCK = 16, 4


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    """The map file and the maps of a clean run (one process)."""
    k1 = np.where(np.arange(N)[None, :] < N // 2, 150.0, 400.0) * np.ones((N, 1))
    beams = {v: FEBeam(K, L, F1, H, k1=v, Q=Q, n_elements=40) for v in np.unique(k1)}
    first = [b.contact_resonances(1)[0] for b in beams.values()]
    f = np.linspace(0.85 * min(first), 1.15 * max(first), 48)
    shapes = {v: 2e-3 * b.slope(f)[:, 0] for v, b in beams.items()}
    y = np.stack([shapes[v] for v in k1.ravel()]).reshape(N, N, -1)
    rng = np.random.default_rng(11)
    y = y + 0.01 * np.abs(y).max() * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
    root = tmp_path_factory.mktemp("faults")
    path = root / "be.h5"
    with h5py.File(path, "w") as h:
        h["response"], h["frequency_hz"] = y, f
        h.attrs.update(spring_constant_n_per_m=K, length_m=L, tip_height_m=H, free_resonance_hz=F1)
    run_map(open_map(str(path)), str(root / "clean"), block=BLOCK, scheduler="sync", progress=False)
    return path, _maps(root / "clean")


def _maps(out: Path) -> dict:
    result = open_result(str(out))
    return {name: result[name].values for name in result.data_vars}


def _done(out: Path) -> np.ndarray:
    try:
        return np.asarray(zarr.open_group(str(out / "maps.zarr"), mode="r")["done"][...])
    except (KeyError, ValueError, OSError):     # not created yet
        return np.zeros(1)


def _wait(condition, timeout_s=120.0):
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.02)


def _alive(processes) -> list:
    """The processes still running (a zombie waiting to be reaped has exited)."""
    alive = []
    for p in processes:
        try:
            if p.status() != psutil.STATUS_ZOMBIE:
                alive.append(p)
        except psutil.NoSuchProcess:
            pass
    return alive


def _assert_same_maps(out: Path, clean: dict):
    maps = _maps(out)
    assert maps.keys() == clean.keys()
    for name, value in maps.items():
        np.testing.assert_array_equal(value, clean[name], err_msg=name)


def test_sigkilled_run_leaves_no_worker_and_resumes_to_identical_maps(scan, tmp_path):
    """SIGKILL (what an out-of-memory killer or a batch scheduler sends) runs no clean-up in the
    killed process: its pool workers must go by themselves, and the rerun finishes the map."""
    path, clean = scan
    out = tmp_path / "run"
    args = ["map", str(path), "--out", str(out), "--block", str(BLOCK), "--workers", "2", "--model", "elastic",
            "--no-progress"]
    run = subprocess.Popen([sys.executable, "-m", "pfmdyn.cli", *args], stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    try:
        _wait(lambda: _done(out).sum() >= 1)
        workers = psutil.Process(run.pid).children(recursive=True)
    finally:
        run.send_signal(signal.SIGKILL)
        run.wait()
    assert len(workers) >= 2
    deadline = time.monotonic() + 3.0       # the kernel's death signal is immediate; the watch thread polls
    while _alive(workers) and time.monotonic() < deadline:
        time.sleep(0.02)
    left = _alive(workers)
    for p in left:
        p.kill()
    assert not left, f"workers outlived the killed run: {[p.pid for p in left]}"
    finished = int(_done(out).sum())
    assert 1 <= finished < (N // BLOCK) ** 2, finished      # killed mid-map
    assert main(args) == 0
    assert int(_done(out).sum()) == (N // BLOCK) ** 2
    _assert_same_maps(out, clean)


def test_killed_distributed_worker_gives_identical_maps(scan, tmp_path):
    """A dask.distributed worker process killed while it fits a block: its nanny restarts it,
    the scheduler reruns the block elsewhere, and the maps are those of a clean run."""
    distributed = pytest.importorskip("distributed")
    path, clean = scan
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  worker_dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        errors = []

        def fit():
            try:
                run_map(open_map(str(path)), str(tmp_path), block=BLOCK, scheduler=cluster.scheduler_address,
                        progress=False)
            except BaseException as exc:   # noqa: BLE001  (reported by the test thread)
                errors.append(exc)

        runner = threading.Thread(target=fit)
        runner.start()
        busy = {}
        _wait(lambda: _done(tmp_path).sum() >= 1 and busy.update(
            {a: k for a, k in client.processing().items() if k and a in pids}) is None and bool(busy))
        victim = next(iter(busy))
        os.kill(pids[victim], signal.SIGKILL)
        runner.join(timeout=180)
        assert not runner.is_alive() and not errors, errors
        assert pids[victim] not in client.run(os.getpid).values()      # that worker process is gone
    _assert_same_maps(tmp_path, clean)
