"""How the test session is split over cores (pytest-xdist, ``--dist loadgroup``).

Each file is one group, so a module fixture (the fresh regeneration of ``generated/``, the
book build) is computed once.  The regeneration test and the derivations' doctests share one
group: both solve the beam problems symbolically, and in one process the second finds the
solutions cached instead of deriving them again (a minute of the detection point alone).
"""
from __future__ import annotations

from pathlib import Path

import pytest

SYMBOLIC = ("tests/test_codegen.py", "derivations/")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    for item in items:
        path = Path(item.path).resolve().relative_to(config.rootpath.resolve()).as_posix()
        item.add_marker(pytest.mark.xdist_group("symbolic" if path.startswith(SYMBOLIC) else path))
