"""Drive sweeps explained as spectra: a base-driven free lever in a fluid, and what changed between two.

A drive sweep (:func:`pfmdyn.io.sweeps.read_sweep_table`: Cytomass ``.txt``, Nanonis ``.dat``) is the
read-out of a lever whose clamp a dither piezo shakes.  Its model (:func:`fit_sweep`) is

``y(f) = G s(f) + b0 + b1 (f / f_c - 1)``,

``s`` the slope at the laser spot per unit base displacement (:meth:`pfmdyn.Cantilever.base_driven`,
every mode, the fluid's load from Sader's hydrodynamic function, :mod:`pfmdyn.medium`), ``G`` a complex
gain (a real scale of ``|s|`` when the file has no phase), ``b0 + b1 (...)`` a linear background
(cross-talk, the piezo's own signal) and ``f_c`` the sweep's centre.  The lever's spring constant and
length are given; fitted are its first resonance *in the medium* and a viscous damping beyond the fluid's
(``viscous_loss``, 0 when none is needed); the width the fluid acts across is given, else assumed
(:data:`WIDTH_NOTE`: one mode cannot tell the two dampings apart).  The amplitudes
are solved out of the fit (variable projection, :func:`pfmdyn.fitting.projection.project`); the
instrument's own fit in the header is reported beside, never used instead of the data.

Two sweeps (:func:`compare_sweeps`): the lever, the fluid, the gain and the background calibrated on
the reference (before), the other sweep (after) explained from them by nested candidates -- nothing,
a gain, background or damping change (nuisances; the damping is ``viscous_loss``, the cell's drag), a point mass (``added_mass``, kg, at ``added_mass_position``
x/L: given, fitted when the sweep spans two modes or more, else undetermined and the mass given as
the end-equivalent one) and the mass with the nuisances -- the one of least BIC named, each with its
gap (the noise-normalised RMS residual, :func:`pfmdyn.fitting.noise.gap`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from ..cantilever import BETA1_FREE, Cantilever
from ..errors import UserError
from ..fitting.noise import GAP_LIMIT, gap, misfit_band, noise_sigma
from ..fitting.parameters import Parameter
from ..fitting.projection import jacobian_covariance, project
from ..fitting.result import Result
from ..io.sweeps import SweepTable
from ..medium import Medium

__all__ = ["SweepFit", "SweepComparison", "fit_sweep", "compare_sweeps", "with_added_mass", "CANDIDATES"]

RESONANCE = Parameter("free_resonance", "Hz", 2.7, 8.0, transform="log10",
                      description="first free resonance in the medium")
EXTRA_LOSS = Parameter("viscous_loss", "", 0.0, 10.0, null=0.0, seeds=(0.0, 0.003, 0.03, 0.3),
                       description="viscous damping beyond the fluid's: 1/Q of free mode 1 under it alone")
ADDED_MASS = Parameter("added_mass_ratio", "", 0.0, 100.0, null=0.0,
                       description="point mass over the lever's mass")
POSITION = Parameter("added_mass_position", "", 0.05, 1.0, description="point mass position x/L")

ASSUMED_WIDTH = 0.1
"""The width, over the length, of a lever whose width is not given (:data:`WIDTH_NOTE`)."""
WIDTH_NOTE = ("not given: assumed L/10; one mode cannot tell the fluid's damping from a viscous one (both "
              "widen the peak), so a narrow lever leaves it to viscous_loss; give --width for the fluid's share")

CANDIDATES = (("nothing", ()), ("gain", ("gain",)), ("background", ("background",)),
              ("gain+background", ("gain", "background")), ("added_mass", ("added_mass",)),
              ("damping", ("damping",)), ("added_mass+gain+background", ("added_mass", "gain", "background")),
              ("added_mass+damping+gain+background", ("added_mass", "damping", "gain", "background")))
"""The explanations of an after-sweep tried by :func:`compare_sweeps`: a name and what is refitted."""

MIN_POINTS = 8
"""Fewer measured points than this cannot fix a resonance, a damping, a gain and a background."""

MODE_RATIOS = (1.0, 6.2669, 17.5475)
"""The free beam's first three resonances over the first: ``(beta_n / beta_1)**2``."""

POSITION_GRID = tuple(np.linspace(0.1, 1.0, 10))
"""Starting positions (x/L) of a fitted added mass."""

_PENALTY = 1e6
"""Residual (in noise units) of a lever the fluid cannot carry (its load exceeds the lever's inertia)."""


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
        loaded, f_loaded = bare, f_vac
    else:
        loaded = replace(bare, tip_mass_ratio=float(ratio), tip_position=float(position))
        f_loaded = f_vac * (loaded.free_root() / BETA1_FREE)**2
    loaded = replace(loaded, free_resonance=f_loaded, viscous_loss=lever.viscous_loss * f_vac / f_loaded)
    return loaded if lever.medium is None else loaded.with_medium(lever.medium)


@dataclass(frozen=True)
class _Fit:
    """One least-squares fit: internal parameters, their covariance, chi2, and the other minima
    refined from other starts as ``(internal, chi2)``."""

    internal: np.ndarray
    covariance: np.ndarray
    chi2: float
    others: tuple = ()


def _columns(lever: Cantilever, frequency, centre: float, amplitude_only: bool) -> np.ndarray:
    """The model's columns ``(n, 3)``: the slope per base displacement, 1 and ``f / f_c - 1``."""
    slope = lever.base_driven(frequency).slope
    slope = np.abs(slope) if amplitude_only else slope
    return np.stack([slope, np.ones_like(slope), frequency / centre - 1.0 + 0 * slope], axis=-1)


def _solve(residual, starts, lower, upper, keep: int = 3) -> _Fit:
    """Least squares refined from the ``keep`` cheapest of ``starts`` (internal coordinates); the best,
    with its covariance scaled by the reduced chi2 (a misfit widens the uncertainties)."""
    if not len(starts[0]):
        r = residual(np.zeros(0))
        return _Fit(np.zeros(0), np.zeros((0, 0)), float(r @ r))
    costs = [float(np.sum(residual(x)**2)) for x in starts]
    outs = sorted((least_squares(residual, np.clip(starts[i], lower, upper), bounds=(lower, upper), x_scale="jac",
                                 diff_step=1e-7, max_nfev=200) for i in np.argsort(costs)[:keep]),
                  key=lambda out: out.cost)
    best, r = outs[0], outs[0].fun
    covariance = jacobian_covariance(best.jac, max(float(r @ r) / max(r.size - len(best.x), 1), 1.0))
    return _Fit(best.x, covariance, float(r @ r), tuple((o.x, 2 * o.cost) for o in outs[1:]))


def _value(parameter: Parameter, internal: float, variance: float) -> dict:
    sd = math.sqrt(variance) if math.isfinite(variance) else math.inf
    return {"value": float(parameter.value(internal)), "stderr": parameter.stderr(internal, sd) if math.isfinite(sd)
            else math.nan, "unit": parameter.unit or "1"}


class SweepFit(Result):
    """One sweep fitted (:func:`fit_sweep`): ``to_dict()`` the JSON fields, ``report()`` the summary;
    attributes ``lever`` (the fitted :class:`~pfmdyn.Cantilever`), ``gain``, ``background`` (``b0,
    b1``), ``centre_hz``, ``amplitude_only``, ``conjugate`` (the file's phase runs the other way),
    ``sigma`` (the noise) and :meth:`model`."""

    def model(self, frequency, lever: Cantilever | None = None, gain=None, background=None) -> np.ndarray:
        """The fitted model at ``frequency`` (Hz), with any of the lever, gain, background replaced."""
        lever = self.lever if lever is None else lever
        gain = self.gain if gain is None else gain
        b0, b1 = self.background if background is None else background
        columns = _columns(lever, np.asarray(frequency, float), self.centre_hz, self.amplitude_only)
        return columns @ np.array([gain, b0, b1])

    def data(self, table: SweepTable) -> np.ndarray:
        """``table``'s response as this fit reads it (amplitude only, or conjugated)."""
        y = table.amplitude if self.amplitude_only else table.response
        return np.conj(y) if self.conjugate else y

    def report(self) -> str:
        """``sweep FILE: ... resonance ..., Q ...; instrument: ...; gap ...``."""
        d = self._fields
        p = d["parameters"]
        width = p["width"]
        extra = p["viscous_loss"]
        lines = [f"sweep {d['path']}: {d['points']} measured points fitted as a base-driven free lever in "
                 f"{d['medium']} (k {d['spring_constant']:g} N/m, L {d['length']:g} m)",
                 f"  resonance in the medium {_pm(p['free_resonance'], 'Hz')}, vacuum {d['vacuum_resonance']:.6g} Hz, "
                 f"Q {d['quality_factor']:.3g}, amplitude peak {d['peak_hz']:.6g} Hz",
                 f"  width {_pm(width, 'm')}" + (" (given)" if width["given"] else f" ({width['why']})"),
                 f"  damping beyond the fluid's: viscous_loss {_pm(extra, '')}",
                 f"  instrument: {_instrument(d['instrument_fit'])}",
                 f"  gap {d['gap']:.3g} (1: fitted to the noise)"] + _unexplained_line(d.get("unexplained"))
        return "\n".join(lines)


def _pm(entry: dict, unit: str) -> str:
    value, err = entry["value"], entry.get("stderr")
    text = f"{value:.6g}" + (f" +- {err:.2g}" if err is not None and math.isfinite(err) and err > 0 else "")
    return text + (f" {unit}" if unit else "")


def _instrument(fields: dict) -> str:
    f, q = fields.get("free_resonance"), fields.get("free_quality_factor")
    if f is None and q is None:
        return "no fit in the header"
    return ", ".join(([f"{f:,.0f} Hz".replace(",", " ")] if f else []) + ([f"Q {q:.3g}"] if q else []))


def _unexplained(frequency, y, residual, sigma) -> dict | None:
    """What the fit leaves when its gap exceeds :data:`GAP_LIMIT`: the gap, the band holding most of
    the misfit and the largest residual as a share of the largest measured value; None otherwise."""
    g = float(gap(np.sum(np.abs(residual / sigma) ** 2), len(residual)))
    if g <= GAP_LIMIT:
        return None
    return {"gap": g, "where": misfit_band(frequency, np.abs(residual / sigma) ** 2),
            "largest_residual": float(np.max(np.abs(residual)) / np.max(np.abs(y)))}


def _unexplained_line(entry: dict | None) -> list[str]:
    if not entry:
        return []
    low, high = entry["where"]
    of = "the value there" if entry.get("relative") else "the largest measured value"
    return [f"  unexplained: the residual at {low / 1e3:.6g}-{high / 1e3:.6g} kHz (gap {entry['gap']:.3g} x noise, "
            f"largest {entry['largest_residual']:.1%} of {of}) is beyond the model"]


def _noise(frequency, y) -> float:
    sigma = noise_sigma(frequency, np.zeros(len(y)), y)
    return max(sigma, 1e-9 * float(np.sqrt(np.mean(np.abs(y)**2))), 1e-300)


def _penalty(y) -> np.ndarray:
    return np.full(2 * len(y) if np.iscomplexobj(y) else len(y), _PENALTY)


def _stack(r) -> np.ndarray:
    return np.concatenate([r.real, r.imag]) if np.iscomplexobj(r) else r


def _peak(lever: Cantilever, frequency) -> float:
    grid = np.linspace(frequency.min(), frequency.max(), 2001)
    return float(grid[np.argmax(np.abs(lever.base_driven(grid).slope))])


def fit_sweep(table: SweepTable, spring_constant: float, length: float, medium: Medium,
              width: float | None = None) -> SweepFit:
    """Fit a drive sweep over its measured points (see the module): the lever's resonance in
    ``medium`` and a damping beyond the fluid's; ``width`` None: assumed (:data:`WIDTH_NOTE`).

    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(4e4, 1e5, 120)
    >>> lever = Cantilever(8.0, 7.2e4, 1e-4, width=4e-5, medium=Medium.water())
    >>> y = (0.3 - 2j) * lever.base_driven(f).slope + 0.5
    >>> table = SweepTable("s.txt", f, np.abs(y), "V", np.degrees(np.angle(y)), {}, None, "synthetic")
    >>> fit = fit_sweep(table, 8.0, 1e-4, Medium.water(), width=4e-5)
    >>> round(fit["parameters"]["free_resonance"]["value"]), round(fit["parameters"]["viscous_loss"]["value"], 6)
    (72000, 0.0)
    """
    frequency = table.frequency_hz
    if len(frequency) < MIN_POINTS:
        raise UserError(f"{table.path}: {len(frequency)} measured points; a sweep fit needs at least {MIN_POINTS}")
    amplitude_only = table.phase_deg is None
    centre = 0.5 * (frequency.min() + frequency.max())
    params = (RESONANCE, EXTRA_LOSS)
    lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])
    given = width is not None
    width = width if given else ASSUMED_WIDTH * length

    def lever_of(x) -> Cantilever:
        return Cantilever(spring_constant, 10.0**x[0], length, width=width, medium=medium, viscous_loss=x[1])

    # the frequencies across the sweep, and where the response departs most from its median (a sharp
    # peak) read as the first mode; only when that leaves a misfit, as the second or third too (a
    # narrow sweep around one peak fits either way: the first mode is the one meant, and a higher one
    # replaces it only when it halves the misfit)
    deviation = np.abs(table.response - np.median(table.response.real) - 1j * np.median(np.imag(table.response)))
    best = None
    for ratios in ((1.0,), MODE_RATIOS):
        seeds_f = np.log10(np.append(np.geomspace(frequency.min() / 3, frequency.max(), 20),
                                     frequency[np.argmax(deviation)] / np.array(ratios)))
        grid = [np.array([a, b]) for a in seeds_f for b in EXTRA_LOSS.seeds]
        for conjugate in ((False,) if amplitude_only else (False, True)):
            y = table.amplitude if amplitude_only else (np.conj(table.response) if conjugate else table.response)
            sigma = _noise(frequency, y)

            def residual(x, y=y, sigma=sigma):
                try:
                    columns = _columns(lever_of(x), frequency, centre, amplitude_only)
                except UserError:       # a width whose fluid the lever cannot carry
                    return _penalty(y)
                pr = project(columns[None], y[None, :, None].astype(columns.dtype))
                return _stack(pr.residual[0, :, 0]) / sigma

            fit = _solve(residual, grid, lower, upper)
            to_beat = best[0].chi2 * (0.5 if best[4] and len(ratios) > 1 else 1.0) if best else np.inf
            if fit.chi2 < to_beat:
                best = (fit, conjugate, y, sigma, len(ratios) == 1)
        if gap(best[0].chi2, len(frequency)) <= GAP_LIMIT:
            break
    fit, conjugate, y, sigma, _ = best
    try:
        lever = lever_of(fit.internal)
        columns = _columns(lever, frequency, centre, amplitude_only)
    except UserError:       # every start ended on the penalty
        raise UserError(f"{table.path}: no lever of this spring constant, length and width carries {medium.name}'s "
                        "load at a resonance near the sweep (check them)") from None
    projected = project(columns[None], y[None, :, None].astype(columns.dtype))
    amplitudes = projected.amplitudes[0, :, 0]
    parameters = {p.key: _value(p, x, fit.covariance[i, i]) for i, (p, x) in enumerate(zip(params, fit.internal))}
    parameters["width"] = {"value": width, "stderr": None, "unit": "m", "given": given}
    if not given:
        parameters["width"]["why"] = WIDTH_NOTE
    from ..analysis.resonances import resonances

    modes = resonances(lever, None, modes=1).free
    fields = {"kind": "drive sweep", "path": table.path, "instrument": table.instrument, "points": len(frequency),
              "medium": medium.name, "spring_constant": spring_constant, "length": length,
              "vacuum_resonance": lever.vacuum_resonance, "quality_factor": float(modes.q[0]),
              "peak_hz": _peak(lever, frequency), "parameters": parameters,
              "gain": {"value": [float(np.real(amplitudes[0])), float(np.imag(amplitudes[0]))],
                       "unit": f"{table.unit or '1'}/rad"},
              "background": {"value": [[float(np.real(a)), float(np.imag(a))] for a in amplitudes[1:]],
                             "unit": table.unit or "1"},
              "amplitude_only": amplitude_only, "phase_reversed": conjugate,
              "instrument_fit": dict(table.fields), "noise": sigma, "gap": float(gap(fit.chi2, len(y))),
              "unexplained": _unexplained(frequency, y, projected.residual[0, :, 0], sigma)}
    return SweepFit(fields, lever=lever, gain=amplitudes[0], background=tuple(amplitudes[1:]), centre_hz=centre,
                    amplitude_only=amplitude_only, conjugate=conjugate, sigma=sigma, chi2=fit.chi2)


def _modes_in(lever: Cantilever, frequency) -> int:
    """How many of the lever's free modes (undamped, in the medium) lie inside the sweep."""
    from ..analysis.resonances import resonances

    wet = resonances(lever, None, modes=3).free.peak_hz
    return int(sum(frequency.min() <= f <= frequency.max() for f in wet if math.isfinite(f)))


def compare_sweeps(after: SweepTable, before: SweepFit, position: float | None = None) -> "SweepComparison":
    """Explain ``after`` from the lever, fluid, gain and background of ``before`` (a :func:`fit_sweep`):
    each of :data:`CANDIDATES` fitted, the one of least BIC named (see the module).  ``position``:
    the added mass's x/L (None: fitted when the sweep spans two modes, else undetermined and the mass
    given at the free end, the end-equivalent mass).

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
    sigma = _noise(frequency, y)
    n = len(y)
    count = 2 * n if np.iscomplexobj(y) else n
    fit_position = position is None and _modes_in(before.lever, frequency) >= 2
    x_mass = 1.0 if position is None else float(position)
    rows, fits = [], {}
    for name, refit in CANDIDATES:
        mass = "added_mass" in refit
        if mass and fit_position:
            fit, solve, lever_of, params = _position_profile(before, refit, frequency, y, sigma)
        else:
            solve, lever_of, residual, params = _candidate(before, refit, frequency, y, sigma, x_mass)
            lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])
            fit = _solve(residual, _starts(before, refit), lower, upper)
        free = [key for key in ("gain", "background") if key in refit]
        k = len(params) + sum(1 if key == "gain" else 2 for key in free) * (1 if before.amplitude_only else 2)
        residual, amplitudes = solve(fit.internal)
        fits[name] = (fit, params, amplitudes, lever_of(fit.internal), residual)
        rows.append({"effect": name, "refitted": list(refit), "parameters": k, "chi2": fit.chi2,
                     "bic": fit.chi2 + k * math.log(count), "gap": float(gap(fit.chi2, n))})
    best = min(rows, key=lambda r: r["bic"])
    fit, params, amplitudes, lever, _ = fits[best["effect"]]
    named = "added_mass" if "added_mass" in best["refitted"] else best["effect"]
    lever_mass = before.lever.beam_mass_per_length(before.lever.vacuum_resonance) * before.lever.length
    parameters = {}
    mass_fit = fits["added_mass+gain+background"][0] if named != "added_mass" else fit
    ratio = _value(ADDED_MASS, mass_fit.internal[0], mass_fit.covariance[0, 0])
    parameters["added_mass_ratio"] = ratio
    parameters["added_mass"] = {"value": ratio["value"] * lever_mass, "stderr": ratio["stderr"] * lever_mass,
                                "unit": "kg", "determined": named == "added_mass"}
    if "damping" in best["refitted"]:
        parameters["viscous_loss"] = {**_value(EXTRA_LOSS, fit.internal[-1], fit.covariance[-1, -1]),
                                      "before": before.lever.viscous_loss}
    if fit_position:
        parameters["added_mass_position"] = _value(POSITION, mass_fit.internal[1], mass_fit.covariance[1, 1])
        rivals = [x for x, chi2 in _rivals(mass_fit, count)]
        if rivals:
            parameters["added_mass_position"].update(
                undetermined=True, why="the modes' shifts agree as well at x/L " + ", ".join(f"{x:.3g}" for x in rivals))
    elif position is not None:
        parameters["added_mass_position"] = {"value": x_mass, "stderr": 0.0, "unit": "1", "given": True}
    else:
        parameters["added_mass_position"] = {"value": None, "stderr": None, "unit": "1", "undetermined": True,
                                             "why": "one mode in the sweep: the mass and its position move the "
                                                    "resonance together; the mass is the end-equivalent one (x/L = 1)"}
    fields = {"kind": "drive sweep comparison", "path": after.path, "reference": before["path"],
              "effect": named, "nuisances": [r for r in best["refitted"] if r != "added_mass"],
              "parameters": parameters, "lever_mass": lever_mass,
              "resonance_before": before.lever.free_resonance, "resonance_after": lever.free_resonance,
              "gap_before": rows[0]["gap"], "gap_after": best["gap"], "steps": rows,
              "gain_after": [float(np.real(amplitudes[0])), float(np.imag(amplitudes[0]))],
              "background_after": [[float(np.real(a)), float(np.imag(a))] for a in amplitudes[1:]],
              "instrument_fit": dict(after.fields), "reference_fit": before.to_dict(), "noise": sigma,
              "unexplained": _unexplained(frequency, y, fits[best["effect"]][4], sigma)}
    return SweepComparison(fields, lever=lever)


def _candidate(before: SweepFit, refit, frequency, y, sigma, position=None):
    """One explanation of the after-sweep: ``solve(x) -> (residual, amplitudes)``, ``lever_of(x)``, the
    noise-scaled real ``residual(x)`` and the nonlinear parameters (the mass's ratio, its position when
    ``position`` is None, the damping), the rest of gain and background kept at ``before``'s."""
    mass, damping = "added_mass" in refit, "damping" in refit
    params = ((ADDED_MASS,) + ((POSITION,) if position is None else ()) if mass else ()) \
        + ((EXTRA_LOSS,) if damping else ())
    free = [i for i, key in enumerate(("gain", "background", "background")) if key in refit]
    fixed = [i for i in range(3) if i not in free]
    known = np.array([before.gain, *before.background])

    def lever_of(x):
        lever = replace(before.lever, viscous_loss=x[-1]) if damping else before.lever
        return with_added_mass(lever, x[0], x[1] if position is None else position) if mass else lever

    def solve(x):
        columns = _columns(lever_of(x), frequency, before.centre_hz, before.amplitude_only)
        rest = y - columns[:, fixed] @ known[fixed]
        if not free:
            return rest, known
        pr = project(columns[None][..., free], rest[None, :, None].astype(np.result_type(columns, rest)))
        amplitudes = known.copy()
        amplitudes[free] = pr.amplitudes[0, :, 0]
        return pr.residual[0, :, 0], amplitudes

    def residual(x):
        try:
            return _stack(np.asarray(solve(x)[0])) / sigma
        except UserError:       # a mass that takes the lever's resonance out of any real range
            return _penalty(y)

    return solve, lever_of, residual, params


def _starts(before: SweepFit, refit) -> list:
    """Starting points at a given position: masses over decades, the damping at ``before``'s."""
    tail = [before.lever.viscous_loss] if "damping" in refit else []
    return [np.array(([s] if "added_mass" in refit else []) + tail)
            for s in ((0.0, 0.003, 0.03, 0.3) if "added_mass" in refit else (0.0,))]


def _position_profile(before, refit, frequency, y, sigma):
    """The mass and its position fitted: the mass at each position of :data:`POSITION_GRID` (a profile
    of chi2 along the lever), then both refined from the profile's local minima, the best kept and the
    others kept as its ``others`` (:func:`_rivals`: the shifts of two modes can agree on both sides
    of a node)."""
    profile = []
    for x in POSITION_GRID:
        _, _, residual, params = _candidate(before, refit, frequency, y, sigma, x)
        lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])
        fit = _solve(residual, _starts(before, refit), lower, upper, keep=1)
        profile.append((fit.chi2, np.insert(fit.internal, 1, x)))
    chi2 = np.array([c for c, _ in profile])
    minima = [i for i in range(len(chi2)) if chi2[i] <= chi2[max(i - 1, 0)] and chi2[i] <= chi2[min(i + 1, len(chi2) - 1)]]
    solve, lever_of, residual, params = _candidate(before, refit, frequency, y, sigma)
    lower, upper = np.array([p.lower for p in params]), np.array([p.upper for p in params])
    refined = sorted((_solve(residual, [profile[i][1]], lower, upper, keep=1) for i in minima), key=lambda f: f.chi2)
    best = replace(refined[0], others=tuple((f.internal, f.chi2) for f in refined[1:]))
    return best, solve, lever_of, params


def _rivals(fit: _Fit, count: int) -> list:
    """Other minima of ``fit`` at another position (x/L more than 0.05 away) within 4 reduced-chi2 units."""
    scale = max(fit.chi2 / count, 1.0)
    return [(x[1], chi2) for x, chi2 in fit.others if chi2 - fit.chi2 < 4.0 * scale and abs(x[1] - fit.internal[1]) > 0.05]


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
        if d["effect"] == "added_mass":
            m = p["added_mass"]
            where = p["added_mass_position"]
            at = "undetermined (one mode); end-equivalent mass" if where.get("undetermined") else \
                f"at x/L {_pm(where, '')}" + (" (given)" if where.get("given") else " (fitted)")
            lines.append(f"  added_mass {_pm(m, 'kg')} ({m['value'] * 1e15:.4g} pg), {at}")
        if "viscous_loss" in p:
            lines.append(f"  damping beyond the fluid's: viscous_loss {p['viscous_loss']['before']:.4g} -> "
                         f"{_pm(p['viscous_loss'], '')}")
        lines.append(f"  resonance in the medium {d['resonance_before']:.6g} -> {d['resonance_after']:.6g} Hz; "
                     f"instrument: {_instrument(d['reference_fit']['instrument_fit'])} -> {_instrument(d['instrument_fit'])}")
        lines.append(f"  gap {d['gap_before']:.3g} (before's model as is) -> {d['gap_after']:.3g}")
        return "\n".join(lines + _unexplained_line(d.get("unexplained")))
