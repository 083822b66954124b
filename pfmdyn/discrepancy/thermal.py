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
drive sweep (:mod:`pfmdyn.discrepancy.sweep`), over a band around the tallest peak.  The residual is
taken in ``log ASD`` (an averaged spectrum's scatter is relative), in units of its noise.

``g`` over the static end-load factor ``2L/3`` (:func:`pfmdyn.generated.formulas.height_per_slope`) is ``detection_scale``: 1 when the spring constant and the
deflection sensitivity the spectrum was converted with agree (the thermal method of ``pfmdyn calibrate``
then gives the same ``k``); otherwise the spring constant that would make it 1 is ``k / scale**2``.
The instrument's own fit in the header is reported beside, never used instead of the data.
"""
from __future__ import annotations

import numpy as np

from ..cantilever import Cantilever
from ..errors import UserError
from ..fitting.result import Result
from ..generated import formulas
from ..io.thermal_tune import ThermalTune
from ..medium import Medium
from .regions import gap_text, lever_resonances, worst_region
from .sweep import (ASSUMED_WIDTH, EXTRA_LOSS, MIN_POINTS, RESONANCE, WIDTH_NOTE, compare_with_instrument,
                    instrument_text, noise_level, parameter_entry, plus_minus, provenance_lines, solve_from_starts,
                    unexplained_entry, unexplained_line)

__all__ = ["ThermalFit", "fit_thermal", "BAND"]

BAND = (0.3, 3.0)
"""The band fitted, as multiples of the tallest peak's frequency (clipped to the measured span)."""


class ThermalFit(Result):
    """One thermal tune fitted (:func:`fit_thermal`): ``to_dict()`` the JSON fields, ``report()`` the
    summary; attributes ``lever`` (the fitted :class:`~pfmdyn.Cantilever`), ``frequency_hz``, ``asd``
    (the band fitted) and ``model_asd``."""

    def report(self) -> str:
        """``thermal tune FILE: ... resonance ..., Q ...; detection ...; instrument: ...; gap ...``."""
        d = self._fields
        p = d["parameters"]
        low, high = d["band_hz"]
        scale = d["detection_scale"]
        lines = [f"thermal tune {d['path']}: {d['points']} points ({low / 1e3:.4g}-{high / 1e3:.4g} kHz) fitted as a "
                 f"thermally driven free lever in {d['medium']} "
                 f"(k {d['spring_constant']:g} N/m, L {d['length']:g} m, T {d['temperature']:.2f} K)",
                 f"  resonance in the medium {plus_minus(p['free_resonance'], 'Hz')}, vacuum {d['vacuum_resonance']:.6g} Hz, "
                 f"Q {d['quality_factor']:.3g}",
                 f"  width {plus_minus(p['width'], 'm')}" + (" (given)" if p["width"]["given"] else f" ({p['width']['why']})"),
                 f"  damping beyond the fluid's: viscous_loss {plus_minus(p['viscous_loss'], '')}",
                 f"  detection: slope-to-deflection factor {scale:.4g} x 2L/3 (1: k and the sensitivity agree; "
                 f"the k that makes it 1: {d['spring_constant'] / scale**2:.4g} N/m), white floor "
                 f"{d['white_floor']:.3g} {d['unit']}",
                 f"  instrument: {instrument_text(d['instrument_fit'], d.get('instrument_comparison'))}"
                 + (f", k {d['instrument_fit']['spring_constant']:g} N/m" if "spring_constant" in d["instrument_fit"]
                    else ""),
                 f"  {gap_text(d['gap'], d.get('worst_region'))}"]
        return "\n".join(lines + unexplained_line(d.get("unexplained")) + provenance_lines(d))


def _band(tune: ThermalTune) -> tuple[np.ndarray, np.ndarray, float]:
    """The points fitted and the tallest peak's frequency (the first mode's start)."""
    ok = (tune.frequency_hz > 0) & np.isfinite(tune.asd) & (tune.asd > 0)
    order = np.argsort(tune.frequency_hz[ok], kind="stable")        # a table's rows in any order
    f, asd = tune.frequency_hz[ok][order], tune.asd[ok][order]
    if len(f) < 5 * MIN_POINTS:
        raise UserError(f"{tune.path}: {len(f)} usable points; a thermal fit needs at least {5 * MIN_POINTS}")
    # the tallest of the log spectrum smoothed over 5 bins (no single-bin spike), above the lowest
    # bins (the offset and 1/f noise)
    smooth = np.convolve(np.log(asd), np.ones(5) / 5, mode="same")
    skip = max(3, len(f) // 100)
    peak = f[skip + int(np.argmax(smooth[skip:-2]))]
    inside = (f >= BAND[0] * peak) & (f <= BAND[1] * peak)
    if inside.sum() < MIN_POINTS:
        raise UserError(f"{tune.path}: {inside.sum()} points around the peak; a thermal fit needs at least {MIN_POINTS}")
    return f[inside], asd[inside], peak


def _floor_and_scale(slope_psd, power) -> tuple[float, float]:
    """``(g**2, w**2)``, both >= 0, minimising ``sum ((g**2 S + w**2) / P - 1)**2``."""
    design = np.stack([slope_psd / power, 1.0 / power], axis=-1)
    norms = np.linalg.norm(design, axis=0)       # the two columns differ by many decades
    solution = np.linalg.lstsq(design / norms, np.ones(len(power)), rcond=None)[0] / norms
    if np.all(solution >= 0):
        return float(solution[0]), float(solution[1])
    return max(float(np.sum(design[:, 0]) / norms[0] ** 2), 0.0), 0.0


def fit_thermal(tune: ThermalTune, spring_constant: float, length: float, medium: Medium, temperature: float,
                width: float | None = None) -> ThermalFit:
    """Fit a thermal tune over the band around its tallest peak (see the module): the lever's resonance in
    ``medium`` at ``temperature`` (K) and a damping beyond the fluid's; ``width`` None: assumed.

    >>> lever = Cantilever(2.0, 7e4, 2e-4, width=3e-5, medium=Medium.air())
    >>> f = np.linspace(100.0, 2e5, 4000)
    >>> asd = np.sqrt((2 * 2e-4 / 3) ** 2 * lever.thermal_noise(f, 300.0).slope + 1e-28)
    >>> fit = fit_thermal(ThermalTune("t.nid", f, asd, "m", {}, {}), 2.0, 2e-4, Medium.air(), 300.0, width=3e-5)
    >>> round(fit["parameters"]["free_resonance"]["value"]), round(fit["detection_scale"], 4)
    (70000, 1.0)
    """
    frequency, asd, start = _band(tune)
    given = width is not None
    width = width if given else ASSUMED_WIDTH * length
    power = asd**2
    log_asd = np.log(asd)
    sigma = noise_level(frequency, log_asd)
    params = (RESONANCE, EXTRA_LOSS)
    lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])

    def lever_of(x) -> Cantilever:
        return Cantilever(spring_constant, 10.0**x[0], length, width=width, medium=medium, viscous_loss=x[1])

    def model(x) -> tuple[np.ndarray, float, float]:
        slope_psd = lever_of(x).thermal_noise(frequency, temperature).slope
        a, b = _floor_and_scale(slope_psd, power)
        return np.sqrt(a * slope_psd + b), a, b

    def residual(x) -> np.ndarray:
        try:
            fitted = model(x)[0]
        except UserError:       # a lever the fluid cannot carry
            return np.full(len(frequency), 1e6)
        with np.errstate(divide="ignore"):
            return np.nan_to_num((np.log(fitted) - log_asd) / sigma, nan=1e6, posinf=1e6, neginf=1e6)

    grid = [np.array([np.log10(start * s), loss]) for s in (0.999, 1.0, 1.001) for loss in EXTRA_LOSS.seeds]
    fit = solve_from_starts(residual, grid, lower, upper)
    try:
        lever = lever_of(fit.internal)
        fitted, a, b = model(fit.internal)
    except UserError:
        raise UserError(f"{tune.path}: no lever of this spring constant, length and width carries {medium.name}'s "
                        "load at a resonance near the peak (check them)") from None
    from ..analysis.resonances import resonances

    parameters = {p.key: parameter_entry(p, x, fit.covariance[i, i]) for i, (p, x) in enumerate(zip(params, fit.internal))}
    parameters["width"] = {"value": width, "stderr": None, "unit": "m", "given": given}
    if not given:
        parameters["width"]["why"] = WIDTH_NOTE
    q = float(resonances(lever, None, modes=1).free.q[0])
    r = np.log(fitted) - log_asd
    unexplained = unexplained_entry(frequency, r, r, sigma)
    if unexplained:     # the residual is relative: its largest share is of the value there
        unexplained["largest_residual"] = float(np.expm1(np.max(np.abs(r))))
        unexplained["relative"] = True
    fields = {"kind": "thermal tune", "path": tune.path, "points": len(frequency),
              "band_hz": [float(frequency.min()), float(frequency.max())], "medium": medium.name,
              "temperature": temperature, "spring_constant": spring_constant, "length": length,
              "vacuum_resonance": lever.vacuum_resonance, "quality_factor": q,
              "parameters": parameters, "detection_scale": float(np.sqrt(a) / formulas.height_per_slope(length)),
              "white_floor": float(np.sqrt(b)), "unit": f"{tune.unit}/sqrt(Hz)",
              "instrument_fit": dict(tune.instrument), "noise": sigma, "gap": float(np.sqrt(np.mean((r / sigma) ** 2))),
              "worst_region": worst_region(frequency, (r / sigma) ** 2, lever_resonances(lever)),
              "unexplained": unexplained, "from_file": sorted(tune.instrument), "assumed": [],
              "instrument_comparison": compare_with_instrument(tune.instrument, {
                  "free_resonance": (lever.free_resonance, parameters["free_resonance"]["stderr"]),
                  "free_quality_factor": (q, None)},
                  float(np.median(np.diff(frequency))))}
    if not given:
        fields["assumed"].append(f"width {width:g} m (L/10: the width was not given)")
    return ThermalFit(fields, lever=lever, frequency_hz=frequency, asd=asd, model_asd=fitted)
