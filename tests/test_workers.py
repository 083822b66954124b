"""Worker processes (:mod:`pfmdyn.fitting.workers`): calls run in forked workers, in order, and the
discrepancy workflow's report does not depend on how many there are."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from pfmdyn.fitting.workers import Forked

TESTS = Path(__file__).resolve().parent


def _clean(code: str) -> str:
    """``code``'s output in a fresh interpreter (no thread of pytest's: a fork is to be had there)."""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                         cwd=TESTS, env={**os.environ, "PYTHONPATH": str(TESTS)})
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def test_calls_run_in_workers_in_order_and_raise_here():
    out = json.loads(_clean(
        "import json, multiprocessing, os\n"
        "from pfmdyn.fitting.workers import Forked\n"
        "def where(state, i):\n"
        "    state.append(i)\n"            # a worker's own copy of the state
        "    return i, os.getpid(), len(state)\n"
        "def nested(state, i):\n"
        "    with Forked(2, state) as inner:\n"
        "        return os.getpid(), inner.map(lambda s: os.getpid(), [()] * 3)\n"
        "def fails(state, text):\n"
        "    return int(text)\n"
        "state = []\n"
        "with Forked(2, state) as forked:\n"
        "    done = forked.map(where, [(i,) for i in range(7)]) + forked.map(where, [(i,) for i in range(7, 9)])\n"
        "    inner = forked.map(nested, [(0,), (1,)])\n"
        "    try:\n"
        "        forked.map(fails, [('1',), ('x',)])\n"
        "        raised = None\n"
        "    except ValueError as exc:\n"
        "        raised = str(exc)\n"
        "    seconds = forked.seconds\n"
        "with Forked(3, state) as three:\n"       # as many workers as asked, from the first calls on
        "    three.map(where, [(0,), (1,)])\n"
        "    few = len(multiprocessing.active_children())\n"
        "print(json.dumps({'me': os.getpid(), 'done': done, 'inner': inner, 'raised': raised, 'state': state,\n"
        "                  'seconds': seconds, 'few': few}))\n"))
    assert [i for i, _, _ in out["done"]] == list(range(9))
    workers = {pid for _, pid, _ in out["done"]}
    assert out["me"] not in workers and len(workers) <= 2
    # each worker keeps its state between calls; this process's is untouched
    assert out["state"] == [] and sum(1 for _, _, n in out["done"] if n == 1) == len(workers)
    # a worker asked for workers runs its calls itself
    assert all(pids == [pid] * 3 for pid, pids in out["inner"])
    assert "invalid literal" in out["raised"] and out["seconds"] >= 0.0
    assert out["few"] == 3


def test_what_a_map_shares_each_worker_takes_once_before_its_calls():
    out = json.loads(_clean(
        "import json, os, time\n"
        "from pfmdyn.fitting.workers import Forked\n"
        "def take(state, shared):\n"
        "    state.append(shared)\n"
        "def seen(state, i):\n"
        "    time.sleep(0.05)\n"           # long enough for both workers to take calls
        "    return os.getpid(), list(state)\n"
        "state = []\n"
        "with Forked(2, state, take) as forked:\n"
        "    done = forked.map(seen, [(i,) for i in range(6)], shared='a') + forked.map(seen, [(i,) for i in range(6)], shared='b')\n"
        "    here = forked.map(seen, [(0,)], shared='c')\n"        # one call runs here: nothing to share
        "print(json.dumps({'done': done, 'here': here, 'state': state}))\n"))
    first, second = out["done"][:6], out["done"][6:]
    assert all(taken == ["a"] for _, taken in first)
    # a worker took each map's share once, however many of its calls it ran
    assert all(taken in (["a", "b"], ["b"]) for _, taken in second)
    assert len({pid for pid, _ in first + second}) == 2
    assert out["here"][0][1] == [] and out["state"] == []
    with pytest.raises(ValueError, match="receive"):
        Forked(2, []).map(len, [()], shared="a")


def test_the_dearest_calls_go_first_and_the_results_keep_the_calls_order():
    out = json.loads(_clean(
        "import json, time\n"
        "from pfmdyn.fitting.workers import Forked\n"
        "def stamp(state, i):\n"
        "    started = time.perf_counter()\n"
        "    time.sleep(0.1)\n"
        "    return i, started\n"
        "with Forked(2, None) as forked:\n"
        "    done = forked.map(stamp, [(i,) for i in range(4)], costs=[1.0, 2.0, float('inf'), 3.0])\n"
        "    took = forked.took\n"
        "print(json.dumps({'done': done, 'took': took}))\n"))
    assert [i for i, _ in out["done"]] == [0, 1, 2, 3] and len(out["took"]) == 4
    started = {i: t for i, t in out["done"]}
    # the untimed call (inf) and the dearest went first, before the two cheaper ones (in the calls' order,
    # the first two would have)
    assert max(started[2], started[3]) < min(started[0], started[1])


def test_what_is_prepared_before_the_fork_is_done_once_and_the_workers_inherit_it():
    out = json.loads(_clean(
        "import json, os\n"
        "from pfmdyn.fitting.workers import Forked\n"
        "def prepare(state):\n"
        "    state.append(os.getpid())\n"
        "def seen(state, i):\n"
        "    return list(state)\n"
        "forked_state, alone_state = [], []\n"
        "with Forked(2, forked_state, prepare=prepare) as forked:\n"
        "    forked.map(seen, [(0,), (1,)])\n"
        "    seen_forked = forked.map(seen, [(0,), (1,), (2,)])\n"
        "with Forked(1, alone_state, prepare=prepare) as alone:\n"
        "    alone.map(seen, [(0,), (1,)])\n"
        "print(json.dumps({'parent': os.getpid(), 'forked': seen_forked, 'alone': alone_state}))\n"))
    # run once, here, before the fork: every worker's calls see it; with no workers to fork, not at all
    assert out["forked"] == [[out["parent"]]] * 3 and out["alone"] == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forked workers and /proc: Linux")
def test_workers_run_one_blas_thread_and_start_none_they_do_not_use():
    """A worker runs one BLAS thread, and where the calling process already ran one it sets no limit itself:
    OpenBLAS starts its thread pool to apply a limit, and new threads spin for a tenth of a second waiting
    for work, on the cores the workers share (a worker's first fit took three times as long)."""
    out = json.loads(_clean(
        "import json, os\n"
        "import numpy as np\n"
        "from threadpoolctl import threadpool_info, threadpool_limits\n"
        "from pfmdyn.fitting.workers import Forked\n"
        "def threads(state):\n"
        "    np.linalg.svd(np.ones((300, 40)))\n"
        "    return len(os.listdir('/proc/self/task')), [pool['num_threads'] for pool in threadpool_info()]\n"
        "np.ones((200, 200)) @ np.ones((200, 200))\n"
        "with Forked(2, None) as forked:\n"
        "    free = forked.map(threads, [(), ()])\n"
        "with threadpool_limits(1, user_api='blas'):\n"
        "    with Forked(2, None) as forked:\n"
        "        limited = forked.map(threads, [(), ()])\n"
        "print(json.dumps({'free': free, 'limited': limited}))\n"))
    for tasks, blas in out["free"] + out["limited"]:
        assert set(blas) == {1}
    # the worker's own thread and the one that watches its parent, nothing of BLAS's
    assert [tasks for tasks, _ in out["limited"]] == [2, 2]


def test_off_the_main_thread_calls_run_here():
    found = []

    def run():
        with Forked(2, None) as forked:
            found.extend(forked.map(lambda state: os.getpid(), [()] * 3))
    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    assert found == [os.getpid()] * 3


@pytest.mark.parametrize("seed", [2])
def test_workers_do_not_change_the_discrepancy_report(seed):
    """One spectrum (finite-element lever, viscous damping, shuffled rows) analysed in turn and in two
    workers: the same report to the bit, and the workers did run."""
    out = _clean(
        "import json, os, tempfile\n"
        "from pathlib import Path\n"
        "import numpy as np\n"
        "from fe_beam import FEBeam, spectrum\n"
        "from pfmdyn.io.tables import read\n"
        "from pfmdyn.discrepancy.spectrum import analyse\n"
        "beam = FEBeam(2.4, 223e-6, 63.2e3, 1e-5, k1=120.0, k2=100.0, n_elements=150, viscous_hz=1500.0)\n"
        "path = Path(tempfile.mkdtemp()) / 's.csv'\n"
        f"path.write_text(spectrum(beam, np.linspace(150e3, 1300e3, 120), (-1.0, 0.0, 2.0), seed={seed}, "
        "order='shuffled'))\n"
        "data = read(path)\n"
        "reports = []\n"
        "for workers in (1, 2):\n"
        "    before = os.times().children_user\n"
        "    reports.append(analyse(data, workers=workers).to_dict())\n"
        "    print(workers, os.times().children_user - before)\n"
        "print(json.dumps(reports[0], default=str) == json.dumps(reports[1], default=str), reports[0]['missing_effects'])\n")
    serial, forked, same = out.strip().splitlines()
    assert float(serial.split()[1]) == 0.0 and float(forked.split()[1]) > 0.5, out
    assert same == "True ['damping']", out


@pytest.mark.parametrize("kind,seed,spot", [("band_spot", 0, 1.0)])
def test_workers_do_not_change_a_drawn_levers_report(kind, seed, spot):
    """A lever drawn over real ranges (a band-limited spectrum of the hidden-effect sweep, its spot
    candidate fitted from many starts): the same report in turn and in two workers."""
    out = _clean(
        "import json, os, tempfile\n"
        "from pathlib import Path\n"
        "from fe_beam import acquisition_case\n"
        "from pfmdyn.io.tables import read\n"
        "from pfmdyn.discrepancy.spectrum import analyse\n"
        f"text, _ = acquisition_case({seed}, {kind!r}, spot={spot!r})\n"
        "path = Path(tempfile.mkdtemp()) / 's.csv'\n"
        "path.write_text(text)\n"
        "data = read(path)\n"
        "before = os.times().children_user\n"
        "one, two = (json.dumps(analyse(data, workers=w).to_dict(), default=str) for w in (1, 2))\n"
        "print(one == two, os.times().children_user - before)\n")
    same, worked = out.split()
    assert same == "True" and float(worked) > 0.5, out


def test_the_time_budget_counts_the_workers_seconds():
    """A problem whose workers have spent the budget stops before its first step (this process alone
    has spent next to nothing)."""
    from types import SimpleNamespace as S

    from pfmdyn.discrepancy import select

    class Problem:
        worker_seconds = 100.0

        def baseline(self):
            return S(gap=40.0, bic=0.0, model=S(effects=(), parameters=()), internal=[], extra={})

        def locate(self, fit):
            return {}

        def candidates(self, fit):
            raise AssertionError("a step started with the budget spent")

    out = select.run(Problem(), time_budget_s=1.0)
    assert out["steps"][0]["decision"] == "stop: time budget of 1 s used"


def test_the_time_budget_leaves_out_compiling():
    """A step that compiles a kernel, as a fresh install's first run does, goes on to the next step: the
    seconds numba spends compiling are not the budget's (they stopped such a run after its baseline)."""
    from types import SimpleNamespace as S

    import numba
    import numpy as np

    from pfmdyn.discrepancy import select

    numba.njit(lambda x: x + 1)(1)      # numba's own set-up, before the budget starts
    fits = [S(gap=gap, bic=bic, model=S(effects=effects, parameters=()), internal=[], extra={}, parameters=dict)
            for gap, bic, effects in ((40.0, 0.0, ()), (20.0, -100.0, ("background",)))]

    class Problem:
        steps = []

        def baseline(self):
            return fits[0]

        def locate(self, fit):
            return {}

        def candidates(self, fit):
            self.steps.append(fit)
            return ["background"] if len(self.steps) == 1 else []

        def trial(self, fit, name):
            kernel = numba.njit(lambda a: np.linalg.solve(a @ a.T + np.eye(3), np.sin(a).sum(axis=1)))
            kernel(np.ones((3, 3)))     # compiled now: a tenth of a second or more
            return fits[1]

        def without(self, fit, component):
            return fits[0]

    out = select.run(Problem(), time_budget_s=0.05)
    assert len(Problem.steps) == 2 and out["steps"][0]["effect"] == "background"
    assert all("time budget" not in step.get("decision", "") for step in out["steps"]), out["steps"]
