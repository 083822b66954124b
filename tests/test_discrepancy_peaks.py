"""The peak prominences of ``discrepancy`` against SciPy's, and the command's imports without ``scipy.signal``."""
from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.signal import peak_prominences

from pfmdyn.discrepancy.peaks import prominences


@pytest.mark.parametrize("seed", range(4))
def test_prominences_are_scipys(seed):
    """Random walks and small integers (plateaus, equal lows on both sides), a NaN now and then, the local
    maxima or any indices: the same rises and bases, to the bit."""
    rng = np.random.default_rng(seed)
    for trial in range(400):
        n = int(rng.integers(1, 80))
        x = rng.integers(0, 6, n).astype(float) if trial % 2 else rng.normal(size=n).cumsum()
        if trial % 7 == 0:
            x[rng.integers(0, n)] = np.nan
        if trial % 3 == 0:
            peaks = np.unique(rng.integers(0, n, 6))
            peaks = peaks[~np.isnan(x[peaks])]
        else:
            peaks = np.flatnonzero(np.r_[False, (x[1:-1] >= x[:-2]) & (x[1:-1] > x[2:]), False]) if n > 2 \
                else np.zeros(0, int)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # SciPy warns of a peak that rises nowhere
            want = peak_prominences(x, peaks)
        got = prominences(x, peaks)
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b, err_msg=f"x={x.tolist()}, peaks={peaks.tolist()}")


def test_discrepancy_imports_no_scipy_signal():
    """``scipy.signal`` (with ``scipy.stats``) took a third of a second of every ``discrepancy`` command."""
    code = ("import sys; import pfmdyn.commands.discrepancy, pfmdyn.discrepancy.spectrum; "
            "print(sorted(m for m in ('scipy.signal', 'scipy.stats') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
