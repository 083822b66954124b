"""Starts of the beam fit from the contact resonances (the short road): an SHO per band, then the
springs that put the lever's resonances there.

A band around a contact resonance looks like a simple harmonic oscillator; its SHO fit
(:func:`pfmdyn.maps.sho.fit_spectra`) gives the resonance ``f0`` and ``Q`` per pixel.  At
``beta`` of ``f0`` (:func:`pfmdyn.analysis.contact_resonance.betas`) the lever's
characteristic is a polynomial in the springs (:mod:`pfmdyn.analysis.contact_resonance`, fact
2), so the springs follow in closed form through the stiffness code's one inversion
(:func:`pfmdyn.analysis.contact_resonance.k1_candidates`):

* ``k2`` given or tied to ``k1`` (one band, or a stated tie): ``k1`` from each band, a
  polynomial of degree 1 or 2;
* ``k2`` fitted (two or more bands): ``(k1, k2)`` from the first two bands, the bilinear pair
  with ``k2`` eliminated, a quadratic in ``k1``.

Where several candidates remain (roots of other modes, other bands) the one whose response
fits the pixel best wins (one response evaluation per candidate, for those pixels only).  A
beam's resonance is an SHO only near its peak (the other modes add a background), so the start
is close, not exact: the Levenberg-Marquardt of :mod:`pfmdyn.maps.fit` finishes it in a few
steps instead of searching a grid of starts.  Pixels with no candidate (no resonance inside a
band, a resonance no spring explains) are not started here (``ok`` False).
"""
from __future__ import annotations

import numpy as np

from ..analysis.contact_resonance import betas, characteristic, k1_candidates, spring_parts
from ..fitting.batched import project_bands
from ..fitting.parameters import bounds as parameter_bounds
from ..generated import formulas
from .sho import fit_spectra

__all__ = ["resonance_start"]

_STEP = 1e-30      # complex step: exact first derivatives


def resonance_start(model, y, *, iterations=40, tolerance=1e-3):
    """Internal parameters ``(n, n_p)`` (``k1``, ``q``, ``k2`` when fitted, as :attr:`model.names`
    order them; the model's baseline ``("internal",)`` only) of the pixels ``y`` ``(n, m, n_freq)``,
    and ``ok`` ``(n,)``: where a start was found (elsewhere the row is NaN).

    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.maps.beam import BeamMapModel
    >>> m = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), np.linspace(2.5e5, 4.5e5, 64))
    >>> y = m.shape_functions(np.array([300.0, 1e6]), np.array([60.0, 60.0]))[:, None]
    >>> p, ok = resonance_start(m, y)
    >>> ok.tolist(), (10.0 ** p[0]).round(0).tolist()     # near (300, 60); none in the band at 1e6 N/m
    ([True, False], [302.0, 60.0])
    """
    lever, f = model.lever, np.asarray(model.frequency_hz, float)
    n = len(y)
    # the bias component carrying most of the response (the intercept on most pixels)
    strongest = np.argmax(np.sum(np.abs(y) ** 2, axis=2), axis=1)
    spectra = y[np.arange(n), strongest]
    beta, q_mode = [], []
    for b in model.bands:
        sho = fit_spectra(f[b], spectra[:, b], iterations=iterations, tolerance=tolerance)
        f0 = sho["measured_resonance"]
        inside = (f0 > f[b][0]) & (f0 < f[b][-1])
        beta.append(np.where(inside, betas(lever, np.where(inside, f0, f[b][0])), np.nan))
        q_mode.append(sho["measured_quality_factor"])
    candidates = _free(model, beta) if model.k2_mode == "free" else _tied(model, beta)
    lower, upper = parameter_bounds(model.parameters)
    with np.errstate(all="ignore"):
        p = np.stack([np.stack([np.log10(k1), _log_q(lever, beta, q_mode, k1, k2)]
                               + ([np.log10(k2)] if model.k2_mode == "free" else []), axis=1)
                      for k1, k2 in candidates])                                # (n_candidates, n, n_p)
        valid = np.all(np.isfinite(p) & (p > lower) & (p < upper), axis=2)
    return _best(model, y, p, valid)


def _log_q(lever, beta, q_mode, k1, k2):
    """log10 of the lever's ``Q`` from the modes' (mean over the bands with a resonance): internal
    friction damps the beam, not the contact springs, so a mode's loss is the lever's times the
    share of its strain energy in the beam, ``1 - d ln omega**2 / d ln s`` with both springs
    scaled by ``s`` (``omega**2 ~ beta**4``; the slopes of the characteristic by complex step)."""
    logs = np.full((len(beta), len(k1)), np.nan)
    for i, (b, q) in enumerate(zip(beta, q_mode)):
        at = np.flatnonzero(np.isfinite(b) & np.isfinite(k1) & np.isfinite(k2))
        if at.size == 0:
            continue
        b, q, s1, s2 = b[at], q[at], k1[at], k2[at]
        springs = characteristic(b, lever, s1 * (1 + 1j * _STEP), s2 * (1 + 1j * _STEP), lever.tip_position).imag
        slope = characteristic(b * (1 + 1j * _STEP), lever, s1, s2, lever.tip_position).imag
        logs[i, at] = np.log10(q * (1 + 4 * springs / slope))     # 1 - 4 (dF/d ln s) / (dF/d ln beta)
    found = np.isfinite(logs)
    return np.where(found.any(axis=0), np.sum(np.where(found, logs, 0.0), axis=0) / np.maximum(found.sum(axis=0), 1),
                    np.nan)


def _tied(model, beta):
    """``(k1, k2)`` candidates with ``k2`` by the model's policy, from each band's ``beta``."""
    degree = 1 if model.k2_mode == "fixed" or model.contact.tie() == 0 else 2
    return _along(model.lever, beta, model.k2_of, degree)


def _along(lever, beta, k2_of, degree, where=True):
    """``(k1, k2)`` candidates with ``k2 = k2_of(k1)`` (a polynomial of ``degree`` in ``k1``), from
    each band's ``beta`` at the pixels ``where`` that band found a resonance (NaN elsewhere)."""
    out = []
    for b in beta:
        at = np.flatnonzero(np.isfinite(b) & where)
        if at.size == 0:
            continue
        roots = k1_candidates(lambda k1: characteristic(b[at], lever, k1, k2_of(k1), lever.tip_position),
                              lever.spring_constant, degree)
        for root in roots:
            k1 = np.full(len(b), np.nan)
            k1[at] = np.real(root)
            out.append((k1, k2_of(k1)))
    return out


_RATIOS = np.geomspace(0.1, 1.0, 5)
"""k2/k1 tried along one band's resonance when the other band shows none."""


def _free(model, beta):
    """``(k1, k2)`` candidates making the first two bands' ``beta`` resonances: the bilinear
    characteristic ``P + k1 Q + k2 R + k1 k2 S`` of each, ``k2`` eliminated (a quadratic in ``k1``).
    Where one band's SHO found no resonance (a weak mode beside an antiresonance), the other's
    with k2/k1 of :data:`_RATIOS`."""
    lever = model.lever
    k = lever.spring_constant
    scale_k2 = formulas.k2_from_ratio(1.0, k, lever.tip_height or 0.0, lever.length)
    one, two = (np.where(np.isfinite(b), b, 1.0) for b in beta[:2])
    (p1, q1, r1, s1), (p2, q2, r2, s2) = (spring_parts(b, lever, lever.tip_position, k, scale_k2) for b in (one, two))
    found = np.isfinite(beta[0]) & np.isfinite(beta[1])
    out = []
    for k1 in k1_candidates(lambda a: (p2 * r1 - r2 * p1) + a * (p2 * s1 + q2 * r1 - r2 * q1 - s2 * p1)
                            + a * a * (q2 * s1 - s2 * q1), k, 2):
        k1 = np.where(found, np.real(k1), np.nan)
        with np.errstate(all="ignore"):
            k2 = -(p1 + k1 * q1) / (r1 + k1 * s1)
        out.append((k1, k2))
    for ratio in _RATIOS:
        out += _along(lever, beta[:2], lambda k1, r=ratio: r * k1, 2, where=~found)
    return out


def _best(model, y, p, valid):
    """Of the candidate starts ``p`` ``(n_candidates, n, n_p)``, per pixel the valid one whose
    response fits ``y`` best (the only valid one where there is one)."""
    count = valid.sum(axis=0)
    choice = np.argmax(valid, axis=0)
    several = np.flatnonzero(count > 1)
    if several.size:
        # one response evaluation for every (candidate, pixel) pair to compare
        candidate, pixel = np.nonzero(valid[:, several])
        g = model.design(p[candidate, several[pixel]], jacobian=False)[0]
        cost = np.full((len(p), several.size), np.inf)
        cost[candidate, pixel] = np.sum(project_bands(g, None, y[several[pixel]], model.bands)[1] ** 2, axis=1)
        choice[several] = np.argmin(cost, axis=0)
    ok = count > 0
    start = p[choice, np.arange(p.shape[1])]
    start[~ok] = np.nan
    return start, ok
