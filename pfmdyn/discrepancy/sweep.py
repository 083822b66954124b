"""Drive sweeps explained as spectra: a base-driven free lever in a fluid.

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

The pieces the other free-lever fits share (:mod:`pfmdyn.discrepancy.reference`, two measurements compared;
:mod:`pfmdyn.discrepancy.thermal`, thermal tunes) live here too: the multi-start least squares, the
parameter entries of the JSON, the report's lines and what a fit leaves unexplained.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from ..digits import rounded
from ..cantilever import Cantilever
from ..errors import UserError
from ..fitting.noise import GAP_LIMIT, gap, misfit_band
from ..fitting.noise import spectrum_noise as noise_level
from ..fitting.parameters import Parameter
from ..fitting.projection import jacobian_covariance, project
from ..fitting.result import Result
from ..io.documents import OVERDAMPED
from ..io.sweeps import SweepTable
from ..medium import Medium
from ..names import NAMES
from .regions import gap_text, lever_resonances, worst_region

__all__ = ["SweepFit", "fit_sweep", "StartsFit", "solve_from_starts", "parameter_entry", "base_driven_columns",
           "sweep_model", "plus_minus", "quality_text", "error_text", "derived_text", "instrument_text", "compare_with_instrument", "explain_header", "disagreement_lines",
           "provenance_lines", "amplitude_peak", "unexplained_entry", "unexplained_line", "noise_level", "penalty", "stacked",
           "RESONANCE", "EXTRA_LOSS", "ASSUMED_WIDTH", "WIDTH_NOTE", "MIN_POINTS", "mode_ratios", "propagated",
           "joint_covariance", "amplitude_stderr", "error_entry", "parts", "with_parts", "UNDETERMINED_ERROR"]

RESONANCE = Parameter("free_resonance", "Hz", 2.7, 8.0, transform="log10",
                      description="first free resonance in the medium")
EXTRA_LOSS = Parameter("viscous_loss", "", 0.0, 10.0, null=0.0, seeds=(0.0, 0.003, 0.03, 0.3),
                       description="viscous damping beyond the fluid's: 1/Q of free mode 1 under it alone")
ASSUMED_WIDTH = 0.1
"""The width, over the length, of a lever whose width is not given (:data:`WIDTH_NOTE`)."""
WIDTH_NOTE = ("not given: assumed L/10; one mode cannot tell the fluid's damping from a viscous one (both "
              "widen the peak), so a narrow lever leaves it to viscous_loss; give the width for the fluid's share")

MIN_POINTS = 8
"""Fewer measured points than this cannot fix a resonance, a damping, a gain and a background."""

def mode_ratios() -> tuple[float, ...]:
    """The free beam's first three resonances over the first, ``(beta_n / beta_1)**2``, from its certified roots.

    >>> [round(r, 4) for r in mode_ratios()]
    [1.0, 6.2669, 17.5475]
    """
    roots = [float(r) for r in _free_roots()]
    return tuple((r / roots[0]) ** 2 for r in roots)


@lru_cache(maxsize=1)
def _free_roots() -> tuple[str, ...]:
    from ..roots.core import family_roots

    return family_roots("free", 3, 12).roots

_PENALTY = 1e6
"""Residual (in noise units) of a lever the fluid cannot carry (its load exceeds the lever's inertia)."""


@dataclass(frozen=True)
class StartsFit:
    """One least-squares fit: internal parameters, their covariance, chi2, and the other minima
    refined from other starts as ``(internal, chi2)``."""

    internal: np.ndarray
    covariance: np.ndarray
    chi2: float
    others: tuple = ()


def base_driven_columns(lever: Cantilever, frequency, centre: float) -> np.ndarray:
    """The model's columns ``(n, 3)``: the slope per base displacement, 1 and ``f / f_c - 1``."""
    slope = lever.base_driven(frequency).slope
    return np.stack([slope, np.ones_like(slope), frequency / centre - 1.0 + 0 * slope], axis=-1)


def sweep_model(columns, amplitudes, amplitude_only: bool, coherent: bool = True) -> np.ndarray:
    """The sweep the model predicts from its columns and amplitudes ``(G, b0, b1)``: the response; or, for a
    file with amplitude only, ``|G s + b0 + b1 u|`` (``coherent``: the background adds to the response, as
    a lock-in's feedthrough does) or ``G |s| + b0 + b1 u`` (it adds to the amplitude, real ``G, b0, b1``).

    >>> columns = np.array([[1j, 1.0, 0.0]])
    >>> sweep_model(columns, np.array([2.0, 1.0, 0.0]), True).tolist(), sweep_model(columns, np.array([2.0, 1.0, 0.0]), True, False).tolist()
    ([2.23606797749979], [3.0])
    """
    if not amplitude_only:
        return columns @ amplitudes
    if coherent:
        return np.abs(columns @ amplitudes)
    return np.abs(columns[:, 0]) * amplitudes[0].real + (columns[:, 1:].real @ np.real(amplitudes[1:]))


OFF_BOUND = 1e-6
"""How far inside its bounds a start is moved, as a share of the range (a bound at infinity: of 1)."""


def _inside(x, lower, upper) -> np.ndarray:
    """``x`` at least :data:`OFF_BOUND` of the range inside the bounds.  SciPy's trf moves a start on a bound
    only 1e-10 inside, scales that parameter's step by its distance to the bound, and stops there (the
    gradient it sees is ~0) though the data ask for it to move.

    >>> _inside(np.array([0.0, 5.0]), np.array([0.0, 4.0]), np.array([10.0, np.inf])).round(9).tolist()
    [1e-05, 5.0]
    """
    span = np.where(np.isfinite(upper - lower), upper - lower, 1.0) * OFF_BOUND
    return np.clip(x, lower + span, upper - span)


def own_jacobian(residual, x, lower, upper, step: float = 1e-7) -> np.ndarray:
    """The residual's Jacobian at ``x`` by one-sided differences (``step`` relative; backwards at the upper
    bound): SciPy's at a bound has that parameter's column zeroed (its variance, and everything it
    correlates with, undetermined).

    >>> own_jacobian(lambda x: np.array([x[0] - 0.5, x[1] ** 2]), np.array([0.0, 0.5]), np.zeros(2), np.ones(2)).round(6).tolist()
    [[1.0, 0.0], [0.0, 1.0]]
    """
    x = np.asarray(x, dtype=float)
    r = residual(x)
    columns = []
    for i in range(x.size):
        h = step * max(1.0, abs(x[i]))
        h = -h if x[i] + h > upper[i] else h
        moved = x.copy()
        moved[i] += h
        columns.append((residual(moved) - r) / h)
    return np.stack(columns, axis=-1)


def solve_from_starts(residual, starts, lower, upper, keep: int = 3) -> StartsFit:
    """Least squares refined from the ``keep`` cheapest of ``starts`` (internal coordinates; a start on a
    bound moved just inside it, :func:`_inside`); the best, with its covariance from the residual's own
    Jacobian (:func:`own_jacobian`) scaled by the reduced chi2 (a misfit widens the uncertainties)."""
    if not len(starts[0]):
        r = residual(np.zeros(0))
        return StartsFit(np.zeros(0), np.zeros((0, 0)), float(r @ r))
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    costs = [float(np.sum(residual(x)**2)) for x in starts]
    outs = sorted((least_squares(residual, _inside(np.asarray(starts[i], dtype=float), lower, upper),
                                 bounds=(lower, upper), x_scale="jac", diff_step=1e-7, max_nfev=200)
                   for i in np.argsort(costs)[:keep]), key=lambda out: out.cost)
    best, r = outs[0], outs[0].fun
    covariance = jacobian_covariance(own_jacobian(residual, best.x, lower, upper),
                                     max(float(r @ r) / max(r.size - len(best.x), 1), 1.0))
    return StartsFit(best.x, covariance, float(r @ r), tuple((o.x, 2 * o.cost) for o in outs[1:]))


def parameter_entry(parameter: Parameter, internal: float, variance: float) -> dict:
    """A fitted parameter's entry; one with a null (no such effect) that sits at it, or within two standard
    errors of it, is not determined: the data do not tell it from none.

    >>> parameter_entry(EXTRA_LOSS, 0.0, 1e-6)["determined"], parameter_entry(EXTRA_LOSS, 0.01, 1e-6)["stderr"]
    (False, 0.001)
    """
    sd = math.sqrt(variance) if math.isfinite(variance) else math.inf
    entry = {"value": float(parameter.value(internal)), "stderr": parameter.stderr(internal, sd) if math.isfinite(sd)
             else math.nan, "unit": parameter.unit or "1"}
    if parameter.null is not None and not abs(internal - parameter.null) > 2 * sd:
        entry.update(determined=False, why=f"at its bound ({parameter.value(parameter.null):g}) or within two "
                                           "standard errors of it: the data do not tell it from none")
    return entry


def propagated(function, internal, covariance, lower=None) -> float:
    """The standard error of ``function(internal)``, a quantity derived from fitted parameters, through their
    ``covariance``: its gradient by central differences a tenth of each parameter's standard error wide
    (forward at a ``lower`` bound); NaN where the covariance or the function does not determine it.

    >>> round(propagated(lambda x: x[0] * x[1], np.array([2.0, 3.0]), np.diag([0.01, 0.04])), 6)
    0.5
    """
    x = np.asarray(internal, dtype=float)
    covariance = np.asarray(covariance, dtype=float)
    if not np.all(np.isfinite(covariance)):
        return math.nan
    sd = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    gradient = np.zeros(x.size)
    try:
        for i in range(x.size):
            if sd[i] == 0.0:
                continue
            h = 0.1 * sd[i]
            up, down = x.copy(), x.copy()
            up[i] += h
            down[i] = x[i] if lower is not None and x[i] - h < lower[i] else x[i] - h
            gradient[i] = (function(up) - function(down)) / (up[i] - down[i])
    except UserError:           # a lever the fluid cannot carry one tenth of an error away
        return math.nan
    variance = float(gradient @ covariance @ gradient)
    return math.sqrt(variance) if math.isfinite(variance) and variance >= 0 else math.nan


def with_parts(amplitudes, values, reals) -> np.ndarray:
    """``amplitudes`` (complex) with the parts ``reals`` (``(index, imaginary)``) set to ``values``.

    >>> with_parts(np.array([1 + 2j, 3j]), [5.0, 7.0], [(0, True), (1, False)]).tolist()
    [(1+5j), (7+3j)]
    """
    a = np.array(amplitudes, dtype=complex)
    for value, (i, imaginary) in zip(values, reals):
        a[i] = a[i].real + 1j * value if imaginary else value + 1j * a[i].imag
    return a


def joint_covariance(residual_of, internal, amplitudes, reals) -> np.ndarray:
    """The covariance of the lever's parameters ``internal`` and the amplitudes' ``reals`` (``(index,
    imaginary)``: the parts fitted) together, from the noise-scaled ``residual_of(internal, amplitudes)``'s
    Jacobian (the amplitudes' uncertainty as well as what the lever's adds to it), scaled by the reduced
    chi2 when above 1."""
    n = len(internal)

    def residual(z):
        return residual_of(z[:n], with_parts(amplitudes, z[n:], reals))

    z = np.r_[internal, [np.imag(amplitudes[i]) if imaginary else np.real(amplitudes[i]) for i, imaginary in reals]]
    if not z.size:              # nothing refitted
        return np.zeros((0, 0))
    free = np.full(z.size, np.inf)
    r = residual(z)
    return jacobian_covariance(own_jacobian(residual, z, -free, free), max(float(r @ r) / max(r.size - z.size, 1), 1.0))


def amplitude_stderr(covariance, offset: int, reals, count: int = 3) -> list[complex]:
    """The standard errors of ``count`` amplitudes (real and imaginary parts) from the joint covariance
    (:func:`joint_covariance`), their fitted ``reals`` from ``offset`` on; a part not fitted has none (0).

    >>> amplitude_stderr(np.diag([1.0, 4.0, 9.0]), 1, [(0, False), (0, True)], 2)
    [(2+3j), 0j]
    """
    out = [0j] * count
    for j, (i, imaginary) in enumerate(reals):
        sd = math.sqrt(covariance[offset + j, offset + j]) if covariance[offset + j, offset + j] >= 0 else math.nan
        out[i] += 1j * sd if imaginary else sd
    return out


def error_entry(stderr: float, why: str) -> dict:
    """A derived quantity's uncertainty as the JSON carries it: ``{"stderr": x}``, or ``{"stderr": None,
    "why": why}`` where it is not a finite number.

    >>> error_entry(2.0, "no covariance"), error_entry(float("nan"), "no covariance")
    ({'stderr': 2.0}, {'stderr': None, 'why': 'no covariance'})
    """
    return {"stderr": float(stderr)} if math.isfinite(stderr) else {"stderr": None, "why": why}


UNDETERMINED_ERROR = "the fit's covariance does not determine it (a parameter the data leave free)"
"""Why a derived quantity has no standard error."""


class SweepFit(Result):
    """One sweep fitted (:func:`fit_sweep`): ``to_dict()`` the JSON fields, ``report()`` the summary;
    attributes ``lever`` (the fitted :class:`~pfmdyn.Cantilever`), ``gain``, ``background`` (``b0,
    b1``), ``centre_hz``, ``amplitude_only``, ``coherent`` (:func:`sweep_model`), ``conjugate`` (the
    file's phase runs the other way), ``sigma`` (the noise) and :meth:`model`."""

    def model(self, frequency, lever: Cantilever | None = None, gain=None, background=None) -> np.ndarray:
        """The fitted model at ``frequency`` (Hz), with any of the lever, gain, background replaced."""
        lever = self.lever if lever is None else lever
        gain = self.gain if gain is None else gain
        b0, b1 = self.background if background is None else background
        columns = base_driven_columns(lever, np.asarray(frequency, float), self.centre_hz)
        return sweep_model(columns, np.array([gain, b0, b1]), self.amplitude_only, self.coherent)

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
                 f"  resonance in the medium {plus_minus(p['free_resonance'], 'Hz')}, vacuum {derived_text(d, 'vacuum_resonance', 'Hz')}, "
                 f"Q {quality_text(d['quality_factor'], d['uncertainties']['quality_factor'])}, "
                 f"amplitude peak {derived_text(d, 'peak_hz', 'Hz')}",
                 f"  width {plus_minus(width, 'm')}" + (" (given)" if width["given"] else f" ({width['why']})"),
                 f"  damping beyond the fluid's: viscous_loss {plus_minus(extra, '')}",
                 f"  instrument: {instrument_text(d['instrument_fit'], d.get('instrument_comparison'))}",
                 f"  {gap_text(d['gap'], d.get('worst_region'))}"] + unexplained_line(d.get("unexplained"))
        return "\n".join(lines + provenance_lines(d))


def quality_text(q: float, error: dict | None = None) -> str:
    """The first mode's Q as a report prints it, with its ``error`` (:func:`error_entry`): undetermined, with
    why, where the mode is overdamped.

    >>> quality_text(3.1234, {"stderr": 0.05}), quality_text(float("nan"))
    ('3.123 +- 0.05', 'undetermined (the first mode in the medium is overdamped: no damped resonance, no Q)')
    """
    if not math.isfinite(q):
        return f"undetermined ({OVERDAMPED})"
    if error and error["stderr"]:
        return rounded(q, error["stderr"]) + error_text(error)
    return f"{q:.3g}" + (error_text(error) if error else "")


def error_text(error: dict) -> str:
    """`` +- x`` of an :func:`error_entry`, or `` +- undetermined (why)``.

    >>> error_text({"stderr": 12.345}), error_text({"stderr": None, "why": "a bound"})
    (' +- 12', ' +- undetermined (a bound)')
    """
    return f" +- {error['stderr']:.2g}" if error["stderr"] is not None else f" +- undetermined ({error['why']})"


def derived_text(d: dict, name: str, unit: str) -> str:
    """A report's derived quantity ``d[name]`` with its error (``d["uncertainties"][name]``) and unit.

    >>> derived_text({"f": 71234.4, "uncertainties": {"f": {"stderr": 40.0}}}, "f", "Hz")
    '71234 +- 40 Hz'
    """
    error = d["uncertainties"][name]
    return f"{rounded(d[name], error['stderr'] or 0.0)}{error_text(error)} {unit}".rstrip()


def plus_minus(entry: dict, unit: str) -> str:
    value, err = entry["value"], entry.get("stderr")
    known = err is not None and math.isfinite(err) and err > 0
    text = rounded(value, err if known else 0.0) + (f" +- {err:.2g}" if known else "")
    return text + (f" {unit}" if unit else "") + (" (not told from none)" if entry.get("determined") is False else "")


def _hz(value: float) -> str:
    return f"{value:,.0f} Hz".replace(",", " ")


def instrument_text(fields: dict, comparison: list | None = None) -> str:
    """The header's own fit, each value named and beside ours for the same quantity (``comparison``,
    :func:`compare_with_instrument`).

    >>> instrument_text({"amplitude_peak": 71789.1, "free_quality_factor": 3.18})
    'amplitude peak 71 789 Hz, Q 3.18'
    >>> instrument_text({"free_resonance": 8.8e4}, [{"name": "free_resonance", "ours": 8.79e4}])
    'resonance 88 000 Hz (ours 87 900 Hz)'
    >>> instrument_text({"free_quality_factor": 442.0}, [{"name": "free_quality_factor", "ours": 396.2, "stderr": 41.0}])
    'Q 442 (ours 396 +- 41)'
    """
    ours = {c["name"]: c for c in comparison or ()}
    shown = []
    for name, label in (("amplitude_peak", "amplitude peak "), ("free_resonance", "resonance "),
                        ("free_quality_factor", "Q ")):
        if fields.get(name):
            text = _hz if name != "free_quality_factor" else "{:.3g}".format
            shown.append(label + text(fields[name]) + (f" (ours {_ours_text(ours[name], text)})" if name in ours else ""))
    return ", ".join(shown) or "no fit in the header"


def _ours_text(comparison: dict, text) -> str:
    """Our value of a :func:`compare_with_instrument` entry; a Q (a header's Q is often far from ours: a
    fit over another window, another weighting) to the digits its standard error leaves, with it (a
    frequency's is on the report's line above)."""
    stderr = comparison.get("stderr")
    if text is _hz or stderr is None or not math.isfinite(stderr) or stderr <= 0:
        return text(comparison["ours"])
    return rounded(comparison["ours"], stderr) + f" +- {stderr:.2g}"


def compare_with_instrument(fields: dict, ours: dict, step_hz: float) -> list[dict]:
    """The header's numbers beside ours for the same quantity (``ours``: name -> ``(value, stderr)``), each
    with the tolerance beyond which they disagree: three times our standard error and the sweep's
    ``step_hz`` (a peak read off measured points is known to a step; a Q through its linewidth ``f/Q``,
    to ``Q**2 step / f``; any other quantity, our error alone), combined; the header's own numbers carry
    more digits than either.

    >>> c = compare_with_instrument({"amplitude_peak": 51.0e3}, {"amplitude_peak": (77.3e3, None)}, 150.0)
    >>> c[0]["disagrees"], round(c[0]["relative_difference"], 2), c[0]["tolerance"]
    (True, -0.34, 450.0)
    >>> round(compare_with_instrument({"spring_constant": 27.1}, {"spring_constant": (9.05, 0.29)}, 48.0)[0]["tolerance"], 6)
    0.87
    """
    frequency = ours.get("free_resonance", ours.get("amplitude_peak", (None, None)))[0]
    out = []
    for name, (value, stderr) in ours.items():
        if not fields.get(name) or value is None or not math.isfinite(value):     # ours undetermined: nothing beside
            continue
        step = {"free_quality_factor": value**2 * step_hz / frequency if frequency else 0.0,
                "free_resonance": step_hz, "amplitude_peak": step_hz}.get(name, 0.0)
        tolerance = 3.0 * math.hypot(stderr if stderr is not None and math.isfinite(stderr) else 0.0, step)
        out.append({"name": name, "instrument": fields[name], "ours": value, "stderr": stderr, "tolerance": tolerance,
                    "basis": "3x our uncertainty" + (" and the frequency step" if step else ""),
                    "relative_difference": (fields[name] - value) / value,
                    "disagrees": bool(abs(fields[name] - value) > tolerance)})
    return out


def explain_header(comparison: list, frequency, amplitude) -> list:
    """Give each disagreeing header number of a sweep (:func:`compare_with_instrument`) the reason the data
    show: a header peak away from the measured points' own maximum too was not read off these points; one
    at that maximum differs from ours because ours is the fitted model's peak (lever, gain, background);
    a header Q is its own model's, ours the lever's first mode in the medium.  ``comparison`` is changed
    in place (a ``why`` per disagreement) and returned.

    >>> f = np.linspace(60e3, 90e3, 31); a = 1 / (1 + ((f - 76e3) / 4e3) ** 2)
    >>> c = compare_with_instrument({"amplitude_peak": 51.0e3}, {"amplitude_peak": (76.3e3, None)}, 1e3)
    >>> explain_header(c, f, a)[0]["why"][:62]
    "the measured points' own amplitude maximum is at 76000 Hz, als"
    """
    top = float(frequency[int(np.argmax(amplitude))])
    for c in comparison:
        if not c["disagrees"]:
            continue
        if c["name"] == "amplitude_peak":
            c["why"] = (f"the measured points' own amplitude maximum is at {top:.6g} Hz, also away from the header's: "
                        "the header's peak was not read off these points (the instrument's fit of another model, or "
                        "a header of another sweep)" if abs(c["instrument"] - top) > c["tolerance"] else
                        f"the header's peak is the measured points' own maximum ({top:.6g} Hz); ours is the peak of "
                        "the fitted model (lever, gain and background), which the background moves")
        elif c["name"] == "free_quality_factor":
            c["why"] = ("the header's Q is its own model's (an oscillator, without the background); ours is the "
                        "first mode of the lever in the medium")
    return comparison


def disagreement_lines(comparison: list | None) -> list[str]:
    """A line for each header number beyond its tolerance from ours (:func:`compare_with_instrument`), in
    its unit, the header's difference from ours relative to ours, the tolerance to two digits.

    >>> print(*disagreement_lines(compare_with_instrument({"spring_constant": 27.13}, {"spring_constant": (9.047, 0.29)}, 38.0)))
      disagrees with the file: spring_constant 27.13 N/m in the header, 9.047 N/m here (header +199.9%; tolerance 0.87 N/m: 3x our uncertainty)
    >>> print(*disagreement_lines(compare_with_instrument({"amplitude_peak": 50965.1}, {"amplitude_peak": (76282.6, 81.0)}, 100.0)))
      disagrees with the file: amplitude_peak 50965.1 Hz in the header, 76282.6 Hz here (header -33.2%; tolerance 390 Hz: 3x our uncertainty and the frequency step)
    """
    def unit(name):
        return "" if name not in NAMES or NAMES[name].unit == "1" else f" {NAMES[name].unit}"

    def two_digits(x):          # 460, 0.88: no exponent
        return f"{float(f'{x:.2g}'):g}"

    return [f"  disagrees with the file: {c['name']} {c['instrument']:.6g}{unit(c['name'])} in the header, "
            f"{c['ours']:.6g}{unit(c['name'])} here (header {c['relative_difference']:+.1%}; tolerance "
            f"{two_digits(c['tolerance'])}{unit(c['name'])}: {c['basis']})"
            + (f"; {c['why']}" if c.get("why") else "")
            for c in comparison or () if c["disagrees"]]


def provenance_lines(d: dict) -> list[str]:
    """What a report took from the file (``from_file``) and what it assumed (``assumed``), one line each,
    after the disagreements with the file."""
    lines = disagreement_lines(d.get("instrument_comparison"))
    if d.get("from_file") is not None:
        lines.append("  from the file: " + (", ".join(d["from_file"]) or "the measured points only"))
    if d.get("assumed"):
        lines.append("  assumed: " + "; ".join(d["assumed"]))
    return lines


def unexplained_entry(frequency, y, residual, sigma) -> dict | None:
    """What the fit leaves when its gap exceeds :data:`GAP_LIMIT`: the gap, the band holding most of
    the misfit and the largest residual as a share of the largest measured value; None otherwise."""
    g = float(gap(np.sum(np.abs(residual / sigma) ** 2), len(residual)))
    if g <= GAP_LIMIT:
        return None
    return {"gap": g, "where": misfit_band(frequency, np.abs(residual / sigma) ** 2),
            "largest_residual": float(np.max(np.abs(residual)) / np.max(np.abs(y)))}


def unexplained_line(entry: dict | None) -> list[str]:
    if not entry:
        return []
    low, high = entry["where"]
    of = "the value there" if entry.get("relative") else "the largest measured value"
    return [f"  unexplained: the residual at {low / 1e3:.6g}-{high / 1e3:.6g} kHz (gap {entry['gap']:.3g} x noise, "
            f"largest {entry['largest_residual']:.1%} of {of}) is beyond the model"]


def penalty(y) -> np.ndarray:
    return np.full(2 * len(y) if np.iscomplexobj(y) else len(y), _PENALTY)


def stacked(r) -> np.ndarray:
    return np.concatenate([r.real, r.imag]) if np.iscomplexobj(r) else r


def amplitude_peak(model, frequency) -> float:
    """Where ``|model(f)|``, a fitted model of the measured response (gain and background included), peaks
    within the sweep's ``frequency``: the quantity an instrument's peak-amplitude frequency is (the lever's
    own slope peaks elsewhere when the background is comparable with the resonance's rise).

    >>> round(amplitude_peak(lambda f: 1 / (1 - (f / 7e4) ** 2 + 0.3j * f / 7e4), np.array([4e4, 1e5])), -1)
    68410.0
    >>> round(7e4 * (1 - 0.3**2 / 2) ** 0.5)       # the oscillator's own peak, to the grid's 15 Hz
    68407
    """
    from scipy.optimize import minimize_scalar

    grid = np.linspace(frequency.min(), frequency.max(), 4001)
    i = int(np.argmax(np.abs(model(grid))))
    if i in (0, grid.size - 1):        # at an end of the sweep: the end
        return float(grid[i])
    # refined between the grid's neighbours: a smooth function of the fitted parameters (its error propagates)
    out = minimize_scalar(lambda f: -abs(model(np.array([f]))[0]), bounds=(grid[i - 1], grid[i + 1]),
                          method="bounded", options={"xatol": 1e-9 * grid[i]})
    return float(out.x)


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
    for ratios in ((1.0,), mode_ratios()):
        seeds_f = np.log10(np.append(np.geomspace(frequency.min() / 3, frequency.max(), 20),
                                     frequency[np.argmax(deviation)] / np.array(ratios)))
        grid = [np.array([a, b]) for a in seeds_f for b in EXTRA_LOSS.seeds]
        for conjugate in ((False,) if amplitude_only else (False, True)):
            y = table.amplitude if amplitude_only else (np.conj(table.response) if conjugate else table.response)
            sigma = noise_level(frequency, y)

            def residual(x, y=y, sigma=sigma):
                try:
                    columns = base_driven_columns(lever_of(x), frequency, centre)
                except UserError:       # a width whose fluid the lever cannot carry
                    return penalty(y)
                columns = _amplitude_columns(columns) if amplitude_only else columns
                pr = project(columns[None], y[None, :, None].astype(columns.dtype))
                return stacked(pr.residual[0, :, 0]) / sigma

            fit = solve_from_starts(residual, grid, lower, upper)
            to_beat = best[0].chi2 * (0.5 if best[4] and len(ratios) > 1 else 1.0) if best else np.inf
            if fit.chi2 < to_beat:
                best = (fit, conjugate, y, sigma, len(ratios) == 1)
        if gap(best[0].chi2, len(frequency)) <= GAP_LIMIT:
            break
    fit, conjugate, y, sigma, _ = best
    try:
        lever = lever_of(fit.internal)
        columns = base_driven_columns(lever, frequency, centre)
    except UserError:       # every start ended on the penalty
        raise UserError(f"{table.path}: no lever of this spring constant, length and width carries {medium.name}'s "
                        "load at a resonance near the sweep (check them)") from None
    coherent = not amplitude_only
    amplitudes = project((_amplitude_columns(columns) if amplitude_only else columns)[None],
                         y[None, :, None].astype(float if amplitude_only else complex)).amplitudes[0, :, 0]
    if amplitude_only:
        refined = _coherent_fit(lever_of, fit, amplitudes, columns, frequency, centre, y, sigma, lower, upper)
        if refined is not None and refined[0].chi2 < fit.chi2:
            fit, amplitudes, coherent = refined[0], refined[1], True
            lever = lever_of(fit.internal)
            columns = base_driven_columns(lever, frequency, centre)
    residual = y - sweep_model(columns, amplitudes, amplitude_only, coherent)
    # Differences along frequency read a peak sampled by a few points per width as noise too (up to
    # several times high); where the fit leaves less than that, its residual, less the degrees of freedom
    # it took, is the honest noise level, and the parameters' uncertainties follow it.
    values = residual.size * (1 if np.isrealobj(residual) else 2)
    taken = len(params) + 2 * amplitudes.size      # at most: a complex gain and background each
    reduced = fit.chi2 / max(values - taken, 1)
    if reduced < 1.0:
        sigma = sigma * math.sqrt(reduced)
        fit = replace(fit, covariance=fit.covariance * reduced, chi2=fit.chi2 / reduced)
    parameters = {p.key: parameter_entry(p, x, fit.covariance[i, i]) for i, (p, x) in enumerate(zip(params, fit.internal))}
    parameters["width"] = {"value": width, "stderr": None, "unit": "m", "given": given}
    if not given:
        parameters["width"]["why"] = WIDTH_NOTE
    from ..analysis.resonances import resonances

    modes = resonances(lever, None, modes=1).free
    peak = amplitude_peak(lambda f: sweep_model(base_driven_columns(lever, f, centre), amplitudes, amplitude_only,
                                                coherent), frequency)
    # the derived quantities' errors through the lever's and the amplitudes' joint covariance
    reals = [(i, False) for i in range(3)] + [(i, True) for i in range(3)
                                              if not amplitude_only or (coherent and i > 0)]
    n = len(params)

    def residual_of(x, a):
        return stacked(sweep_model(base_driven_columns(lever_of(x), frequency, centre), a, amplitude_only, coherent)
                       - y) / sigma

    joint = joint_covariance(residual_of, fit.internal, amplitudes, reals)
    amplitude_errors = amplitude_stderr(joint, n, reals)

    def peak_of(z):
        a = with_parts(amplitudes, z[n:], reals)
        return amplitude_peak(lambda f: sweep_model(base_driven_columns(lever_of(z[:n]), f, centre), a,
                                                    amplitude_only, coherent), frequency)

    z = np.r_[fit.internal, [np.imag(amplitudes[i]) if im else np.real(amplitudes[i]) for i, im in reals]]
    lever_covariance = joint[:n, :n]
    errors = {"vacuum_resonance": error_entry(propagated(lambda x: lever_of(x).vacuum_resonance, fit.internal,
                                                         lever_covariance, lower), UNDETERMINED_ERROR),
              "quality_factor": error_entry(propagated(lambda x: float(resonances(lever_of(x), None, modes=1).free.q[0]),
                                                       fit.internal, lever_covariance, lower), UNDETERMINED_ERROR),
              "peak_hz": error_entry(propagated(peak_of, z, joint, np.r_[lower, np.full(len(reals), -np.inf)]),
                                     UNDETERMINED_ERROR)}
    comparison = compare_with_instrument(table.fields, {
        "amplitude_peak": (peak, errors["peak_hz"]["stderr"]), "free_resonance": (lever.free_resonance, parameters["free_resonance"]["stderr"]),
        "free_quality_factor": (float(modes.q[0]), None)}, float(np.median(np.diff(frequency))))
    explain_header(comparison, frequency, np.abs(y))
    fields = {"kind": "drive sweep", "path": table.path, "instrument": table.instrument, "points": len(frequency),
              "medium": medium.name, "spring_constant": spring_constant, "length": length,
              "vacuum_resonance": lever.vacuum_resonance, "quality_factor": float(modes.q[0]),
              "peak_hz": peak, "parameters": parameters,
              "uncertainties": errors,
              "gain": {"value": [float(np.real(amplitudes[0])), float(np.imag(amplitudes[0]))],
                       "stderr": parts(amplitude_errors[0]), "unit": f"{table.unit or '1'}/rad"},
              "background": {"value": [[float(np.real(a)), float(np.imag(a))] for a in amplitudes[1:]],
                             "stderr": [parts(e) for e in amplitude_errors[1:]],
                             "unit": table.unit or "1", "adds_to": "response" if coherent else "amplitude"},
              "amplitude_only": amplitude_only, "phase_reversed": conjugate,
              "instrument_fit": dict(table.fields), "noise": sigma, "gap": float(gap(fit.chi2, len(y))),
              "worst_region": worst_region(frequency, np.abs(residual / sigma) ** 2, lever_resonances(lever)),
              "unexplained": unexplained_entry(frequency, y, residual, sigma),
              "instrument_comparison": comparison, "from_file": sorted(table.fields), "assumed": []}
    if not given:
        fields["assumed"].append(f"width {width:g} m (L/10: the width was not given)")
    return SweepFit(fields, lever=lever, gain=amplitudes[0], background=tuple(amplitudes[1:]), centre_hz=centre,
                    amplitude_only=amplitude_only, coherent=coherent, conjugate=conjugate, sigma=sigma, chi2=fit.chi2)


def parts(value: complex) -> list:
    """``[re, im]`` of a complex number, a non-finite part None (JSON has no NaN).

    >>> parts(complex(1.5, float("nan")))
    [1.5, None]
    """
    return [float(v) if math.isfinite(v) else None for v in (value.real, value.imag)]


def _amplitude_columns(columns) -> np.ndarray:
    """Real columns ``|s|, 1, u`` of the background added to the amplitude (:func:`sweep_model`)."""
    return np.stack([np.abs(columns[:, 0]), columns[:, 1].real, columns[:, 2].real], axis=-1)


PHASES = 8
"""Starting phases of a background added to the response of a file with amplitude only."""


def _coherent_fit(lever_of, fit: StartsFit, amplitudes, columns, frequency, centre, y, sigma, lower, upper):
    """An amplitude-only sweep refitted with its background added to the response: the lever's parameters
    and ``G`` (real: the amplitude has no phase), ``b0``, ``b1`` (complex), started from the background
    added to the amplitude at :data:`PHASES` phases of ``b0``; ``(fit, amplitudes)`` or None."""
    g, c0, c1 = (float(np.real(a)) for a in amplitudes)
    starts = [np.r_[fit.internal, abs(g), abs(c0) * np.cos(phi), abs(c0) * np.sin(phi), c1, 0.0]
              for phi in np.linspace(0.0, 2 * np.pi, PHASES, endpoint=False)]
    n = len(fit.internal)

    def amplitudes_of(z):
        return np.array([z[n], z[n + 1] + 1j * z[n + 2], z[n + 3] + 1j * z[n + 4]])

    def residual(z):
        try:
            model = sweep_model(base_driven_columns(lever_of(z[:n]), frequency, centre), amplitudes_of(z), True)
        except UserError:
            return penalty(y)
        return (model - y) / sigma

    free = np.full(5, np.inf)
    refined = solve_from_starts(residual, starts, np.r_[lower, 0.0, -free[1:]], np.r_[upper, free])
    try:
        lever_of(refined.internal[:n])
    except UserError:       # every start ended on the penalty
        return None
    return StartsFit(refined.internal[:n], refined.covariance[:n, :n], refined.chi2), amplitudes_of(refined.internal)

