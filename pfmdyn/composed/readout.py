"""The lever read at the spot ``x_s = sigma L``: :func:`response`, :func:`slope`, :func:`deflection`,
:func:`slope_and_jacobian` (as arrays, :func:`slopes_and_partials`), and where an engine reads them
(:class:`Reading`: :data:`at_end` or at a spot).

Each read-out takes one of three routes: compiled (:class:`_Compiled`, :mod:`.kernels`; when
:data:`pfmdyn.composed.KERNELS` is on and there is no probe), written out in NumPy
(:class:`pfmdyn.composed.written_out._WrittenOut`),
or assembled (:class:`pfmdyn.composed.assembly._Lever`: a probe's drives, the ``gamma`` partial).
Separate from the forms because it only chooses among them and scales their states to slopes.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from .. import composed
from ..generated import lever_pieces as pieces
from .assembly import _Lever
from .parameters import (_POINT, DRIVES, JACOBIAN_PARAMETERS, SPOT_JACOBIAN_PARAMETERS, TIP_DRIVES, Parameters,
                         _drive_columns)
from .written_out import _WrittenOut


class _Compiled:
    """The read-out of :mod:`pfmdyn.composed.kernels` with :class:`_WrittenOut`'s ``z`` (batch first, flat; one
    column per drive asked) and, computed with it, ``dz``: the slope's partials w.r.t. ``names`` (batch, partial,
    drive).

    Examples
    --------
    >>> args = (2.5, 0.95, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> bool(np.allclose(_Compiled(*args).z, _WrittenOut(*args).z, rtol=1e-13, atol=0))
    True
    """

    def __init__(self, beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=DRIVES, names=()):
        kernels = _kernels()
        args = [np.asarray(a) for a in (beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)]
        self.shape = np.broadcast(*args).shape
        n = math.prod(self.shape)
        real = not any(np.iscomplexobj(a) for a in args)       # real arguments, real results (as NumPy's)
        # each argument per member as a row of one complex block (the lever's: beta, the tip's springs,
        # stiffness and mass) or one real block (the lengths): fresh, C-ordered rows (a read-only or
        # strided view would be another specialisation to compile)
        lever, lengths = np.empty((6, n), complex), np.empty((5, n))
        for block, at, part in ((lever, (0, 2, 3, 4, 5, 8), np.asarray), (lengths, (1, 9, 6, 7, 10), np.real)):
            for row, i in zip(block, at):
                row.reshape(self.shape)[...] = part(args[i])
        beta, k, kvv, kll, kvl, mu = lever
        sigma, g, H, L, rho_g = lengths
        self.beta, self.L = (beta if np.iscomplexobj(args[0]) else beta.real), L
        two = bool((args[9].real != 1.0).any()) or "gamma" in names
        point, kinds, use = _codes(tuple(names), tuple(drives))
        jump, djump = np.empty((n, 12), complex), np.empty((len(names), n, 12), complex)
        kernels.tip_point(beta, k, kvv, kll, kvl, H, L, mu, rho_g, point, jump, djump)
        # the load's constant by NumPy's powers: the q0 column's cancellations amplify their last digits
        uc = pieces.load_constant(beta, k, L)
        z, dz = np.empty((n, 2, len(use)), complex), np.empty((n, len(names), len(use)), complex)
        kernels.read_out(beta, sigma, g, uc, k, jump, djump, kinds, two, use, z, dz)
        self.z = z.real if real else z
        self.dz = dz.real if real else dz

    out = _Lever.out


@functools.cache
def _kernels():
    """:mod:`pfmdyn.composed.kernels`, imported on first use (numba's import stays out of the start-up)."""
    from . import kernels

    return kernels


@functools.lru_cache(maxsize=64)
def _codes(names, drives):
    """What :func:`pfmdyn.composed.kernels.tip_point` and :func:`~pfmdyn.composed.kernels.read_out` take for the
    partials ``names`` and the ``drives``: each partial's row of the tip's point (-1: none), how it enters, and
    the drives' columns."""
    kernels = _kernels()
    codes = {"beta": kernels.BETA, "sigma": kernels.SIGMA, "k": kernels.K, "gamma": kernels.GAMMA}
    return (np.array([_POINT.index(p) if p in _POINT else -1 for p in names], np.int64),
            np.array([codes.get(p, kernels.TIP) for p in names], np.int64),
            np.array(_drive_columns(drives, DRIVES), np.int64))


def _written_out(names=(), probe=None) -> bool:
    """Whether a read-out is written out (:class:`_WrittenOut`, no assembly): all but a probe's and
    the partial w.r.t. ``gamma``, which the assembled system gives."""
    return probe is None and "gamma" not in names


def response(beta, parameters: Parameters, sigma=1.0, drives=TIP_DRIVES, probe=None):
    """Slope ``u'(x_s)`` and deflection ``u(x_s)`` at ``x_s = sigma L`` (the free end by default) per unit
    drive: two tuples over ``drives`` (of :data:`DRIVES`, and of :data:`PROBE_DRIVES` at ``x = probe L``
    when ``probe`` is given).  The deflection is absolute: driven by the base (``y0``), the deflection
    relative to the base is this minus one.

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> slopes, deflections = response(2.5, lever)
    >>> [f"{v:.8g}" for v in slopes]
    ['7346.2326', '5310.5162', '66.641964', '-0.016021027']
    >>> free = Parameters(k=2.0, kvv=0.0, kll=0.0, kvl=0.0, H=1e-5, L=2e-4, mu=0.0, gamma=1.0, rho_g=0.0)
    >>> [round(float(v), 9) for v in response(1e-3, free, 0.7, ("y0",))[1]]
    [1.0]
    """
    if probe is None and composed.KERNELS:
        lever = _Compiled(beta, sigma, *parameters, drives=drives)
        z = lever.z
    elif _written_out(probe=probe):
        lever = _WrittenOut(beta, sigma, *parameters, drives=tuple(drives))
        z = lever.z
    else:
        beta, sigma = np.broadcast_arrays(np.asarray(beta), np.asarray(sigma, dtype=float))
        lever = _Lever(beta, *parameters, probe=probe)
        z = lever.state(lever.reader(sigma))[:, :, _drive_columns(drives, lever.drives)]
    theta = (lever.beta / lever.L)[:, None] * z[:, 1]
    return tuple(np.moveaxis(lever.out(theta), -1, 0)), tuple(np.moveaxis(lever.out(z[:, 0]), -1, 0))


def slope(beta, parameters: Parameters, sigma=1.0, drives=TIP_DRIVES):
    """Slope ``u'(sigma L)`` per unit drive (a tuple of arrays over ``drives``, by default ``d1, d2, f0, q0``).

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> [f"{v:.8g}" for v in slope(2.5, lever, 0.8)]
    ['7446.7015', '3613.9492', '70.728402', '-0.01440258']
    """
    return response(beta, parameters, sigma, drives)[0]


def deflection(beta, parameters: Parameters, sigma=1.0, drives=TIP_DRIVES):
    """Deflection ``u(sigma L)`` per unit drive (a tuple of arrays over ``drives``; absolute).

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> [f"{v:.7g}" for v in deflection(2.5, lever, 0.8)]
    ['0.9396194', '0.04499747', '0.00966206', '1.391756e-06']
    """
    return response(beta, parameters, sigma, drives)[1]


def slope_and_jacobian(beta, parameters: Parameters, sigma=1.0, wrt=SPOT_JACOBIAN_PARAMETERS, drives=TIP_DRIVES):
    """:func:`slope` and its partials w.r.t. :data:`SPOT_JACOBIAN_PARAMETERS` (None where not in ``wrt``).

    Returns
    -------
    values : tuple of ndarray, as :func:`slope`
    jacobian : ``jacobian[i][j]``, the derivative of ``values[i]`` w.r.t. ``SPOT_JACOBIAN_PARAMETERS[j]``

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> values, jacobian = slope_and_jacobian(2.5, lever, 0.8, wrt=('sigma',))
    >>> [f"{v:.8g}" for v in [row[1] for row in jacobian]]
    ['-1968.7118', '15554.443', '-48.327618', '-0.042736975']
    """
    values, partials = slopes_and_partials(beta, parameters, sigma, wrt, drives)
    return _tuples(values, partials, SPOT_JACOBIAN_PARAMETERS)


def slopes_and_partials(beta, parameters: Parameters, sigma=1.0, wrt=SPOT_JACOBIAN_PARAMETERS, drives=TIP_DRIVES):
    """:func:`slope_and_jacobian` as arrays, the drives first: the slopes ``values[i]`` per unit ``drives[i]``
    and the partials ``partials[name][i]`` by name (those of ``wrt``), without the tuples.

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> values, partials = slopes_and_partials(2.5, lever, 0.8, wrt=('sigma',))
    >>> values.shape, list(partials), f"{partials['sigma'][1]:.8g}"
    ((4,), ['sigma'], '15554.443')
    """
    names = [p for p in SPOT_JACOBIAN_PARAMETERS if p in wrt]
    if composed.KERNELS:      # every partial, gamma's too
        lever = _Compiled(beta, sigma, *parameters, drives=drives, names=tuple(names))
        z1, dz = lever.z[:, 1], lever.dz
    elif _written_out(names):
        lever = _WrittenOut(beta, sigma, *parameters, drives=tuple(drives))
        z1, dz = lever.z[:, 1], _by_partial([d[:, 1] for d in lever.partials(names).values()], lever.z[:, 1])
    else:
        beta, sigma = np.broadcast_arrays(np.asarray(beta), np.asarray(sigma, dtype=float))
        lever = _Lever(beta, *parameters, split="gamma" in names, derivatives=True)
        reader = lever.reader(sigma)
        use = _drive_columns(drives, lever.drives)
        z1 = lever.state(reader)[:, 1, use]
        dc = lever.d_system([p for p in names if p != "sigma"])
        dz = _by_partial([lever.d_state(reader, name, dc.get(name, np.zeros_like(lever.c)))[:, 1, use]
                          for name in names], z1)
    scale = (lever.beta / lever.L)[:, None]
    d = scale[:, None] * dz             # every partial's slope at once
    if "beta" in names:                 # beta moves the scale too
        d[:, names.index("beta")] += z1 / lever.L[..., None]
    return _drives_first(lever, scale * z1), {name: _drives_first(lever, d[:, j]) for j, name in enumerate(names)}


def _by_partial(columns, z1):
    """The partials of the slope ``columns`` (each as ``z1``, (batch, drives)) as one array (batch, partial, drives)."""
    return np.stack(columns, axis=1) if columns else np.empty(z1.shape[:1] + (0,) + z1.shape[1:], z1.dtype)


def _drives_first(lever, x):
    """Flat results ``x`` (batch, drives) in the arguments' broadcast shape, the drives first."""
    x = lever.out(x)
    return x.transpose(x.ndim - 1, *range(x.ndim - 1))


def _tuples(values, partials, names):
    """The slopes and partials of :func:`slopes_and_partials` as :func:`slope_and_jacobian` gives them, the
    partials' columns ``names`` (None where not computed)."""
    return tuple(values), tuple(tuple(partials[p][i] if p in partials else None for p in names)
                                for i in range(len(values)))


class Reading:
    """Where an engine reads the lever: at the free end (:data:`at_end`: its partials are those of
    :data:`JACOBIAN_PARAMETERS`, the characteristic's) or at a laser spot ``sigma`` (its partial too,
    :data:`SPOT_JACOBIAN_PARAMETERS`).  One forward model, :func:`slope_and_jacobian`, behind both.

    Examples
    --------
    >>> lever = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> bool(at_end.slope(2.5, lever)[0] == Reading(1.0).slope(2.5, lever)[0])
    True
    """

    def __init__(self, sigma=None):
        self.sigma = sigma
        self.JACOBIAN_PARAMETERS = JACOBIAN_PARAMETERS if sigma is None else SPOT_JACOBIAN_PARAMETERS

    @property
    def _at(self):
        return 1.0 if self.sigma is None else self.sigma

    def slope(self, beta, parameters: Parameters):
        return slope(beta, parameters, self._at)

    def slope_and_jacobian(self, beta, parameters: Parameters, wrt=None):
        return _tuples(*self.slopes_and_partials(beta, parameters, wrt), self.JACOBIAN_PARAMETERS)

    def slopes_and_partials(self, beta, parameters: Parameters, wrt=None):
        """:func:`slopes_and_partials` here, w.r.t. ``wrt`` (by default every one of :attr:`JACOBIAN_PARAMETERS`)."""
        return slopes_and_partials(beta, parameters, self._at, self.JACOBIAN_PARAMETERS if wrt is None else wrt)


at_end = Reading()
"""The reading at the free end."""
