"""Batched per-pixel fit of the elastic-contact beam response (:class:`pfmdyn.maps.beam.BeamMapModel`)
to band-excitation spectra.

The complex amplitudes of each band (and, with a bias axis, of each bias component) enter linearly
and are projected out (variable projection); ``k1``, ``Q``, ``k2``, ``g`` and ``x`` are fitted by
a Levenberg-Marquardt iteration that treats every pixel of a block at once, each pixel with its
own damping factor, started from the pixel's contact resonances
(:mod:`pfmdyn.maps.resonance_start`: an SHO per band, the springs by the stiffness inversion;
two or three design evaluations then finish it).  Pixels it cannot start, or whose fit stays
unexplained, at a bound or far above the block's gap (:data:`OUTLIER_GAP`), start from a grid of
shape functions over ``k1`` and ``Q`` (with k2 fitted, from three k2/k1), the lower cost kept.

Cost is dominated by the generated transfer function over ``(pixels, frequencies)``; one
*design evaluation* per iteration gives the transfer functions and their derivatives for the
whole block (:meth:`pfmdyn.maps.beam.BeamMapModel.design`), and the derivatives of the
projected residual follow from them in closed form (Golub and Pereyra 1973;
:mod:`pfmdyn.fitting.projection`, shared with ``pfmdyn discrepancy``).  The iteration and the covariance of all parameters, nonlinear and
amplitudes, are the batched engine's (:mod:`pfmdyn.fitting.batched`, shared with the SHO fit).
"""
from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np

from ..errors import UserError
from ..fitting.noise import GAP_LIMIT, gap, noise_sigmas
from ..fitting.parameters import bounds as parameter_bounds
from ..fitting.batched import amplitude_column, band_covariance, levenberg_marquardt
from . import bias as bias_axis
from .beam import BeamMapModel
from .resonance_start import resonance_start
from .outputs import ALWAYS, SCALED

__all__ = ["CHUNK", "OUTLIER_GAP", "fit_block", "fittable"]

CHUNK = 256
"""Pixels fitted together: large enough to make the per-call overhead negligible, small enough
for the ``(pixels, frequencies)`` temporaries to stay in cache (1024 at once is ~1.5x slower)."""


def _start(model, y, q0, k1_range):
    """Best (k1, Q) per pixel and k2/k1 of the grid (:func:`_grid`): ``log_k1``, ``log_q``
    ``(n_ratio, n)``, ``log_ratio`` ``(n_ratio,)``; k1 and Q refined by the vertex of the
    parabola through the best grid value and its neighbours on each axis."""
    log_k1, log_q, log_ratio, g = _grid(model.lever, model.contact, np.asarray(model.frequency_hz, float).tobytes(),
                                        q0, tuple(k1_range))
    n, m = y.shape[:2]
    # one matrix product over (pixel, bias component) rows: batched products of 1-row matrices are slow
    proj = sum(np.sum(np.abs(y[..., b].reshape(n * m, -1) @ g[:, b].conj().T).reshape(n, m, -1) ** 2, axis=1)
               / np.sum(np.abs(g[:, b]) ** 2, axis=1) for b in model.bands)
    proj = proj.reshape(n, len(log_ratio), -1).transpose(1, 0, 2).reshape(-1, len(log_q), len(log_k1))
    iq, ik = np.unravel_index(np.argmax(proj.reshape(len(proj), -1), axis=1), proj.shape[1:])
    rows = np.arange(len(proj))
    return (_vertex(proj[rows, iq], ik, log_k1).reshape(-1, n), _vertex(proj[rows, :, ik], iq, log_q).reshape(-1, n),
            log_ratio)


@functools.lru_cache(maxsize=8)
def _grid(lever, contact, frequency_bytes, q0, k1_range):
    """Shape functions of the start grid, computed once per lever, contact policy, frequencies and
    range: log-spaced k1 over the part of ``k1_range`` that puts a resonance inside a band, Q over
    ``q0 / 16`` to ``4 q0`` (levers have Q 5-500), and, when k2 is fitted (two or more bands),
    k2/k1 of 0.1, 0.4 and 1 (the lateral spring moves the modes of stiff contacts: k2 = 0 starts
    them decades off); otherwise k2 follows the policy (``log_ratio`` NaN).

    A resonance moves by at most half the relative change of k1 (less on stiff contacts), and a
    sharp one correlates only with a start that places it within a few line widths: 48 steps over
    the four decades of the default range move it by up to 10 %, over the k1 whose resonance lies
    in the band by far less.
    """
    model = BeamMapModel(lever, np.frombuffer(frequency_bytes), contact=contact)
    free = model.k2_mode == "free"
    log_ratio = np.log10([0.1, 0.4, 1.0]) if free else np.array([np.nan])
    log_k1 = _resonant(model, np.log10(np.geomspace(*k1_range, 400)), q0, 10.0**log_ratio)
    log_q = np.log10(q0 * np.geomspace(1 / 16, 4, 7))
    ratio, q, k1 = (10.0**a.ravel() for a in np.meshgrid(log_ratio, log_q, log_k1, indexing="ij"))
    return log_k1, log_q, log_ratio, model.shape_functions(k1, q, k2=ratio * k1 if free else None)


def _resonant(model, log_k1, q0, ratios, count=48):
    """``count`` log-spaced k1 from four steps below the smallest to four above the largest of
    ``log_k1`` whose response peaks inside a band (not at its edges) for some k2/k1 of ``ratios``
    (NaN: k2 by the model's policy); all of ``log_k1``'s range when none does (a band away from
    every resonance)."""
    k1 = 10.0**np.tile(log_k1, len(ratios))
    k2 = None if np.isnan(ratios).all() else np.repeat(ratios, len(log_k1)) * k1
    g = np.abs(model.shape_functions(k1, np.full(k1.size, 4 * q0), k2=k2))
    inside = np.zeros(k1.size, bool)
    for b in model.bands:
        peak = np.argmax(g[:, b], axis=1)
        inside |= (peak > 0) & (peak < b.stop - b.start - 1)
    hit = np.flatnonzero(inside.reshape(len(ratios), -1).any(axis=0))
    if hit.size == 0:
        return np.linspace(log_k1[0], log_k1[-1], count)
    lo, hi = log_k1[max(hit[0] - 4, 0)], log_k1[min(hit[-1] + 4, len(log_k1) - 1)]
    return np.linspace(lo, hi, count)


def _vertex(values, best, axis):
    """Abscissa of the parabola's vertex through ``values[best - 1 : best + 2]`` on an evenly
    spaced ``axis`` (the grid value itself at an edge or without curvature)."""
    inner = np.clip(best, 1, len(axis) - 2)
    rows = np.arange(len(values))
    lo, mid, hi = (values[rows, inner + d] for d in (-1, 0, 1))
    curvature = lo - 2 * mid + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where((best == inner) & (curvature < 0), 0.5 * (lo - hi) / curvature, 0.0)
    return axis[best] + np.clip(shift, -0.5, 0.5) * (axis[1] - axis[0])


def _initial(model, y, q0, k1_range, iterations, tolerance, short_road=True):
    """Starting parameters and where they came from the contact resonances
    (:mod:`pfmdyn.maps.resonance_start`, with ``short_road``); the other pixels start from the
    (k1, Q) grid (with two or more bands, the lowest of the fits started at each k2/k1 of the
    grid).  With extra damping mechanisms, the fitted baseline with the extras switched off
    (nested, so the fit never ends worse than the baseline)."""
    if model.mechanisms != ("internal",):
        base = replace(model, mechanisms=("internal",))
        p_base, short = _initial(base, y, q0, k1_range, iterations, tolerance, short_road)
        p_base = levenberg_marquardt(base, y, p_base, parameter_bounds(base.parameters), iterations, tolerance)[0]
        return np.stack([p_base[:, base.names.index(p.name)] if p.name in base.names else np.full(len(y), p.null)
                         for p in model.parameters], axis=1), short
    if short_road:
        p, short = resonance_start(model, y, iterations=iterations, tolerance=tolerance)
    else:
        p, short = np.empty((len(y), len(model.names))), np.zeros(len(y), bool)
    if not short.all():
        p[~short] = _grid_initial(model, y[~short], q0, k1_range, iterations, tolerance)
    return p, short


def _grid_initial(model, y, q0, k1_range, iterations, tolerance):
    """Starts from the (k1, Q) grid (:func:`_start`); with k2 fitted, the best of the fits
    started at each k2/k1 of the grid."""
    log_k1, log_q, log_ratio = _start(model, y, q0, k1_range)
    start = {"k1": log_k1, "q": log_q, "k2": log_k1 + log_ratio[:, None]}
    p = np.stack([start[n] for n in model.names], axis=2)          # (n_ratio, n, n_p)
    if len(p) == 1:
        return p[0]
    # k1 and k2 trade off against each other: one start per k2/k1, the fit that ends lowest wins
    p, *_, cost, _, _ = levenberg_marquardt(model, np.concatenate([y] * len(p)), p.reshape(-1, p.shape[2]),
                                             parameter_bounds(model.parameters), iterations, tolerance)
    best = np.argmin(cost.reshape(-1, len(y)), axis=0)
    return p.reshape(-1, len(y), p.shape[1])[best, np.arange(len(y))]


OUTLIER_GAP = 1.5
"""A pixel started from its resonances whose fit ends unexplained, at a bound, or with a gap above
this many times the block's median is fitted again from the grid, the lower cost kept: a resonance
the SHO misread (a weak mode beside an antiresonance) can start the fit in a minimum that almost
explains the data (gaps of 1.6-2 where the block's are ~0.95, the largest of the right fits 1.3)."""


def fit_block(model: BeamMapModel, response, *, q0=100.0, k1_range=None, iterations=40,
              gap_threshold=GAP_LIMIT, tolerance=1e-3, surface_potential_v=None) -> dict[str, np.ndarray]:
    """Fit every pixel of ``response``, :data:`CHUNK` pixels at once.

    ``response`` is complex, ``(..., n_freq)``, or ``(..., n_bias, n_freq)`` when the model has
    biases.  Returns the arrays of :attr:`BeamMapModel.outputs`, each of the pixel shape
    ``response.shape[:-1]`` (``[:-2]`` with biases), plus ``cost`` (the squared relative
    residual).  ``gap`` is the noise-normalised RMS residual (:mod:`pfmdyn.fitting.noise`); a pixel
    is ``explained`` below ``gap_threshold`` (2: a misfit the noise does not explain is above).  A pixel stops when the predicted decrease of its cost is below ``tolerance``
    times the noise variance (the step is then ~``sqrt(tolerance)`` standard errors).
    ``surface_potential_v`` (V) places ``d_eff`` (``amplitude``, ``phase``) on the response-bias
    line (None: the fitted ``V_surf`` with ``+distributed``, else 0).  A pixel whose spectra hold
    NaN or inf, or are all zero, is masked: NaN in every map, ``explained`` 0.  k1, k2 and Q are fitted
    as logarithms: their standard errors are half the width of ``exp(log x +- sd)``,
    ``x sinh(sd)`` (``x sd`` when small; huge, not small, when the data leave ``x`` undetermined,
    e.g. k2 driven to its bound on a soft contact).

    Examples
    --------
    >>> from pfmdyn import Cantilever
    >>> f = np.linspace(2.5e5, 4.5e5, 48)
    >>> m = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), f)
    >>> y = 3e-3 * m.shape_functions(np.array([300.0]), np.array([60.0]))
    >>> out = fit_block(m, y)
    >>> round(float(out["k1"][0]), 6), round(float(out["quality_factor"][0]), 6)
    (300.0, 60.0)

    With biases, the electrostatic slope and the nulling bias (here ``1e-3 (V - 2)``):

    >>> mb = replace(m, bias_v=np.array([-2.0, 0.0, 2.0]))
    >>> out = fit_block(mb, 1e-3 * (mb.bias_v[:, None] - 2.0) * m.shape_functions(np.array([300.0]), np.array([60.0])))
    >>> round(float(out["electrostatic"]), 9), round(float(out["nulling_bias"]), 9)
    (0.001, 2.0)

    A pixel with a NaN is masked, the others fitted:

    >>> y2 = np.concatenate([y, np.full_like(y, np.nan)])
    >>> out = fit_block(m, y2)
    >>> out["k1"].round(6).tolist(), out["explained"].tolist()
    ([300.0, nan], [1.0, 0.0])
    """
    bias = bias_axis.basis(model.bias_v)
    y = np.ascontiguousarray(response, complex)     # the sums' rounding follows the memory layout
    tail = (len(model.bias_v), len(model.frequency_hz)) if bias.has_bias else (len(model.frequency_hz),)
    if y.shape[-len(tail):] != tail:
        raise UserError(f"response has shape {y.shape}; its last axes must be {tail} (biases, frequencies)")
    shape = y.shape[:-len(tail)]
    y = y.reshape(-1, bias.q.shape[0], tail[-1])
    if k1_range:
        model = replace(model, k1_range=tuple(k1_range))
    k1_range = model.k1_span
    settings = (q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v)
    fitted = np.flatnonzero(fittable(y))
    out = {name: np.full(len(y), np.nan) for name in [*model.outputs, "cost"]}
    out["explained"][:] = 0.0
    for i in range(0, len(fitted), CHUNK):
        rows = fitted[i:i + CHUNK]
        for name, value in _fit_pixels(model, y[rows], *settings).items():
            out[name][rows] = value
    return {name: value.reshape(shape) for name, value in out.items()}


def fittable(spectra) -> np.ndarray:
    """Which pixels of ``spectra`` (pixels first) can be fitted: not those holding NaN or inf, nor
    those with no response at all (a dropped spectrum), which the fit masks.

    >>> fittable(np.array([[1.0, 2.0], [np.nan, 1.0], [0.0, 0.0]])).tolist()
    [True, False, False]
    """
    axes = tuple(range(1, np.ndim(spectra)))
    return np.all(np.isfinite(spectra), axis=axes) & np.any(spectra != 0, axis=axes)


def _fit_pixels(model, y, q0, k1_range, iterations, gap_threshold, tolerance, bias, surface_potential_v):
    scale = np.sqrt(np.sum(np.abs(y) ** 2, axis=(1, 2)))
    scale[scale == 0] = 1.0
    # the noise of each pixel's spectra as pfmdyn discrepancy estimates it (floored: noise-free data)
    sigma = noise_sigmas(model.frequency_hz, model.bias_v, y)
    count = y.shape[1] * y.shape[2]
    y, outside = bias_axis.project(y / scale[:, None, None], bias)
    names = model.names
    bounds = parameter_bounds(model.parameters)
    p, short = _initial(model, y, q0, k1_range, iterations, tolerance)
    solution = levenberg_marquardt(model, y, p, bounds, iterations, tolerance)
    gaps = gap((solution[4] + outside) * (scale / sigma) ** 2, count)
    typical = np.median(gaps[short]) if short.any() else np.inf
    retry = np.flatnonzero(short & ((gaps >= gap_threshold) | (gaps > OUTLIER_GAP * typical)
                                    | _at_bound(model, solution[0])))
    if retry.size:
        p = _initial(model, y[retry], q0, k1_range, iterations, tolerance, short_road=False)[0]
        again = levenberg_marquardt(model, y[retry], p, bounds, iterations, tolerance)
        better = again[4] < solution[4][retry]
        for whole, part in zip(solution[:6], again):
            whole[retry[better]] = part[better]
        solution[6][:, retry[better]] = again[6][:, better]         # the partials: pixels on their second axis
    p, c, _, _, cost, g, dg = solution
    cost = cost + outside
    dof = max(2 * bias.q.shape[0] * y.shape[2] - len(names) - 2 * c[0].size, 1)
    cov = band_covariance(model, g, dg, c, cost / dof)
    sd = {n: np.sqrt(np.abs(cov[:, i, i])) for i, n in enumerate(names)}
    col = {n: p[:, i] for i, n in enumerate(names)}
    # half the width of 10**(log10 x +- sd): see fit_block
    spread = {q.name: q.spread(col[q.name], sd[q.name]) / q.values(col[q.name]) for q in model.parameters if q.log}
    k1 = 10.0**col["k1"]
    k2 = model.k2_of(k1, col.get("k2"))
    k2_sd = k2 * spread["k2"] if "k2" in spread else (
        np.zeros(len(y)) if model.k2_mode == "fixed" else k2 * spread["k1"])
    gap_map = gap(cost * (scale / sigma) ** 2, count)
    at_bound = _at_bound(model, p)
    _, m, n_bands, K = c.shape
    first = np.concatenate([amplitude_column(len(names), q, 0, 0, n_bands, K) + np.arange(2 * K) for q in range(m)])
    band = model.bands[0]
    linear = bias_axis.linear_maps(c[:, :, 0], cov[:, first[:, None], first], bias, surface_potential_v,
                                   g[..., band])
    # the fit's error and an assumed k2 tie's share (as pfmdyn stiffness states it)
    k1_sd = np.hypot(k1 * spread["k1"], model.k1_policy_stderr(k1))
    out = {"k1": k1, "k1_stderr": k1_sd, "k2": k2, "k2_stderr": k2_sd,
           "quality_factor": 10.0**col["q"], "quality_factor_stderr": 10.0**col["q"] * spread["q"],
           "viscous_loss": col.get("g"), "viscous_loss_stderr": sd.get("g"),
           "contact_loss": col.get("x"), "contact_loss_stderr": sd.get("x"),
           "gap": gap_map, "at_bound": at_bound.astype(float),
           "explained": ((gap_map < gap_threshold) & ~at_bound).astype(float), "cost": cost}
    out.update({name: value * scale if name in SCALED else value for name, value in linear.items()})
    # a parameter at its bound is where the fit was stopped, not a measurement: report nothing there
    for name in out:
        if name not in ALWAYS and out[name] is not None:
            out[name] = np.where(at_bound, np.nan, out[name])
    return {name: out[name] for name in [*model.outputs, "cost"]}


def _at_bound(model, p):
    """Whether any parameter of ``p`` ``(n, n_p)`` sits at its bound, per pixel."""
    return np.any([q.at_bound(p[:, i]) for i, q in enumerate(model.parameters)], axis=0)
