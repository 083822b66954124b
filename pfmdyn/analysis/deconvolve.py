"""``pfmdyn deconvolve``: separate electrostatic and electromechanical response (Section VI.4).

At each frequency the complex response is linear in the tip bias (Eq. 41),

.. math::

    R(V) = \\tilde d_{eff} + \\tilde G_{elec} (V - V_{surf}) = b + c V,

so a least-squares line through the measured :math:`R(V)` gives the electrostatic slope
:math:`\\tilde G_{elec} = c`, the intercept :math:`b` and, for a known surface potential,
:math:`\\tilde d_{eff} = b + c V_{surf}`.  The error map :math:`R - (b + cV)` shows where the
response is not linear in bias (Fig. 14 of the paper: mostly near resonances).

Uncertainties assume independent noise of equal variance on the real and imaginary parts of
every point; that variance is estimated from the residuals of each frequency's fit, so it
needs at least three biases (with two, the standard errors are NaN).  All reported standard
errors are those of the real part, which equal those of the imaginary part.

With a lever and contact given, :func:`surface_displacement` turns the measured ``d_eff``
(in the units of the data, i.e. as calibrated by the deflection sensitivity) into the true
surface displacement per volt, with the calibration factor of :mod:`pfmdyn.analysis.spot`.

References
----------
Jesse, Baddorf, Kalinin (2006), Sections VI.2-VI.4, Eq. 41.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..cantilever import Cantilever, Contact
from ..errors import UserError
from ..generated import formulas
from ..fitting.bias_line import bias_lines
from .spot import calibration

CONDITION_LIMIT = 10.0
"""Largest ``|d ln C / d ln f|`` of the calibration factor ``C`` at which it is used: beyond,
a 1 % error in the lever's resonances (or the damping the lossless calibration leaves out)
changes it by more than 10 %, so the true displacement is undetermined there."""

_STEP = 1e-4
"""Relative frequency step of the central difference for ``d ln C / d ln f``."""


@dataclass(frozen=True)
class Deconvolution:
    """Per-frequency fit results (arrays of length M) and per-point residuals (length N).

    Attributes
    ----------
    frequency_hz, n_bias : ndarray
        The M frequencies and the number of biases measured at each.
    g_elec, intercept, d_eff : ndarray of complex
        Slope :math:`c`, intercept :math:`b` and :math:`b + c V_{surf}`.
    g_elec_se, d_eff_se : ndarray
        Standard errors of the real (equally, imaginary) parts.
    v_null, v_null_se : ndarray
        Nulling bias (:func:`nulling_bias`) and its standard error (V).
    surface_potential_v : float
        The :math:`V_{surf}` used for ``d_eff``.
    point_frequency_hz, point_bias_v : ndarray
        Coordinates of the N measured points.
    residual : ndarray of complex
        Error map :math:`R - (b + cV)` at every measured point.
    """

    frequency_hz: np.ndarray
    n_bias: np.ndarray
    g_elec: np.ndarray
    intercept: np.ndarray
    d_eff: np.ndarray
    g_elec_se: np.ndarray
    d_eff_se: np.ndarray
    v_null: np.ndarray
    v_null_se: np.ndarray
    surface_potential_v: float
    point_frequency_hz: np.ndarray
    point_bias_v: np.ndarray
    residual: np.ndarray


class TipQuality(NamedTuple):
    """Weighted mean and spread of the nulling bias over frequency (V)."""

    mean_v: float
    spread_v: float


def nulling_bias(intercept, slope):
    """Real bias at which the fitted response :math:`|b + cV|` is smallest.

    :math:`V_{null} = -\\operatorname{Re}(b\\bar c)/|c|^2`.  When :math:`b/c` is real the
    fitted response vanishes there; writing :math:`b = d_{eff} - c V_{surf}` this is
    :math:`V_{null} = V_{surf} - d_{eff}/G_{elec}` (the paper's :math:`V_{surf} \\pm
    d_{eff}/G_{elec}`, the sign depending on the domain).  Otherwise the response has no real
    zero and :math:`V_{null}` is the bias of its minimum amplitude.

    Parameters
    ----------
    intercept, slope : array_like of complex
        :math:`b` and :math:`c` of the fitted lines.

    Returns
    -------
    ndarray
        :math:`V_{null}` in volts (non-finite where the slope is zero).

    Examples
    --------
    >>> float(nulling_bias(2 - 4j, -1 + 2j))  # b + cV = (1 - 2j)(2 - V)
    2.0
    """
    intercept, slope = np.asarray(intercept), np.asarray(slope)
    with np.errstate(divide="ignore", invalid="ignore"):  # a zero slope has no nulling bias
        return formulas.nulling_bias(intercept.real, intercept.imag, slope.real, slope.imag)


def nulling_bias_gradient(intercept, slope):
    """Derivatives of the generated nulling bias with respect to (Re b, Im b, Re c, Im c).

    By complex steps (exact to rounding, no cancellation): the formula is a rational
    function of the four parts, so it accepts a complex increment in any one of them.

    >>> [round(float(d[0]), 12) for d in nulling_bias_gradient(np.array([2 - 4j]), np.array([-1 + 2j]))]
    [0.2, -0.4, 0.4, -0.8]
    """
    parts = [intercept.real, intercept.imag, slope.real, slope.imag]
    scales = [np.abs(intercept)] * 2 + [np.abs(slope)] * 2
    out = []
    for i, scale in enumerate(scales):
        h = np.where(scale > 0, 1e-20 * scale, 1e-300)   # far below each part's size
        stepped = [p + 1j * h if j == i else p for j, p in enumerate(parts)]
        out.append(np.imag(formulas.nulling_bias(*stepped)) / h)
    return out


def tip_quality(v_null, v_null_se=None) -> TipQuality:
    """Spread of the nulling bias over frequency: the tip-quality indicator of Section VI.3.

    On a sample with a known, appreciable piezoresponse, :math:`V_{null}(\\omega) = V_{surf} -
    d_{eff}(\\omega)/G_{elec}(\\omega)` moves with frequency because the electromechanical and
    electrostatic responses have different spectra: a large spread means a good tip.  A
    near-constant :math:`V_{null} \\approx V_{surf}` (spread near zero) means the signal is
    electrostatic-dominated, e.g. a worn tip that has lost electrical contact.  (On a
    non-piezoelectric sample the spread is near zero whatever the tip.)

    Parameters
    ----------
    v_null : array_like
        Nulling bias at each frequency (V); non-finite values are ignored.
    v_null_se : array_like, optional
        Standard errors used as inverse-variance weights, so that frequencies where the
        electrostatic slope is tiny and :math:`V_{null}` is ill-determined count little.  If
        omitted, or if any is zero or non-finite, all frequencies weigh the same.

    Returns
    -------
    TipQuality
        Weighted mean and weighted standard deviation of :math:`V_{null}` (V).

    Examples
    --------
    >>> tip_quality([1.0, 3.0, 2.0, 2.0])
    TipQuality(mean_v=2.0, spread_v=0.7071067811865476)
    >>> tip_quality([float("nan")] * 2)        # G_elec = 0 everywhere: undetermined (NaN), no warning
    TipQuality(mean_v=nan, spread_v=nan)
    """
    v_null = np.asarray(v_null, dtype=float)
    with np.errstate(divide="ignore"):
        weights = np.ones_like(v_null) if v_null_se is None else np.asarray(v_null_se, dtype=float) ** -2.0
    keep = np.isfinite(v_null)
    if not np.all(np.isfinite(weights[keep])):
        weights = np.ones_like(v_null)
    v_null, weights = v_null[keep], weights[keep]
    if not v_null.size:         # no frequency's response changes with the bias: none nulls it
        return TipQuality(math.nan, math.nan)
    mean = np.sum(weights * v_null) / np.sum(weights)
    spread = np.sqrt(np.sum(weights * (v_null - mean) ** 2) / np.sum(weights))
    return TipQuality(float(mean), float(spread))


def deconvolve(frequency_hz, bias_v, response, surface_potential_v) -> Deconvolution:
    """Fit :math:`R = b + cV` at every frequency and derive :math:`G_{elec}`, :math:`d_{eff}`, :math:`V_{null}`.

    Parameters
    ----------
    frequency_hz, bias_v : array_like
        Point coordinates, in any order (:func:`pfmdyn.fitting.bias_line.bias_lines`), with at least
        two distinct biases per frequency (biases that differ by rounding are one:
        :data:`pfmdyn.fitting.bias_line.BIAS_RESOLUTION`; else a :class:`~pfmdyn.errors.UserError`).
    response : array_like of complex
        Measured response :math:`x + iy` at every point.
    surface_potential_v : float
        :math:`V_{surf}` (V), e.g. from a non-contact measurement.

    Returns
    -------
    Deconvolution
        Per-frequency results and the error map.

    Examples
    --------
    >>> v = np.array([-1.0, 0.0, 1.0, 2.0])
    >>> r = (3 + 1j) + (2 - 1j) * (v - 0.5)  # d_eff = 3 + 1j, G_elec = 2 - 1j, V_surf = 0.5
    >>> fit = deconvolve(np.full(4, 1e5), v, r, surface_potential_v=0.5)
    >>> complex(fit.d_eff[0]), complex(fit.g_elec[0]), round(float(fit.v_null[0]), 12)
    ((3+1j), (2-1j), -0.5)
    """
    frequency_hz = np.asarray(frequency_hz, dtype=float)
    bias_v = np.asarray(bias_v, dtype=float)
    response = np.asarray(response, dtype=complex)
    lines = bias_lines(frequency_hz, bias_v, response)
    if np.any(lines.spread <= 0):       # the reader's rule (pfmdyn.io.spectra), for biases equal but for rounding
        at = np.flatnonzero(lines.spread <= 0)[0]
        low, high = np.min(bias_v[lines.group == at]), np.max(bias_v[lines.group == at])
        shown = f"{low:.12g} V" if low == high else f"{low:.17g} to {high:.17g} V, one setpoint but for rounding"
        raise UserError(f"only one bias value at frequency {lines.frequency_hz[at]:.12g} Hz ({shown}); the linear fit"
                        " needs at least two distinct biases")
    n, mean_v, sxx = lines.count, lines.mean_bias, lines.spread
    slope, intercept, residual = lines.slope, lines.intercept, lines.residual

    # Each frequency's own variance, for its coefficients' uncertainties (the fits' one robust
    # level from the same residuals: pfmdyn.fitting.noise).
    dof = 2 * (n - 2)  # real and imaginary parts each lose two degrees of freedom
    with np.errstate(invalid="ignore", divide="ignore"):
        noise_var = np.where(dof > 0, lines.squared_residual() / dof, np.nan)

    def variance(u_b, u_c):
        """Variance of u_b*b + u_c*c for one real/imaginary component, from (X^T X)^-1."""
        return noise_var * (u_b**2 / n + (u_b * mean_v - u_c) ** 2 / sxx)

    v_null = nulling_bias(intercept, slope)
    # Delta method: the real parts of (b, c) and their imaginary parts are independent pairs.
    with np.errstate(divide="ignore", invalid="ignore"):
        d_b_re, d_b_im, d_c_re, d_c_im = nulling_bias_gradient(intercept, slope)
    v_null_var = variance(d_b_re, d_c_re) + variance(d_b_im, d_c_im)
    return Deconvolution(
        frequency_hz=lines.frequency_hz,
        n_bias=n,
        g_elec=slope,
        intercept=intercept,
        d_eff=intercept + slope * surface_potential_v,
        g_elec_se=np.sqrt(variance(0.0, 1.0)),
        d_eff_se=np.sqrt(variance(1.0, surface_potential_v)),
        v_null=v_null,
        v_null_se=np.sqrt(v_null_var),
        surface_potential_v=float(surface_potential_v),
        point_frequency_hz=frequency_hz,
        point_bias_v=bias_v,
        residual=residual,
    )


@dataclass(frozen=True)
class SurfaceDisplacement:
    """Per-frequency conversion of a :class:`Deconvolution` to true surface displacement.

    Attributes
    ----------
    spot_position : float
        ``x_s/L`` of the spot.
    calibration_factor : ndarray
        Measured over true displacement (:func:`pfmdyn.analysis.spot.calibration`); NaN where
        undetermined.
    d_eff, g_elec : ndarray of complex
        ``d_eff / C`` and ``G_elec / C``, in the units of the data (NaN where undetermined).
    d_eff_se : ndarray
        ``d_eff_se / |C|``.
    d_eff_error_per_volt : ndarray or None
        The amplitude the distributed capacitive load adds at the spot, as measured (m per
        volt of ac drive per volt of ``V_dc - V_surf``); None without the lever width.
    undetermined : tuple of (float, float, str)
        Frequency ranges (Hz) where the calibration is undetermined, and why.
    """

    spot_position: float
    calibration_factor: np.ndarray
    d_eff: np.ndarray
    g_elec: np.ndarray
    d_eff_se: np.ndarray
    d_eff_error_per_volt: np.ndarray | None
    undetermined: tuple


def surface_displacement(result: Deconvolution, lever: Cantilever, contact: Contact) -> SurfaceDisplacement:
    """True surface displacement per volt at every frequency, for the lever's spot.

    The measured ``d_eff`` (and ``G_elec``) are divided by the calibration factor ``C`` of
    :func:`pfmdyn.analysis.spot.calibration`: the data are taken to be calibrated with a
    deflection sensitivity (InvOLS) from a static force curve in the same contact, read at
    the same spot.  Where ``|d ln C / d ln f| >`` :data:`CONDITION_LIMIT` (around a contact
    resonance, a pole of ``C``, or a zero of the spot's response to the surface, a zero of
    ``C``) the values are NaN and the range is listed with its reason.

    Parameters
    ----------
    result : Deconvolution
        From :func:`deconvolve`.
    lever, contact : Cantilever, Contact
        The probe, its ``spot_position``, and the contact (``k1``, ``k2`` or a policy).

    Returns
    -------
    SurfaceDisplacement

    Examples
    --------
    >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5, spot_position=0.8)
    >>> fit = deconvolve([70.0] * 3, [-1.0, 0.0, 1.0], [1, 2, 3], surface_potential_v=0.0)
    >>> round(float(surface_displacement(fit, lever, Contact(k1=200.0)).d_eff[0].real), 6)  # static: C = 1
    2.0
    """
    f = result.frequency_hz
    factor, error = calibration(lever, contact, f)
    up, _ = calibration(lever, contact, f * (1 + _STEP))
    down, _ = calibration(lever, contact, f * (1 - _STEP))
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.log(np.abs(up / down)) / (2 * _STEP)            # d ln|C| / d ln f
        bad = ~(np.abs(slope) <= CONDITION_LIMIT) | ~np.isfinite(factor) | (factor == 0)
    ranges = []
    for run in np.split(np.flatnonzero(bad), np.flatnonzero(np.diff(np.flatnonzero(bad)) > 1) + 1):
        if run.size:
            ranges.append((float(f[run[0]]), float(f[run[-1]]), _why(slope, factor, run)))
    used = np.where(bad, np.nan, factor)
    with np.errstate(invalid="ignore"):     # NaN where undetermined, on purpose
        return SurfaceDisplacement(spot_position=float(lever.spot_position), calibration_factor=used,
                                   d_eff=result.d_eff / used, g_elec=result.g_elec / used,
                                   d_eff_se=result.d_eff_se / np.abs(used), d_eff_error_per_volt=error,
                                   undetermined=tuple(ranges))


_POLE = "a contact resonance (the lossless calibration has a pole there; the lever's damping decides)"
_ZERO = "a zero of the spot's response to the surface (the spot reads almost none of its motion)"


def _why(slope, factor, run) -> str:
    """What makes the calibration undetermined over the samples ``run``: ``|C|`` rises into a pole
    and falls out of it (``d ln|C|/d ln f`` from + to -), falls into a zero and rises out of it
    (from - to +); the samples either side of the run are read too.  With no such turn in the data
    (the run at an end of the sweep), a large ``|C|`` (it is 1 statically) means a pole.

    >>> _why(np.array([5.0, 40.0, -30.0, -4.0]), np.array([3.0, 20.0, -9.0, -2.0]), np.array([1, 2]))[:18]
    'a contact resonanc'
    """
    lo, hi = max(run[0] - 1, 0), min(run[-1] + 2, len(slope))
    signs = np.sign(slope[lo:hi])
    turns = signs[1:] - signs[:-1]
    found = ([_POLE] if np.any(turns < 0) else []) + ([_ZERO] if np.any(turns > 0) else [])
    if not found:
        found = [_POLE if np.nanmax(np.abs(factor[run])) > 1.0 else _ZERO]
    return " and ".join(found)


def summary(result: Deconvolution, unit: str) -> str:
    """Short human-readable summary of a deconvolution.

    Parameters
    ----------
    result : Deconvolution
        From :func:`deconvolve`.
    unit : str
        Unit of the response, for the printout.

    Returns
    -------
    str
        A few lines: counts, median amplitudes, nulling bias and the tip-quality indicator.

    Examples
    --------
    >>> fit = deconvolve([1e5] * 3, [-1.0, 0.0, 1.0], [1, 2, 3], surface_potential_v=0.0)
    >>> print(summary(fit, "pm").splitlines()[0])
    frequencies: 1 (100 kHz to 100 kHz); biases per frequency: 3
    >>> print(summary(deconvolve([1e5] * 2, [0.0, 1.0], [2, 2], surface_potential_v=0.0), "pm").splitlines()[-1])
    nulling bias: undetermined at every frequency (G_elec = 0: the response does not change with the bias, so no bias nulls it); tip-quality indicator likewise
    """
    quality = tip_quality(result.v_null, result.v_null_se)
    low, high = result.frequency_hz[[0, -1]] / 1e3
    biases = f"{result.n_bias.min()}" if result.n_bias.min() == result.n_bias.max() else (
        f"{result.n_bias.min()} to {result.n_bias.max()}"
    )
    return "\n".join([
        f"frequencies: {len(result.frequency_hz)} ({low:.4g} kHz to {high:.4g} kHz); biases per frequency: {biases}",
        f"median |d_eff|: {np.median(np.abs(result.d_eff)):.4g} {unit} (V_surf = {result.surface_potential_v:g} V);"
        f" median |G_elec|: {np.median(np.abs(result.g_elec)):.4g} {unit}/V",
        f"nulling bias: weighted mean {quality.mean_v:.4g} V; tip-quality indicator (its spread over frequency):"
        f" {quality.spread_v:.3g} V (near 0 with V_null ~ V_surf: electrostatic-dominated or worn tip)"
        if math.isfinite(quality.mean_v) else
        "nulling bias: undetermined at every frequency (G_elec = 0: the response does not change with the bias, "
        "so no bias nulls it); tip-quality indicator likewise",
    ])
