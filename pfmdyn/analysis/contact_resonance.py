"""Contact resonances of the whole lever model, and the contact stiffness that explains them.

The model is the composed characteristic (:mod:`pfmdyn.composed`: tip at
``x_tip = gamma L``, tip mass, springs ``k1``, ``k2`` rotated by the tilt through
``generated/tilt_rotation.py``), evaluated in one place, :func:`characteristic`.  Four facts
make the inverse problem exact and checkable:

1. **Frequency to beta.**  A resonance ``f`` of a lever whose measured free resonance (with
   its tip) is ``f1`` has ``beta = beta_1 sqrt(f / f1)``, ``beta_1`` the first free root of
   that lever (:meth:`pfmdyn.Cantilever.free_root`; it depends on the tip position when the
   tip has mass).
2. **Polynomial in the springs.**  The rotated springs are linear in ``(k1, k2)`` and the
   characteristic holds them linearly and through ``kvv kll - kvl**2 = k1 k2`` only: at a
   fixed ``beta`` and tip position it is bilinear in ``(k1, k2)``.  With ``k2`` given or tied,
   ``k2 = r k1`` (:class:`pfmdyn.Contact`), it is a polynomial in ``k1`` of degree 1 or 2, so at most
   two ``k1`` put a resonance at a measured frequency, found in closed form
   (:func:`k1_at`); two modes at a known tip position give ``(k1, k2)`` from a quadratic
   (:func:`k1_k2_at`).
3. **Mode numbers.**  A ``beta`` is mode ``n`` of a lever when ``n - 1`` roots of the
   characteristic lie below it (sign changes on a grid of step :data:`GRID_STEP` from
   :data:`BETA_MIN`: the characteristic is entire, its roots simple and about ``pi`` apart).
   Of the candidates of 2. exactly those with the measured mode numbers are kept.
4. **Tip position.**  At each tip position ``gamma`` each mode alone gives ``k1(gamma)``
   exactly (2. and 3.); two modes are explained where their curves cross.  Scanning
   ``gamma`` over a box and counting the crossings at two resolutions
   (:func:`pfmdyn.analysis.tip_position.tip_position_scan`) shows whether the solution is
   unique there (the L1/L method of Rabe et al., NIST).

Solutions are polished by least squares on all modes (:func:`fit`), residuals being the
shift in ``beta`` to the nearest root, and their covariance follows by first-order
propagation of the frequency and spring-constant uncertainties (:func:`covariance`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..cantilever import Cantilever, Contact
from ..errors import UserError
from .. import composed
from ..generated import formulas
from ..generated.tilt_rotation import rotated
from ..roots.bracket import refine

__all__ = ["GRID_STEP", "BETA_MIN", "characteristic", "betas", "mode_numbers", "k1_candidates", "k1_at",
           "k1_k2_at", "branch_limits", "spring_parts", "beta_shifts", "fit", "SOURCES", "RESOLUTION", "covariance_by_source", "covariance",
           "require_tip_height"]

GRID_STEP = 0.02
"""Grid step in ``beta`` for counting roots: far below their spacing (about pi)."""
BETA_MIN = 0.3
"""Lowest ``beta`` searched (the generated characteristic's domain, ``Re beta > 0.3``)."""
_STEP = 1e-30          # complex step: exact first derivatives in beta
_STIFF = 1e12          # k1 / k of the stiff (k1 -> oo) limit


def characteristic(beta, lever: Cantilever, k1, k2, tip_position):
    """The composed characteristic (zeros in ``beta``: the resonances) for springs ``k1``, ``k2``.

    The one call of the composed characteristic in the stiffness code:
    springs rotated by the lever's tilt, its tip height, length, tip mass and rotary inertia
    (``rho_g``); broadcast over ``beta``, ``k1``, ``k2`` and ``tip_position``.

    >>> lever = Cantilever(2.0, 7e4, 2e-4)
    >>> abs(float(characteristic(1.8751040687119611, lever, 0.0, 0.0, 1.0))) < 1e-12
    True
    """
    kvv, kll, kvl = rotated(k1, k2, lever.alpha)
    # the free lever's parameters (its tip height, the tip's mass and inertia), the springs and tip here
    parameters = lever.model_parameters(None)._replace(kvv=kvv, kll=kll, kvl=kvl, gamma=tip_position)
    with np.errstate(all="ignore"):
        return composed.characteristic(beta, parameters)


def _free_root(lever: Cantilever, tip_position: float) -> float:
    return lever.free_root() if tip_position == lever.tip_position else \
        replace(lever, tip_position=float(tip_position)).free_root()


def betas(lever: Cantilever, frequency, tip_position=None) -> np.ndarray:
    """``beta = beta_1 sqrt(f / f1)`` of frequencies ``f`` (Hz) with the tip at ``tip_position`` (``f1`` in
    vacuum; in a medium, times ``(1 + Re load)**(1/4)``, its added mass).

    >>> round(float(betas(Cantilever(2.0, 7e4, 2e-4), 4 * 7e4)), 10)
    3.7502081374
    """
    gamma = lever.tip_position if tip_position is None else tip_position
    if np.ndim(gamma):
        b1 = np.array([_free_root(lever, float(g)) for g in np.ravel(gamma)]).reshape(np.shape(gamma))
    else:
        b1 = _free_root(lever, float(gamma))
    f = np.asarray(frequency, dtype=float)
    beta = formulas.beta_from_frequency(f, lever.vacuum_resonance, b1)
    # in a medium, its added mass at each frequency (an undamped inversion takes no loss)
    return beta if lever.medium is None else beta * (1.0 + np.real(lever.fluid_load(f))) ** 0.25


def mode_numbers(beta, lever: Cantilever, k1, k2, tip_position) -> np.ndarray:
    """The mode number of each ``beta`` (1 + roots below it), broadcast over all arguments.

    >>> lever = Cantilever(2.0, 7e4, 2e-4)
    >>> mode_numbers([1.87510406871, 4.69409113297], lever, 0.0, 0.0, 1.0).tolist()
    [1, 2]
    """
    beta, k1, k2, gamma = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (beta, k1, k2, tip_position)))
    top = np.where(np.isfinite(beta), beta, BETA_MIN) * (1 - 1e-9)
    count = max(2, int(np.ceil((np.max(top, initial=BETA_MIN) - BETA_MIN) / GRID_STEP)) + 1)
    t = np.linspace(0.0, 1.0, count).reshape((count,) + (1,) * beta.ndim)
    grid = BETA_MIN + t * np.maximum(top - BETA_MIN, 0.0)
    values = characteristic(grid, lever, k1, k2, gamma)
    modes = 1 + np.sum(np.sign(values[:-1]) * np.sign(values[1:]) < 0, axis=0)
    return np.where(np.isfinite(beta), modes, 0)


def _polish(g, x, iterations: int = 6):
    """Newton steps on ``g`` (entire in ``x``, complex-step slope) from the closed-form roots ``x``."""
    x = np.asarray(x, dtype=float)
    scale = np.maximum(np.abs(x), 1e-300)
    for _ in range(iterations):
        h = 1e-20 * scale
        with np.errstate(all="ignore"):
            value = g(x + 1j * h)
            step = value.real / (value.imag / h)
        good = np.isfinite(step) & (np.abs(step) < 0.5 * scale)
        x = np.where(good, x - step, x)
    return x


def _degree(contact: Contact) -> int:
    """Degree of the characteristic in ``k1`` (module, fact 2): 2 when ``k2`` is tied to ``k1``."""
    return 2 if contact.ratio else 1


def k1_candidates(f, scale: float, degree: int) -> list[np.ndarray]:
    """The ``k1`` zeroing ``f(k1) = c0 + c1 k1 (+ c2 k1**2)``, a characteristic along a contact's
    path (module, fact 2), from ``f`` at ``k1 = 0, scale`` (and ``1e4 scale``); NaN where complex.

    The one inversion of the stiffness code: the whole lever's (:func:`k1_at`) and the paper's
    lever's in closed form, per pixel of a map (:mod:`pfmdyn.analysis.stiffness`).  The roots are
    analytic in ``f``'s other arguments: at ``beta + i h`` their imaginary parts are ``h`` times
    their slopes (complex step).

    >>> f = lambda k1: 6.0 - 5.0 * k1 + k1**2
    >>> sorted(float(r.real) for r in k1_candidates(f, 1.0, 2))
    [2.0, 3.0]
    """
    f0, fs = f(0.0), f(scale)
    with np.errstate(all="ignore"):
        if degree == 1:
            return [-f0 * scale / (fs - f0)]
        big = 1e4 * scale
        slope_s, slope_big = (fs - f0) / scale, (f(big) - f0) / big
        c2 = (slope_big - slope_s) / (big - scale)
        c1 = slope_s - c2 * scale
        root = np.sqrt(c1 * c1 - 4 * c2 * f0 + 0j)
        return [np.where(np.abs(r.imag) <= 1e-9 * np.abs(r), r, np.nan)
                for r in ((-c1 + root) / (2 * c2), (-c1 - root) / (2 * c2))]


def k1_at(beta, mode, lever: Cantilever, contact: Contact, tip_position) -> np.ndarray:
    """The ``k1`` (N/m) making ``beta`` resonance ``mode``; NaN where none does (vectorised).

    The characteristic at ``beta`` is a polynomial of degree :func:`_degree` in ``k1``
    (module, fact 2): its real positive roots (:func:`k1_candidates`) are polished by Newton
    steps on the characteristic itself, and the root whose ``beta`` is mode ``mode`` is kept (fact 3).

    >>> lever = Cantilever(2.0, 75e3, 2e-4)
    >>> round(float(k1_at(betas(lever, 300e3), 1, lever, Contact(), 1.0)), 4)   # the paper's model
    109.7483
    """
    beta, gamma = np.broadcast_arrays(np.asarray(beta, dtype=float), np.asarray(tip_position, dtype=float))
    f = lambda k1: characteristic(beta, lever, k1, contact.k2_of(k1), gamma)    # noqa: E731
    candidates = [c.real for c in k1_candidates(f, lever.spring_constant, _degree(contact))]
    out = np.full(beta.shape, np.nan)
    for candidate in candidates:
        candidate = np.where(np.isfinite(candidate) & (candidate > 0), candidate, np.nan)
        if not np.isfinite(candidate).any():
            continue
        candidate = _polish(f, candidate)
        ok = np.isfinite(candidate) & (candidate > 0)
        ok &= mode_numbers(beta, lever, np.where(ok, candidate, 0.0), contact.k2_of(np.where(ok, candidate, 0.0)),
                           gamma) == mode
        out = np.where(ok & np.isnan(out), candidate, out)
    return out


def branch_limits(mode: int, lever: Cantilever, contact: Contact, tip_position: float) -> tuple[float, float]:
    """``beta`` of resonance ``mode`` at ``k1 = 0`` and ``k1 -> oo`` (``k1 = 1e12 k``).

    Every resonance is nondecreasing in ``k1`` (the contact springs add a positive
    semi-definite stiffness), so a resonance of this mode lies between the two.

    >>> [round(b, 4) for b in branch_limits(1, Cantilever(2.0, 7e4, 2e-4), Contact(), 1.0)]
    [1.8751, 3.9266]
    """
    out = []
    for k1 in (0.0, _STIFF * lever.spring_constant):
        f = lambda b: characteristic(b, lever, k1, contact.k2_of(k1), tip_position)   # noqa: E731
        top = BETA_MIN + 6.0 * (mode + 1)         # above any branch limit of a lever tipped at >= 0.5 L
        grid = np.arange(BETA_MIN, top, GRID_STEP)
        values = f(grid)
        change = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)
        if len(change) < mode:
            out.append(float("nan"))
            continue
        i = change[mode - 1]
        out.append(float(refine(f, grid[i], grid[i + 1], values[i], values[i + 1], rtol=1e-14)))
    return out[0], out[1]


def spring_parts(beta, lever: Cantilever, tip_position, scale_k1: float, scale_k2: float):
    """``(P, Q, R, S)`` of the characteristic ``F = P + k1 Q + k2 R + k1 k2 S`` at ``beta``
    (module, fact 2), from ``F`` at ``k1 = 0, scale_k1`` and ``k2 = 0, scale_k2``.

    >>> p, q, r, s = spring_parts(3.0, Cantilever(2.0, 7e4, 2e-4), 1.0, 2.0, 1.0)
    >>> round(float(-p / q), 4)        # k1 (N/m) making beta = 3 a resonance, k2 = 0
    14.2352
    """
    f = lambda k1, k2: characteristic(beta, lever, k1, k2, tip_position)     # noqa: E731
    p = f(0.0, 0.0)
    q = (f(scale_k1, 0.0) - p) / scale_k1
    r = (f(0.0, scale_k2) - p) / scale_k2
    s = (f(scale_k1, scale_k2) - p - q * scale_k1 - r * scale_k2) / (scale_k1 * scale_k2)
    return p, q, r, s


def k1_k2_at(beta_pair, mode_pair, lever: Cantilever, tip_position: float) -> list[tuple[float, float]]:
    """Every ``(k1, k2)`` (N/m, ``k1 > 0``, ``k2 >= 0``) making two ``beta`` resonances of the given modes.

    Eliminating ``k2`` from the two bilinear equations leaves a quadratic in ``k1``; its
    roots, polished with :func:`fit` and kept when the mode numbers match, are all the
    solutions.  Needs the lever's tip height (``k2`` acts through ``H``).

    >>> from pfmdyn.roots.bracket import grid_roots
    >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5)
    >>> b = grid_roots(lambda x: characteristic(x, lever, 100.0, 50.0, 1.0), np.arange(1, 9, 0.01))[:2]
    >>> [(round(k1, 6), round(k2, 6)) for k1, k2 in k1_k2_at(b, (1, 2), lever, 1.0)]
    [(100.0, 50.0)]
    """
    k, H = lever.spring_constant, lever.tip_height
    scale_k2 = formulas.k2_from_ratio(1.0, k, H, lever.length)     # k2 H**2/(k L**2) = 1
    (p1, q1, r1, s1), (p2, q2, r2, s2) = (spring_parts(b, lever, tip_position, k, scale_k2) for b in beta_pair)
    coefficients = [q2 * s1 - s2 * q1, p2 * s1 + q2 * r1 - r2 * q1 - s2 * p1, p2 * r1 - r2 * p1]
    out = []
    with np.errstate(all="ignore"):
        roots = np.roots(coefficients) if np.all(np.isfinite(coefficients)) else []
    for a in roots:
        if abs(a.imag) > 1e-9 * abs(a) or a.real <= 0:
            continue
        k1 = float(a.real)
        k2 = float(-(p1 + k1 * q1) / (r1 + k1 * s1))
        if not np.isfinite(k2) or k2 < -1e-9 * max(scale_k2, k1):
            continue
        out.append((k1, max(k2, 0.0)))
    return out


def beta_shifts(lever: Cantilever, contact: Contact, contact_hz, values: dict) -> np.ndarray:
    """Shift in ``beta`` from each measured resonance to the nearest root of the model (a Newton step).

    >>> beta_shifts(Cantilever(2.0, 75e3, 2e-4), Contact(), [300e3], {"k1": 100.0}).round(6)   # k1 too soft
    array([-0.017213])
    """
    gamma = values.get("tip_position", lever.tip_position)
    k1 = values["k1"]
    k2 = values["k2"] if "k2" in values else contact.k2_of(k1)
    b = betas(lever, contact_hz, gamma)
    value = characteristic(b + 1j * _STEP * b, lever, k1, k2, gamma)
    return -value.real / (value.imag / (_STEP * b))


_BOUNDS = {"k1": (0.0, np.inf), "k2": (0.0, np.inf), "tip_position": (0.05, 1.0)}


def fit(lever: Cantilever, contact: Contact, contact_hz, start: dict) -> tuple[dict, float]:
    """Least-squares polish of ``start`` (names -> values) on all resonances; the RMS ``beta`` shift.

    >>> lever = Cantilever(2.0, 75e3, 2e-4)
    >>> values, rms = fit(lever, Contact(), [300e3], {"k1": 109.7})
    >>> round(values["k1"], 4), rms < 1e-12
    (109.7483, True)
    """
    from scipy.optimize import least_squares

    names = list(start)
    scale = np.array([max(abs(start[n]), 1e-3 * lever.spring_constant if n != "tip_position" else 0.1)
                      for n in names])
    low = np.array([_BOUNDS[n][0] for n in names]) / scale
    high = np.array([_BOUNDS[n][1] for n in names]) / scale
    x0 = np.clip(np.array([start[n] for n in names]) / scale, low, high)

    def residual(x):
        return beta_shifts(lever, contact, contact_hz, dict(zip(names, x * scale)))
    with np.errstate(all="ignore"):
        sol = least_squares(residual, x0, bounds=(low, high), xtol=1e-15, ftol=1e-15, gtol=1e-15, method="trf")
    values = {n: float(v) for n, v in zip(names, sol.x * scale)}
    return values, float(np.sqrt(np.mean(sol.fun ** 2)))


SOURCES = ("contact_uncertainty", "free_resonance_uncertainty", "spring_constant_uncertainty",
           "tip_height_uncertainty", "k2_policy_uncertainty")
"""The inputs whose standard uncertainties :func:`covariance_by_source` propagates: the contact
resonances (Hz, each), the free resonance (Hz), the spring constant (N/m), the tip height (m) and the
ratio ``k2/k1`` of a tied contact."""


RESOLUTION = 1e-8
"""Smallest relative sensitivity (d ln value / d ln input) that :func:`covariance_by_source` resolves: its
central differences (relative step 1e-6) of Newton steps exact to ~1e-15 carry ~1e-9 of noise; a smaller one
is taken as none (k1 of a (k1, k2) pair does not move with the tip height, which only rescales k2)."""


def covariance_by_source(lever: Cantilever, contact: Contact, contact_hz, values: dict, stderrs: dict) -> dict:
    """First-order covariance of ``values`` (their order) contributed by each input of :data:`SOURCES`
    whose standard uncertainty ``stderrs`` gives (missing or 0: none; the contact resonances' one for all or
    one per resonance).

    The residuals vanish (or are least squares) at the solution; by the implicit-function
    theorem ``d values / d data = -pinv(J_values) J_data``, both Jacobians by central
    differences of the residuals (relative step 1e-6).  The tip height acts only with a tip
    height, the tie only when ``k2`` is tied to ``k1``.

    >>> lever = Cantilever(2.0, 75e3, 2e-4, tip_height=10e-6)
    >>> parts = covariance_by_source(lever, Contact(poisson=0.3), [300e3], {"k1": 115.0},
    ...     {"contact_uncertainty": 100.0, "tip_height_uncertainty": 1e-6, "k2_policy_uncertainty": 0.035})
    >>> sorted(parts), all(float(c[0, 0]) > 0 for c in parts.values())
    (['contact_uncertainty', 'k2_policy_uncertainty', 'tip_height_uncertainty'], True)
    """
    names = list(values)
    fc = np.asarray(contact_hz, dtype=float)
    ratio = contact.ratio if contact.k2 is None else None
    sigma = {"contact_uncertainty": np.broadcast_to(np.asarray(stderrs.get("contact_uncertainty") or 0.0, dtype=float),
                                                    fc.shape)}
    for name in SOURCES[1:]:
        acts = {"tip_height_uncertainty": lever.tip_height is not None,
                "k2_policy_uncertainty": ratio is not None and "k2" not in values}.get(name, True)
        sigma[name] = np.array([float(stderrs.get(name) or 0.0) if acts else 0.0])
    d0 = np.concatenate([fc, [lever.free_resonance, lever.spring_constant, lever.tip_height or 0.0, ratio or 0.0]])

    def residual(p, data):
        lv = replace(lever, free_resonance=data[-4], spring_constant=data[-3],
                     tip_height=data[-2] if lever.tip_height is not None else None)
        tie = Contact(k2_over_k1=data[-1]) if ratio is not None else contact
        return beta_shifts(lv, tie, data[:-4], dict(zip(names, p)))

    p0 = np.array([values[n] for n in names])

    def jacobian(fun, x0, columns, limited=()):
        cols = []
        for i in columns:
            h = 1e-6 * max(abs(x0[i]), 1e-12)
            up, down = x0.copy(), x0.copy()
            up[i] += h
            down[i] -= h
            if i in limited and up[i] > 1.0:        # a tip position at the free end: one-sided
                cols.append((fun(x0) - fun(down)) / h)
            else:
                cols.append((fun(up) - fun(down)) / (2 * h))
        return np.column_stack(cols)

    at_end = tuple(i for i, n in enumerate(names) if n == "tip_position")
    spans = dict(zip(sigma, (range(len(fc)),) + tuple(range(len(fc) + i, len(fc) + i + 1) for i in range(4))))
    scale = np.where(p0 != 0, np.abs(p0), 1e-3 * lever.spring_constant)
    out = {}
    with np.errstate(all="ignore"):
        inverse = np.linalg.pinv(jacobian(lambda p: residual(p, d0), p0, range(len(p0)), at_end))
        for name, s in sigma.items():
            if np.any(s > 0):
                span = list(spans[name])
                sensitivity = -inverse @ jacobian(lambda d: residual(p0, d), d0, span)
                # an elasticity below the differences' resolution is no dependence (a tiny stderr is noise)
                elasticity = sensitivity * np.abs(d0[span]) / scale[:, None]
                sensitivity = np.where(np.abs(elasticity) < RESOLUTION, 0.0, sensitivity)
                out[name] = (sensitivity * s**2) @ sensitivity.T
    return out


def covariance(lever: Cantilever, contact: Contact, contact_hz, values: dict, contact_stderr: float = 0.0,
               free_stderr: float = 0.0, spring_constant_stderr: float = 0.0) -> np.ndarray:
    """First-order covariance of ``values`` (their order) from the frequencies' and the spring
    constant's standard uncertainties (:func:`covariance_by_source`, summed).

    >>> cov = covariance(Cantilever(2.0, 75e3, 2e-4), Contact(), [300e3], {"k1": 109.7483}, contact_stderr=100.0)
    >>> round(float(np.sqrt(cov[0, 0])), 3)   # N/m
    0.393
    """
    parts = covariance_by_source(lever, contact, contact_hz, values, {
        "contact_uncertainty": contact_stderr, "free_resonance_uncertainty": free_stderr,
        "spring_constant_uncertainty": spring_constant_stderr})
    return sum(parts.values(), np.zeros((len(values), len(values))))


def require_tip_height(lever: Cantilever, why: str) -> None:
    """A one-line error when ``why`` needs the tip height and the lever has none.

    >>> require_tip_height(Cantilever(2.0, 7e4, 2e-4), "a tilt")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: a tilt needs the tip height (with the lever length)
    """
    if lever.tip_height is None:
        raise UserError(f"{why} needs the tip height (with the lever length)", quantity="tip_height")
