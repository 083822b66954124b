"""A compiled kernel's cached machine code follows the files it was compiled from (pfmdyn.compiled)."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("numba")

KERNEL = """
import numba
from pfmdyn.compiled import forget_when_changed
from . import piece

_step = numba.njit(cache=True)(piece.step)


@numba.njit(cache=True)
def doubled(x):
    return 2 * _step(x)
"""


def _run(tmp_path) -> int:
    """``doubled(1)`` in a fresh interpreter."""
    code = "from pkg import kernel; print(kernel.doubled(1))"
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    return int(done.stdout)


@pytest.mark.parametrize("forget", [True, False])
def test_a_kernel_follows_the_piece_it_compiles_in(tmp_path, forget):
    """A kernel calling another file's compiled function: after that file changes, the kernel runs the new code
    with :func:`~pfmdyn.compiled.forget_when_changed`, and numba alone keeps the old one (what the test guards)."""
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "piece.py").write_text("def step(x):\n    return x + 1\n")
    (package / "kernel.py").write_text(KERNEL + ("forget_when_changed(__name__, piece)\n" if forget else ""))
    assert _run(tmp_path) == 4                  # compiled and cached
    assert _run(tmp_path) == 4                  # from the cache
    (package / "piece.py").write_text(textwrap.dedent("""\
        def step(x):
            return x + 2        # changed (the size too: numba's own stamp is the file's time and size)
    """))
    assert _run(tmp_path) == (6 if forget else 4)
