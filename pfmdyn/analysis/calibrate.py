"""The spring constant of a free lever from its thermal tune, two independent ways.

* **Thermal** (equipartition): the first mode is fitted as a damped oscillator over a white floor
  (:func:`pfmdyn.analysis.thermal.fit_thermal_peaks`; bin-averaged where the peak is narrower than a few
  bins and that fits, or with a resonance that drifted over the averages where that fits better, said in
  :attr:`Calibration.model`); its mean square ``pi A**2 f0 Q / 2`` (generated
  ``formulas.oscillator_mean_square``) in metres (an ASD in volts times ``invols``) gives
  ``k = chi kB T / <d*^2>`` with the first-mode factor ``chi`` of the optical lever read at the spot
  through a static InvOLS measured with the tip at ``tip_position`` (generated
  ``formulas.thermal_factor_slope*``, derived in ``derivations/calibration.py``; 0.817 at the end).
  A spectrum already in metres was converted by the instrument; it is taken as converted with the
  instrument's static InvOLS, which is what the factor assumes (said in :attr:`Calibration.assumptions`).
* **Sader** (Sader, Chon & Mulvaney 1999): ``k = 0.1906 rho b**2 L Q Gamma_i(Re) omega_f**2`` with the
  fitted f and Q, the medium's density and viscosity and the lever's plan (``formulas.sader_spring_constant``).

Both give the spring constant *at the tip* (``k (L/x_tip)**3`` for a set-back tip, Proksch et al. 2004).
Uncertainties (standard, 1 sigma) combine the fit's covariance with the stated inputs: the length and
width (defaults 2 % and 5 % of the nominal values, a datasheet's usual spread), the temperature (1 K);
the InvOLS carries none here (it is named when it could reconcile the two).  The two are *consistent*
when they differ by less than twice their combined uncertainty; otherwise :attr:`Calibration.reconcile`
lists each single input that would make them agree and the factor it would need, when that factor is
plausible for it (:func:`plausible_factors`); none may be.  They are never averaged.  The fitted peak's
uncertainty includes its shape: how far its parameters move when the spectrum is weighted in power
instead of in log (:class:`pfmdyn.analysis.thermal.ThermalPeak`), named ``peak shape``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..constants import BOLTZMANN
from ..errors import UserError
from ..generated import formulas
from ..io.thermal_tune import ThermalTune
from ..medium import Medium, hydrodynamic_function, reynolds_number
from .thermal import ThermalPeak, broad_mode, fit_thermal_peaks

LIQUID_DENSITY = 100.0
"""kg/m^3: a fluid denser than this is a liquid (air 1.2, water 1000), whose load the oscillator misses."""
LOW_Q = 30.0
"""Below this Q of the oscillator's fit the fluid's load changes across the peak: the whole lever instead."""

__all__ = ["Estimate", "LeverMode", "Calibration", "thermal_factor", "thermal_spring_constant",
           "sader_spring_constant", "first_mode", "first_mode_model", "stated_uncertainties", "calibrate"]
LENGTH_TOLERANCE, WIDTH_TOLERANCE, TEMPERATURE_UNCERTAINTY = 0.02, 0.05, 1.0
"""Default standard uncertainties: relative for a nominal length and width, K for the temperature."""
COVERAGE = 2.0
"""Two estimates agree when they differ by less than this many combined standard uncertainties."""


@dataclass(frozen=True)
class Estimate:
    """A spring constant (N/m) with its standard uncertainty and the relative share of each source;
    NaN with ``reason`` when the inputs cannot determine it."""

    value: float
    stderr: float
    sources: dict = field(default_factory=dict)
    reason: str = ""

    @property
    def determined(self) -> bool:
        return math.isfinite(self.value)


@dataclass(frozen=True)
class LeverMode:
    """The first mode from the fluid-loaded whole lever (:func:`pfmdyn.discrepancy.thermal.lever_mode`):
    ``peak`` its resonance and Q in the medium (the oscillator of the same mean square, for the figure),
    ``spring_constant`` its thermal k at the tip (N/m), ``sources`` the relative share of each uncertainty,
    ``fit`` the whole-lever fit."""

    peak: ThermalPeak
    spring_constant: float
    sources: dict
    fit: object = field(default=None, repr=False)


def thermal_factor(spot_position: float = 1.0, tip_position: float = 1.0) -> float:
    """First-mode factor ``chi`` of ``k_tip = chi kB T / <d*^2>`` for an optical lever read at the spot and
    calibrated statically with the tip at ``tip_position`` (fractions of L).

    >>> round(thermal_factor(), 4), round(thermal_factor(0.9), 4), round(thermal_factor(1.0, 0.95), 4)
    (0.8174, 0.8316, 0.8605)
    """
    beyond = spot_position >= tip_position
    f = formulas.thermal_factor_slope if beyond else formulas.thermal_factor_slope_inside
    return float(f(spot_position, tip_position))


def thermal_spring_constant(mean_square: float, temperature: float, spot_position: float = 1.0,
                            tip_position: float = 1.0) -> float:
    """``chi kB T / <d*^2>`` (N/m): equipartition of the first mode's mean square (m^2).

    >>> round(thermal_spring_constant(1e-22, 300.0), 2)
    33.86
    """
    return thermal_factor(spot_position, tip_position) * BOLTZMANN * temperature / mean_square


def sader_spring_constant(medium: Medium, width: float, length: float, frequency_hz: float, quality_factor: float,
                          tip_position: float = 1.0) -> float:
    """Sader's spring constant (N/m) at the tip from the first mode's frequency and Q in ``medium``; NaN
    outside the hydrodynamic function's fitted range.

    >>> round(sader_spring_constant(Medium.air(313.15), 40e-6, 225e-6, 179.8e3, 442.0), 2)
    25.15
    """
    gamma = hydrodynamic_function(reynolds_number(medium, frequency_hz, width))
    k = formulas.sader_spring_constant(medium.density, width, length, quality_factor, gamma.imag, frequency_hz)
    return float(k) / tip_position**3


@dataclass(frozen=True)
class Calibration:
    """What :func:`calibrate` found: the fitted first mode, both estimates, their agreement."""

    peak: ThermalPeak
    thermal: Estimate
    sader: Estimate
    consistent: bool | None
    reconcile: list
    assumptions: list
    inputs: dict
    instrument: dict
    plausible: dict = field(default_factory=dict)
    model: str = "damped oscillator"
    """The first mode's fit (:func:`first_mode_model`)."""
    lever_fit: object = field(default=None, repr=False)
    """The whole-lever fit (:class:`pfmdyn.discrepancy.thermal.ThermalFit`) when ``model`` is the lever's."""

    def to_json(self) -> dict:
        """The JSON document of ``pfmdyn calibrate`` (undetermined numbers are NaN, written null)."""
        def estimate(e):
            return {"spring_constant": e.value, "spring_constant_stderr": e.stderr,
                    "sources": {k: v for k, v in e.sources.items()}, "reason": e.reason}
        return {"free_resonance": self.peak.frequency_hz, "free_resonance_stderr": self.peak.frequency_uncertainty_hz,
                "free_quality_factor": self.peak.quality_factor,
                "free_quality_factor_stderr": self.peak.quality_factor_uncertainty,
                "thermal": estimate(self.thermal), "sader": estimate(self.sader), "consistent": self.consistent,
                "reconcile": [{"input": name, "factor": factor, "why": self.plausible[name][2]}
                              for name, factor in self.reconcile],
                "assumptions": list(self.assumptions), "inputs": dict(self.inputs), "instrument": dict(self.instrument)}


FAINT = 1.1
"""The least prominence of a first mode looked for when none stands out 1.5 times (a stiff lever's peak twice
its white floor on a 1/f rise several times that floor: 1.3 over its surroundings; the median over 5 bins
of a spectrum of 1,000 averages scatters by ~0.7 %)."""


def first_mode(tune: ThermalTune) -> ThermalPeak:
    """The first mode as a damped oscillator over a white floor (:func:`~pfmdyn.analysis.thermal.fit_thermal_peaks`,
    or one over the whole band for a mode too wide for their windows, or among fainter peaks (:data:`FAINT`)).

    >>> f = np.linspace(0, 4e5, 8001)
    >>> round(first_mode(ThermalTune("t", f, formulas.oscillator_asd(f, 1.8e5, 440.0, 1e-15, 3e-14), "m", {}, {})).quality_factor)
    440
    """
    try:
        peaks = [p for p in fit_thermal_peaks(tune.frequency_hz, tune.asd) if p.mode == 1] or \
            [p for p in (broad_mode(tune.frequency_hz, tune.asd),) if p] or \
            [p for p in fit_thermal_peaks(tune.frequency_hz, tune.asd, min_prominence=FAINT) if p.mode == 1]
    except UserError as exc:                # a spectrum too short, unsorted...: the message names the file
        raise UserError(f"{tune.path}: {exc}", exc.quantity) from None
    if not peaks:
        raise UserError(f"{tune.path}: no resonance peak found in the thermal spectrum")
    return peaks[0]


def first_mode_model(medium: Medium, peak: ThermalPeak | None, length: float | None, width: float | None, unit: str,
                     invols: float | None) -> str:
    """Which fit gives ``pfmdyn calibrate`` its first mode: ``"damped oscillator"`` or ``"fluid-loaded lever"``.

    This is the one place where the two thermal fits of a tune part.  ``pfmdyn discrepancy`` explains a tune
    with the whole lever in its fluid (:func:`pfmdyn.discrepancy.thermal.fit_thermal`: every mode, Sader's
    hydrodynamic load); ``calibrate`` takes the same fit where the fluid matters: in a liquid (denser than
    :data:`LIQUID_DENSITY`) or at a Q below :data:`LOW_Q`, the load changes across the peak, and an
    oscillator's f, Q and area are biased (resonance 1-6 % high, k up to 25 % off in water;
    ``benchmarks/thermal_regimes.py``).  Elsewhere it fits the damped oscillator (Hutter & Bechhoefer):
    the same numbers to a fraction of a per cent when Q is high, needs neither the lever's plan nor its k
    (the whole lever does: it iterates k), is the model the instrument's own fit uses (like beside like),
    and takes milliseconds.  The whole lever also needs the spectrum in metres (or the InvOLS).  ``peak``
    None: no oscillator was found.

    >>> peak = ThermalPeak(1, 2e4, 3.0, 1.0, 0.0, ((0,) * 4,) * 4)
    >>> first_mode_model(Medium.water(), peak, 2e-4, 3e-5, "m", None), first_mode_model(Medium.water(), peak, None, None, "m", None)
    ('fluid-loaded lever', 'damped oscillator')
    """
    loaded = medium.density > LIQUID_DENSITY or (peak is not None and peak.quality_factor < LOW_Q)
    converted = unit == "m" or invols is not None
    return "fluid-loaded lever" if loaded and length is not None and width is not None and converted \
        else "damped oscillator"


def stated_uncertainties(length: float | None, width: float | None, length_uncertainty: float | None,
                         width_uncertainty: float | None) -> tuple:
    """Standard uncertainties (m) of the length and width: the given ones, else :data:`LENGTH_TOLERANCE`
    and :data:`WIDTH_TOLERANCE` of the nominal values (None without the value).

    >>> stated_uncertainties(2.5e-4, 4e-5, None, 1e-6)
    (5e-06, 1e-06)
    """
    u_length = None if length is None else LENGTH_TOLERANCE * length if length_uncertainty is None else length_uncertainty
    u_width = None if width is None else WIDTH_TOLERANCE * width if width_uncertainty is None else width_uncertainty
    return u_length, u_width


def _combine(value: float, sources: dict) -> Estimate:
    return Estimate(value, abs(value) * math.sqrt(sum(v**2 for v in sources.values())), sources)


PLAUSIBLE_INVOLS = (0.5, 2.0)
"""A static InvOLS can be off by this factor (taken on a soft surface, the spot moved since, another
sensitivity used to convert the spectrum); beyond it, it is no reconciliation."""
PLAUSIBLE_HEATING = 30.0
"""K: a lever can be this much warmer or cooler than stated (the laser heats it, the room differs)."""


def plausible_factors(length_tolerance: float, width_tolerance: float, temperature: float) -> dict:
    """The factors each input could plausibly be off by (low, high, why): three standard uncertainties
    of a length or width (relative ones given), :data:`PLAUSIBLE_INVOLS`, :data:`PLAUSIBLE_HEATING`.

    >>> r = plausible_factors(0.02, 0.05, 300.0); r["length"][:2], r["temperature"][:2]
    ((0.94, 1.06), (0.9, 1.1))
    """
    return {"invols": (*PLAUSIBLE_INVOLS, "the static InvOLS, or the sensitivity the spectrum was converted with"),
            "length": (1 - 3 * length_tolerance, 1 + 3 * length_tolerance, "the length, within three standard uncertainties"),
            "width": (1 - 3 * width_tolerance, 1 + 3 * width_tolerance, "the width, within three standard uncertainties"),
            "temperature": (1 - PLAUSIBLE_HEATING / temperature, 1 + PLAUSIBLE_HEATING / temperature,
                            f"the lever's temperature, within {PLAUSIBLE_HEATING:g} K (laser heating, the room)")}


def _bisect(f, low: float, high: float):
    """Root of ``f`` on ``[low, high]`` in log space, or None without a sign change."""
    from scipy.optimize import brentq

    grid = np.geomspace(low, high, 25)
    values = np.array([f(g) for g in grid])
    change = np.flatnonzero(np.isfinite(values[:-1]) & np.isfinite(values[1:]) & (values[:-1] * values[1:] <= 0))
    if not change.size:
        return None
    low, high = grid[change[0]], grid[change[0] + 1]
    return math.exp(brentq(lambda t: f(math.exp(t)), math.log(low), math.log(high), xtol=1e-12))


def calibrate(tune: ThermalTune, *, length: float | None = None, width: float | None = None, medium: Medium,
              temperature: float, invols: float | None = None, spot_position: float = 1.0,
              tip_position: float = 1.0, length_uncertainty: float | None = None,
              width_uncertainty: float | None = None, temperature_uncertainty: float = TEMPERATURE_UNCERTAINTY,
              medium_factory=None, mode: ThermalPeak | LeverMode | None = None) -> Calibration:
    """Both spring constants of the lever whose thermal tune is ``tune``.

    ``medium_factory(temperature)`` rebuilds the medium at another temperature (how the temperature's
    uncertainty and a reconciling temperature reach Sader's estimate); None keeps ``medium`` fixed.
    ``mode``: the first mode already fitted (a :class:`LeverMode` gives the thermal k too); None: the
    damped oscillator (:func:`first_mode`; which to use: :func:`first_mode_model`).

    Examples
    --------
    >>> f = np.linspace(0, 4e5, 8001)
    >>> tune = ThermalTune("synthetic", f, formulas.oscillator_asd(f, 1.8e5, 440.0, 1.03e-15, 3e-14), "m", {}, {})
    >>> c = calibrate(tune, length=225e-6, width=40e-6, medium=Medium.air(313.15), temperature=313.15)
    >>> round(c.thermal.value, 1), round(c.sader.value, 1), c.consistent
    (26.8, 25.1, True)
    """
    lever = mode if isinstance(mode, LeverMode) else None
    peak = lever.peak if lever else mode or first_mode(tune)
    f0, q, amp = peak.frequency_hz, peak.quality_factor, peak.amplitude
    assumptions, inputs = [], {"temperature": temperature, "medium": medium.name, "spot_position": spot_position,
                               "tip_position": tip_position}
    if not lever and (medium.density > LIQUID_DENSITY or q < LOW_Q):
        assumptions.append("the first mode as an oscillator, though the fluid's load changes across the peak (its "
                           "resonance reads 1-6 % high, k up to 25 % off): give the length and width (and the InvOLS "
                           "of a spectrum in volts) for the fluid-loaded whole lever")
    # Thermal.
    mean_square = float(formulas.oscillator_mean_square(f0, q, amp))
    if tune.unit == "V":
        if invols is None:
            thermal = Estimate(math.nan, math.nan, reason="the spectrum is in volts: needs the InvOLS")
        else:
            mean_square *= invols**2
            inputs["invols"] = invols
    else:
        if invols is not None:
            raise UserError(f"{tune.path}: the spectrum is already in metres; an InvOLS applies to a spectrum in volts")
        assumptions.append("the spectrum in metres was converted by the instrument with a static InvOLS (optical "
                           "lever, tip pressed on a hard surface): the thermal factor assumes it")
    if lever and (tune.unit == "m" or invols is not None):
        thermal = _combine(lever.spring_constant, dict(lever.sources))
        assumptions.append("the lever's plan (length, width) and the fluid's properties set the load that the whole "
                           "lever's first mode and k follow (Sader's hydrodynamic function)")
    elif tune.unit == "m" or invols is not None:
        log_mean_square = (1 / f0, 1 / q, 2 / amp, 0.0)       # d log <d^2> / d (f0, Q, A, w)
        scatter = peak.stderr(log_mean_square, "fit")      # the profile where the bins, not the data, set the area
        fit = {"fit": scatter} if scatter >= peak.area_profile else {"fit (profile over Q)": peak.area_profile}
        thermal = _combine(thermal_spring_constant(mean_square, temperature, spot_position, tip_position),
                           dict(fit, **{"peak shape": peak.stderr(log_mean_square, "shape"),
                                        "temperature": temperature_uncertainty / temperature}))
    # Sader.
    rebuild = medium_factory or (lambda t: medium)

    def sader(L=length, b=width, t=temperature, f=f0, quality=q, scale=1.0):
        fluid = rebuild(t)
        fluid = Medium(fluid.density * scale, fluid.viscosity * scale, fluid.name)
        return sader_spring_constant(fluid, b, L, f, quality, tip_position)

    if length is None or width is None:
        sader_estimate = Estimate(math.nan, math.nan, reason="needs the lever's length and width")
    else:
        inputs.update(length=length, width=width)
        u_length, u_width = stated_uncertainties(length, width, length_uncertainty, width_uncertainty)
        k_s = sader()
        if not math.isfinite(k_s):
            re = float(reynolds_number(medium, f0, width))
            sader_estimate = Estimate(math.nan, math.nan, reason=f"Re = {re:.3g} is outside the hydrodynamic "
                                      "function's fitted range 1e-6 to 1e4")
        else:
            def rel(**change):          # relative change of k_s for a one-sigma change of one input
                return abs(sader(**change) / k_s - 1)
            shape = peak.shape
            sources = {"fit": math.hypot(rel(f=f0 + peak.stderr((1, 0, 0, 0), "fit")),
                                         rel(quality=q + peak.stderr((0, 1, 0, 0), "fit"))),
                       "peak shape": rel(f=f0 + shape[0], quality=q + shape[1]),
                       "length": rel(L=length + u_length), "width": rel(b=width + u_width)}
            if medium_factory is not None:
                sources["temperature"] = rel(t=temperature + temperature_uncertainty)
            sader_estimate = _combine(k_s, sources)
            assumptions.append(f"length {length:.4g} m +- {u_length:.2g}, width {width:.4g} m +- {u_width:.2g} "
                               f"(standard uncertainties), temperature +- {temperature_uncertainty:g} K")
    # Agreement, and what would restore it.
    consistent, reconcile = None, []
    if thermal.determined and sader_estimate.determined:
        combined = math.hypot(thermal.stderr, sader_estimate.stderr)
        consistent = bool(abs(thermal.value - sader_estimate.value) <= COVERAGE * combined)
        if not consistent:
            ratio = thermal.value / sader_estimate.value
            candidates = [("invols", math.sqrt(ratio)),         # k_thermal ~ 1/InvOLS^2
                          ("length", ratio),                     # k_Sader ~ L
                          ("width", _bisect(lambda s: sader(b=width * s) - thermal.value, 0.2, 5.0))]
            if medium_factory is not None:
                def mismatch(s):        # NaN where the medium has no such temperature (water below 0 C)
                    try:
                        return thermal.value * s - sader(t=temperature * s)
                    except UserError:
                        return math.nan
                candidates.append(("temperature", _bisect(mismatch, 0.5, 2.0)))
            ranges = plausible_factors(u_length / length, u_width / width, temperature)
            reconcile = [(name, factor) for name, factor in candidates
                         if factor and ranges[name][0] <= factor <= ranges[name][1]]
    instrument = dict(tune.instrument, **{k: v for k, v in tune.conditions.items()})
    if length is not None and width is not None and {"free_resonance", "free_quality_factor"} <= set(instrument):
        # the textbook formula on the instrument's own fit of the tune, beside ours on the data
        instrument["sader_spring_constant_of_its_fit"] = sader_spring_constant(
            medium, width, length, instrument["free_resonance"], instrument["free_quality_factor"], tip_position)
    return Calibration(peak, thermal, sader_estimate, consistent, reconcile, assumptions, inputs, instrument,
                       plausible_factors(LENGTH_TOLERANCE, WIDTH_TOLERANCE, temperature) if length is None or width is None
                       else plausible_factors(u_length / length, u_width / width, temperature),
                       "fluid-loaded lever" if lever else "damped oscillator" + (f", {peak.sampling}" if peak.sampling else "")
                       + (f", its resonance drifting by {peak.drift * f0:.3g} Hz (standard deviation) over the averages"
                          if not lever and peak.drift else ""),
                       lever.fit if lever else None)
