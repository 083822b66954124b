"""Fixtures shared by the test modules."""
from __future__ import annotations

import fcntl
import os
import pickle

import pytest


@pytest.fixture(scope="session")
def all_verdicts(tmp_path_factory):
    """The verdicts of ``pfmdyn verify`` (:func:`pfmdyn.verify.compute`), computed once per test run:
    by the first pytest-xdist worker that asks, the others reading its pickle (tests/test_verify.py
    checks them, tests/test_book.py builds the book from them: half a minute of CPU each time)."""
    from pfmdyn import verify
    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent          # the run's folder, above each worker's own
    path = shared / "verdicts.pickle"
    with open(shared / "verdicts.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.exists():
            path.write_bytes(pickle.dumps(verify.compute(progress=False)))
        return pickle.loads(path.read_bytes())


@pytest.fixture(autouse=True, scope="session")
def _one_process_per_test_worker():
    """Under pytest-xdist every core already runs a test file: the discrepancy workflow's own worker
    processes (one per core by default) would only share those cores.  Its report is the same with
    any number (tests/test_workers.py runs both in a fresh interpreter)."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        yield
        return
    from pfmdyn.discrepancy import spectrum
    cores, spectrum.cores = spectrum.cores, lambda: 1
    yield
    spectrum.cores = cores
