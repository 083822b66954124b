"""Every derived result of the sweep, tune and comparison fits carries its standard error (propagated from the
fit's covariance) and holds the truth within 3 of it; the JSON records validate."""
from __future__ import annotations

import copy
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from schema_check import validate  # noqa: E402
from test_sweeps_fit import beam_slope, in_medium, lever_case, mass_at_the_end_pair, sweep_of, write_sweep  # noqa: E402
from test_thermal_fit import tune_case  # noqa: E402

from pfmdyn.discrepancy.reference import compare_sweeps  # noqa: E402
from pfmdyn.discrepancy.sweep import fit_sweep  # noqa: E402
from pfmdyn.discrepancy.thermal import fit_thermal  # noqa: E402
from pfmdyn.io import documents  # noqa: E402
from pfmdyn.io.sweeps import read_sweep_table  # noqa: E402
from pfmdyn.medium import mass_per_length  # noqa: E402


def _true_q(case) -> float:
    """The true lever's first-mode Q in its medium (the Cantilever takes its resonance there), by the exact damped
    root (in_medium's is Sader's relation)."""
    from pfmdyn import Cantilever
    from pfmdyn.analysis.resonances import resonances

    lever = Cantilever(case["k"], in_medium(case)[0], case["L"], width=case["w"], medium=case["medium"],
                       viscous_loss=case["g"])
    return float(resonances(lever, None, modes=1).free.q[0])


def _covers(value, stderr, truth):
    assert stderr is not None and math.isfinite(stderr) and stderr > 0, (value, stderr)
    assert abs(value - truth) < 3 * stderr, (value, stderr, truth)


def test_a_sweeps_derived_results_carry_errors_that_hold_the_truth(tmp_path):
    rng, case = lever_case(2)
    draws = copy.deepcopy(rng)
    f, y = sweep_of(rng, case)
    # sweep_of's own draws again: the gain's and the background's
    f0, q = in_medium(case)
    lo, hi = f0 * max(1 - 3 / q, 0.4), f0 * min(1 + 3 / q, 1.8)
    draws.uniform(lo, hi, len(f))
    gain = (1 + draws.uniform()) * np.exp(1j * draws.uniform(-np.pi, np.pi)) / np.abs(beam_slope(f0, **case))[0]
    b0 = 0.3 * np.exp(1j * draws.uniform(-np.pi, np.pi))
    fit = fit_sweep(read_sweep_table(write_sweep(tmp_path / "s.txt", f, y, rng)), case["k"], case["L"],
                    case["medium"], width=case["w"])
    errors = fit["uncertainties"]
    _covers(fit["vacuum_resonance"], errors["vacuum_resonance"]["stderr"], case["f_vac"])
    _covers(fit["quality_factor"], errors["quality_factor"]["stderr"], _true_q(case))
    grid = np.linspace(f.min(), f.max(), 200001)
    truth = np.abs(gain * beam_slope(grid, **case) + b0 + 0.1 * (grid / f0 - 1))
    _covers(fit["peak_hz"], errors["peak_hz"]["stderr"], grid[np.argmax(truth)])
    # the background's constant at the sweep's centre (the model's b0 + b1 (f / f_c - 1))
    centre = fit.centre_hz
    measured = complex(*fit["background"]["value"][0])
    measured = np.conj(measured) if fit["phase_reversed"] else measured
    truth_b0 = b0 + 0.1 * (centre / f0 - 1)
    re, im = fit["background"]["stderr"][0]
    _covers(measured.real, re, truth_b0.real)
    _covers(measured.imag, im, truth_b0.imag)
    assert all(v > 0 for v in fit["gain"]["stderr"])
    doc = documents.sweep_fit(fit.to_dict(), given=["spring_constant", "length"])
    validate(doc)
    for name in ("vacuum_resonance", "free_quality_factor", "amplitude_peak", "gain", "background"):
        assert doc["results"][name]["stderr"] is not None, name


def test_a_tunes_derived_results_carry_errors_that_hold_the_truth():
    case, tune = tune_case(2)
    fit = fit_thermal(tune, case["k"], case["L"], case["medium"], case["temperature"], width=case["w"])
    errors = fit["uncertainties"]
    _covers(fit["vacuum_resonance"], errors["vacuum_resonance"]["stderr"], case["f_vac"])
    _covers(fit["quality_factor"], errors["quality_factor"]["stderr"], _true_q(case))
    _covers(fit["matching_spring_constant"], errors["matching_spring_constant"]["stderr"], case["k"])
    _covers(fit["detection_scale"], errors["detection_scale"]["stderr"], 1.0)
    # the floor: 5 % of the peak's amplitude (tune_case)
    floor = fit["white_floor"]
    assert errors["white_floor"]["stderr"] > 0 and errors["white_floor"]["stderr"] < 0.1 * floor
    doc = documents.thermal_fit(fit.to_dict(), given=["spring_constant", "length"])
    validate(doc)
    for name in ("vacuum_resonance", "free_quality_factor", "detection_scale", "white_floor", "matching_spring_constant"):
        assert doc["results"][name]["stderr"] is not None, name


def test_a_comparisons_lever_mass_gain_and_background_carry_errors(tmp_path):
    case, before, f1, y1, rng = mass_at_the_end_pair(tmp_path)
    out = compare_sweeps(read_sweep_table(write_sweep(tmp_path / "a.txt", f1, y1, rng)), before, 1.0)
    truth = mass_per_length(case["k"], case["L"], case["f_vac"]) * case["L"]
    _covers(out["lever_mass"], out["uncertainties"]["lever_mass"]["stderr"], truth)
    doc = documents.sweep_comparison(out.to_dict())
    validate(doc)
    for name in ("lever_mass", "gain", "background"):
        assert doc["results"][name]["stderr"] is not None, name
    # the text as the JSON: each with its error
    line = next(text for text in out.report().splitlines() if text.startswith("  lever mass"))
    assert f"+- {out['uncertainties']['lever_mass']['stderr']:.2g} kg" in line
    assert line.count(" +- ") == 1 + 2 + 4 and "undetermined" not in line
