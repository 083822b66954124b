"""The undamped resonances of a discrepancy model: the real roots of the composed characteristic
(:func:`pfmdyn.composed.characteristic`) with the model's springs (contact modes) or without
(free modes), and their sensitivity to the model's parameters.

Frequencies follow ``f = f1 (beta / beta1)**2`` with ``f1`` the metadata's free resonance and
``beta1`` the first free root of the same model (:func:`pfmdyn.cantilever.free_root`).
"""
from __future__ import annotations

import numpy as np

from ..cantilever import free_root
from .. import composed
from ..generated import formulas
from ..generated.tilt_rotation import rotated
from ..roots.bracket import grid_roots
from .effects import spring_parameters
from .model import Model, characteristic_partials, free_root_and_jacobian

__all__ = ["characteristic_args", "resonance_sensitivity", "resonances", "resonances_many"]


_CHARACTERISTIC = ("k1", "k2", "alpha", "mu", "gamma")
"""The model's parameters :func:`characteristic_args` reads (the springs, the tilt, the tip's mass and position)."""


def resonances(model: Model, internal, contact: bool, f_max: float, refine_roots: bool = True) -> np.ndarray:
    """Undamped resonances (Hz) below ``f_max``: real zeros of the generated characteristic.

    Sign changes on a grid in ``beta`` bracket the roots (:func:`pfmdyn.roots.bracket.grid_roots`);
    the characteristic function is entire (no poles), so every sign change is a root.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> (resonances(Model(meta), [-9.0, -9.0], True, 7e4) / 1e4).round(4).tolist()   # 6.267:1
    [1.0, 6.2669]
    """
    c = model.coords(internal)
    m = model.meta
    # free_root's value, kept (a fit asks the same tip again, and for the sensitivity its partials)
    b1 = free_root_and_jacobian(m.spring_constant, m.tip_height, m.length, c["mu"], c["gamma"])[0]
    lever = characteristic_args(model, internal, contact)
    top = float(formulas.beta_from_frequency(f_max, m.free_resonance, b1))
    grid = np.linspace(0.3, top, max(150, int(12 * top)))
    if composed.KERNELS:       # the same steps compiled (one call, not one per iteration)
        from ..composed.kernels import characteristic_roots
        roots = characteristic_roots(grid, np.array([lever], float), refine_roots, 1e-13)
    else:
        roots = grid_roots(lambda b: composed.characteristic(b, lever), grid, refine_roots)
    return formulas.frequency_from_beta(roots, m.free_resonance, b1)


def resonances_many(model: Model, internals, contact: bool, f_max: float) -> list[np.ndarray]:
    """:func:`resonances` without refinement (roots linearly interpolated on the same grid)
    for many parameter vectors at once: one vectorised evaluation of the characteristic
    per distinct free root, for start grids.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> [(f / 1e4).round(3).tolist() for f in resonances_many(Model(meta), [[-9.0, -9.0]] * 2, True, 7e4)]
    [[1.0, 6.267], [1.0, 6.267]]
    """
    return _resonances_of(model.meta, _characteristic_args_many(model, np.asarray(internals, float), contact), f_max)


def _resonances_of(m, args: np.ndarray, f_max: float) -> list[np.ndarray]:
    """:func:`resonances_many` of the levers whose characteristic takes the rows of ``args`` (of
    :func:`_characteristic_args_many`), the lever's metadata ``m``."""
    if not len(args):
        return []
    # the free root depends on the tip alone: once per tip (a start grid's rows share one)
    tips, tip_of = np.unique(args[:, 6:8], axis=0, return_inverse=True)
    b1s = np.array([free_root(m.spring_constant, m.tip_height, m.length, mu, gamma) for mu, gamma in tips])[tip_of]
    out: list[np.ndarray] = [np.empty(0)] * len(args)
    for b1 in np.unique(b1s):
        rows = np.flatnonzero(b1s == b1)
        top = float(formulas.beta_from_frequency(f_max, m.free_resonance, b1))
        grid = np.linspace(0.3, top, max(150, int(12 * top)))
        with np.errstate(all="ignore"):
            levers = composed.Parameters(*(args[rows, j, None] for j in range(args.shape[1])))     # a column
            vals = composed.characteristic(grid, levers)
        row, idx = np.nonzero(np.sign(vals[:, :-1]) * np.sign(vals[:, 1:]) < 0)
        lo, hi, flo, fhi = grid[idx], grid[idx + 1], vals[row, idx], vals[row, idx + 1]
        with np.errstate(all="ignore"):
            roots = formulas.frequency_from_beta(hi - fhi * (hi - lo) / (fhi - flo), m.free_resonance, b1)
        ends = np.cumsum(np.bincount(row, minlength=len(rows))).tolist()
        for i, start, end in zip(rows, [0] + ends[:-1], ends):
            out[i] = roots[start:end]
    return out


def _characteristic_args_many(model: Model, internals: np.ndarray, contact: bool) -> np.ndarray:
    """:func:`characteristic_args` of each row of ``internals`` (rows x parameters); a start grid's
    rows, alike but for the springs, at once (the same numbers: the springs' coordinates one by one,
    their rotation elementwise).

    >>> from types import SimpleNamespace
    >>> model = Model(SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4), ("tilt",))
    >>> rows = np.array([[2.0, 1.0, 0.1], [2.5, 1.5, 0.1]])
    >>> bool((_characteristic_args_many(model, rows, True) == [characteristic_args(model, x, True) for x in rows]).all())
    True
    """
    springs = len(model.springs)
    if not contact or not len(internals) or np.any(internals[:, springs:] != internals[0, springs:]):
        return np.array([characteristic_args(model, x, contact) for x in internals], dtype=float)
    c = model.coords(internals[0])
    k1, k2 = ([p.value(v) for v in internals[:, j]] if j < springs else [c[p.name]] * len(internals)
              for j, p in enumerate(spring_parameters(model.meta, False)))
    kvv, kll, kvl = np.broadcast_arrays(*rotated(np.array(k1), np.array(k2), c["alpha"]))
    out = np.tile(np.array(characteristic_args(model, internals[0], contact), float), (len(internals), 1))
    out[:, 1], out[:, 2], out[:, 3] = kvv, kll, kvl
    return out


def characteristic_args(model: Model, internal, contact: bool) -> tuple:
    """Parameters of :func:`pfmdyn.composed.characteristic` for the model: ``(k, kvv, kll, kvl, H, L,
    mu, gamma, rho_g)``, the springs rotated by the tilt (zero for free modes).

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> [float(a) for a in characteristic_args(Model(meta), [2.0, 2.0], True)]
    [1.0, 100.0, 100.0, 0.0, 1e-05, 0.0001, 0.0, 1.0, 0.0]
    """
    c = model.coords(internal)
    m = model.meta
    kvv, kll, kvl = rotated(c["k1"], c["k2"], c["alpha"]) if contact else (0.0, 0.0, 0.0)
    return composed.Parameters(k=m.spring_constant, kvv=kvv, kll=kll, kvl=kvl, H=m.tip_height, L=m.length, mu=c["mu"],
                               gamma=c["gamma"], rho_g=0.0)


def resonance_sensitivity(model: Model, internal, contact: bool, frequency_hz) -> np.ndarray:
    """``d f_n / d internal_j`` (Hz) at undamped resonances ``frequency_hz`` of the model.

    Implicit differentiation of the characteristic ``F(beta_n; p) = 0``:
    ``d beta_n / dp = -F_p / F_beta``; ``f_n = f1 (beta_n / beta_1)**2`` also moves with
    the free root ``beta_1`` (tip mass, set-back).  The partials ``F_p`` come from
    :func:`pfmdyn.discrepancy.model.characteristic_partials` (one call for the contact roots and
    one for the free root); the model's parameters are algebraic functions of the internal ones.

    >>> from types import SimpleNamespace
    >>> model = Model(SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4))
    >>> f = resonances(model, [2.0, 2.0], True, 7e4)       # contact mode 1 at k1 = k2 = 100 k
    >>> (resonance_sensitivity(model, [2.0, 2.0], True, f) / f[:, None]).round(3).tolist()
    [[0.19, 0.143]]
    """
    internal = np.asarray(internal, float)
    m = model.meta
    f = np.asarray(frequency_hz, float)
    c = model.coords(internal)
    b1, d_b1_dp = free_root_and_jacobian(m.spring_constant, m.tip_height, m.length, c["mu"], c["gamma"])
    beta = formulas.beta_from_frequency(f, m.free_resonance, b1)
    moved = ("kvv", "kll", "kvl", "mu", "gamma")
    at = [composed.PARAMETERS.index(p) for p in moved]
    a0 = np.array(characteristic_args(model, internal, contact), float)
    # the model's parameters are plain functions of the internal ones: their change per unit
    # of each internal one, by forward differences (columns j; none for a parameter the
    # characteristic does not take: a loss, the spot)
    steps = 1e-7 * np.maximum(1.0, np.abs(internal))
    per_unit = np.zeros((len(moved), len(internal)))
    for j, h in enumerate(steps):
        if model.parameters[j].name not in _CHARACTERISTIC:
            continue
        xs = internal.copy()
        xs[j] += h
        per_unit[:, j] = (np.array(characteristic_args(model, xs, contact), float)[at] - a0[at]) / h
    # only the partials of the parameters that move (the tip at the end: one segment, no gamma)
    rows = np.flatnonzero(per_unit.any(axis=1))
    wrt = ("beta",) + tuple(moved[i] for i in rows)
    with np.errstate(all="ignore"):
        d = characteristic_partials(beta, composed.Parameters(*a0), wrt)
        ratio = (d[1:] / d[0]).reshape(len(rows), len(f))
        d_beta = -(ratio.T @ per_unit[rows])
        d_b1 = np.array(d_b1_dp) @ per_unit[[moved.index("mu"), moved.index("gamma")]]    # already d beta1 / dp
        out = formulas.frequency_change(f[:, None], beta[:, None], d_beta, b1, d_b1[None, :])
    out[~np.isfinite(out)] = 0.0
    return out
