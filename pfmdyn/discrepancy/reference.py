"""Two measurements compared: what changed between a reference drive sweep and another.

The lever, the fluid, the gain and the background are calibrated on the reference (before,
:func:`pfmdyn.discrepancy.sweep.fit_sweep`); the other sweep (after) is explained from them by nested
candidates (:func:`compare_sweeps`) -- nothing, a gain, background or damping change (nuisances; the
damping is ``viscous_loss``, the cell's drag), a point mass (``added_mass``, kg, at
``added_mass_position`` x/L: given, fitted when the sweep spans two modes or more, else undetermined and
the mass given as the end-equivalent one) and the mass with the nuisances -- the one of least BIC
named, each with its gap (the noise-normalised RMS residual, :func:`pfmdyn.fitting.noise.gap`).

A fitted position is searched over the whole lever (:func:`_position_profile`), the mass at each
position started also where it moves the first mode as far as the peak moved (:func:`_shift_seed`: a
sharp peak moved by many widths has a basin narrower than the decades between the other starts);
positions that explain the shifts as well (a position and its mirror about a node of mode 2) are all
reported, each with its mass.  A mass named while the explanation leaves a gap above
:data:`UNSETTLED` is not stated as determined: the minimum found need not be the lever's.  Where the
reference lever's resonances, scaled by one factor (:data:`RISE`), explain the other sweep only raised
(beyond :data:`SWAPPED` standard errors), no mass is named (a mass only lowers them) and a note says the
files may be swapped.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..digits import rounded
from ..cantilever import BETA1_FREE, Cantilever
from ..errors import UserError
from ..fitting.noise import gap
from ..fitting.parameters import Parameter
from ..fitting.projection import project
from ..fitting.result import Result
from ..io.sweeps import SweepTable
from .regions import gap_text, lever_resonances, worst_region
from .sweep import (EXTRA_LOSS, UNDETERMINED_ERROR, StartsFit, amplitude_stderr, derived_text, error_entry, joint_covariance, parts, SweepFit, amplitude_peak, base_driven_columns, compare_with_instrument,
                    explain_header, instrument_text, mode_ratios, noise_level, parameter_entry, penalty, provenance_lines, plus_minus, solve_from_starts, stacked, sweep_model, unexplained_entry, unexplained_line)

__all__ = ["SweepComparison", "compare_sweeps", "with_added_mass", "mode2_node", "CANDIDATES"]

ADDED_MASS = Parameter("added_mass_ratio", "", 0.0, 100.0, null=0.0,
                       description="point mass over the lever's mass")


POSITION = Parameter("added_mass_position", "", 0.05, 1.0)


RISE = Parameter("resonance_factor", "", 0.5, 2.0, description="the lever's vacuum resonance over the reference's")
"""The factor on the reference lever's resonances that explains the after-sweep best (gain and background
refitted; :func:`_resonance_factor`): only a test of the order, never an explanation named (it would
rival a mass wherever one mode is swept)."""


CANDIDATES = (("nothing", ()), ("gain", ("gain",)), ("background", ("background",)),
              ("gain+background", ("gain", "background")), ("added_mass", ("added_mass",)),
              ("damping", ("damping",)), ("damping+gain+background", ("damping", "gain", "background")),
              ("added_mass+gain+background", ("added_mass", "gain", "background")),
              ("added_mass+damping+gain+background", ("added_mass", "damping", "gain", "background")))
"""The explanations of an after-sweep tried by :func:`compare_sweeps`: a name and what is refitted.  Each
mass candidate has its twin without the mass, so a mass is named only where the data need it."""


UNSETTLED = 3.0
"""A gap (noise levels) above which the named explanation leaves a misfit: its mass is reported with the
reason, not as determined (a wrong minimum of the position held a mass 24 % low at a stated 6 %)."""


POSITION_GRID = tuple(np.linspace(0.1, 1.0, 10))
"""Starting positions (x/L) of a fitted added mass."""


def with_added_mass(lever: Cantilever, ratio: float, position: float = 1.0) -> Cantilever:
    """``lever`` (in its medium) with a point mass ``ratio`` times its own mass at ``position`` (x/L):
    its vacuum resonance lowered by the mass (the free root of the loaded beam), then put back in
    the medium; the viscous drag per length kept.

    >>> from pfmdyn.medium import Medium
    >>> lever = Cantilever(8.0, 7.2e4, 1e-4, width=4e-5, medium=Medium.water())
    >>> round(with_added_mass(lever, 0.0).free_resonance), with_added_mass(lever, 0.01).free_resonance < 7.2e4
    (72000, True)
    """
    f_vac = lever.vacuum_resonance
    bare = replace(lever, free_resonance=f_vac, medium=None, tip_mass_ratio=0.0, tip_position=1.0)
    if ratio == 0.0:
        return _at_vacuum_resonance(lever, bare, f_vac)
    loaded = replace(bare, tip_mass_ratio=float(ratio), tip_position=float(position))
    return _at_vacuum_resonance(lever, loaded, f_vac * (loaded.free_root() / BETA1_FREE)**2)


def _at_vacuum_resonance(lever: Cantilever, bare: Cantilever, f_vac: float) -> Cantilever:
    """``bare`` (``lever`` in vacuum, changed) at the vacuum resonance ``f_vac``, ``lever``'s viscous drag per
    length kept, back in ``lever``'s medium."""
    moved = replace(bare, free_resonance=f_vac, viscous_loss=lever.viscous_loss * lever.vacuum_resonance / f_vac)
    return moved if lever.medium is None else moved.with_medium(lever.medium)


def _modes_in(lever: Cantilever, frequency) -> int:
    """How many of the lever's free modes (undamped, in the medium) lie inside the sweep."""
    from ..analysis.resonances import resonances

    wet = resonances(lever, None, modes=3).free.peak_hz
    # a mode whose damped root a heavy fluid hides: where the vacuum ratio puts it above the first (a fluid
    # loads higher modes less, so it sits at or above that)
    wet = [f if math.isfinite(f) else wet[0] * ratio for f, ratio in zip(wet, mode_ratios())]
    return int(sum(frequency.min() <= f <= frequency.max() for f in wet if math.isfinite(f)))


def compare_sweeps(after: SweepTable, before: SweepFit, position: float | None = None) -> "SweepComparison":
    """Explain ``after`` from the lever, fluid, gain and background of ``before`` (a :func:`fit_sweep`):
    each of :data:`CANDIDATES` fitted, the one of least BIC named (see the module).  ``position``:
    the added mass's x/L (None: fitted when the sweep spans two modes, else undetermined and the mass
    given at the free end, the end-equivalent mass).

    >>> from pfmdyn.discrepancy.sweep import fit_sweep
    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(4e4, 1e5, 120)
    >>> lever = Cantilever(8.0, 7.2e4, 1e-4, width=4e-5, medium=Medium.water())
    >>> table = lambda y: SweepTable("s.txt", f, np.abs(y), "V", np.degrees(np.angle(y)), {}, None, "synthetic")
    >>> y = lambda lev: (0.3 - 2j) * lev.base_driven(f).slope + 0.5
    >>> before = fit_sweep(table(y(lever)), 8.0, 1e-4, Medium.water(), width=4e-5)
    >>> out = compare_sweeps(table(y(with_added_mass(lever, 0.02, 0.9))), before, position=0.9)
    >>> out["effect"], round(out["parameters"]["added_mass_ratio"]["value"], 4)
    ('added_mass', 0.02)
    """
    if before.amplitude_only != (after.phase_deg is None):
        raise UserError(f"{after.path}: {'no' if after.phase_deg is None else 'a'} phase column, while the reference "
                        f"has {'none' if before.amplitude_only else 'one'}: compare sweeps of the same kind")
    frequency = after.frequency_hz
    y = before.data(after)
    sigma = noise_level(frequency, y)
    n = len(y)
    count = 2 * n if np.iscomplexobj(y) else n
    fit_position = position is None and _modes_in(before.lever, frequency) >= 2
    x_mass = 1.0 if position is None else float(position)
    rows, fits = [], {}
    # the mass that moves the first mode as far as the peak moved, at each position tried
    shifted = {x: _shift_seed(before, frequency, y, x) for x in (POSITION_GRID if fit_position else (x_mass,))}
    seeds = _position_seeds(before, frequency, y) if fit_position else []
    for name, refit in CANDIDATES:
        mass = "added_mass" in refit
        if mass and fit_position:
            fit, solve, lever_of, params = _position_profile(before, refit, frequency, y, sigma, shifted, seeds)
        else:
            solve, lever_of, residual, params = _candidate(before, refit, frequency, y, sigma, x_mass)
            fit = solve_from_starts(residual, _starts(before, refit, shifted[x_mass]), *_bounds(before, refit, params))
        k = len(params) + len(_free_reals(before, refit))
        residual, amplitudes = solve(fit.internal)
        fits[name] = (fit, params, amplitudes, lever_of(fit.internal), residual, lever_of)
        rows.append({"effect": name, "refitted": list(refit), "parameters": k, "chi2": fit.chi2,
                     "bic": fit.chi2 + k * math.log(count), "gap": float(gap(fit.chi2, n))})
    rise = _resonance_factor(before, frequency, y, sigma)
    # resonances that rose are no added mass's: then the best explanation without one
    best = min((r for r in rows if not (_order_notes(rise) and "added_mass" in r["refitted"])), key=lambda r: r["bic"])
    fit, params, amplitudes, lever, _, lever_of = fits[best["effect"]]
    named = "added_mass" if "added_mass" in best["refitted"] else best["effect"]
    lever_mass = before.lever.beam_mass_per_length(before.lever.vacuum_resonance) * before.lever.length
    # m ~ k / f_vac**2: twice the reference's vacuum resonance's relative error
    f_vac_error = before["uncertainties"]["vacuum_resonance"]
    mass_error = error_entry(2 * lever_mass * f_vac_error["stderr"] / before.lever.vacuum_resonance
                             if f_vac_error["stderr"] is not None else math.nan, UNDETERMINED_ERROR)
    parameters = {}
    mass_fit = fits["added_mass+gain+background"][0] if named != "added_mass" else fit
    ratio = parameter_entry(ADDED_MASS, mass_fit.internal[0], mass_fit.covariance[0, 0])
    if fit_position and ratio["stderr"] is not None and math.isfinite(ratio["stderr"]):
        # the masses that move mode 1 alike one standard error of the position away: near the clamp a mass
        # acts as m x**4, a curve the covariance's straight line follows only over a short way
        along = _valley_spread(before.lever, *mass_fit.internal[:2], math.sqrt(max(mass_fit.covariance[1, 1], 0.0)))
        ratio = dict(ratio, stderr=max(ratio["stderr"], along))
    parameters["added_mass_ratio"] = ratio
    # A mass at its null bound, or within two standard errors of it, is no mass the data determine.
    at_bound = not ratio["value"] > 2 * (ratio["stderr"] or 0.0) or ratio["value"] <= 1e-9
    parameters["added_mass"] = {"value": ratio["value"] * lever_mass, "stderr": ratio["stderr"] * lever_mass,
                                "unit": "kg", "determined": named == "added_mass" and not at_bound}
    if at_bound and fit_position:
        # no mass the data need, and no bound either: near the clamp a mass moves neither mode
        parameters["added_mass"].update(stderr=None, why=(
            "at its bound (zero) or within two standard errors of it, its position free: a mass near the clamp "
            "moves neither mode, so the data bound no mass; a position given bounds it there"))
    elif at_bound:
        parameters["added_mass"]["why"] = "at its bound (zero) or within two standard errors of it"
    elif named == "added_mass" and best["gap"] > UNSETTLED:
        # a misfit the candidates leave: the minimum found need not be the lever's (its curvature, the
        # standard error, says nothing of that)
        parameters["added_mass"].update(determined=False, why=(
            f"the best explanation leaves gap {best['gap']:.3g} x noise (above {UNSETTLED:g}): what the candidates "
            "do not explain may move the mass; the value is that of the nearest minimum"))
    if "damping" in best["refitted"]:
        i = len(params) - 1
        parameters["viscous_loss"] = {**parameter_entry(EXTRA_LOSS, fit.internal[i], fit.covariance[i, i]),
                                      "before": before.lever.viscous_loss}
    if fit_position:
        parameters["added_mass_position"] = parameter_entry(POSITION, mass_fit.internal[1], mass_fit.covariance[1, 1])
        rivals = _rivals(mass_fit, count)
        if rivals:
            # e.g. a position and its mirror about a node of mode 2: each solution with its mass and gap
            solutions = [{"added_mass_position": float(x[1]), "added_mass": float(x[0] * lever_mass),
                          "gap": float(gap(chi2, n))} for x, chi2 in [(mass_fit.internal, mass_fit.chi2), *rivals]]
            parameters["added_mass_position"].update(
                undetermined=True, solutions=solutions,
                why="the modes' shifts agree as well at x/L " + ", ".join(f"{x[1]:.3g}" for x, _ in rivals))
            if parameters["added_mass"]["determined"] and any(
                    abs(s["added_mass"] - parameters["added_mass"]["value"]) > 2 * parameters["added_mass"]["stderr"]
                    for s in solutions[1:]):
                parameters["added_mass"].update(determined=False, solutions=solutions, why=(
                    "each position that explains the shifts as well needs its own mass (see solutions)"))
    elif position is not None:
        parameters["added_mass_position"] = {"value": x_mass, "stderr": 0.0, "unit": "1", "given": True}
    else:
        parameters["added_mass_position"] = {"value": None, "stderr": None, "unit": "1", "undetermined": True,
                                             "why": "one mode in the sweep: the mass and its position move the "
                                                    "resonance together; the mass is the end-equivalent one (x/L = 1)"}
    from ..analysis.resonances import resonances

    fields = {"kind": "drive sweep comparison", "path": after.path, "reference": before["path"],
              "effect": named, "nuisances": [r for r in best["refitted"] if r != "added_mass"],
              "parameters": parameters, "lever_mass": lever_mass, "uncertainties": {"lever_mass": mass_error},
              **_amplitude_errors(before, best["refitted"], fit, amplitudes, lever_of, len(params), frequency, y, sigma),
              "resonance_before": before.lever.free_resonance, "resonance_after": lever.free_resonance,
              "resonance_stderr": [before["parameters"]["free_resonance"]["stderr"],
                                   _resonance_stderr(before, fit, lever_of, len(params))],
              "gap_before": rows[0]["gap"], "gap_after": best["gap"], "steps": rows,
              "gain_after": [float(np.real(amplitudes[0])), float(np.imag(amplitudes[0]))],
              "background_after": [[float(np.real(a)), float(np.imag(a))] for a in amplitudes[1:]],
              "instrument_fit": dict(after.fields), "reference_fit": before.to_dict(), "noise": sigma,
              "unexplained": unexplained_entry(frequency, y, fits[best["effect"]][4], sigma),
              "worst_region": worst_region(frequency, np.abs(fits[best["effect"]][4] / sigma) ** 2,
                                           lever_resonances(lever)),
              "notes": _order_notes(rise),
              "instrument_comparison": explain_header(compare_with_instrument(after.fields, {
                  "amplitude_peak": (amplitude_peak(
                      lambda f: before.model(f, lever, amplitudes[0], tuple(amplitudes[1:])), frequency), None),
                  "free_resonance": (lever.free_resonance, None),
                  "free_quality_factor": (float(resonances(lever, None, modes=1).free.q[0]), None)},
                  float(np.median(np.diff(frequency)))), frequency, np.abs(y)),
              "from_file": sorted(after.fields), "assumed": list(before["assumed"])}
    return SweepComparison(fields, lever=lever)


def _complex_text(value: list, stderr: list) -> str:
    """A complex amplitude ``[re, im]`` and its standard errors ``[re, im]`` (None: undetermined) as a report prints it.

    >>> _complex_text([1.2345e-3, -2e-5], [3e-6, None])
    '(0.0012345 +- 3e-06) + (-2e-05 +- undetermined)i'
    """
    return " + ".join(f"({rounded(v, e or 0.0)} +- {f'{e:.2g}' if e is not None else 'undetermined'})" for v, e in
                      zip(value, stderr)) + "i"


def _amplitude_errors(before: SweepFit, refit, fit: StartsFit, amplitudes, lever_of, count: int, frequency, y,
                      sigma) -> dict:
    """``gain_after_stderr`` and ``background_after_stderr`` (``[re, im]`` each): a refitted amplitude's from
    the fit's covariance (with its lever's parameters; an amplitude solved out, through
    :func:`~pfmdyn.discrepancy.sweep.joint_covariance`), one kept at the reference's its standard error there."""
    reals = _free_reals(before, refit)
    if before.amplitude_only:       # the refitted parts are parameters after the lever's
        errors = amplitude_stderr(fit.covariance, count, reals)
    else:
        def residual_of(x, a):
            return stacked(sweep_model(base_driven_columns(lever_of(x), frequency, before.centre_hz), a, False) - y) / sigma

        errors = amplitude_stderr(joint_covariance(residual_of, fit.internal[:count], amplitudes, reals), count, reals)
    kept = [complex(*(v if v is not None else math.nan for v in pair))
            for pair in [before["gain"]["stderr"], *before["background"]["stderr"]]]
    refitted = {i for i, _ in reals}
    errors = [errors[i] if i in refitted else kept[i] for i in range(3)]
    return {"gain_after_stderr": parts(errors[0]), "background_after_stderr": [parts(e) for e in errors[1:]]}


def _resonance_stderr(before: SweepFit, fit: StartsFit, lever_of, count: int) -> float:
    """The standard error of the first resonance of the lever ``lever_of(fit.internal)``: the reference's, scaled
    with it, and that of the first ``count`` refitted parameters (their covariance, through the lever)."""
    x = np.asarray(fit.internal, dtype=float)
    resonance = lever_of(x).free_resonance
    gradient = np.zeros(count)
    for i in range(count):
        step = 1e-6 * max(abs(x[i]), 1e-6)
        shifted = x.copy()
        shifted[i] -= step if i == 0 and x[i] > step else -step       # a mass stays non-negative
        gradient[i] = (lever_of(shifted).free_resonance - resonance) / (shifted[i] - x[i])
    scaled = resonance / before.lever.free_resonance * before["parameters"]["free_resonance"]["stderr"]
    variance = float(gradient @ np.asarray(fit.covariance)[:count, :count] @ gradient) + scaled ** 2
    return math.sqrt(variance) if math.isfinite(variance) else math.nan


SWAPPED = 3.0
"""Standard errors by which the fitted :data:`RISE` must exceed 1 for the sweeps to look swapped."""


def _resonance_factor(before: SweepFit, frequency, y, sigma) -> tuple[float, float]:
    """The factor on the reference lever's resonances (:data:`RISE`) that explains the after-sweep best, gain
    and background refitted, and its standard error: a scan over 0.7-1.4 (a sharp peak moved by many widths
    has a narrow basin), refined from its best."""
    refit = ("rise", "gain", "background")
    solve, _, residual, params = _candidate(before, refit, frequency, y, sigma)
    tail = _starts(before, refit)[0]
    scan = [np.r_[factor, tail] for factor in np.geomspace(0.7, 1.4, 57)]
    start = min(scan, key=lambda x: float(np.sum(residual(x) ** 2)))
    fit = solve_from_starts(residual, [start], *_bounds(before, refit, params), keep=1)
    return float(fit.internal[0]), float(math.sqrt(max(fit.covariance[0, 0], 0.0)))


def _order_notes(rise: tuple[float, float]) -> list[str]:
    """A hint when the two measurements look swapped: the reference lever's resonances raised explain the
    after-sweep (``rise``: :func:`_resonance_factor`), which no added mass does (a mass only lowers them)."""
    factor, stderr = rise
    if factor - 1 > SWAPPED * stderr:
        return [f"the resonances rose (the reference lever's, times {factor:.5g} +- {stderr:.2g}, explain it best): "
                "an added mass only lowers them, so no mass is named; if a mass was added, the two files may be "
                "swapped (the reference is the measurement before)"]
    return []


def _free_reals(before: SweepFit, refit) -> list[tuple[int, bool]]:
    """The amplitudes refitted, as ``(index in (G, b0, b1), imaginary part)``: a gain is complex for a
    complex sweep and real for an amplitude; the background complex unless it adds to the amplitude."""
    complex_gain, complex_background = not before.amplitude_only, before.coherent
    out = [(0, False)] + ([(0, True)] if complex_gain else []) if "gain" in refit else []
    for i in (1, 2) if "background" in refit else ():
        out += [(i, False)] + ([(i, True)] if complex_background else [])
    return out


def _candidate(before: SweepFit, refit, frequency, y, sigma, position=None):
    """One explanation of the after-sweep: ``solve(x) -> (residual, amplitudes)``, ``lever_of(x)``, the
    noise-scaled real ``residual(x)`` and the nonlinear parameters (the mass's ratio, its position when
    ``position`` is None, the damping), the rest of gain and background kept at ``before``'s.  A complex
    sweep's refitted amplitudes are solved out (linear); an amplitude's are parameters after those (its
    model is not linear in them, :func:`~pfmdyn.discrepancy.sweep.sweep_model`)."""
    mass, damping, rise = "added_mass" in refit, "damping" in refit, "rise" in refit
    params = ((ADDED_MASS,) + ((POSITION,) if position is None else ()) if mass else ()) \
        + ((RISE,) if rise else ()) + ((EXTRA_LOSS,) if damping else ())
    n = len(params)
    free = [i for i, key in enumerate(("gain", "background", "background")) if key in refit]
    fixed = [i for i in range(3) if i not in free]
    known = np.array([before.gain, *before.background], dtype=complex)
    reals = _free_reals(before, refit)

    def lever_of(x):
        lever = replace(before.lever, viscous_loss=x[n - 1]) if damping else before.lever
        if rise:
            return _at_vacuum_resonance(lever, replace(lever, medium=None), lever.vacuum_resonance * x[0])
        return with_added_mass(lever, x[0], x[1] if position is None else position) if mass else lever

    def solve(x):
        columns = base_driven_columns(lever_of(x), frequency, before.centre_hz)
        if before.amplitude_only:
            amplitudes = known.copy()
            for value, (i, imaginary) in zip(x[n:], reals):
                amplitudes[i] = amplitudes[i].real + 1j * value if imaginary else value + 1j * amplitudes[i].imag
            return y - sweep_model(columns, amplitudes, True, before.coherent), amplitudes
        rest = y - columns[:, fixed] @ known[fixed]
        if not free:
            return rest, known
        pr = project(columns[None][..., free], rest[None, :, None].astype(complex))
        amplitudes = known.copy()
        amplitudes[free] = pr.amplitudes[0, :, 0]
        return pr.residual[0, :, 0], amplitudes

    def residual(x):
        try:
            return stacked(np.asarray(solve(x)[0])) / sigma
        except UserError:       # a mass that takes the lever's resonance out of any real range
            return penalty(y)

    return solve, lever_of, residual, params


def _bounds(before: SweepFit, refit, params) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of :func:`_candidate`'s parameters (an amplitude's are free)."""
    extra = len(_free_reals(before, refit)) if before.amplitude_only else 0
    return (np.r_[[p.lower for p in params], np.full(extra, -np.inf)],
            np.r_[[p.upper for p in params], np.full(extra, np.inf)])


def _starts(before: SweepFit, refit, shifted: float | None = None) -> list:
    """Starting points at a given position: masses over decades (and ``shifted``, the mass that moves the
    first mode as far as the measured peak moved, :func:`_shift_seed`), the damping and an amplitude's
    refitted parts at ``before``'s."""
    tail = [before.lever.viscous_loss] if "damping" in refit else []
    known = [before.gain, *before.background]
    tail += [known[i].imag if imaginary else known[i].real for i, imaginary in _free_reals(before, refit)] \
        if before.amplitude_only else []
    seeds = (0.0, 0.003, 0.03, 0.3) + ((shifted,) if shifted else ())
    return [np.array(([s] if "added_mass" in refit else []) + tail)
            for s in (seeds if "added_mass" in refit else (0.0,))]


def _shift_seed(before: SweepFit, frequency, y, position: float) -> float | None:
    """The mass ratio at ``position`` that lowers the first mode by the shift of the tallest measured point
    in its window (below the geometric middle of modes 1 and 2) from where ``before``'s model peaks there:
    a start inside the true minimum's basin, which for a sharp peak moved by many widths is narrower
    than the decades between the other starts; None when the peak did not fall."""
    f = np.asarray(frequency, float)
    window = f < np.sqrt(mode_ratios()[1]) * before.lever.free_resonance
    if window.sum() < 3:
        return None
    fw = f[window]
    peak_after = fw[np.argmax(np.abs(y[window]))]
    peak_before = fw[np.argmax(np.abs(before.model(fw)))]
    if not peak_after < peak_before:
        return None
    target = before.lever.free_resonance * peak_after / peak_before

    def excess(log_ratio):
        try:
            return with_added_mass(before.lever, 10.0**log_ratio, position).free_resonance - target
        except UserError:
            return -target
    low, high = -6.0, math.log10(ADDED_MASS.upper)
    if not excess(low) > 0 > excess(high):
        return None
    from scipy.optimize import brentq

    return float(10.0 ** brentq(excess, low, high, xtol=1e-4))


def _peak_ratios(before: SweepFit, frequency, y) -> tuple[float, float] | None:
    """How far each of the first two modes' peaks moved: the tallest measured point of each mode's window
    (split at the geometric middles of modes 1, 2 and 3) over where ``before``'s model peaks there; None
    when a window holds under three points, mode 1's peak did not fall or mode 2's rose."""
    f = np.asarray(frequency, float)
    ratios, edges = mode_ratios(), [0.0]
    edges += [math.sqrt(ratios[0] * ratios[1]), math.sqrt(ratios[1] * ratios[2])]
    out = []
    for low, high in zip(edges[:-1], edges[1:]):
        window = (f >= low * before.lever.free_resonance) & (f < high * before.lever.free_resonance)
        if window.sum() < 3:
            return None
        fw = f[window]
        moved = fw[np.argmax(np.abs(y[window]))] / fw[np.argmax(np.abs(before.model(fw)))]
        if not (moved < 1.0 or out and moved <= 1.0):      # mode 2 may stay: a mass at its node
            return None
        out.append(float(moved))
    return out[0], out[1]


def _two_free_roots(lever: Cantilever, ratio: float, position: float) -> np.ndarray:
    """The first two free roots ``beta`` of the lever in vacuum with a point mass ``ratio`` at ``position``
    (the composed model's characteristic, bracketed on a grid and refined)."""
    from .. import composed
    from ..roots.bracket import refine

    def char(b):
        return composed.characteristic(b, lever.model_parameters(None)._replace(mu=ratio, gamma=position, rho_g=0.0))
    grid = np.linspace(0.3, 5.0, 95)
    with np.errstate(all="ignore"):
        values = char(grid)
    change = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[:2]
    if len(change) < 2:
        return np.full(2, np.nan)
    return refine(char, grid[change], grid[change + 1], values[change], values[change + 1], rtol=1e-12)


def _valley_spread(lever: Cantilever, ratio: float, position: float, position_stderr: float) -> float:
    """Half the difference of the masses that move the first free mode (in vacuum) as ``ratio`` at
    ``position`` does from one ``position_stderr`` either side: the mass's spread along its valley with
    the position (0 where no such mass is within the bounds)."""
    if not (ratio > 0 and position_stderr > 0):
        return 0.0
    from scipy.optimize import brentq

    target = _two_free_roots(lever, ratio, position)[0]
    masses = []
    for x in (position - position_stderr, position + position_stderr):
        x = min(max(x, POSITION.lower), POSITION.upper)

        def excess(log_ratio, x=x):
            return _two_free_roots(lever, 10.0**log_ratio, x)[0] - target
        low, high = -6.0, math.log10(ADDED_MASS.upper)
        if not excess(low) > 0 > excess(high):
            masses.append(ADDED_MASS.upper if x < position else 0.0)
            continue
        masses.append(10.0 ** brentq(excess, low, high, xtol=1e-6))
    return abs(masses[0] - masses[1]) / 2


POSITION_SCAN = tuple(np.linspace(0.05, 1.0, 96))
"""Positions (x/L) scanned for the masses that move the first two modes as the peaks moved."""


def _position_seeds(before: SweepFit, frequency, y) -> list[tuple[float, float]]:
    """Starts ``(mass ratio, x/L)`` where a mass moves both of the first two modes as far as their peaks
    moved (:func:`_peak_ratios`), the lever taken in vacuum: at each position of :data:`POSITION_SCAN` the
    mass that moves mode 1 so, then where mode 2's move crosses the measured one (a position and its
    mirror about the node of mode 2 both), else where it comes nearest.  A sharp mode has a valley in
    (mass, position) narrower than the position profile's steps; these start inside it."""
    moved = _peak_ratios(before, frequency, y)
    if moved is None:
        return []
    bare = _two_free_roots(before.lever, 0.0, 1.0)
    from scipy.optimize import brentq

    scan = []
    for x in POSITION_SCAN:
        def excess(log_ratio, x=x):
            return (_two_free_roots(before.lever, 10.0**log_ratio, x)[0] / bare[0]) ** 2 - moved[0]
        low, high = -6.0, math.log10(ADDED_MASS.upper)
        if not excess(low) > 0 > excess(high):
            continue
        ratio = 10.0 ** brentq(excess, low, high, xtol=1e-6)
        scan.append((x, ratio, (_two_free_roots(before.lever, ratio, x)[1] / bare[1]) ** 2 - moved[1]))
    if not scan:
        return []
    miss = np.array([s[2] for s in scan])
    seeds = [(scan[i][1], scan[i][0]) for i in np.flatnonzero(np.sign(miss[:-1]) * np.sign(miss[1:]) <= 0)]
    nearest = scan[int(np.nanargmin(np.abs(miss)))]
    return seeds + [(nearest[1], nearest[0])]


def _position_profile(before, refit, frequency, y, sigma, shifted, seeds=()):
    """The mass and its position fitted: the mass at each position of :data:`POSITION_GRID` (a profile
    of chi2 along the lever; ``shifted``: position -> the start of :func:`_shift_seed`), then both
    refined from the profile's local minima, from ``seeds`` (:func:`_position_seeds`: ``(mass, x/L)`` that
    move both modes as the peaks moved) and from the best's mirror about mode 2's node, the best kept
    and the others kept as its ``others`` (:func:`_rivals`: the shifts of two modes can agree on both
    sides of a node)."""
    profile = []
    for x in POSITION_GRID:
        _, _, residual, params = _candidate(before, refit, frequency, y, sigma, x)
        fit = solve_from_starts(residual, _starts(before, refit, shifted[x]), *_bounds(before, refit, params), keep=1)
        profile.append((fit.chi2, np.insert(fit.internal, 1, x)))
    chi2 = np.array([c for c, _ in profile])
    minima = [i for i in range(len(chi2)) if chi2[i] <= chi2[max(i - 1, 0)] and chi2[i] <= chi2[min(i + 1, len(chi2) - 1)]]
    solve, lever_of, residual, params = _candidate(before, refit, frequency, y, sigma)
    bounds = _bounds(before, refit, params)
    starts = [profile[i][1] for i in minima]
    template = profile[0][1]
    for ratio, x in seeds:
        start = template.copy()
        start[:2] = ratio, x
        starts.append(start)
    refined = sorted((solve_from_starts(residual, [s], *bounds, keep=1) for s in starts), key=lambda f: f.chi2)
    # The mirror of the best position about mode 2's node moves both modes alike: a minimum the grid, a
    # tenth of the lever apart, can miss when both sit in one of its steps (x/L 0.76 and 0.82; 0.779 and
    # 0.788, their masses 3 % apart, for a sharp mode 2).
    mirror = 2 * mode2_node() - refined[0].internal[1]
    if POSITION.lower <= mirror <= POSITION.upper and abs(mirror - refined[0].internal[1]) > _apart(refined[0]):
        start = refined[0].internal.copy()
        start[1] = mirror
        refined = sorted([*refined, solve_from_starts(residual, [start], *bounds, keep=1)], key=lambda f: f.chi2)
    best = replace(refined[0], others=tuple((f.internal, f.chi2) for f in refined[1:]))
    return best, solve, lever_of, params


def mode2_node() -> float:
    """x/L of the node of the second free mode of a uniform clamped-free beam (where a point mass moves mode 1
    alone), from the mode's root ``1 + cos(b) cosh(b) = 0`` and its shape.

    >>> round(mode2_node(), 4)
    0.7834
    """
    from scipy.optimize import brentq

    b = brentq(lambda v: 1 + math.cos(v) * math.cosh(v), 4.0, 5.0, xtol=1e-14)
    ratio = (math.cosh(b) + math.cos(b)) / (math.sinh(b) + math.sin(b))
    shape = lambda x: math.cosh(b * x) - math.cos(b * x) - ratio * (math.sinh(b * x) - math.sin(b * x))  # noqa: E731
    return float(brentq(shape, 0.5, 0.95, xtol=1e-14))


def _apart(fit: StartsFit) -> float:
    """How far (x/L) another minimum's position must be from ``fit``'s to be another place: three of its
    standard errors, at least :data:`MIN_APART`."""
    return max(3.0 * math.sqrt(max(fit.covariance[1, 1], 0.0)), MIN_APART)


MIN_APART = 0.002
"""The least separation (x/L) of two positions reported as two solutions (a sharp mode's mirror about the
node of mode 2 can sit 0.008 away with a mass 3 % apart)."""


def _rivals(fit: StartsFit, count: int) -> list:
    """Other minima ``(internal, chi2)`` of ``fit`` within 4 reduced-chi2 units at another position: farther
    than :func:`_apart` from the best and from each other."""
    scale = max(fit.chi2 / count, 1.0)
    apart = _apart(fit)
    out = []
    for x, chi2 in sorted(fit.others, key=lambda other: other[1]):      # one per place: starts may meet
        if chi2 - fit.chi2 < 4.0 * scale and all(abs(x[1] - kept[1]) > apart for kept in [fit.internal, *(o for o, _ in out)]):
            out.append((x, chi2))
    return out


class SweepComparison(Result):
    """Two sweeps compared (:func:`compare_sweeps`): ``to_dict()`` the JSON fields, ``report()`` the
    table of candidates and the named change; attribute ``lever``, the after-sweep's lever."""

    def report(self) -> str:
        """The candidates (refitted parameters, gap, BIC), the named change, the resonances, the gaps."""
        d = self._fields
        p = d["parameters"]
        lines = [f"{d['path']} explained from {d['reference']} (lever, fluid, gain, background calibrated there)",
                 f"  {'effect':<36} refitted  gap     BIC"]
        lines += [f"  {r['effect']:<36} {r['parameters']:>8}  {r['gap']:<7.3g} {r['bic']:.6g}" for r in d["steps"]]
        lines.append(f"  named: {d['effect']}" + (f" (nuisances: {', '.join(d['nuisances'])})" if d["nuisances"] else ""))
        if d["effect"] == "added_mass" and not p["added_mass"]["determined"]:
            m = p["added_mass"]
            lines.append(f"  added_mass undetermined ({m['why']}): {plus_minus(m, 'kg')}")
            lines += [f"    or {v['added_mass']:.4g} kg at x/L {v['added_mass_position']:.3g} (gap {v['gap']:.3g})"
                      for v in m.get("solutions", [])[1:]]
        elif d["effect"] == "added_mass":
            m = p["added_mass"]
            where = p["added_mass_position"]
            if where.get("solutions"):
                others = ", ".join(f"{v['added_mass_position']:.3g}" for v in where["solutions"][1:])
                at = f"at x/L {where['value']:.3g} or {others} ({where['why']})"
            elif where.get("undetermined"):
                at = "the end-equivalent mass (one mode cannot place it: position undetermined)"
            else:
                at = f"at x/L {plus_minus(where, '')}" + (" (given)" if where.get("given") else " (fitted)")
            lines.append(f"  added_mass {plus_minus(m, 'kg')} ({m['value'] * 1e15:.4g} pg), {at}")
        if "viscous_loss" in p:
            lines.append(f"  damping beyond the fluid's: viscous_loss {p['viscous_loss']['before']:.4g} -> "
                         f"{plus_minus(p['viscous_loss'], '')}")
        lines.append(f"  lever mass {derived_text(d, 'lever_mass', 'kg')} (the reference's); after: gain "
                     f"{_complex_text(d['gain_after'], d['gain_after_stderr'])}, background "
                     + ", ".join(_complex_text(b, e) for b, e in zip(d["background_after"], d["background_after_stderr"])))
        before_hz, after_hz = ({"value": d[f"resonance_{when}"], "stderr": d["resonance_stderr"][i]}
                               for i, when in enumerate(("before", "after")))
        lines.append(f"  resonance in the medium {plus_minus(before_hz, '')} -> {plus_minus(after_hz, 'Hz')}; "
                     f"instrument: {instrument_text(d['reference_fit']['instrument_fit'], d['reference_fit'].get('instrument_comparison'))} -> {instrument_text(d['instrument_fit'], d.get('instrument_comparison'))}")
        lines.append(f"  gap {d['gap_before']:.3g} (before's model as is) -> "
                     + gap_text(d["gap_after"], d.get("worst_region"))[4:])
        lines += [f"  note: {text}" for text in d.get("notes", [])]
        return "\n".join(lines + unexplained_line(d.get("unexplained")) + provenance_lines(d))
