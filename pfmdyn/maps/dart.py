"""DART images (dual AC resonance tracking) to maps: the two-frequency oscillator, then the lever.

At each pixel the tip's AC bias holds two frequencies ``f1 = fc - df/2`` and ``f2 = fc + df/2``
about the tracked centre ``fc``; two lock-ins give the deflection signal's amplitude and lag at
each, i.e. two complex signals ``s_j = A_j exp(-i phi_j)`` per volt of drive (``exp(i omega t)``
convention: a lag is a negative argument).  Four reals per pixel fix four unknowns, twice:

* **the oscillator** (Gannepalli, Yablon, Proksch and Kalinin, Nanotechnology 22, 355705
  (2011)): ``s(f) = D f0**2 / (f0**2 - f**2 + i f f0 / Q)``.  Written as ``c / s_j = f0**2 - f_j**2
  + i f_j f0/Q`` with ``c = D f0**2`` it is linear in ``(Re c, Im c, f0**2, f0/Q)``: the paper's
  closed form, derived in ``derivations/formulas.py`` (``generated/formulas.py``:
  ``two_frequency_*``; :func:`oscillator`).  It is undetermined where that
  system is singular or gives ``f0**2 <= 0`` or ``Q <= 0`` (both points far on one side of the
  peak, phases that do not straddle it);
* **the lever** (:class:`pfmdyn.Cantilever` with its internal loss ``quality_factor``, the k2
  policy, tip position, tilt and spot): the ratio ``s2 / s1`` equals the lever's ``T(f2) / T(f1)``,
  which depends on the contact's ``k1`` and ``contact_loss`` only, one complex equation for two
  reals, solved by Newton steps on all pixels at once from the oscillator's start
  (:func:`lever_inversion`, each step halved until it lowers the residual); the drive then follows,
  ``d_eff = s1 / (T(f1) V)``.  The lever's maps of a pixel are undetermined (NaN, ``determined`` 0)
  where Newton does not converge or the contact would supply energy (its loss below zero by more
  than three standard errors).

The lever knows one thing more than the oscillator: ``d_eff`` is real, the domain's phase 0 or 180
degrees, so a pixel's four numbers hold three unknowns (``k1``, ``contact_loss``, ``|d_eff|``), not four.
The phases' sum ``arg(s1 s2)`` then fixes the contact too: it is ``arg(T(f1) T(f2))`` plus twice the
domain's phase, which the lock-ins' offset and a background (the electrostatic force's) move, one phase
per image for each side of the drives' axis (:func:`domain_phases`, from all the pixels' drives).  :func:`pooled_contact` fits that row beside the ratio's two (:func:`real_drive_phase`), which narrows
one pixel's contact resonance below the oscillator's Cramér-Rao bound (``sigma / 2Q`` relative: four
numbers, four unknowns); where a pixel's rows misfit its contact by more than five standard deviations (a
drive not real there: a background, a tilted domain), the ratio's contact stands alone (``real_drive`` 0).

**The contact resonance and Q** reported are the two-frequency oscillator's through the lever's response
at the pixel's own drives (for the contact found), or where no oscillator goes through it (a negative Q:
an anti-resonance of the slope at the spot near the peak) the lever's damped complex pole
(:func:`lever_pole`).  The contact, moreover, is a grain's, alike at its pixels: :func:`pooled_contact` fits
each pixel's ``k1`` and contact loss to its own and its alike neighbours' signals (within ``pool`` pixels, a
grain boundary parting them; each neighbour read at its own drives), and the resonance and Q follow from
that contact at the pixel's drives, as far from the noise as the pool is large.  ``d_eff`` is the pixel's own
signals over that contact's response (their geometric mean), signed by the side of the image's drive axis
it is on.  The oscillator's resonance and Q through the measured signals, which need no lever, stand where
the lever's inversion fails.

``T`` is the deflection signal per unit surface displacement ``d1`` (along ``k1``, toward the
lever): the slope at the laser spot times ``2L/3``, as a static InvOLS reads it.  So ``d_eff > 0``
when the surface moves toward the lever in phase with the bias, whatever side of a resonance or
anti-resonance the drive is on (the oscillator's drive phase flips above the slope's
anti-resonance; the lever's ``d_eff`` does not).

Uncertainties: the lock-in noise is taken as circular complex noise of relative size ``sigma``
on both signals (each ``s_j (1 + e_j)``, ``E|e_j|**2 = sigma**2``), propagated to first order through
the pooled fit's covariance; ``sigma`` is estimated from the image itself (:func:`channel_noise`).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from ..analysis.contact_resonance import betas, k1_at
from ..cantilever import Cantilever, Contact
from .. import composed
from ..generated.formulas import (point_mass_contact_stiffness, point_mass_static_gain, two_frequency_drive,
                                  two_frequency_resonance_squared, two_frequency_width)
from ..generated.tilt_rotation import rotated
from ..io.results import document as envelope
from ..io.results import quantity
from ..names import NAMES
from .store import write_maps

__all__ = ["Oscillator", "LeverFit", "PooledContact", "oscillator", "oscillator_sensitivity", "channel_noise",
           "alike_sums", "deflection_signal", "lever_inversion", "pooled_contact", "real_drive_phase", "domain_phases",
           "lever_pole",
           "point_mass_k1", "start_k1", "drive_axis", "MAPS", "OSCILLATOR_MAPS", "invert", "write_dart", "document"]

_NEWTON_STEPS = 30
_STEP = 1e-6          # finite-difference step in log k1 and in the contact loss
_HALVINGS = 8         # a Newton step halved at most this often (then taken anyway)


class Oscillator(NamedTuple):
    """The two-frequency oscillator at each pixel: resonance (Hz), Q, drive ``D`` (complex, the
    static signal per volt) and whether the closed form determines them."""

    resonance: np.ndarray
    quality_factor: np.ndarray
    drive: np.ndarray
    determined: np.ndarray


def oscillator(f1, f2, s1, s2) -> Oscillator:
    """The damped harmonic oscillator through two complex signals ``s1``, ``s2`` at ``f1``, ``f2`` (Hz).

    Closed form (the module's 2 x 2 system), vectorised; undetermined pixels are NaN.

    The oscillator is the derived SHO (``generated/formulas.py``; BGlib's sign there, hence the minus):

    >>> from pfmdyn.generated.formulas import sho_response
    >>> f0, q, d = 3e5, 80.0, 2e-11 * np.exp(0.3j)
    >>> s = lambda f: -d * sho_response(f, f0, q)
    >>> o = oscillator(2.97e5, 3.05e5, s(2.97e5), s(3.05e5))
    >>> round(float(o.resonance)), round(float(o.quality_factor), 9), bool(np.isclose(o.drive, d)), bool(o.determined)
    (300000, 80.0, True, True)
    """
    f1, f2, s1, s2 = np.broadcast_arrays(*(np.asarray(v) for v in (f1, f2, s1, s2)))
    with np.errstate(all="ignore"):
        # the forms are homogeneous in the signals: scaled to |s1| = 1 (no overflow in z**2 f**3)
        scale = np.abs(s1)
        z1, z2 = scale / s1, scale / s2
        parts = (f1, f2, z1.real, z1.imag, z2.real, z2.imag)
        f0_squared, width = two_frequency_resonance_squared(*parts), two_frequency_width(*parts)
        determined = np.isfinite(f0_squared) & np.isfinite(width) & (f0_squared > 0) & (width > 0)
        resonance = np.where(determined, np.sqrt(np.abs(f0_squared)), np.nan)
        return Oscillator(resonance, np.where(determined, resonance / width, np.nan),
                          np.where(determined, scale * two_frequency_drive(*parts), np.nan), determined)


def oscillator_sensitivity(f1, f2, s1, s2, base: Oscillator | None = None) -> Oscillator:
    """Standard deviations of :func:`oscillator`'s outputs per unit ``sigma`` (module: relative
    circular noise on both signals), by finite differences in the four noise directions; ``drive``
    holds that of ``log |D|`` (real) and ``determined`` that of D's phase (rad).

    >>> s = lambda f: 1e-11 * 3e5**2 / (3e5**2 - f**2 + 1j * f * 3e5 / 80)
    >>> u = oscillator_sensitivity(2.97e5, 3.05e5, s(2.97e5), s(3.05e5))
    >>> 1e3 < float(u.resonance) < 1e5, 10 < float(u.quality_factor) < 1e3
    (True, True)
    """
    base = oscillator(f1, f2, s1, s2) if base is None else base
    h = 1e-7
    squares = [0.0, 0.0, 0.0, 0.0]
    for e1, e2 in ((h, 0), (1j * h, 0), (0, h), (0, 1j * h)):
        moved = oscillator(f1, f2, s1 * (1 + e1), s2 * (1 + e2))
        with np.errstate(all="ignore"):
            ratio = moved.drive / base.drive
            changes = ((moved.resonance - base.resonance) / h, (moved.quality_factor - base.quality_factor) / h,
                       np.log(np.abs(ratio)) / h, np.angle(ratio) / h)
        squares = [s + d**2 / 2 for s, d in zip(squares, changes)]        # each direction carries sigma**2 / 2
    return Oscillator(*(np.sqrt(s) for s in squares))


def channel_noise(pairs) -> float:
    """``sigma`` from an image: the pixel-to-pixel scatter along the fast scan of maps that the
    tracking does not move (the lever's ``k1``, contact loss, drive) over what ``sigma = 1`` would make.

    ``pairs``: ``(values, sensitivity)`` of such maps, ``(y, x)`` each.  Differences of neighbours,
    each over the root-sum-square of the two pixels' sensitivities, have standard deviation
    ``sigma``; their median absolute value (times 1.4826), pooled over the maps, is robust to the
    few that straddle a grain or domain boundary.

    >>> rng = np.random.default_rng(0)
    >>> g = np.full((64, 64), 3.0)
    >>> round(channel_noise([(5.0 + 0.02 * g * rng.standard_normal(g.shape), g)]), 2)
    0.02
    """
    pooled = []
    for values, sensitivity in pairs:
        values, sensitivity = np.asarray(values, float), np.asarray(sensitivity, float)
        with np.errstate(all="ignore"):
            pooled.append(np.ravel(np.diff(values, axis=-1) / np.hypot(sensitivity[..., 1:], sensitivity[..., :-1])))
    z = np.concatenate(pooled) if pooled else np.empty(0)
    z = z[np.isfinite(z)]
    return float(1.4826 * np.median(np.abs(z))) if z.size else math.nan


def alike_sums(values, variances, quantities, radius: int, gate: float = 3.0, centre=None):
    """Sums of ``quantities`` (``(m, y, x)``) over each pixel's alike neighbours: those within ``radius``
    pixels (a square, the pixel included) whose ``values`` (``(n, y, x)``, with ``variances``) all
    agree with the pixel's to ``gate`` standard deviations of their difference, or with ``centre``
    (``(n, y, x)``, exact: a pooled estimate) to ``gate`` of their own.  A grain's contact is
    alike at its pixels, which the lock-in noise scatters independently; a grain boundary parts them.
    Pixels with a value not finite are nobody's neighbours (their own sums are NaN).

    >>> values = np.where(np.arange(6) < 3, 1.0, 2.0)[None, None, :] * np.ones((1, 4, 6))
    >>> alike_sums(values, np.full(values.shape, 1e-4), np.ones((1, 4, 6)), 1)[0, 0].tolist()   # the two grains apart
    [4.0, 6.0, 4.0, 4.0, 6.0, 4.0]
    """
    values, variances, quantities = (np.asarray(v, float) for v in (values, variances, quantities))
    ny, nx = values.shape[-2:]
    usable = np.all(np.isfinite(values) & np.isfinite(variances), axis=0) & np.all(np.isfinite(quantities), axis=0)
    pad = lambda a: np.pad(a, ((0, 0), (radius, radius), (radius, radius)), constant_values=np.nan)  # noqa: E731
    v, var, q = pad(np.where(usable, values, np.nan)), pad(np.where(usable, variances, np.nan)), \
        pad(np.where(usable, quantities, 0.0))
    sums = np.zeros(quantities.shape)
    reference, spread = (values, variances) if centre is None else (np.asarray(centre, float), 0.0)
    with np.errstate(invalid="ignore"):
        for dy in range(2 * radius + 1):
            for dx in range(2 * radius + 1):
                window = (slice(None), slice(dy, dy + ny), slice(dx, dx + nx))
                alike = np.all(np.abs(v[window] - reference) <= gate * np.sqrt(spread + var[window]), axis=0)
                sums += np.where(alike, np.nan_to_num(q[window]), 0.0)
    return np.where(usable, sums, np.nan)


def point_mass_k1(resonance, lever: Cantilever):
    """The point-mass (oscillator) contact stiffness ``k ((fc / f0)**2 - 1)`` of a resonance ``fc``
    (``generated/formulas.py``: ``point_mass_contact_stiffness``).

    >>> round(float(point_mass_k1(3e5, Cantilever(2.0, 7.5e4, 2e-4))), 6)
    30.0
    """
    return point_mass_contact_stiffness(np.asarray(resonance), lever.free_resonance, lever.spring_constant)


def _arguments(lever: Cantilever, contact: Contact, k1, loss, frequency):
    """The composed model's ``beta`` and :class:`~pfmdyn.composed.Parameters` at ``frequency`` for arrays
    of ``k1`` and ``contact_loss``: :meth:`Cantilever._damped` (the one damping substitution) and the
    contact's k2 law, rotated, on the free lever's parameters."""
    damped = lever._damped(frequency, _PixelContact(k1, loss))
    kvv, kll, kvl = rotated(damped.k1, contact.k2_of(k1), lever.alpha)
    return damped.beta, lever.model_parameters(None)._replace(k=damped.k, kvv=kvv, kll=kll, kvl=kvl, mu=damped.mu)


class _PixelContact(NamedTuple):
    """``k1`` and ``contact_loss`` per pixel, as :meth:`Cantilever._damped` reads a contact."""

    k1: np.ndarray
    contact_loss: np.ndarray


def deflection_signal(lever: Cantilever, contact: Contact, frequency, k1, loss):
    """The deflection signal per unit surface displacement ``d1`` (along ``k1``, toward the lever):
    the slope at the spot times ``2L/3`` (a static InvOLS), broadcast over the arguments.

    >>> lever = Cantilever(2.0, 7.5e4, 2e-4, quality_factor=300.0)
    >>> t = deflection_signal(lever, Contact(), [1e3, 3e6], 100.0, 0.01)
    >>> round(float(t[0].real), 4), bool(t[1].real < 0)    # k1 / (k + k1) well below resonance; in antiphase far above
    (0.9804, True)
    """
    frequency, k1, loss = np.broadcast_arrays(*(np.asarray(v, float) for v in (frequency, k1, loss)))
    beta, parameters = _arguments(lever, contact, k1, loss, frequency)
    with np.errstate(all="ignore"):
        (slope,) = composed.slope(beta, parameters, lever.spot_position, drives=("d1",))
    return np.asarray(slope, complex).reshape(frequency.shape) * (2 * lever.length / 3)


def lever_pole(lever: Cantilever, contact: Contact, k1, loss, start, steps: int = 40):
    """The lever's damped first contact resonance near ``start`` (Hz) as an oscillator's resonance and Q:
    the complex root ``r`` of the composed characteristic (Newton in complex frequency, all pixels at
    once) gives ``|r|`` and ``|r| / (2 Im r)`` (an oscillator's own root gives back its ``f0`` and ``Q``).
    Where the two-frequency oscillator is undetermined (an anti-resonance of the slope at the spot
    near the resonance), :func:`invert` reports these.

    >>> lever = Cantilever(2.0, 75e3, 2e-4)           # lossless lever, contact with a dashpot
    >>> f, q = lever_pole(lever, Contact(), np.array([109.7483]), np.array([0.01]), np.array([3e5]))
    >>> round(float(f[0]) / 3e5, 3), 10 < float(q[0]) < 1e3
    (1.0, True)
    """
    k1, loss, f = (np.asarray(v, float).ravel() for v in (k1, loss, start))
    f = f.astype(complex)

    def characteristic(frequency):
        beta, parameters = _arguments(lever, contact, k1, loss, frequency)
        return composed.characteristic(beta, parameters)

    with np.errstate(all="ignore"):
        for _ in range(steps):
            h = 1e-7 * f
            value = characteristic(f)
            step = value * h / (characteristic(f + h) - value)
            step = np.where(np.isfinite(step), step, 0.0)
            f = f - step
            if np.all(np.abs(step) < 1e-12 * np.abs(f)):
                break
        return np.abs(f), np.abs(f) / (2 * f.imag)


class LeverFit(NamedTuple):
    """The lever's inversion at each pixel: ``k1`` (N/m), ``contact_loss``, the drive ``d`` (complex,
    m/V), their standard deviations per unit ``sigma`` (``k1`` relative, ``contact_loss`` absolute,
    ``log |d|``), and whether Newton's steps converged."""

    k1: np.ndarray
    contact_loss: np.ndarray
    drive: np.ndarray
    k1_sensitivity: np.ndarray
    loss_sensitivity: np.ndarray
    drive_sensitivity: np.ndarray
    converged: np.ndarray


def start_k1(lever: Cantilever, contact: Contact, resonance, points: int = 96):
    """The undamped lever's ``k1`` whose first contact resonance is ``resonance`` (Hz; NaN where
    none is), Newton's start: :func:`pfmdyn.analysis.contact_resonance.k1_at` on ``points``
    frequencies spanning the map's, interpolated in ``log k1`` over ``log f`` (the map's pixels
    need not pay for the mode count each).

    >>> round(float(start_k1(Cantilever(2.0, 75e3, 2e-4), Contact(), 300e3)), 4)
    109.7483
    """
    resonance = np.asarray(resonance, float)
    ok = np.isfinite(resonance) & (resonance > lever.free_resonance)
    out = np.full(resonance.shape, np.nan)
    if not ok.any():
        return out
    low, high = np.min(resonance[ok]), np.max(resonance[ok])
    grid = np.geomspace(low, high, points) if high > low else np.array([low])
    k1 = k1_at(betas(lever, grid), 1, lever, contact, lever.tip_position)
    known = np.isfinite(k1) & (k1 > 0)
    if known.sum() == 1:
        out[ok] = np.where(np.isclose(resonance[ok], grid[known][0]), k1[known][0], np.nan)
    elif known.any():
        # beyond the known ends (a resonance above the pinned lever's, an oscillator pulled by an
        # anti-resonance near the peak) the nearest end: a start, which Newton moves
        out[ok] = np.exp(np.interp(np.log(resonance[ok]), np.log(grid[known]), np.log(k1[known])))
    return out


def _log_ratios(lever, contact, f1, f2, points):
    """``log(T(f2)/T(f1))`` and ``T(f1)`` at each ``(k1, loss)`` of ``points``, in one call of the lever."""
    n, m = len(f1), len(points)
    t = deflection_signal(lever, contact, np.tile(np.concatenate([f1, f2]), m),
                          np.concatenate([np.concatenate([k1, k1]) for k1, _ in points]),
                          np.concatenate([np.concatenate([loss, loss]) for _, loss in points])).reshape(m, 2, n)
    with np.errstate(all="ignore"):
        return [(np.log(t[j, 1] / t[j, 0]), t[j, 0]) for j in range(m)]


def _linearised(lever, contact, f1, f2, target, k1, loss, phase=None):
    """The residual ``log(T(f2)/T(f1)) - target`` as ``(re, im)`` (the phase modulo 2 pi) and its Jacobian
    in ``(log k1, loss)`` by forward differences, ``(n, 2)`` and ``(n, 2, 2)``; with ``phase`` (the
    signals' summed phase, a real drive's, :func:`real_drive_phase`), a third row: ``arg(T(f1) T(f2)) - phase``
    (modulo 2 pi), ``(n, 3)`` and ``(n, 3, 2)``."""
    (g, t), (gk, tk), (gx, tx) = _log_ratios(lever, contact, f1, f2, [
        (k1, loss), (k1 * math.exp(_STEP), loss), (k1, loss + _STEP)])
    r = g - target
    rows = [r.real, np.angle(np.exp(1j * r.imag))]
    dk, dx = (gk - g) / _STEP, (gx - g) / _STEP
    jac = [np.stack([dk.real, dx.real], -1), np.stack([dk.imag, dx.imag], -1)]
    if phase is not None:
        with np.errstate(all="ignore"):     # arg(T1 T2) = 2 arg T1 + arg(T2 / T1)
            rows.append(np.angle(t * t * np.exp(1j * (g.imag - phase))))
            jac.append(np.stack([2 * np.log(tk / t).imag / _STEP + dk.imag,
                                 2 * np.log(tx / t).imag / _STEP + dx.imag], -1))
    return np.stack(rows, -1), np.stack(jac, -2)


def lever_inversion(lever: Cantilever, contact: Contact, f1, f2, s1, s2, k1, loss, drive_amplitude: float,
                    steps: int = _NEWTON_STEPS) -> LeverFit:
    """``k1``, ``contact_loss`` and ``d_eff`` explaining the deflection signals ``s1``, ``s2`` (m, complex,
    driven by ``drive_amplitude`` volts) at ``f1``, ``f2`` on ``lever``, from the start ``k1``,
    ``loss`` (flat arrays).  Newton on ``log(T(f2)/T(f1)) = log(s2/s1)`` in ``(log k1, loss)``, its
    Jacobian by forward differences, all pixels at once; a pixel stops when its step is below
    1e-10 (relative in k1, absolute in the loss).

    >>> lever = Cantilever(2.0, 75e3, 2e-4, quality_factor=300.0)
    >>> f = np.array([3.10e5, 3.16e5])
    >>> t = deflection_signal(lever, Contact(), f, 120.0, 0.02)
    >>> fit = lever_inversion(lever, Contact(), f[:1], f[1:], -3e-12 * t[:1], -3e-12 * t[1:], np.array([100.0]),
    ...                       np.array([0.01]), 1.0)
    >>> round(float(fit.k1[0]), 6), round(float(fit.contact_loss[0]), 9), round(float(fit.drive[0].real * 1e12), 9)
    (120.0, 0.02, -3.0)
    """
    f1, f2, s1, s2 = (np.asarray(v).ravel() for v in (f1, f2, s1, s2))
    log_k1, loss = np.log(np.asarray(k1, float).ravel()), np.asarray(loss, float).ravel().copy()
    with np.errstate(invalid="ignore", divide="ignore"):     # a pixel without signal (NaN, 0) stays inactive
        target = np.log(s2 / s1)
    active = np.isfinite(log_k1) & np.isfinite(loss) & np.isfinite(target)
    converged = np.zeros(len(f1), bool)
    jacobian = np.full((len(f1), 2, 2), np.nan)
    for _ in range(steps):
        i = np.flatnonzero(active & ~converged)
        if not i.size:
            break
        k1_i = np.exp(log_k1[i])
        r, jac = _linearised(lever, contact, f1[i], f2[i], target[i], k1_i, loss[i])
        jacobian[i] = jac
        with np.errstate(all="ignore"):
            step = -np.einsum("...ij,...j->...i", _inverse(jac), r)
        bad = ~np.all(np.isfinite(step), -1)
        step[bad] = 0.0
        active[i[bad]] = False
        # k1 changes at most e**0.5 a step, and a step is halved until it lowers the residual
        step *= np.minimum(1.0, 0.5 / np.maximum(np.abs(step[:, 0]), 1e-300))[:, None]
        norm, pending = np.hypot(r[:, 0], r[:, 1]), np.abs(step).max(-1) > 1e-8
        for _ in range(_HALVINGS):
            j = np.flatnonzero(pending)
            if not j.size:
                break
            ((trial, _),) = _log_ratios(lever, contact, f1[i[j]], f2[i[j]],
                                        [(k1_i[j] * np.exp(step[j, 0]), loss[i[j]] + step[j, 1])])
            rt = trial - target[i[j]]
            lower = np.abs(rt.real + 1j * np.angle(np.exp(1j * rt.imag))) < norm[j]
            pending[j[lower]] = False
            step[j[~lower]] /= 2
        log_k1[i] += step[:, 0]
        loss[i] += step[:, 1]
        converged[i] = (np.abs(step[:, 0]) < 1e-10) & (np.abs(step[:, 1]) < 1e-10)
    k1 = np.exp(log_k1)
    ((_, t1),) = _log_ratios(lever, contact, f1, f2, [(k1, loss)])
    with np.errstate(all="ignore"):
        drive = s1 / (t1 * drive_amplitude)
        # d(log k1, loss) = J^-1 d(log s2/s1); d log(s2/s1) = e2 - e1: variance sigma**2 in each part
        inverse = _inverse(jacobian)
        covariance = inverse @ np.swapaxes(inverse, -1, -2)
        # log d = log s1 - log T1(k1, loss): e1 enters directly and through k1, loss
        dt1 = _t1_partials(lever, contact, f1, k1, loss, t1)
        drive_variance = _drive_variance(inverse, dt1)
    # a contact the signals do not fix (an infinite spread: a dashpot pinning it) is not found
    ok = converged & np.all(np.isfinite(jacobian), axis=(-1, -2)) & np.isfinite(covariance[:, 0, 0] + covariance[:, 1, 1]
                                                                           + drive_variance)
    nan = lambda v: np.where(ok, v, np.nan)      # noqa: E731
    return LeverFit(nan(k1), nan(loss), nan(drive), nan(np.sqrt(covariance[:, 0, 0])),
                    nan(np.sqrt(covariance[:, 1, 1])), nan(np.sqrt(drive_variance)), ok)


class PooledContact(NamedTuple):
    """:func:`pooled_contact`'s answer at each pixel: ``k1`` (N/m), ``contact_loss``, their covariance per
    unit ``sigma**2`` (``(n, 2, 2)`` in ``(log k1, contact_loss)``), the ratio of ``k1``'s standard deviation to
    the pixel's own (:class:`LeverFit`), the pixel's own misfit (the sum of its rows' squared residuals
    per ``sigma**2``, linearised) and whether its phase row was fitted (its drive taken as real)."""

    k1: np.ndarray
    contact_loss: np.ndarray
    covariance: np.ndarray
    narrowed: np.ndarray
    misfit: np.ndarray
    real: np.ndarray


def pooled_contact(lever: Cantilever, contact: Contact, f1, f2, s1, s2, fit: LeverFit, sigma: float, shape,
                   radius: int, phase=None, misfit_limit: float = math.inf) -> PooledContact:
    """Each pixel's contact (``k1``, ``contact_loss``) fitted to its own and its alike neighbours' signals
    (:func:`alike_sums` within ``radius``, 0 for the pixel alone; alike by :func:`lever_inversion`'s ``fit``
    and its spread at noise ``sigma``): least squares on ``log(s2/s1)`` and, with ``phase`` (:func:`real_drive_phase`),
    on ``arg(s1 s2)`` too, the phase of a real drive's signals, except at the pixels whose own rows misfit the
    contact found by more than ``misfit_limit`` (fitted again without theirs, twice at most); each row's noise is
    ``sigma`` at every pixel (relative lock-in noise), each neighbour read at its own drives.  One Gauss-Newton
    step from the inverse-variance mean of the pixels' own contacts (a pixel's own Newton step is linear from
    there, so the nonlinear inversion's bias at each pixel does not add up in the pool).

    >>> lever = Cantilever(2.0, 75e3, 2e-4, quality_factor=300.0)
    >>> rng = np.random.default_rng(3)
    >>> f1 = 3.10e5 + 2e3 * rng.uniform(size=(6, 6)); f2 = f1 + 6e3
    >>> noise = lambda s: s * (1 + 0.01 * (rng.standard_normal(s.shape) + 1j * rng.standard_normal(s.shape)) / 2**0.5)
    >>> s1, s2 = (noise(-2e-12 * deflection_signal(lever, Contact(), f, 120.0, 0.02)) for f in (f1, f2))
    >>> fit = lever_inversion(lever, Contact(), f1, f2, s1, s2, np.full(36, 120.0), np.full(36, 0.02), 1.0)
    >>> args = (lever, Contact(), f1.ravel(), f2.ravel(), s1.ravel(), s2.ravel(), fit, 0.01, (6, 6))
    >>> pooled = pooled_contact(*args, 2)
    >>> bool(np.std(pooled.k1 / 120 - 1) < np.std(fit.k1 / 120 - 1) / 2), bool(np.all(pooled.narrowed < 0.6))
    (True, True)
    >>> alone = pooled_contact(*args, 0, phase=real_drive_phase(s1.ravel(), s2.ravel(), 0.0))   # a real drive's phases
    >>> bool(np.std(alone.contact_loss - 0.02) < np.std(fit.contact_loss - 0.02) / 1.5), bool(np.all(alone.misfit < 16))
    (True, True)
    """
    grid = tuple(shape) if len(shape) == 2 else (1, len(f1))
    gate_values = np.stack([np.log(fit.k1), fit.contact_loss]).reshape(2, *grid)
    gate_variances = (sigma * np.stack([fit.k1_sensitivity, fit.loss_sensitivity])).reshape(2, *grid) ** 2
    misfit = np.full(len(f1), np.nan)
    real = np.full(len(f1), phase is not None)
    with np.errstate(all="ignore"):
        weights = 1 / gate_variances
        sums = alike_sums(gate_values, gate_variances, np.concatenate([weights, weights * gate_values]), radius)
        theta = (sums[2:] / sums[:2]).reshape(2, -1)
        i = np.flatnonzero(np.all(np.isfinite(theta), 0))
        r, jac = _linearised(lever, contact, f1[i], f2[i], np.log(s2[i] / s1[i]), np.exp(theta[0, i]), theta[1, i],
                             None if phase is None else phase[i])
        def solve(real):
            """The pooled contact, its information and the pixels' rows' residuals there, the phase rows of the
            pixels ``real`` in the fit."""
            weight = np.ones(r.shape)
            weight[~real[i], 2:] = 0.0        # a pixel whose drive is not taken as real gives no phase row to the fit
            own = np.einsum("nki,nkj->nij", weight[..., None] * jac, jac)
            # each pixel's normal equations J^T J (theta - theta_own) = -J^T r, summed over its alike neighbours
            rhs = np.einsum("nij,jn->ni", own, theta[:, i]) - np.einsum("nki,nk->ni", jac, weight * r)
            parts = np.full((5, len(f1)), np.nan)
            parts[:, i] = np.stack([own[:, 0, 0], own[:, 0, 1], own[:, 1, 1], rhs[:, 0], rhs[:, 1]])
            # alike now means: near the pool's estimate, not the pixel's own noisy one
            pooled = alike_sums(gate_values, gate_variances, parts.reshape(5, *grid), radius,
                                centre=theta.reshape(2, *grid)).reshape(5, -1)
            information = np.stack([np.stack([pooled[0], pooled[1]], -1), np.stack([pooled[1], pooled[2]], -1)], -2)
            moved = np.einsum("nij,jn->in", _inverse(information), pooled[3:])
            return moved, information, r + np.einsum("nkj,jn->nk", jac, moved[:, i] - theta[:, i])

        for attempt in range(3):    # the misfits' neighbours fit again once those are out of their pools
            moved, information, residual = solve(real)
            misfit[i] = np.sum(residual**2, -1) / sigma**2
            fits = (phase is not None) & ~(misfit > misfit_limit)
            if attempt == 2 or np.array_equal(fits, real):
                break
            real = fits
        covariance = _inverse(information)
        return PooledContact(np.exp(moved[0]), moved[1], covariance, np.sqrt(covariance[:, 0, 0]) / fit.k1_sensitivity,
                             misfit, real)


def real_drive_phase(s1, s2, axis):
    """``arg(s1 s2)`` less twice the drive's phase ``axis`` (radians; per pixel, :func:`domain_phases`): what
    ``arg(T(f1) T(f2))`` is where the drive's phase is that (or that plus 180 degrees, squared away), the row
    :func:`pooled_contact` adds to the ratio's two.

    >>> round(float(real_drive_phase(-2j, 3 + 0j, 0.25)), 6)      # -90 deg less 2 x 0.25 rad
    -2.070796
    """
    return np.angle(np.asarray(s1) * np.asarray(s2) * np.exp(-2j * axis))


def _neighbours_contact(fit: LeverFit, shape, radius: int = 2):
    """The mean contact (``k1``, ``contact_loss``) of the pixels found within ``radius`` of each pixel."""
    grid = tuple(shape) if len(shape) == 2 else (1, len(fit.k1))
    found = fit.converged.astype(float)
    with np.errstate(all="ignore"):
        parts = np.nan_to_num(np.stack([found, found * np.log(fit.k1), found * fit.contact_loss]))
        sums = alike_sums(np.zeros((1, *grid)), np.ones((1, *grid)), parts.reshape(3, *grid), radius).reshape(3, -1)
        return np.exp(sums[1] / sums[0]), sums[2] / sums[0]


def _inverse(m):
    """Inverses of 2 x 2 matrices ``(..., 2, 2)``, NaN where singular."""
    det = m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    adjugate = np.stack([np.stack([m[..., 1, 1], -m[..., 0, 1]], -1), np.stack([-m[..., 1, 0], m[..., 0, 0]], -1)], -2)
    return adjugate / det[..., None, None]


def _t1_partials(lever, contact, f1, k1, loss, t1):
    """``d log|T(f1)| / d(log k1, loss)`` (real parts of the complex log's partials)."""
    tk = deflection_signal(lever, contact, f1, k1 * math.exp(_STEP), loss)
    tx = deflection_signal(lever, contact, f1, k1, loss + _STEP)
    return np.stack([np.log(tk / t1).real, np.log(tx / t1).real], -1) / _STEP


def _drive_variance(inverse, dt1):
    """Variance of ``log|d|`` per ``sigma**2``: ``log|d| = log|s1| - log|T1|``, with ``(log k1, loss)
    = J^-1 (Re, Im)(e2 - e1)``; ``e1``'s real and imaginary parts and ``e2``'s each carry
    ``sigma**2 / 2``."""
    g = np.einsum("...i,...ij->...j", dt1, inverse)      # d log|T1| per unit (Re, Im) of e2 - e1
    # per unit Re e1: 1 + g_re; Im e1: g_im; Re e2: -g_re; Im e2: -g_im
    return ((1 + g[..., 0]) ** 2 + g[..., 1] ** 2 + g[..., 0] ** 2 + g[..., 1] ** 2) / 2


def drive_axis(lever: Cantilever, contact: Contact, f1, s1, k1, loss) -> float:
    """The axis (degrees, in ``(-90, 90]``) about which the pixels' drives ``s1 / T(f1)`` cluster, their
    sign aside (half the argument of the mean of ``(d/|d|)**2``).  The domains' drive is in phase or in
    antiphase with the bias, so the axis is the lock-ins' phase offset modulo 180 degrees; ``d_eff``'s
    sign reads a drive within 90 degrees of zero as positive, right while the offset is within 90.

    >>> lever = Cantilever(2.0, 75e3, 2e-4, quality_factor=300.0)
    >>> f1 = np.full(4, 3.1e5)
    >>> s1 = deflection_signal(lever, Contact(), f1, 120.0, 0.02) * np.array([1, -1, 1, -1]) * np.exp(-0.5j)
    >>> round(drive_axis(lever, Contact(), f1, s1, np.full(4, 120.0), np.full(4, 0.02)), 6)      # a 0.5 rad lag
    -28.64789
    """
    with np.errstate(all="ignore"):
        return _axis(np.asarray(s1) / deflection_signal(lever, contact, f1, k1, loss))


def domain_phases(drive, axis: float, least: int = 16):
    """Each pixel's domain phase (radians): the median argument of the drives ``drive`` (complex) on its side of
    ``axis`` (radians, :func:`drive_axis`), that side's ``axis`` (or ``axis + pi``) where it has fewer than
    ``least`` pixels.  The domains' drive is in phase or in antiphase with the bias, but for the lock-ins' offset
    (one per image) and a background (the electrostatic force's, one per image): two phases, not always 180
    degrees apart.

    >>> drive = np.exp(1j * np.radians([10.0, 11.0, 12.0, 185.0, 186.0, 187.0]))
    >>> np.round(np.degrees(domain_phases(drive, 0.0, least=3)), 6).tolist()
    [11.0, 11.0, 11.0, -174.0, -174.0, -174.0]
    """
    drive = np.asarray(drive)
    with np.errstate(all="ignore"):
        turned = drive * np.exp(-1j * axis)
        negative = turned.real < 0
        phases = np.full(drive.shape, np.nan)
        for side, flip in ((~negative, 1.0), (negative, -1.0)):
            angles = np.angle(flip * turned[side & np.isfinite(drive)])
            offset = np.median(angles) if angles.size >= least else 0.0
            phases[side] = np.angle(np.exp(1j * (axis + offset + (0.0 if flip > 0 else math.pi))))
    return phases


def _axis(drive) -> float:
    """:func:`drive_axis` of the drives ``drive`` (complex): the mean's axis, then moved by the median of the
    drives' angles from it (modulo 180 degrees): a patch whose drive is not real does not turn the image's."""
    with np.errstate(all="ignore"):
        drive = np.ravel(drive)
        drive = drive[np.isfinite(drive) & (drive != 0)]
        if not drive.size:
            return math.nan
        squared = (drive / np.abs(drive)) ** 2
        axis = np.angle(np.mean(squared)) / 2
        axis = math.degrees(axis + np.median(np.angle(squared * np.exp(-2j * axis))) / 2)
    axis = (axis + 90.0) % 180.0 - 90.0
    return 90.0 if axis == -90.0 else axis


MAPS = ("contact_resonance", "contact_quality_factor", "k1", "contact_loss", "d_eff")
"""The maps with a ``_stderr`` each (:func:`invert`); then the oscillator's readings of the same pixels."""
OSCILLATOR_MAPS = ("oscillator_k1", "oscillator_k1_error", "oscillator_d_eff", "oscillator_d_eff_error")


def _signed(drive):
    """A complex drive as a signed real: its modulus, negative where it is nearer antiphase."""
    return np.abs(drive) * np.where(np.cos(np.angle(drive)) < 0, -1.0, 1.0)


POOL = 5
MISFIT = 25.0
"""A pixel's misfit (:class:`PooledContact`) above which its drive is not taken as real: five standard deviations."""
"""Radius (pixels) over which :func:`invert` pools a pixel's contact with its alike neighbours."""


def invert(f1, f2, s1, s2, lever: Cantilever, contact: Contact, drive_amplitude: float, *, pool: int = POOL,
           block: int = 4096, progress=None, tip_height_uncertainty: float = 0.0) -> tuple[dict, float]:
    """Every pixel of a DART image both ways: maps (name -> array of the signals' shape; :data:`MAPS`
    with ``_stderr``, :data:`OSCILLATOR_MAPS`, ``real_drive``, ``determined``) and ``sigma`` (:func:`channel_noise`).

    ``s1``, ``s2``: the deflection signals (m, complex, ``A exp(-i phi)``) at ``f1``, ``f2`` (Hz);
    ``contact``: the k2 policy (:meth:`pfmdyn.Contact.policy`); ``pool``: the radius (pixels) of
    :func:`pooled_contact` (0: each pixel's contact alone; ``d_eff`` is each pixel's own always);
    ``progress(done, total)`` is called after each ``block`` of pixels.  ``tip_height_uncertainty`` (m):
    its shares in ``k1_stderr`` and ``contact_loss_stderr``, each pixel's drives' ratio held (as a
    band-excitation map and ``pfmdyn stiffness`` hold the contact resonance).

    >>> lever = Cantilever(2.0, 75e3, 2e-4, quality_factor=300.0)
    >>> f1, f2 = np.array([[3.10e5, 3.11e5]]), np.array([[3.16e5, 3.17e5]])
    >>> s1, s2 = (2e-12 * deflection_signal(lever, Contact(), f, 120.0, 0.02) for f in (f1, f2))
    >>> maps, sigma = invert(f1, f2, s1, s2, lever, Contact(), 1.0)
    >>> np.round(maps["k1"], 6).tolist(), np.round(maps["d_eff"] * 1e12, 9).tolist()
    ([[120.0, 120.0]], [[2.0, 2.0]])
    """
    shape = np.shape(s1)
    f1, f2, s1, s2 = (np.broadcast_to(v, shape).ravel() for v in (f1, f2, s1, s2))
    sho = oscillator(f1, f2, s1, s2)
    spread = oscillator_sensitivity(f1, f2, s1, s2, sho)
    # where the oscillator is undetermined Newton starts from the tracked centre
    k1_start = start_k1(lever, contact, np.where(sho.determined, sho.resonance, (f1 + f2) / 2))
    # the contact's share of the loss: what the oscillator's 1/Q has beyond the lever's own, at fc
    with np.errstate(all="ignore"):
        loss_start = np.where(sho.determined, np.clip(1 / sho.quality_factor - 1 / lever.quality_factor, 1e-4, None)
                              * lever.free_resonance / sho.resonance, 0.01)
    fits = []
    for start in range(0, len(f1), block):
        part = slice(start, start + block)
        fits.append(lever_inversion(lever, contact, f1[part], f2[part], s1[part], s2[part], k1_start[part],
                                    loss_start[part], drive_amplitude))
        if progress is not None:
            progress(min(start + block, len(f1)), len(f1))
    fit = LeverFit(*(np.concatenate(parts) for parts in zip(*fits))) if fits else \
        LeverFit(*([np.empty(0)] * 6 + [np.empty(0, bool)]))
    # where Newton found nothing from the oscillator's start (pulled by an anti-resonance near the peak, a
    # tracking far off, noise on a contact the signals hardly fix), again from the contact of the neighbours
    # found, from the tracked centre, then from a few stiffer and softer contacts
    centre_k1 = start_k1(lever, contact, (f1 + f2) / 2)
    for scale, loss in (("neighbours", None), (None, 0.01), (0.5, 0.01), (2.0, 0.01), (0.7, 0.03), (1.4, 0.03)):
        again = np.flatnonzero(~fit.converged)
        if not again.size:
            break
        if scale == "neighbours":
            k1_again, loss_again = (v[again] for v in _neighbours_contact(fit, shape))
        else:
            k1_again = centre_k1[again] if scale is None else scale * np.where(np.isfinite(k1_start[again]),
                                                                                k1_start[again], centre_k1[again])
            loss_again = np.full(again.size, loss)
        retry = lever_inversion(lever, contact, f1[again], f2[again], s1[again], s2[again], k1_again,
                                loss_again, drive_amplitude)
        fields = []
        for whole, part in zip(fit, retry):
            whole = whole.copy()
            whole[again] = np.where(retry.converged, part, whole[again])
            fields.append(whole)
        fit = LeverFit(*fields)
    with np.errstate(all="ignore"):
        sigma = channel_noise([(np.log(fit.k1).reshape(shape), fit.k1_sensitivity.reshape(shape)),
                               (fit.contact_loss.reshape(shape), fit.loss_sensitivity.reshape(shape)),
                               (np.log(np.abs(fit.drive)).reshape(shape), fit.drive_sensitivity.reshape(shape))])
    u = 0.0 if not math.isfinite(sigma) else sigma
    # a contact that would supply energy (its loss below zero by more than three standard errors) explains
    # nothing: phases the lever's resonance cannot give (an upper drive leading the lower one)
    passive = fit.contact_loss + 3 * u * fit.loss_sensitivity >= 0
    fit = LeverFit(*(np.where(passive, v, np.nan) for v in fit[:6]), fit.converged & passive)
    with np.errstate(all="ignore"):
        k1_pm = point_mass_k1(sho.resonance, lever)
        # the oscillator's static gain read as the point-mass lever's: tip deflection d k1 / (k + k1)
        d_pm = _signed(sho.drive / drive_amplitude / point_mass_static_gain(lever.spring_constant, k1_pm))
        axis = math.radians(_axis(fit.drive)) if fit.converged.any() else 0.0
        if u > 0:
            # each pixel's contact fitted to its and its alike neighbours' signals (a grain's), read at its own drives,
            # its drive at its domain's phase (the ratio's contact alone where the phases misfit)
            pooled = pooled_contact(lever, contact, f1, f2, s1, s2, fit, u, shape, pool,
                                    phase=real_drive_phase(s1, s2, domain_phases(fit.drive, axis)),
                                    misfit_limit=MISFIT)
        else:
            covariance = np.zeros((len(f1), 2, 2))
            covariance[:, 0, 0], covariance[:, 1, 1] = fit.k1_sensitivity**2, fit.loss_sensitivity**2
            pooled = PooledContact(fit.k1, fit.contact_loss, covariance, np.ones(len(f1)), np.zeros(len(f1)),
                                   np.ones(len(f1), bool))
        k1, loss, covariance = pooled.k1, pooled.contact_loss, pooled.covariance
        # the lever's response at the pixel's drives, and moved by each of the contact's two numbers
        responses = [(t1, t1 * np.exp(g)) for g, t1 in _log_ratios(lever, contact, f1, f2, [
            (k1, loss), (k1 * math.exp(_STEP), loss), (k1, loss + _STEP)])]
        # the contact resonance and Q: the oscillator through the lever's response at the pixel's drives, or
        # the lever's pole where none goes through it (an anti-resonance of the slope at the spot near the
        # peak); the oscillator through the measured signals where the lever's inversion fails
        lever_sho, *moved = (oscillator(f1, f2, *t) for t in responses)
        resonance = np.where(fit.converged, lever_sho.resonance, sho.resonance)
        quality = np.where(fit.converged, lever_sho.quality_factor, sho.quality_factor)
        pole = fit.converged & ~lever_sho.determined
        at_pole = {}
        if pole.any():
            resonance[pole], quality[pole] = lever_pole(lever, contact, k1[pole], loss[pole], (f1[pole] + f2[pole]) / 2)
            # the pole moved by each of the contact's two numbers, from where it is
            moved_pole = [lever_pole(lever, contact, k, l, resonance[pole]) for k, l in (
                (k1[pole] * math.exp(_STEP), loss[pole]), (k1[pole], loss[pole] + _STEP))]
            at_pole = {"resonance": (resonance[pole], [m[0] for m in moved_pole]),
                       "quality_factor": (quality[pole], [m[1] for m in moved_pole])}
        spreads = {}
        for name in ("resonance", "quality_factor"):
            gradient = np.stack([(getattr(m, name) - getattr(lever_sho, name)) / _STEP for m in moved], -1)
            through = np.sqrt(np.einsum("ni,nij,nj->n", gradient, covariance, gradient))
            if name in at_pole:         # the pole's through the contact's covariance, as the oscillator's
                value, shifted = at_pole[name]
                gradient = np.stack([(m - value) / _STEP for m in shifted], -1)
                through[pole] = np.sqrt(np.einsum("ni,nij,nj->n", gradient, covariance[pole], gradient))
            # the oscillator's through the measured signals where the lever fails, as one pixel's, narrowed as k1 is
            spreads[name] = np.where(np.isfinite(through) & (lever_sho.determined | pole), through,
                                     getattr(spread, name) * np.where(fit.converged, pooled.narrowed, 1.0))
        # the drive: the signals over the lever's responses (their geometric mean), signed by its side of the axis
        t1, t2 = responses[0]
        drives = (s1 / t1, s2 / t2)
        d_eff = np.sqrt(np.abs(drives[0] * drives[1])) / drive_amplitude * \
            np.where(((drives[0] + drives[1]) * np.exp(-1j * axis)).real < 0, -1.0, 1.0)
        # log|d| = mean of log|s_j| (noise sigma**2 / 4, apart from the contact's rows) less mean log|T_j|
        gradient = np.stack([(np.log(np.abs(m1 * m2 / (t1 * t2))) / (2 * _STEP)) for m1, m2 in responses[1:]], -1)
        drive_sd = np.sqrt(0.25 + np.einsum("ni,nij,nj->n", gradient, covariance, gradient))
        height_k1, height_loss = _height_shares(lever, contact, f1, f2, k1, loss, tip_height_uncertainty)
        maps = {"contact_resonance": resonance, "contact_resonance_stderr": u * spreads["resonance"],
                "contact_quality_factor": quality, "contact_quality_factor_stderr": u * spreads["quality_factor"],
                "k1": k1, "k1_stderr": np.hypot(k1 * u * np.sqrt(covariance[:, 0, 0]), height_k1), "contact_loss": loss,
                "contact_loss_stderr": np.hypot(u * np.sqrt(covariance[:, 1, 1]), height_loss),
                "d_eff": d_eff, "d_eff_stderr": u * np.abs(d_eff) * drive_sd,
                "oscillator_k1": k1_pm, "oscillator_k1_error": k1_pm / k1 - 1,
                "oscillator_d_eff": d_pm, "oscillator_d_eff_error": d_pm / d_eff - 1,
                "real_drive": (pooled.real & fit.converged).astype(np.uint8),
                "determined": fit.converged.astype(np.uint8)}
    return {name: value.reshape(shape) for name, value in maps.items()}, sigma


def _height_shares(lever: Cantilever, contact: Contact, f1, f2, k1, loss, tip_height_uncertainty: float):
    """The tip height's shares in the standard errors of each pixel's ``k1`` (N/m) and ``contact_loss``: the
    ratio of its responses at its drives held, ``d(log k1, loss)/dH = -J^-1 d log(T2/T1)/dH`` (:func:`_linearised`'s
    Jacobian; the tip height's derivative by a forward difference), times ``tip_height_uncertainty`` (m); 0
    without a tip height or its uncertainty, or where the Jacobian is singular."""
    zero = np.zeros(len(f1))
    if not tip_height_uncertainty or lever.tip_height is None:
        return zero, zero
    h = _STEP * lever.tip_height
    ((g, _),) = _log_ratios(lever, contact, f1, f2, [(k1, loss)])
    ((g_h, _),) = _log_ratios(replace(lever, tip_height=lever.tip_height + h), contact, f1, f2, [(k1, loss)])
    _, jac = _linearised(lever, contact, f1, f2, g, k1, loss)
    moved = (g_h - g) / h
    with np.errstate(all="ignore"):
        slope = -np.einsum("...ij,...j->...i", _inverse(jac), np.stack([moved.real, moved.imag], -1))
        shares = np.abs(slope) * tip_height_uncertainty * np.stack([k1, np.ones_like(k1)], -1)
    shares = np.where(np.isfinite(shares), shares, 0.0)
    return shares[:, 0], shares[:, 1]


def write_dart(path: str, maps: dict, attrs: dict | None = None) -> None:
    """:func:`invert`'s maps into a new Zarr group at ``path`` (xarray's convention,
    :func:`pfmdyn.maps.store.write_maps`), units and long names from :mod:`pfmdyn.names`.

    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/maps.zarr"
    >>> write_dart(path, {"k1": np.ones((2, 2)), "k1_stderr": np.ones((2, 2)), "determined": np.ones((2, 2), np.uint8)})
    >>> from pfmdyn.maps.store import open_group
    >>> open_group(path)["k1_stderr"].attrs["long_name"]
    'standard uncertainty of k1'
    """
    described = {}
    for name, values in maps.items():
        base = name.removesuffix("_stderr")
        if name == "determined":
            unit, text = "1", "1 where the oscillator and the lever both determine the pixel, else 0"
        else:
            unit = NAMES[base].unit
            text = NAMES[base].meaning if base == name else f"standard uncertainty of {NAMES[base].label}"
        described[name] = (values, unit, text)
    write_maps(path, described, attrs)


def document(maps: dict, sigma: float, lever: dict, settings: dict, source: str, store: str, k2_policy: str,
             pool: int = POOL, phases: str = "phases as read") -> dict:
    """The JSON document of a DART image (:func:`pfmdyn.io.results.document`, kind ``dart``): the lever
    and the settings as records (``lever``, ``settings``: name -> ``(value, status[, why])``), the
    maps' medians over the determined pixels (each ``stderr`` the median pixel's), the noise, the
    pixel counts; the pooling radius (:func:`invert`) and how the phases were read (``phases``) in the notes.

    >>> maps = {"k1": np.array([[100.0, np.nan]]), "k1_stderr": np.array([[2.0, np.nan]]),
    ...         "determined": np.array([[1, 0]], np.uint8)}
    >>> doc = document(maps, 0.01, {"spring_constant": (2.0, "given")}, {}, "a.ibw", "o/maps.zarr", "k2 left out")
    >>> doc["results"]["k1"], doc["fit"]["determined_fraction"]["value"]
    ({'value': 100.0, 'stderr': 2.0, 'unit': 'N/m', 'status': 'derived'}, 0.5)
    """
    ok = maps["determined"].astype(bool)

    def median(name):       # of d_eff's magnitude: the domains' signs would cancel
        values = maps[name][ok] if name in maps else np.empty(0)
        values = np.abs(values) if "d_eff" in name else values
        values = values[np.isfinite(values)]
        return float(np.median(values)) if values.size else math.nan

    results = {name: quantity(name, median(name), median(name + "_stderr") if name + "_stderr" in maps else None,
                              status="derived", why=None if ok.any() else "no pixel determined")
               for name in (*MAPS, *OSCILLATOR_MAPS) if name in maps}
    as_records = lambda given: {name: quantity(name, entry[0], status=entry[1],       # noqa: E731
                                               why=entry[2] if len(entry) > 2 else None)
                                for name, entry in given.items()}
    fit = {"pixels": quantity("pixels", list(ok.shape), status="file", why="the image's shape", dims=["axis"]),
           "determined_fraction": quantity("determined_fraction", float(ok.mean()) if ok.size else math.nan,
                                           status="derived", why=None if ok.size else "an empty image"),
           "channel_noise": quantity("channel_noise", sigma, status="derived",
                                     why=None if math.isfinite(sigma) else "too few neighbouring pixels determined"),
           **as_records(settings)}
    pooling = (f"contact (k1, contact_loss, contact resonance and Q): each pixel's fitted to its and its alike "
               f"neighbours' signals within {pool} pixels" if pool > 0 else "contact: each pixel's alone")
    if "real_drive" in maps and ok.any():
        pooling += (f"; the drive real (its phases' sum fitted with the contact) at {maps['real_drive'][ok].mean():.1%} "
                    "of the determined pixels, the ratio's contact alone at the others (real_drive)")
    return envelope("map", "dart", {"path": source, "store": store}, as_records(lever), results, fit,
                    [k2_policy, pooling, phases, "results: medians over the determined pixels (of d_eff's magnitude: "
                     "its sign is in the map), each stderr the median pixel's"])
