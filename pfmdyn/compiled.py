"""The compiled kernels' machine code on disk, kept true to every file it was compiled from.

numba keys a kernel's cache on the stamp of the file that defines it.  A kernel that calls another file's
compiled function (a generated piece, a step of another kernel module) or reads its constants holds a copy of
them in its machine code, and a change to that file leaves the copy in place: after ``pfmdyn codegen`` rewrote
``generated/lever_pieces.py`` the tip point's kernel went on running the old pieces.  :func:`forget_when_changed`,
called by each kernel module as it is imported, drops its cached kernels when one of those files has changed
since they were cached (an install replaces every file, so there this changes nothing).
"""
from __future__ import annotations

import hashlib
import sys
from pathlib import Path

__all__ = ["forget_when_changed"]


def forget_when_changed(module: str, *sources) -> bool:
    """Drop the cached machine code of the kernels module ``module`` defines (its numba functions with
    ``cache=True``) when the files of the modules ``sources``, whose functions or constants they compile in,
    differ from when it was cached (a stamp beside numba's cache records their sha256); True if dropped.

    Without such kernels, or where numba keeps its cache elsewhere than this numba version does, nothing is
    done (numba's own behaviour).

    >>> import numpy as np
    >>> forget_when_changed("numpy", np)        # numpy defines no compiled kernels
    False
    """
    from numba.core.dispatcher import Dispatcher

    kernels = [f for f in vars(sys.modules[module]).values()
               if isinstance(f, Dispatcher) and f.py_func.__module__ == module
               and getattr(f, "_cache", None) is not None]
    if not kernels:
        return False
    digest = hashlib.sha256(b"".join(Path(m.__file__).read_bytes() for m in sources)).hexdigest()
    try:
        stamp = Path(kernels[0]._cache._cache_path) / f"{module.rsplit('.', 1)[-1]}.sources"
        if stamp.exists() and stamp.read_text() == digest:
            return False
        for kernel in kernels:
            kernel._cache.flush()
        stamp.write_text(digest)
    except (AttributeError, OSError):       # another numba's internals, a cache not to be written: as numba does
        return False
    return True
