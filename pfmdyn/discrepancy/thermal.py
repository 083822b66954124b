"""Thermal tunes explained as spectra: a free lever driven by thermal noise in a fluid.

A thermal tune (:func:`pfmdyn.io.thermal_tune.read_thermal_tune`) is the amplitude spectral density of
the lever's Brownian motion as the instrument converted it to a deflection.  Its model
(:func:`fit_thermal`) is

``ASD(f)**2 = g**2 S(f) + w**2``,

``S`` the one-sided power spectral density of the slope at the laser spot (fluctuation-dissipation:
:meth:`pfmdyn.Cantilever.thermal_noise`, every mode, the fluid's load and damping from Sader's
hydrodynamic function), ``g`` the factor that turned slope into deflection and ``w`` a white detection
floor.  ``g`` and ``w`` are solved out of the fit (weighted linear least squares in power at each step);
fitted are the first resonance *in the medium* and a viscous damping beyond the fluid's, as for a
drive sweep (:mod:`pfmdyn.discrepancy.sweep`), over a band around the first mode's peak.  The residual is
taken in ``log ASD`` (an averaged spectrum's scatter is relative), in units of its noise.

``g`` over the static end-load factor ``2L/3`` (:func:`pfmdyn.generated.formulas.height_per_slope`) is ``detection_scale``: 1 when the spring constant and the
deflection sensitivity the spectrum was converted with agree (the thermal method of ``pfmdyn calibrate``
then gives the same ``k``); otherwise the spring constant that would make it 1 is ``k / scale**2``.
The instrument's own fit in the header is reported beside, never used instead of the data.
"""
from __future__ import annotations

import math

import numpy as np

from ..analysis.thermal import first_mode_index
from ..cantilever import Cantilever
from ..errors import UserError
from ..fitting.projection import jacobian_covariance
from ..fitting.result import Result
from ..generated import formulas
from ..io.thermal_tune import ThermalTune
from ..medium import Medium
from ..fitting.noise import gap
from .regions import gap_text, lever_resonances, regions, worst_region
from .sweep import (ASSUMED_WIDTH, EXTRA_LOSS, MIN_POINTS, RESONANCE, WIDTH_NOTE, compare_with_instrument,
                    UNDETERMINED_ERROR, derived_text, error_entry, instrument_text, noise_level, parameter_entry,
                    plus_minus, propagated, provenance_lines, quality_text,
                    solve_from_starts,
                    unexplained_entry, unexplained_line)

__all__ = ["ThermalFit", "fit_thermal", "quality_factor_in_medium", "lever_mode", "calibrate_tune", "bin_nodes", "coarse_bins", "BAND",
           "BINS_PER_LINEWIDTH", "COARSE_SHARE", "COARSE_ABOVE"]

BAND = (0.3, 3.0)
"""The band fitted, as multiples of the first mode's peak frequency (clipped to the measured span)."""


class ThermalFit(Result):
    """One thermal tune fitted (:func:`fit_thermal`): ``to_dict()`` the JSON fields, ``report()`` the
    summary; attributes ``lever`` (the fitted :class:`~pfmdyn.Cantilever`), ``frequency_hz``, ``asd``
    (the band fitted) and ``model_asd``."""

    def report(self) -> str:
        """``thermal tune FILE: ... resonance ..., Q ...; detection ...; instrument: ...; gap ...``."""
        d = self._fields
        p = d["parameters"]
        low, high = d["band_hz"]
        lines = [f"thermal tune {d['path']}: {d['points']} points ({low / 1e3:.4g}-{high / 1e3:.4g} kHz) fitted as a "
                 f"thermally driven free lever in {d['medium']} "
                 f"(k {d['spring_constant']:g} N/m, L {d['length']:g} m, T {d['temperature']:.2f} K)",
                 f"  resonance in the medium {plus_minus(p['free_resonance'], 'Hz')}, vacuum {derived_text(d, 'vacuum_resonance', 'Hz')}, "
                 f"Q {quality_text(d['quality_factor'], d['uncertainties']['quality_factor'])}",
                 f"  width {plus_minus(p['width'], 'm')}" + (" (given)" if p["width"]["given"] else f" ({p['width']['why']})"),
                 f"  damping beyond the fluid's: viscous_loss {plus_minus(p['viscous_loss'], '')}",
                 f"  detection: slope-to-deflection factor {derived_text(d, 'detection_scale', '')} x 2L/3 (1: k and "
                 f"the sensitivity agree; the k that makes it 1: {derived_text(d, 'matching_spring_constant', 'N/m')}), "
                 f"white floor {derived_text(d, 'white_floor', d['unit'])}",
                 f"  instrument: {instrument_text(d['instrument_fit'], d.get('instrument_comparison'))}"
                 + (f", k {d['instrument_fit']['spring_constant']:g} N/m (ours, where the detection factor is 1: "
                    f"{derived_text(d, 'matching_spring_constant', 'N/m')})" if "spring_constant" in d["instrument_fit"] else ""),
                 f"  {gap_text(d['gap'], d.get('worst_region'))}"]
        return "\n".join(lines + unexplained_line(d.get("unexplained")) + provenance_lines(d))


def _band(tune: ThermalTune) -> tuple[np.ndarray, np.ndarray, float]:
    """The points fitted and the first mode's peak frequency (:func:`~pfmdyn.analysis.thermal.first_mode_index`:
    not the tallest peak where that is mode 2)."""
    ok = (tune.frequency_hz > 0) & np.isfinite(tune.asd) & (tune.asd > 0)
    order = np.argsort(tune.frequency_hz[ok], kind="stable")        # a table's rows in any order
    f, asd = tune.frequency_hz[ok][order], tune.asd[ok][order]
    if len(f) < 5 * MIN_POINTS:
        raise UserError(f"{tune.path}: {len(f)} usable points; a thermal fit needs at least {5 * MIN_POINTS}")
    peak = f[first_mode_index(f, asd)]
    inside = (f >= BAND[0] * peak) & (f <= BAND[1] * peak)
    if inside.sum() < MIN_POINTS:
        raise UserError(f"{tune.path}: {inside.sum()} points around the peak; a thermal fit needs at least {MIN_POINTS}")
    return f[inside], asd[inside], peak


def _floor_and_scale(slope_psd, power, frequency, weights=1.0) -> np.ndarray:
    """``(g**2, w**2, p**2)``, all >= 0, minimising ``sum (weights ((g**2 S + w**2 + p**2 f0/f) / P - 1))**2``
    (``f0`` the band's lowest frequency: ``p`` the 1/f floor there; ``weights`` each point's inverse relative
    scatter, more for a mean of more bins)."""
    from scipy.optimize import nnls

    weights = np.broadcast_to(weights, power.shape)
    design = np.stack([slope_psd, np.ones(len(power)), frequency[0] / frequency], axis=-1) * (weights / power)[:, None]
    norms = np.linalg.norm(design, axis=0)       # the columns differ by many decades
    return nnls(design / norms, weights)[0] / norms


def quality_factor_in_medium(lever: Cantilever) -> float:
    """The first mode's Q in the medium, the damped oscillator's at the resonance ``f`` (the real root of
    ``r**2 (1 + Re load) = 1``, ``r = f / f_vac``): ``1/Q = (-Im load + g / r) / (1 + Re load) + 1/Q_int``
    (``derivations/damping.py``: drag ``g + i r load``); finite at any damping, where a complex root
    may not exist.

    >>> round(quality_factor_in_medium(Cantilever(27.0, 1.8e5, 225e-6, width=40e-6, medium=Medium.air(313.15))))
    474
    """
    load = lever.fluid_load(lever.free_resonance) if lever.medium is not None else 0j
    r = lever.free_resonance / lever.vacuum_resonance
    loss = (lever.viscous_loss / r - load.imag) / (1 + load.real) + 1 / lever.quality_factor
    return float(1 / loss) if loss > 0 else math.inf


def fit_thermal(tune: ThermalTune, spring_constant: float, length: float, medium: Medium, temperature: float,
                width: float | None = None, *, start=None, shape: bool = True) -> ThermalFit:
    """Fit a thermal tune over the band around its first mode's peak (see the module): the lever's resonance in
    ``medium`` at ``temperature`` (K) and a damping beyond the fluid's; ``width`` None: assumed; ``start``
    (the ``internal`` of an earlier fit) the only start.  The resonance's and the damping's errors hold the
    peak's shape too (how far they move when the fit is weighted in power: the peak's top, not its
    flanks); ``shape`` False leaves it out (a step of an iteration).  Attribute ``scale_stderr``: the
    relative standard error of ``g**2``, the fit's scatter with the resonance and damping free.

    >>> lever = Cantilever(2.0, 7e4, 2e-4, width=3e-5, medium=Medium.air())
    >>> f = np.linspace(100.0, 2e5, 4000)
    >>> asd = np.sqrt((2 * 2e-4 / 3) ** 2 * lever.thermal_noise(f, 300.0).slope + 1e-28)
    >>> fit = fit_thermal(ThermalTune("t.nid", f, asd, "m", {}, {}), 2.0, 2e-4, Medium.air(), 300.0, width=3e-5)
    >>> round(fit["parameters"]["free_resonance"]["value"]), round(fit["detection_scale"], 4)
    (70000, 1.0)
    """
    frequency, asd, peak = _band(tune)
    measured_points = len(frequency)
    given = width is not None
    width = width if given else ASSUMED_WIDTH * length
    noise = noise_level(frequency, np.log(asd))
    step = float(np.median(np.diff(frequency)))
    frequency, power, spans = coarse_bins(frequency, asd**2, peak, step) if measured_points > COARSE_ABOVE else \
        (frequency, asd**2, np.full(measured_points, step))
    asd = np.sqrt(power)
    log_asd = np.log(asd)
    sigma = noise * np.sqrt(step / spans)      # a mean of m bins scatters 1/sqrt(m) as much
    params = (RESONANCE, EXTRA_LOSS)
    lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])

    def lever_of(x) -> Cantilever:
        return Cantilever(spring_constant, 10.0**x[0], length, width=width, medium=medium, viscous_loss=x[1])

    averaged = None         # (points near the peak, offsets across a bin): see below

    def slope_psd(x) -> np.ndarray:
        lever = lever_of(x)
        psd = lever.thermal_noise(frequency, temperature).slope
        if averaged is not None:
            near, nodes = averaged
            psd[near] = lever.thermal_noise(nodes.ravel(), temperature).slope.reshape(nodes.shape).mean(axis=1)
        return psd

    def model(x, in_power: bool = False) -> tuple[np.ndarray, np.ndarray]:
        psd = slope_psd(x)
        weights = sigma.min() / sigma * (power / power.max() if in_power else 1.0)
        coefficients = _floor_and_scale(psd, power, frequency, weights)
        return np.sqrt(coefficients[0] * psd + coefficients[1] + coefficients[2] * frequency[0] / frequency), coefficients

    def residual(x, in_power: bool = False) -> np.ndarray:
        try:
            fitted = model(x, in_power)[0]
        except UserError:       # a lever the fluid cannot carry
            return np.full(len(frequency), 1e6)
        with np.errstate(divide="ignore"):
            r = (fitted**2 - power) / power.max() * sigma.min() / sigma if in_power else (np.log(fitted) - log_asd) / sigma
            return np.nan_to_num(r, nan=1e6, posinf=1e6, neginf=1e6)

    grid = [np.asarray(start, dtype=float)] if start is not None else \
        [np.array([np.log10(peak * s), loss]) for s in (0.999, 1.0, 1.001) for loss in EXTRA_LOSS.seeds]
    fit = solve_from_starts(residual, grid, lower, upper, keep=1 if start is not None else 3)
    averaged = bin_nodes(frequency, spans, lever_of(fit.internal))
    if averaged is not None:    # a peak a few bins wide or narrower: refitted as each bin's mean, as measured
        fit = solve_from_starts(residual, [fit.internal], lower, upper, keep=1)
    try:
        lever = lever_of(fit.internal)
        fitted, (a, b, c) = model(fit.internal)
        covariance, floors = _covariance(fit.internal, slope_psd, (a, b, c), frequency, fitted, log_asd, sigma)
    except UserError:
        raise UserError(f"{tune.path}: no lever of this spring constant, length and width carries {medium.name}'s "
                        "load at a resonance near the peak (check them)") from None
    r = np.log(fitted) - log_asd
    inflation = peak_misfit(frequency, r / sigma, lever) ** 2
    # the peak's shape: the same fit weighted in power (the peak's top) moves the resonance and damping where
    # the peak is no lever's (a drifting resonance; the shared tune's Q 396 -> 436, as the SHO over the
    # instrument's window, 392 in log and 439 in power); an exact spectrum's moves them by its noise
    moved = solve_from_starts(lambda x: residual(x, True), [fit.internal], lower, upper, keep=1).internal - \
        fit.internal if shape else np.zeros(2)
    lever_covariance = covariance[:2, :2] * inflation + np.outer(moved, moved)
    parameters = {p.key: parameter_entry(p, x, lever_covariance[i, i])
                  for i, (p, x) in enumerate(zip(params, fit.internal))}
    parameters["width"] = {"value": width, "stderr": None, "unit": "m", "given": given}
    if not given:
        parameters["width"]["why"] = WIDTH_NOTE
    q = quality_factor_in_medium(lever)
    scale = float(np.sqrt(a) / formulas.height_per_slope(length))
    log_scale_sd = math.sqrt(covariance[2, 2]) if covariance[2, 2] >= 0 else math.nan     # of log g**2
    errors = {"vacuum_resonance": error_entry(propagated(lambda x: lever_of(x).vacuum_resonance, fit.internal,
                                                         lever_covariance, lower), UNDETERMINED_ERROR),
              "quality_factor": error_entry(propagated(lambda x: quality_factor_in_medium(lever_of(x)), fit.internal,
                                                       lever_covariance, lower), UNDETERMINED_ERROR),
              "detection_scale": error_entry(0.5 * scale * log_scale_sd, UNDETERMINED_ERROR),
              "matching_spring_constant": error_entry(spring_constant / scale**2 * log_scale_sd, UNDETERMINED_ERROR),
              # the floor's column is in the covariance only where it adds to the spectrum somewhere
              "white_floor": error_entry(0.5 * math.sqrt(b) * math.sqrt(covariance[3, 3]) if floors[0] else math.nan,
                                         "the white floor adds under 0.1% of the power anywhere in the band: "
                                         "the data do not determine it")}
    unexplained = unexplained_entry(frequency, r, r, sigma)
    if unexplained:     # the residual is relative: its largest share is of the value there
        unexplained["largest_residual"] = float(np.expm1(np.max(np.abs(r))))
        unexplained["relative"] = True
    fields = {"kind": "thermal tune", "path": tune.path, "points": measured_points,
              "band_hz": [float(frequency.min()), float(frequency.max())], "medium": medium.name,
              "temperature": temperature, "spring_constant": spring_constant, "length": length,
              "vacuum_resonance": lever.vacuum_resonance, "quality_factor": q,
              "parameters": parameters, "detection_scale": scale, "matching_spring_constant": spring_constant / scale**2,
              "white_floor": float(np.sqrt(b)), "uncertainties": errors, "unit": f"{tune.unit}/sqrt(Hz)",
              "instrument_fit": dict(tune.instrument), "noise": noise, "gap": float(np.sqrt(np.mean((r / sigma) ** 2))),
              "worst_region": worst_region(frequency, (r / sigma) ** 2, lever_resonances(lever),
                                           bands=measured_points <= COARSE_ABOVE),     # coarse bins: no bands
              "unexplained": unexplained, "from_file": sorted(tune.instrument), "assumed": [],
              "instrument_comparison": compare_with_instrument(tune.instrument, {
                  "free_resonance": (lever.free_resonance, parameters["free_resonance"]["stderr"]),
                  "free_quality_factor": (q, errors["quality_factor"]["stderr"])},
                  float(np.median(np.diff(frequency))))}
    if not given:
        fields["assumed"].append(f"width {width:g} m (L/10: the width was not given)")
    return ThermalFit(fields, lever=lever, frequency_hz=frequency, asd=asd, model_asd=fitted, internal=fit.internal,
                      one_over_f_floor=float(np.sqrt(c)), scale_stderr=float(np.sqrt(covariance[2, 2])))


BINS_PER_LINEWIDTH = 5.0
"""A peak narrower than this many bins is fitted as each bin's mean (as ``calibrate``'s oscillator,
:func:`pfmdyn.analysis.thermal.oscillator_bin_power`): point-sampled, its resonance's error missed the truth by
3-8 of itself in 2/20 vacuum and 7/20 sub-bin tunes of ``benchmarks/thermal_regimes.py``."""


def bin_nodes(frequency, spans, lever: Cantilever):
    """Where a tune's spectrum is read as each bin's mean, not a point: ``(near, nodes)``, the points within
    20 linewidths and 5 bins of ``lever``'s first resonance and, for each, the midpoint rule's nodes across
    its bin (``spans``, Hz; at least 4 a linewidth, 5 a bin, at most 401); None where the linewidth spans
    :data:`BINS_PER_LINEWIDTH` bins or more.

    >>> lever = Cantilever(27.0, 1.8e5, 225e-6, width=40e-6, medium=Medium.air(313.15))
    >>> f = np.arange(1.7e5, 1.9e5, 250.0)
    >>> near, nodes = bin_nodes(f, np.full(f.size, 250.0), lever)     # linewidth 380 Hz: 1.5 bins
    >>> int(near.sum()), (nodes[0] - f[near][0]).round(1).tolist()
    (61, [-100.0, -50.0, 0.0, 50.0, 100.0])
    """
    step = float(np.min(spans))
    q = quality_factor_in_medium(lever)
    linewidth = lever.free_resonance / q if math.isfinite(q) else 0.0
    if not linewidth < BINS_PER_LINEWIDTH * step:
        return None
    count = int(min(max(math.ceil(4 * step / linewidth) if linewidth > 0 else 401, 5), 401))
    near = np.abs(frequency - lever.free_resonance) < max(20 * linewidth, 5 * step)
    offsets = (np.arange(count) + 0.5) / count - 0.5
    return near, frequency[near][:, None] + spans[near][:, None] * offsets


COARSE_ABOVE = 20_000
"""A band of more points than this is fitted over coarser bins away from the peak (:func:`coarse_bins`): the
whole-lever model costs ~20 us a point and a call (100,000 points: ~90 s a fit); fewer are fitted as measured."""

COARSE_SHARE = 0.01
"""Away from the peak a tune's bins are averaged over spans of this share of their distance from it (each
bin's own near it): ~100 points per decade of distance, whatever the tune's length."""


def coarse_bins(frequency, power, peak: float, step: float):
    """``(frequency, power, spans)`` of a tune with its bins away from the ``peak`` averaged in groups a
    :data:`COARSE_SHARE` of their distance from it wide (a Welch spectrum's mean over bins is the power in
    the wider bin, the model's bin mean; far from the peak the spectrum is straight across it): a
    1,000,000-point tune fitted over ~2,500 points.  ``spans`` the Hz each point covers.

    >>> f = np.arange(1.0, 100001.0)
    >>> coarse, p, spans = coarse_bins(f, np.ones_like(f), 5e4, 1.0)
    >>> coarse.size < 3000, float(spans.sum()), bool(np.all(p == 1.0)), float(spans[np.argmin(abs(coarse - 5e4))])
    (True, 100000.0, True, 1.0)
    """
    distance = np.abs(frequency - peak) / step          # in bins
    group = np.floor(np.log1p(COARSE_SHARE * distance) / np.log1p(COARSE_SHARE)) * np.sign(frequency - peak)
    _, inverse, counts = np.unique(group, return_inverse=True, return_counts=True)
    mean = lambda v: np.bincount(inverse, weights=v) / counts       # noqa: E731
    return mean(frequency), mean(power), counts * step


def peak_misfit(frequency, normalised_residual, lever: Cantilever) -> float:
    """How much wider the resonance's and the damping's standard errors are than the fit's covariance says:
    the gap over the first resonance's half-power band over the gap of the whole band (which scaled the
    covariance), at least 1.  Those two rest on the peak: a misfit there (a resonance that drifted over the
    averages, a peak no oscillator has) moves them, while the floor's many good values would hide it (the
    shared tune: gap 1.26 overall, 5.6 over the peak; ten tunes in air whose resonance drifted by a linewidth
    over the averages: the unscaled error held the resonance within 2 of it in 8, this one in 10, as
    ``calibrate``'s oscillator did).

    >>> f = np.linspace(1.7e5, 1.9e5, 1001)
    >>> lever = Cantilever(27.0, 1.8e5, 225e-6, width=40e-6, medium=Medium.air(313.15))
    >>> r = np.where(abs(f - lever.free_resonance) < 190.0, 10.0, 1.0)      # 10 noise levels over the peak only
    >>> round(peak_misfit(f, r, lever), 2), peak_misfit(f, np.ones_like(f), lever)
    (5.89, 1.0)
    """
    energy = np.asarray(normalised_residual, float) ** 2
    band = regions(frequency, lever_resonances(lever, 1))
    if not band or not band[0]["mask"].any():
        return 1.0
    mask = band[0]["mask"]
    return float(max(gap(np.sum(energy[mask]), mask.sum()) / max(gap(np.sum(energy), energy.size), 1.0), 1.0))


def _covariance(x, slope_psd, coefficients, frequency, fitted, log_asd, sigma) -> np.ndarray:
    """Covariance of (x, log g**2, log w**2, log p**2), all free, and which floors it holds: the Jacobian of the log residual (a floor
    that adds next to nothing held), scaled by the reduced chi2 when above 1.  Its own Jacobian, not the
    least-squares solver's, which zeroes the column of a parameter at its bound (no damping beyond the
    fluid's, as in water: its variance, and Q's with it, undetermined)."""
    psd = slope_psd(x)
    columns = []
    for i in range(2):       # the resonance (log10 Hz) and the extra damping
        moved = np.array(x, dtype=float)
        moved[i] += 1e-6
        columns.append(coefficients[0] * (slope_psd(moved) - psd) / 1e-6)
    floors = [value * shape for value, shape in zip(coefficients[1:], (np.ones_like(psd), frequency[0] / frequency))]
    kept = [bool(np.max(floor / fitted**2) > 1e-3) for floor in floors]
    columns += [coefficients[0] * psd] + [floor for floor, keep in zip(floors, kept) if keep]
    J = np.stack(columns, axis=-1) / (2 * fitted**2 * sigma)[:, None]
    r = (np.log(fitted) - log_asd) / sigma
    return jacobian_covariance(J, max(float(r @ r) / max(r.size - J.shape[1], 1), 1.0)), kept


def lever_mode(tune: ThermalTune, length: float, width: float, medium: Medium, temperature: float,
               spring_constant: float, *, length_uncertainty: float, width_uncertainty: float,
               temperature_uncertainty: float, tip_position: float = 1.0, spot_position: float = 1.0):
    """The first mode and thermal spring constant of the fluid-loaded whole lever (:func:`fit_thermal`) of a
    tune in metres (converted with a static InvOLS, the thermal method's assumption): the ``k`` at which the
    slope-to-deflection factor is the static ``2L/3`` (``detection_scale`` 1), found by ``k -> k / scale**2``
    from ``spring_constant`` (the spectrum's shape depends on ``k`` only through the fluid's mass ratio: a
    few steps).  ``k`` at a set-back tip or spot: times the oscillator's factor ratio (:func:`~pfmdyn.analysis.
    calibrate.thermal_factor`).  Each stated uncertainty's share of ``k`` is one refit (length, width) or
    exact (temperature: ``k ~ T``).

    >>> lever = Cantilever(2.0, 7.9e4, 2e-4, width=3e-5, viscous_loss=0.02).with_medium(Medium.water(298.15))
    >>> f = np.linspace(100.0, 1e5, 1000)
    >>> asd = np.sqrt((2 * 2e-4 / 3) ** 2 * lever.thermal_noise(f, 298.15).slope + 1e-26)
    >>> mode = lever_mode(ThermalTune("t", f, asd, "m", {}, {}), 2e-4, 3e-5, Medium.water(298.15), 298.15, 1.5,
    ...                   length_uncertainty=4e-6, width_uncertainty=1.5e-6, temperature_uncertainty=1.0)
    >>> round(mode.spring_constant, 4), round(mode.peak.frequency_hz), round(mode.peak.quality_factor, 3)
    (2.0, 29560, 3.813)
    """
    from ..analysis.calibrate import LeverMode, thermal_factor
    from ..analysis.thermal import ThermalPeak
    from ..constants import BOLTZMANN

    k, start, last, soft, fit = spring_constant, None, None, 0.0, None      # soft: the stiffest k too soft
    for _ in range(24):
        try:
            trial = fit_thermal(tune, k, length, medium, temperature, width, start=start, shape=False)
        except UserError:       # too soft to carry the fluid at the peak: back towards the last that did
            soft = max(soft, k)
            if last is not None and np.log(np.exp(last[0]) / k) < 1e-4:
                break           # the data ask for a lever at the edge of floating: the last that did
            k = 2.0 * k if last is None else float(np.sqrt(k * np.exp(last[0])))
            continue
        fit = trial
        # log scale**2 against log k: slope 1 but for the mass ratio's share; secant steps to its root
        u, h = np.log(k), 2 * np.log(fit["detection_scale"])
        slope = (h - last[1]) / (u - last[0]) if last is not None and u != last[0] else 1.0
        k, start, last = np.exp(u - h / (slope if 0.3 < slope < 3 else 1.0)), fit.internal, (u, h)
        if k <= soft:           # never below a lever known to sink
            k = float(np.sqrt(soft * np.exp(u)))
        if abs(h) < 1e-5:
            break
    if fit is None or abs(last[1]) > 0.01:
        raise UserError(f"{tune.path}: no lever of this length and width in {medium.name} explains the tune "
                        "(check them)")
    fitted_k = float(np.exp(last[0]))
    fit = fit_thermal(tune, fitted_k, length, medium, temperature, width, start=fit.internal)     # with its shape
    k = fitted_k / fit["detection_scale"] ** 2

    def moved(**change) -> float:        # k's relative change for one input one sigma lower (less load: a lever that floats)
        other = dict(dict(length=length, width=width), **change)
        refit = fit_thermal(tune, fitted_k, other["length"], medium, temperature, other["width"], start=fit.internal,
                            shape=False)
        return abs(refit["detection_scale"] ** -2 / fit["detection_scale"] ** -2 - 1)

    sources = {"fit": fit.scale_stderr, "length": moved(length=length - length_uncertainty),
               "width": moved(width=width - width_uncertainty), "temperature": temperature_uncertainty / temperature}
    lever, p = fit.lever, fit["parameters"]
    q = fit["quality_factor"]
    r = lever.free_resonance / lever.vacuum_resonance
    # dQ/dg = Q**2 / (r (1 + Re load)): the extra damping's scatter in Q
    load = lever.fluid_load(lever.free_resonance).real if lever.medium is not None else 0.0
    q_stderr = q**2 * p["viscous_loss"]["stderr"] / (r * (1 + load)) if np.isfinite(q) else np.inf
    k_tip = float(k) * thermal_factor(spot_position, tip_position) / thermal_factor()
    # the oscillator with this mode's f, Q and mean square (chi kB T / k at the end: the plot's and the report's)
    mean_square = thermal_factor() * BOLTZMANN * temperature / k
    f0 = float(lever.free_resonance)
    amplitude = float(np.sqrt(mean_square / formulas.oscillator_mean_square(f0, q, 1.0)))
    variance = np.diag([p["free_resonance"]["stderr"] ** 2, q_stderr**2, 0.0, 0.0])
    peak = ThermalPeak(1, f0, q, amplitude, fit["white_floor"], tuple(map(tuple, variance.tolist())))
    return LeverMode(peak, k_tip, sources, fit)


def calibrate_tune(tune: ThermalTune, *, medium: Medium, temperature: float, length: float | None = None,
                   width: float | None = None, invols: float | None = None, **options):
    """``pfmdyn calibrate``: :func:`pfmdyn.analysis.calibrate.calibrate` with its first mode from the
    damped oscillator or, where that is biased and the plan is given, the fluid-loaded whole lever
    (:func:`lever_mode`; why and when: :func:`pfmdyn.analysis.calibrate.first_mode_model`).  ``options``:
    :func:`~pfmdyn.analysis.calibrate.calibrate`'s.

    >>> f = np.linspace(0, 4e5, 8001)
    >>> tune = ThermalTune("t", f, formulas.oscillator_asd(f, 1.8e5, 440.0, 1.03e-15, 3e-14), "m", {}, {})
    >>> c = calibrate_tune(tune, length=225e-6, width=40e-6, medium=Medium.air(313.15), temperature=313.15)
    >>> c.model, round(c.thermal.value, 1)
    ('damped oscillator', 26.8)
    """
    from ..analysis.calibrate import (TEMPERATURE_UNCERTAINTY, calibrate, first_mode, first_mode_model,
                                      stated_uncertainties, thermal_spring_constant)

    try:
        peak = first_mode(tune)
    except UserError:           # no oscillator stands out (a low hump on a 1/f rise): the whole lever may
        peak = None
    mode = peak
    if first_mode_model(medium, peak, length, width, tune.unit, invols) == "fluid-loaded lever":
        metres = tune if tune.unit == "m" else ThermalTune(tune.path, tune.frequency_hz, tune.asd * invols, "m",
                                                            tune.instrument, tune.conditions)
        u_length, u_width = stated_uncertainties(length, width, options.get("length_uncertainty"),
                                                 options.get("width_uncertainty"))
        if peak is not None:
            mean_square = float(formulas.oscillator_mean_square(peak.frequency_hz, peak.quality_factor,
                                                                peak.amplitude * (invols or 1.0)))
        else:                   # the band's power above its lowest level: a start, not an estimate
            frequency, asd, _ = _band(metres)
            mean_square = float(np.sum(asd**2 - np.min(asd) ** 2) * np.median(np.diff(frequency)))
        mode = lever_mode(metres, length, width, medium, temperature, thermal_spring_constant(mean_square, temperature),
                          length_uncertainty=u_length, width_uncertainty=u_width,
                          temperature_uncertainty=options.get("temperature_uncertainty", TEMPERATURE_UNCERTAINTY),
                          tip_position=options.get("tip_position", 1.0), spot_position=options.get("spot_position", 1.0))
    return calibrate(tune, length=length, width=width, medium=medium, temperature=temperature, invols=invols,
                     mode=mode, **options)
