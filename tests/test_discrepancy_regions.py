"""A gap that cannot hide a misfit (:mod:`pfmdyn.discrepancy.regions`): a misfit confined to the
resonance is reported there, though the overall gap, dominated by the floor, looks like noise."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from test_thermal_fit import tune_case  # noqa: E402

from pfmdyn.discrepancy.thermal import fit_thermal  # noqa: E402
from pfmdyn.io.thermal_tune import ThermalTune  # noqa: E402


def _fit(tune, case):
    return fit_thermal(tune, case["k"], case["L"], case["medium"], case["temperature"], width=case["w"])


def test_a_misfit_at_the_peak_only_is_not_fitted_to_the_noise():
    case, tune = tune_case(2, points=1500)
    clean = _fit(tune, case)
    assert clean["gap"] < 2 and clean["worst_region"]["gap"] < 2
    assert "(1: fitted to the noise)" in clean.report()
    # the same tune with its peak flattened by 20 % over a few bins (the independent beam's shape
    # is no longer any lever's): a misfit the 1500-point floor dilutes
    f0 = clean.lever.free_resonance
    peak = np.abs(tune.frequency_hz - f0) < 0.5 * f0 / clean["quality_factor"]
    asd = np.where(peak, 0.8 * tune.asd, tune.asd)
    out = _fit(ThermalTune("tune.nid", tune.frequency_hz, asd, "m", {}, {}), case)
    worst = out["worst_region"]
    assert out["gap"] < 2 < worst["gap"], (out["gap"], worst)
    assert worst["region"].startswith("resonance at") and worst["band_hz"][0] < f0 < worst["band_hz"][1]
    text = out.report()
    assert "fitted to the noise)" not in text and "not fitted to the noise there" in text
