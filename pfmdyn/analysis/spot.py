"""Where the laser spot sits: the lever read at ``x_s`` instead of its end.

The optical lever reads the slope ``u0'(x_s)`` wherever the spot was put; the paper reads it
at ``x_s = L`` (Section II).  From the composed lever (:mod:`pfmdyn.composed`, certified in
:mod:`pfmdyn.composed.balls`, both assembled from ``derivations/pieces.py``) this module
gives, for one lever in contact at one frequency:

* the **electrostatic blind spots**: every ``x_s/L`` in ``(0, 1]`` where the slope response
  to the uniform capacitive load ``q0`` vanishes, certified with ball arithmetic (complete,
  none twice: :func:`pfmdyn.derivations.certify.zeros_in` on the composed numerator);
* the **electrostatic-to-electromechanical slope ratio** ``theta_q0 / theta_d1`` along the
  lever;
* the **static sensitivity** ``S = u_tip / (L theta(x_s))`` (``2/3`` at the end of a free
  lever: the paper's ``A = 2 theta L / 3``), free and in contact;
* the **calibration factor**: measured amplitude over true surface displacement ``d1``
  when the deflection sensitivity (InvOLS) comes from a static force curve in the same
  contact, at the given frequency; and the **d_eff error**: the apparent ``d_eff`` the
  distributed load adds at ``x_s`` (zero at a blind spot), per volt of ``V_dc - V_surf``.

Responses are those of the lossless lever (a blind spot is a real zero of the slope; the
cantilever's losses are left out).  Static values are the composed (dynamic) lever at the
quasi-static ``beta = 1e-3`` (:func:`static_limit`; relative error below 1e-12).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import flint
import numpy as np

from ..cantilever import Cantilever, Contact
from ..errors import UserError
from .. import composed
from ..composed import balls as composed_balls
from ..generated import formulas
from ..generated.characteristic import FLINT
from ..derivations.certify import CertificationError, zeros_in

__all__ = ["SpotResult", "BlindSpots", "parameters", "dimensionless", "lossless_beta", "blind_spots", "slope_along",
           "static_limit", "sensitivities", "calibration", "spot_analysis", "ratio_map", "EPSILON_0", "SPREAD_RESULTS",
           "spread"]

EPSILON_0 = 8.8541878128e-12
"""Vacuum permittivity (F/m), for the capacitive load per volt."""

_QUASI_STATIC_BETA = 1e-3
"""Where :func:`static_limit` evaluates a response (``beta**4`` 1e-12 of the first mode's)."""


def parameters(lever: Cantilever, contact: Contact) -> dict:
    """Keyword arguments of the generated detection functions (besides ``beta``, ``sigma``).

    The contact springs in beam axes (``kvv, kll, kvl``: the tilt rotates ``k1``, ``k2``).

    >>> parameters(Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5), Contact(k1=200.0))["kvv"]
    200.0
    """
    if contact.k1 is None:
        raise UserError("the spot analysis needs the contact stiffness k1", quantity="k1")
    if lever.tip_height is None:
        raise UserError("the spot analysis needs the tip height", quantity="tip_height")
    return {name: float(value) for name, value in lever.model_parameters(contact)._asdict().items()}


def dimensionless(lever: Cantilever, contact: Contact) -> dict:
    """The parameters of the blind-spot functions (``kvv/k``, ``kll H**2/(k L**2)``, ``kvl H/(k L)``)."""
    p = parameters(lever, contact)
    k, H, L = p["k"], p["H"], p["L"]
    return {"kvv_over_k": p["kvv"] / k, "kll_ratio": float(formulas.k2_ratio(p["kll"], k, H, L)),
            "kvl_ratio": p["kvl"] * H / (k * L), "mu": p["mu"], "gamma": p["gamma"], "rho_g": p["rho_g"]}


def lossless_beta(lever: Cantilever, frequency) -> np.ndarray:
    """``beta`` at ``frequency`` (Hz) of the lever without losses (blind spots are real zeros)."""
    return np.real(replace(lever, quality_factor=math.inf, viscous_loss=0.0).beta(frequency))


def slope_along(lever: Cantilever, contact: Contact, beta, sigma) -> tuple:
    """Slope at ``x_s = sigma L`` per unit d1, d2, f0, q0 (SI: 1/m, 1/m, 1/N, 1/(N/m) per m).

    >>> lever, contact = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5), Contact(k1=200.0)
    >>> a = slope_along(lever, contact, 1.0, 1.0)[0]; b = slope_along(lever, contact, 1.0, 0.999999)[0]
    >>> bool(abs(a - b) < 1e-5 * abs(a))
    True
    """
    return composed.slope(np.asarray(beta, dtype=float), composed.Parameters(**parameters(lever, contact)),
                          np.asarray(sigma, dtype=float))


def static_limit(fn, *args, **kwargs):
    """``fn(beta, ...)`` at ``beta = 0``: evaluated at the quasi-static ``beta = 1e-3``.

    The composed lever is accurate to rounding there (tested against the static beam); the
    responses are analytic in ``beta**4``, so the static value differs by ``(beta / beta_1)**4``,
    below 1e-12.

    >>> round(float(static_limit(lambda b: 1 / (1 - b**4 / 12.36))), 8)    # a first resonance
    1.0
    """
    return np.asarray(fn(_QUASI_STATIC_BETA, *args, **kwargs))


@dataclass(frozen=True)
class BlindSpots:
    """Certified zeros of the ``q0`` slope in ``(0, 1]``: positions and enclosing intervals."""

    positions: tuple = ()
    intervals: tuple = ()
    certified: bool = True
    reason: str = ""


def blind_spots(lever: Cantilever, contact: Contact, beta: float, digits: int = 10) -> BlindSpots:
    """Every ``x_s/L`` in ``(0, 1]`` where the slope per unit ``q0`` vanishes, certified.

    Zeros of the generated numerator (the denominator does not depend on the spot) on
    ``(0, gamma]`` (spot before the tip; the clamp's zero at 0 is excluded by proof) and on
    ``[gamma, 1]`` (beyond it), by :func:`pfmdyn.derivations.certify.zeros_in` on a Taylor model
    (:func:`_taylor_model`).  A failed proof (a double zero, a zero exactly at the tip or at
    the end) gives ``certified = False`` with the reason and no positions.

    >>> lever = Cantilever(1.0, 7e4, 2.25e-4, tip_height=1.5e-5)
    >>> blind_spots(lever, Contact(k1=1e5), 0.01).positions          # nearly pinned: (15 - sqrt(33))/16 = 0.578464
    (0.5784871059,)
    """
    params = {name: _exact(v) for name, v in dimensionless(lever, contact).items()}
    b = params["beta"] = _exact(beta)
    gamma = lever.tip_position
    # The numerator is a small difference of O(1) terms at low frequency: carry the bits it loses.
    prec = 96 + int(16 * max(0.0, -math.log2(max(beta, 1e-30))))
    old = flint.ctx.prec, flint.ctx.cap
    try:
        flint.ctx.prec = prec
        pieces = [("before", 0, gamma, 1)] + ([("beyond", gamma, 1, 0)] if gamma < 1 else [])
        balls = []
        for name, lo, hi, zero_at_lo in pieces:
            coefficients = composed_balls.q0_slope_coefficients(FLINT, **params)[name]
            f = composed_balls.q0_slope
            model = _taylor_model(lambda s: f(s, FLINT, coefficients, b), coefficients, b, lo, hi)
            found = zeros_in(model, lo, hi, digits, zero_at_lower=zero_at_lo, prec=prec)
            if balls and found and balls[-1].overlaps(found[0]):
                raise CertificationError(f"a zero at the tip position {gamma} (both branches)")
            balls += found
    except CertificationError as exc:
        return BlindSpots(certified=False, reason=str(exc))
    finally:
        flint.ctx.prec, flint.ctx.cap = old
    positions = tuple(round(float(x.mid()), digits) for x in balls)
    intervals = tuple((float(x.lower()), float(x.upper())) for x in balls)
    return BlindSpots(positions, intervals)


def _taylor_model(f, coefficients, beta: flint.arb, lo: float, hi: float):
    """``f`` on ``[lo, hi]`` as its Taylor polynomial at ``lo`` plus a rigorous remainder ball.

    ``f = A cos(beta t) + B sin(beta t) + C cosh(beta t) + E sinh(beta t) + F`` with ``t`` the
    spot's argument over ``beta`` (``sigma`` or ``1 - sigma``, both in ``[0, 1]``), so its
    ``n``-th Taylor coefficient is bounded by ``(|A| + |B| + |C| + |E|) cosh(beta) beta**n / n!``
    everywhere on the interval: the remainder of degree ``n`` is that ball times
    ``(sigma - lo)**n``, and the same model differentiated encloses ``f'`` (its remainder is
    ``n`` times the bound times ``(sigma - lo)**(n - 1)``).  Evaluated in Horner form the model
    has none of the cancellation of the closed form at low frequency, where
    ``A cos + C cosh`` nearly cancel over any interval.
    """
    n = 24 + int(4 * float(beta.mid()))
    flint.ctx.cap = n + 2
    lo_ball = flint.arb(str(lo))
    taylor = f(flint.arb_series([lo_ball, 1], prec=n)).coeffs()
    taylor = [flint.arb(c) for c in taylor] + [flint.arb(0)] * (n - len(taylor))
    size = sum(abs(flint.arb(c)) for c in coefficients[:4])
    bound = size * beta.cosh() * beta ** n / flint.arb(n).fac()
    tail = flint.arb(0, bound.upper())

    def model(s):
        t = s - lo_ball
        out = tail
        for c in reversed(taylor):
            out = out * t + c
        return out
    return model


def _exact(value: float) -> flint.arb:
    """A float as an exact ball (its binary value)."""
    return flint.arb(float(value))


def sensitivities(lever: Cantilever, contact: Contact, sigma) -> dict:
    """Static ``S = u_tip / (L theta(x_s))``: free (tip force, no contact) and in contact (``d1``).

    ``free``: a force on the tip of the free lever (how a free-lever or thermal calibration
    sees it); ``2/3`` at ``x_s = L`` with the tip at the end is the paper's ``A = 2 theta L / 3``.
    ``contact``: the surface moving the tip by ``d1`` through the contact springs (a force
    curve on this contact): ``S = d1 / (L theta_d1(x_s))``.

    >>> s = sensitivities(Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5), Contact(k1=200.0), 1.0)
    >>> round(float(s["free"]), 6)
    0.666667
    """
    L, gamma = lever.length, lever.tip_position
    touching_lever = composed.Parameters(**parameters(lever, contact))
    free = touching_lever._replace(kvv=0.0, kll=0.0, kvl=0.0)
    theta = static_limit(lambda b: composed.slope(b, free, sigma)[2])
    tip = static_limit(lambda b: composed.deflection(b, free, gamma)[2])
    touching = static_limit(lambda b: composed.slope(b, touching_lever, sigma)[0])
    return {"free": np.real(tip / (L * theta)), "contact": np.real(1.0 / (L * touching))}


@dataclass(frozen=True)
class SpotResult:
    """What :func:`spot_analysis` finds for one lever at one frequency (SI; positions as x_s/L)."""

    lever: Cantilever
    contact: Contact
    drive_frequency: float
    beta: float
    blind_spot: BlindSpots
    positions: np.ndarray = field(repr=False)
    ratio: np.ndarray = field(repr=False)
    spot_position: float = 1.0
    free_sensitivity: float = math.nan
    contact_sensitivity: float = math.nan
    calibration_factor: complex = math.nan
    paper_calibration_factor: complex = math.nan
    d_eff_error_per_volt: complex | None = None

    def to_dict(self) -> dict:
        """JSON-ready dictionary (the document ``pfmdyn spot`` writes).

        >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5)
        >>> spot_analysis(lever, Contact(k1=200.0), 20e3, positions=5).to_dict()["blind_spot"]
        [0.6008736276]
        """
        def cplx(z):
            return None if z is None else {"re": float(np.real(z)), "im": float(np.imag(z)), "abs": float(abs(z))}
        out = {"drive_frequency": self.drive_frequency, "beta": self.beta,
               "blind_spot": list(self.blind_spot.positions),
               "blind_spot_intervals": [list(i) for i in self.blind_spot.intervals],
               "certified": self.blind_spot.certified,
               "spot_position": self.spot_position,
               "q0_to_d1_slope_ratio": {"spot_position": [float(p) for p in self.positions],
                                        "re": [float(v) for v in np.real(self.ratio)],
                                        "im": [float(v) for v in np.imag(self.ratio)], "unit": "m**2/N"},
               "free_sensitivity": float(self.free_sensitivity),
               "contact_sensitivity": float(self.contact_sensitivity),
               "calibration_factor": cplx(self.calibration_factor),
               "paper_calibration_factor": cplx(self.paper_calibration_factor),
               "d_eff_error_per_volt": cplx(self.d_eff_error_per_volt),
               "lever": self.lever.to_dict(), "k1": self.contact.k1, "k2": self.contact.k2_of(self.contact.k1)}
        if not self.blind_spot.certified:
            out["reason"] = self.blind_spot.reason
        if self.d_eff_error_per_volt is None:
            out["d_eff_error_per_volt_undetermined"] = "needs the lever width"
        return out


MAX_BETA = 200.0
"""Highest dimensionless frequency analysed (about the 64th mode): beyond it an Euler-Bernoulli
lever is no model of a real one, and the blind-spot proof's Taylor degree (grows with beta)
makes a run take minutes."""


def spot_analysis(lever: Cantilever, contact: Contact, frequency: float, *,
                  positions=201) -> SpotResult:
    """Blind spots, the q0/d1 slope ratio along the lever and, at the lever's ``spot_position``,
    the sensitivities, calibration factor and d_eff error (see the module docstring).

    ``positions``: the number of evenly spaced ``x_s/L`` in ``(0, 1]`` for the ratio, or the
    positions themselves.  The lever's ``width`` sizes the capacitive load per volt (parallel
    plate over the tip height); without it the d_eff error is undetermined (None).

    >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5, spot_position=0.8)
    >>> r = spot_analysis(lever, Contact(k1=200.0), 20e3, positions=5)
    >>> round(r.calibration_factor.real, 4), round(float(r.free_sensitivity), 4)
    (0.9965, 0.6944)
    """
    if not (math.isfinite(frequency) and frequency > 0):
        raise UserError(f"frequency must be a positive number of Hz, got {frequency!r}", quantity="drive_frequency")
    if not (contact.k1 or 0.0) > 0:
        # With no contact spring the surface does not drive the tip: no d1 response, no force curve.
        raise UserError(f"the spot analysis needs a contact: k1 must be > 0 N/m, got {contact.k1}", quantity="k1")
    beta = float(lossless_beta(lever, frequency))
    if beta > MAX_BETA:
        top = frequency * (MAX_BETA / beta) ** 2
        raise UserError(f"frequency {frequency:g} Hz is beyond what the beam model is evaluated for here "
                        f"(beta = {beta:.4g} > {MAX_BETA:g}, about mode {MAX_BETA / math.pi:.0f}): at most {top:.4g} Hz "
                        "for this lever", quantity="drive_frequency")
    grid = np.linspace(0, 1, positions + 1)[1:] if np.isscalar(positions) else np.asarray(positions, float)
    theta = slope_along(lever, contact, beta, grid)
    spot = lever.spot_position
    sens = sensitivities(lever, contact, spot)
    at = slope_along(lever, contact, beta, spot)
    factor, error = calibration(lever, contact, frequency, sensitivity=sens["contact"])
    return SpotResult(lever=lever, contact=contact, drive_frequency=float(frequency), beta=beta,
                      blind_spot=blind_spots(lever, contact, beta), positions=grid, ratio=theta[3] / theta[0],
                      spot_position=float(spot), free_sensitivity=float(sens["free"]),
                      contact_sensitivity=float(sens["contact"]), calibration_factor=complex(factor),
                      paper_calibration_factor=complex(2 * lever.length / 3 * at[0]),
                      d_eff_error_per_volt=None if error is None else complex(error))


def calibration(lever: Cantilever, contact: Contact, frequency, *, sensitivity=None) -> tuple:
    """Calibration factor and d_eff error per volt at the lever's ``spot_position``, per frequency.

    The factor is the measured amplitude over the true surface displacement ``d1`` when the
    deflection sensitivity (InvOLS) comes from a static force curve on this contact read at
    the same spot: ``L S_contact theta_d1(x_s, omega)`` (1 in the static limit).  The d_eff
    error is the amplitude the distributed capacitive load (parallel plate over the tip
    height, needs the lever ``width``) adds at the spot, in metres per volt of the ac drive per
    volt of ``V_dc - V_surf``; None without the width.  Lossless lever, as everywhere here: at a
    contact resonance the factor has a pole, at a zero of the spot's ``d1`` response a zero.

    Parameters
    ----------
    lever, contact : Cantilever, Contact
        The probe (its ``spot_position`` is the spot) and the contact (``k1`` needed).
    frequency : float or array_like
        Drive frequencies (Hz, > 0).
    sensitivity : float, optional
        :func:`sensitivities` ``["contact"]`` at the spot, if already known.

    Returns
    -------
    factor : ndarray (real)
    error : ndarray (real) or None

    >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5, spot_position=0.8)
    >>> factor, error = calibration(lever, Contact(k1=200.0), [70.0, 20e3])
    >>> [round(float(c), 4) for c in factor], error is None
    ([1.0, 0.9965], True)
    """
    if sensitivity is None:
        sensitivity = sensitivities(lever, contact, lever.spot_position)["contact"]
    at = slope_along(lever, contact, lossless_beta(lever, np.asarray(frequency, float)), lever.spot_position)
    invols = float(sensitivity) * lever.length        # metres of d1 per unit slope, static
    error = None
    if lever.width is not None:
        q_per_volt = float(formulas.capacitive_load_per_volt2(EPSILON_0, lever.width, lever.tip_height))
        error = np.real(invols * at[3] * q_per_volt)
    return np.real(invols * at[0]), error


def ratio_map(lever: Cantilever, contact: Contact, frequencies, positions) -> np.ndarray:
    """``theta_q0 / theta_d1`` on a grid: rows ``frequencies`` (Hz), columns ``positions`` (x_s/L).

    >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5)
    >>> m = ratio_map(lever, Contact(k1=200.0), [10e3, 50e3], [0.5, 1.0])
    >>> m.shape
    (2, 2)
    """
    beta = lossless_beta(lever, np.asarray(frequencies, float))[:, None]
    theta = slope_along(lever, contact, beta, np.asarray(positions, float)[None, :])
    return theta[3] / theta[0]


SPREAD_RESULTS = ("blind_spot", "contact_sensitivity", "calibration_factor", "paper_calibration_factor",
                  "d_eff_error_per_volt")
"""The results of :func:`spot_analysis` that move with the contact and the tip height (the free sensitivity does
not: it is the free lever's)."""


def _at_spot(lever: Cantilever, contact: Contact, frequency: float) -> dict:
    """:data:`SPREAD_RESULTS` of one lever (real parts: the lossless lever's are real); a list of blind spots."""
    r = spot_analysis(lever, contact, frequency, positions=[lever.spot_position])
    out = {"blind_spot": list(r.blind_spot.positions), "contact_sensitivity": r.contact_sensitivity,
           "calibration_factor": r.calibration_factor.real, "paper_calibration_factor": r.paper_calibration_factor.real}
    if r.d_eff_error_per_volt is not None:
        out["d_eff_error_per_volt"] = r.d_eff_error_per_volt.real
    return out


def spread(lever: Cantilever, contact: Contact, frequency: float, variations: dict) -> tuple[dict, dict]:
    """Standard uncertainty of each of :data:`SPREAD_RESULTS` over the inputs that were assumed, and each input's
    share: the results with each input moved down and up by its standard uncertainty (``variations``: input ->
    ``((lever, contact), (lever, contact))``), half their difference, added in quadrature over the inputs.  Where a
    blind spot appears or goes within an input's spread, the blind spots' uncertainties are NaN.

    Returns ``(stderr, shares)``: result -> standard uncertainty (a list for the blind spots), and input ->
    result -> its part.

    >>> lever = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5, spot_position=0.8)
    >>> moved = {"tip_height_uncertainty": tuple((replace(lever, tip_height=h), Contact(k1=200.0, k2=100.0))
    ...                                          for h in (1.4e-5, 1.6e-5))}
    >>> stderr, shares = spread(lever, Contact(k1=200.0, k2=100.0), 20e3, moved)
    >>> 0 < stderr["contact_sensitivity"] < 0.1, shares["tip_height_uncertainty"]["blind_spot"] == stderr["blind_spot"]
    (True, True)
    """
    nominal = _at_spot(lever, contact, frequency)
    shares = {}
    for source, (down, up) in variations.items():
        low, high = _at_spot(*down, frequency), _at_spot(*up, frequency)
        shares[source] = {}
        for name, value in nominal.items():
            if name == "blind_spot":
                same = len(low[name]) == len(high[name]) == len(value)
                shares[source][name] = ([abs(b - a) / 2 for a, b in zip(low[name], high[name])] if same
                                        else [math.nan] * len(value))
            else:
                shares[source][name] = abs(high[name] - low[name]) / 2
    stderr = {}
    for name, value in nominal.items():
        parts = [shares[source][name] for source in shares]
        stderr[name] = ([math.hypot(*column) for column in zip(*parts)] if parts else [0.0] * len(value)) \
            if name == "blind_spot" else math.hypot(*parts)
    return stderr, shares
