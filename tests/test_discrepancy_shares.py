"""``pfmdyn discrepancy`` names nothing that does not explain: each named effect's share of the
misfit is stated, and while the final gap stays above a few noise levels an effect is named only
when it takes a large share of the misfit on its own; the rest is ``unexplained``, with where and
how large.

The rule is checked on a stub problem (gaps as a table of effect sets, no fitting) and on the
independent finite-element beam (``tests/fe_beam.py``) read at a laser spot away from the free
end, with a background, viscous damping and a resonance outside the library (the instrument's).
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam, silicon_lever, spectrum  # noqa: E402

from pfmdyn.discrepancy import select  # noqa: E402
from pfmdyn.discrepancy.report import report as make_report  # noqa: E402
from pfmdyn.discrepancy.spectrum import analyse  # noqa: E402
from pfmdyn.io.tables import read  # noqa: E402

N = 2000


class Stub:
    """A problem whose fits are gaps looked up by effect set (``gaps(effects, refit)``: ``refit`` for
    the fits of :meth:`without`, which start from the current values)."""

    def __init__(self, gaps, library=("damping_viscous", "tilt", "tip_mass", "background")):
        self.gaps, self.library = gaps, library

    def make(self, effects, refit=False) -> SimpleNamespace:
        effects = tuple(effects)
        gap, k = self.gaps(set(effects), refit), 2 + len(effects)
        public = tuple(dict.fromkeys("damping" if e.startswith("damping_") else e for e in effects))
        model = SimpleNamespace(effects=effects, parameters=(), public_effects=list(public),
                                damping_mechanisms=[e[8:] for e in effects if e.startswith("damping_")])
        return SimpleNamespace(gap=gap, bic=N * math.log(gap**2) + k * math.log(N), model=model, k=k, n=N,
                               internal=np.array([]), fitted=None, extra={}, parameters=lambda: {},
                               report=lambda: "")

    def baseline(self):
        return self.make(())

    def candidates(self, fit):
        return [e for e in self.library if e not in fit.model.effects]

    def trial(self, fit, name):
        return self.make(fit.model.effects + (name,))

    def without(self, fit, component):
        return self.make((e for e in fit.model.effects if e != component), refit=True)

    def locate(self, fit):
        return {"band_hz": [1.0e5, 2.0e5], "signature": "peak width"}


def _after_damping(factor: float, end: float | None = None):
    """Damping takes 188 -> 60; a tilt and then a tip mass each multiply the gap by ``factor``
    (the tip mass: to ``end`` when given); alone they do nothing."""
    def gaps(effects, refit):
        if "damping_viscous" not in effects:
            return 188.0
        gap = 60.0 * (factor if "tilt" in effects else 1.0)
        if "tip_mass" in effects:
            gap = end if end and "tilt" in effects else factor * gap
        return gap
    return gaps


def test_material_effects_that_explain_less_than_is_left_are_not_named():
    """Far from the noise: a tilt and a tip mass each lower the gap by 26 % after damping (material:
    BIC and 25 %), 60 -> 32.9, but each explains less than stays unexplained (45 % of what the
    others leave): removed with the reason; damping (90 % of the misfit) stays; ``unexplained``
    gives where, the gap and the share left; JSON and summary state the shares."""
    result = select.run(Stub(_after_damping(0.74)))
    assert [s["effect"] for s in result["steps"][:3]] == ["damping_viscous", "tilt", "tip_mass"]
    report = make_report(result)
    assert report["missing_effects"] == ["damping"] and report["gap_after"] == 60.0
    assert report["effect_shares"]["damping"]["share"] == pytest.approx((188**2 - 60**2) / (188**2 - 1))
    left = report["unexplained"]
    assert left["where"] == [1.0e5, 2.0e5] and left["gap"] == 60.0
    assert left["share"] == pytest.approx((60**2 - 1) / (188**2 - 1))
    assert set(left["small_share"]) == {"tilt", "tip_mass"} and max(left["small_share"].values()) < 0.5
    text = report.report()
    assert "missing effects: damping (viscous) [89.8% of the misfit]" in text, text
    assert "(gap 60 x noise, 10.2% of the baseline misfit)" in text, text
    assert "not named, under 50% of the misfit the others leave: tilt (45.3%), tip_mass (45.3%)" in text, text
    json.dumps(dict(report))


def test_effects_left_after_an_implausible_one_is_dropped_are_named_only_with_their_share():
    """The complaint's path: damping, a tilt and a tip mass take 188 -> 12; damping is then dropped
    as implausible, and the tilt and the tip mass left take only 188 -> 172 (16 %), although each
    looks needed against its refit without it, stuck in a worse minimum (230): measured from the
    baseline (a fit of fewer effects), neither is named, and the report is the baseline's with the
    whole misfit unexplained."""
    def gaps(effects, refit):
        effects = effects - {"background"}        # no help
        if "damping_viscous" in effects:
            return {1: 60.0, 2: 30.0, 3: 12.0}[len(effects)]
        return 172.0 if len(effects) == 2 else (230.0 if refit and effects else 188.0)
    import pfmdyn.discrepancy.select as module
    stub = Stub(gaps)
    original = module.implausible
    module.implausible = lambda fit: ({"damping_viscous": "viscous_loss at the upper bound"}
                                      if "damping_viscous" in fit.model.effects else {})
    try:
        report = make_report(select.run(stub))
    finally:
        module.implausible = original
    assert report["missing_effects"] == [] and report["gap_after"] == 188.0, report["missing_effects"]
    left = report["unexplained"]
    assert set(left["implausible"]) == {"damping_viscous"} and set(left["small_share"]) == {"tilt", "tip_mass"}
    assert left["share"] == 1.0 and left["where"] == [1.0e5, 2.0e5]
    assert max(left["small_share"].values()) < 0.2


def test_effects_that_bring_the_gap_to_the_noise_are_named_with_their_share():
    """The same path ending at the noise (gap 1.2): all three named, each with its share; the
    tilt and the tip mass take little of the baseline's misfit but all of what the others leave."""
    report = make_report(select.run(Stub(_after_damping(0.68, 1.2))))
    assert sorted(report["missing_effects"]) == ["damping", "tilt", "tip_mass"] and report["unexplained"] is None
    shares = report["effect_shares"]
    assert shares["tilt"]["share"] < 0.06 and shares["tilt"]["share_of_rest"] > 0.99
    assert report["explained_share"] == pytest.approx(1 - (1.2**2 - 1) / (188**2 - 1))
    assert "tilt [4.7% of the misfit, 100.0% of what the others leave]" in report.report()


def _instrument_resonance(text: str, frequency_hz: float, size: float) -> str:
    """``text`` with a resonance outside the lever added to every sweep (a holder or piezo mode: the
    same complex Lorentzian, Q 100, peak ``size`` times the median |response|, at every bias)."""
    lines = text.splitlines()
    out = []
    rows = np.array([[float(c) for c in line.split(",")] for line in lines if line[0].isdigit()])
    scale = size * np.median(np.hypot(rows[:, 2], rows[:, 3]))
    for line in lines:
        if not line[0].isdigit():
            out.append(line)
            continue
        f, v, x, y = (float(c) for c in line.split(","))
        z = complex(x, y) + scale * 1j * frequency_hz**2 / 100 / (frequency_hz**2 - f**2 + 1j * f * frequency_hz / 100)
        out.append(f"{f!r},{v!r},{float(z.real)!r},{float(z.imag)!r}")
    return "\n".join(out) + "\n"


def _spot_lever(seed: int, size: float) -> tuple[str, dict]:
    """A lever (k 0.2-40 N/m) read at 0.7 L, viscous damping (free mode-1 Q 20-63), a background of
    10 % of the median response, three biases, 0.5 % noise, 400 frequencies over three contact
    modes, and an instrument resonance of ``size`` between contact modes 1 and 2."""
    rng = np.random.default_rng(seed)
    k, L, w, H, f1 = silicon_lever(rng)
    k1 = k * 10 ** rng.uniform(1, 2.5)
    k2 = k1 * rng.uniform(0.5, 1.0)
    q1 = 10 ** rng.uniform(1.3, 1.8)
    beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, viscous_hz=f1 / q1, spot=0.7, n_elements=60)
    contact = FEBeam(k, L, f1, H, k1=k1, k2=k2, n_elements=60).contact_resonances(4)
    freq = np.linspace(0.5 * contact[0], 0.5 * (contact[2] + contact[3]), 400)
    text = spectrum(beam, freq, (-2.0, 0.0, 2.0), noise=0.005, background=0.1, seed=seed, order="instrument")
    extra = 0.5 * (contact[0] + contact[1])
    return _instrument_resonance(text, extra, size), {"k1": k1, "contact_hz": contact[:3], "extra_hz": extra}


@pytest.mark.slow
def test_spot_lever_with_a_resonance_outside_the_library_is_unexplained_there(tmp_path):
    """A lever read at 0.7 L with a background, viscous damping and an instrument resonance between
    contact modes 1 and 2 (peak 4 x the median response): no library effect reaches it, the gap
    stays tens of noise levels.  The report says ``unexplained``, how large (gap, share of the
    misfit) and where (a band around the instrument's resonance); it names nothing false and
    nothing that explains less than stays unexplained; every named effect's share is in the JSON
    and the summary.  Damping and the spot are named (they take 84 % and 19 % of the misfit)."""
    text, truth = _spot_lever(1, 4.0)
    path = tmp_path / "s.csv"
    path.write_text(text)
    with threadpool_limits(1, user_api="blas"):        # as the command runs it (without its time budget)
        result = analyse(read(path))
    summary, report = result.report(), json.loads(json.dumps(result.to_dict()))
    named = report["missing_effects"]
    assert {"damping", "spot_position"} <= set(named) <= {"damping", "spot_position", "background"}, named
    left = report["unexplained"]
    assert left["gap"] == report["gap_after"] > 10 and 0 < left["share"] < 0.01, left
    assert left["where"][0] <= truth["extra_hz"] <= left["where"][1], (left["where"], truth["extra_hz"])
    assert left["where"][1] - left["where"][0] < 0.1 * truth["extra_hz"], left["where"]
    assert f"(gap {left['gap']:.3g} x noise, {left['share']:.1%} of the baseline misfit)" in summary, summary
    shares = report["effect_shares"]
    assert set(shares) == set(named) and report["explained_share"] > 0.99
    for name in named:
        assert shares[name]["share_of_rest"] >= 0.5, (name, shares[name])
        mechanisms = f" ({', '.join(report['damping_mechanisms'])})" if name == "damping" else ""
        assert f"{name}{mechanisms} [{shares[name]['share']:.1%} of the misfit" in summary, summary
    assert shares["damping"]["share"] > 0.5 and shares["spot_position"]["share"] > 0.1, shares
