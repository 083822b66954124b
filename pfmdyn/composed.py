"""The composed lever: the derived pieces assembled per frequency into one small linear system.

The lever is two uniform segments, clamp to tip (``0 < xi < gamma``) and tip to free end
(``gamma < xi < 1``; of zero length when the tip is at the end), joined at the tip point
(contact springs ``kvv, kll, kvl`` at height ``H``, tip mass ``mu``, rotary inertia ``rho_g``,
drives ``d1, d2, f0``) and loaded by ``q0`` along their length.  Each piece is derived once in
``derivations/pieces.py`` and generated in ``generated/lever_pieces.py``; here they are only
assembled (the dynamic-stiffness way): per segment four unknowns, eight rows (clamp, continuity
and jump at the tip, free end), one right-hand side per drive, solved with NumPy and batched over
every frequency and parameter given.  The beam is then read anywhere (:func:`slope`,
:func:`deflection` at ``x_s = sigma L``).

Numerics.  A segment with ``|beta l| <= 1`` uses the Krylov-Duncan field matrix (its state at the
start as unknowns, series free of cancellation, and the load's particular solution of zero
initial state), a longer one the bounded basis ``cos, sin, e^{-s}, e^{s - beta l}``: nothing
overflows and nothing cancels, from the quasi-static ``beta = 1e-3`` to ``Re beta = 200``.
Derivatives come from the same system (``dc = A^-1 (db - dA c)``), and the characteristic is its
determinant, scaled to be continuous across the two bases: written out from the segments' values
(the Schur complements of the clamp's rows and of the segment beyond the tip), not assembled, as
are its partials with the tip at the end and the read-outs but a probe's and the ``gamma`` partial
(:class:`_WrittenOut`).  The read-outs without a probe, the characteristic and its partials with
the tip at the end run compiled (:mod:`pfmdyn.composed_kernels`, the same steps per member; :data:`KERNELS`),
the NumPy forms here their reference.

Arguments are those of the paper's variables: ``beta`` (complex for a damped lever), ``k`` the
lever's spring constant, ``kvv, kll, kvl`` the contact springs in beam axes, ``H, L``, ``mu`` the
tip mass over the lever's, ``gamma = x_tip / L``, ``rho_g = r_g / L``, ``sigma = x_s / L``.

One module, over 450 lines, because the assembled system and its written-out forms are one model:
they share the choice of basis per segment, its scale factors and the determinant's sign (a root
bracket reads the sign), and the tests hold each written-out form to the assembled one.
"""
from __future__ import annotations

import math
from functools import cached_property
from typing import NamedTuple

import numpy as np

from .generated import lever_pieces as pieces

__all__ = ["Parameters", "PARAMETERS", "JACOBIAN_PARAMETERS", "SPOT_JACOBIAN_PARAMETERS", "DRIVES", "slope",
           "deflection", "response", "slope_and_jacobian", "characteristic", "characteristic_and_jacobian"]


class Parameters(NamedTuple):
    """The lever's parameters after ``beta`` (and the spot's ``sigma``) of every function here, typed and
    named; a tuple, so ``f(beta, *parameters)`` is the positional call.  Built from a probe in one place,
    :meth:`pfmdyn.cantilever.Cantilever.model_parameters`; each may be an array (broadcast with ``beta``).

    >>> p = Parameters(k=2.0, kvv=98.0, kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=0.9, rho_g=0.05)
    >>> f"{characteristic(2.5, *p):.8g}" == f"{characteristic(2.5, 2.0, 98.0, 52.0, 9.0, 1e-5, 2e-4, 0.1, 0.9, 0.05):.8g}"
    True
    """

    k: float
    """The lever's spring constant (N/m)."""
    kvv: float
    """The contact's vertical spring in the lever's axes (N/m; complex with a contact dashpot)."""
    kll: float
    """Its longitudinal spring in the lever's axes (N/m)."""
    kvl: float
    """Their coupling (N/m; a tilt's)."""
    H: float
    """The tip height (m)."""
    L: float
    """The lever's length (m)."""
    mu: float
    """The tip's mass over the lever's."""
    gamma: float
    """The tip's position over the length, ``0 < gamma <= 1``."""
    rho_g: float
    """The tip's radius of gyration over the length."""


PARAMETERS = Parameters._fields
JACOBIAN_PARAMETERS = ("beta", "k", "kvv", "kll", "kvl", "mu", "gamma", "rho_g")
"""The parameters of :func:`characteristic_and_jacobian`'s partials (and of the slope at the end)."""
SPOT_JACOBIAN_PARAMETERS = ("beta", "sigma", "k", "kvv", "kll", "kvl", "mu", "gamma", "rho_g")
DRIVES = ("d1", "d2", "f0", "m0", "q0", "y0")
"""Every drive the system is solved for: the tip's (surface displacements ``d1, d2``, force ``f0``,
couple ``m0``), the distributed load ``q0`` and the base (the clamp's displacement ``y0``)."""
TIP_DRIVES = ("d1", "d2", "f0", "q0")
"""The drives the read-outs give by default (the paper's)."""
PROBE_DRIVES = ("f_probe", "m_probe")
"""A force and a couple at a bare point of the lever (the probe), where asked."""
_Q0, _Y0 = DRIVES.index("q0"), DRIVES.index("y0")
_POINT = pieces.JACOBIAN_PARAMETERS
_BOUNDED_AT_START = float(np.linalg.det(np.array(pieces.bounded_basis(0.0, 0.0)[:16], dtype=float).reshape(4, 4)))


def _solve(A, b=None):
    """``A^-1 b`` batched (``A^-1`` without ``b``); NaN for the members whose ``A`` is singular or not finite."""
    solve = np.linalg.inv if b is None else lambda A: np.linalg.solve(A, b)   # noqa: E731
    try:
        with np.errstate(all="ignore"):
            return solve(A)
    except np.linalg.LinAlgError:
        eye = np.eye(A.shape[-1])
        bad = ~np.isfinite(A).all(axis=(-2, -1))
        with np.errstate(all="ignore"):
            bad |= np.abs(np.linalg.det(np.where(bad[..., None, None], eye, A))) == 0
        out = solve(np.where(bad[..., None, None], eye, A))
        out[bad] = np.nan
        return out


_CIRCULANT = np.array([[(j - m) % 4 for j in range(4)] for m in range(5)])
"""``F[m][j] = K[(j - m) % 4]``: the field matrix and its ``d/ds`` (row 4) from ``K = (S, T, U, V)``."""


def _rows(values, n, dtype=None) -> np.ndarray:
    """``values`` (arrays of length ``n`` or scalars) as the rows of one ``(len(values), n)`` array."""
    dtype = dtype or np.result_type(*values, float)
    out = np.empty((len(values), n), dtype)
    for i, v in enumerate(values):
        out[i] = v
    return out


def _columns(values, n, dtype=None) -> np.ndarray:
    """``values`` as the columns of one ``(n, len(values))`` array."""
    return _rows(values, n, dtype).T


class _Segment:
    """A segment read at ``t`` (length ``ell``): basis ``E[:, n, j]``, load ``P[:, n]`` per unit q0, and
    their derivatives along ``s = beta t`` (``dE``, ``dP``) and w.r.t. ``s_end = beta ell`` (``dE_end``).

    Members with ``short`` use the Krylov-Duncan field matrix, the others the bounded basis.  The
    five rows ``d**n/ds**n``, ``n = 0..4``, are kept: the basis is rows 0-3, its ``d/ds`` rows 1-4."""

    def __init__(self, beta, t, ell, short, uc):
        s = beta * t
        if short.all():
            self.rows, self.load = self._krylov_duncan(s, uc)
        elif not short.any():
            self.rows, self.load = self._bounded(s, beta * ell, uc)
        else:
            rows = np.empty(beta.shape + (5, 4), np.result_type(beta, uc))
            load = np.empty(beta.shape + (5,), rows.dtype)
            for mask, make in ((short, self._krylov_duncan), (~short, self._bounded)):
                args = (s[mask], uc[mask]) if make == self._krylov_duncan else (s[mask], (beta * ell)[mask], uc[mask])
                rows[mask], load[mask] = make(*args)
            self.rows, self.load = rows, load
        self.short = short
        self.E, self.dE = self.rows[:, :4], self.rows[:, 1:]
        self.P, self.dP = self.load[:, :4], self.load[:, 1:]

    @staticmethod
    def _krylov_duncan(s, uc):
        s_1, t, u, v = pieces.krylov_duncan(s)
        K = _columns((s_1 + 1.0, t, u, v), s.shape[0])
        # the load of zero initial state, uc (e0 - F[:, 0]), and its d/ds: -uc (S - 1, V, U, T, S)
        return K[:, _CIRCULANT], -uc[:, None] * _columns((s_1, v, u, t, K[:, 0]), s.shape[0])

    @staticmethod
    def _bounded(s, s_end, uc):
        rows = _columns(pieces.bounded_basis(s, s_end), s.shape[0]).reshape(-1, 5, 4)
        load = np.zeros(s.shape + (5,), np.result_type(rows, uc))
        load[:, 0] = uc
        return rows, load

    @cached_property
    def dE_end(self):
        """``d E / d s_end``: only the bounded basis' ``e^{s - s_end}`` column depends on it."""
        out = np.zeros_like(self.E)
        out[:, :, 3] = np.where(self.short[:, None], 0.0, -self.E[:, :, 3])
        return out

    def parts(self, count, take=None, uc=None):
        """The segment evaluations of ``count`` stacked batches (one evaluation serves them all); with
        ``take``, each member's row among shared ones and its load constant ``uc`` (the rows' is 1)."""
        n = self.E.shape[0] // count
        return [_Part(self, slice(i * n, (i + 1) * n), take, uc) for i in range(count)]

    def derivative(self, name, beta, t, ell, moves_end, moves_start):
        """``(dE, dP)`` w.r.t. ``name``.  ``moves_end``, ``moves_start``: ``d ell/d gamma`` and
        ``d t/d gamma`` (the segment's length and the read point follow the tip)."""
        b = beta[:, None, None]
        if name == "beta":
            return (t[:, None, None] * self.dE + ell[:, None, None] * self.dE_end,
                    t[:, None] * self.dP - 4 * self.P / beta[:, None])
        if name == "gamma":
            ds = (moves_start * beta)[:, None, None]
            return ds * self.dE + moves_end[:, None, None] * b * self.dE_end, ds[:, 0] * self.dP
        if name == "sigma":
            return b * self.dE, b[:, 0] * self.dP
        return None


class _Part:
    """One batch of a stacked :class:`_Segment` evaluation (views; copies of shared rows with ``take``)."""

    def __init__(self, whole, part, take=None, uc=None):
        self.whole, self.part, self.take = whole, part, take
        rows, load = whole.rows[part], whole.load[part]
        if take is not None:
            rows, load = rows[take], load[take] * uc[:, None]
        self.E, self.dE, self.P, self.dP = rows[:, :4], rows[:, 1:], load[:, :4], load[:, 1:]

    @property
    def dE_end(self):
        d = self.whole.dE_end[self.part]
        return d if self.take is None else d[self.take]

    derivative = _Segment.derivative


class _Lever:
    """The assembled system ``A c = b`` of one batch (all arguments broadcast and flattened).

    Segments run between the clamp, the points and the free end: the tip's point, and with
    ``probe`` a bare point at ``x = probe L`` driven by its own force and couple (:data:`PROBE_DRIVES`;
    on the same side of the tip for the whole batch).  One segment when the tip is at the end
    everywhere and nothing else is asked (``gamma = 1``, no ``gamma`` derivative, no probe); each
    segment four unknowns, one right-hand side per drive."""

    def __init__(self, beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, *, split=False, derivatives=False,
                 probe=None):
        args = [np.asarray(a) for a in (beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)]
        self.shape = np.broadcast_shapes(*(a.shape for a in args))
        dtype, n = np.result_type(*args, float), math.prod(self.shape)
        flat = [np.full(n, a, dtype) if a.ndim == 0 else np.broadcast_to(a.astype(dtype), self.shape).reshape(-1)
                for a in args]
        self.beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g = flat
        self.k, self.L, self.gamma = k, L, np.real(gamma)
        self.derivatives = derivatives      # solve for A^-1 with c: derivatives will be asked
        # the point's parameters as plain numbers where they are one value (cheaper than arrays)
        one = [a.item() if a.ndim == 0 else f for a, f in zip(args, flat)]
        self.uc = pieces.load_constant(self.beta, one[1], one[6]) + 0 * self.beta
        self.point = (self.beta, *one[1:8], one[9])
        self.jump = _columns(pieces.point_jump(*self.point), n, dtype)
        g = self.gamma
        self.drives = DRIVES if probe is None else DRIVES + PROBE_DRIVES
        # the points in order along the lever: (position, J, G over the drives); the tip's index
        tip_drives = self._drive_block(self.jump[:, 4:], DRIVES.index("d1"))
        points = [(g, self.jump[:, :4].reshape(-1, 2, 2), tip_drives)]
        self.tip = 0
        if probe is not None:
            if derivatives or split:
                raise ValueError("a probed lever is solved for its response only")
            at = np.broadcast_to(np.real(np.asarray(probe, dtype=float)), self.shape).reshape(-1)
            # a force and a couple act on a point through the f0 and m0 columns of its jump, which
            # hold no spring or mass: a bare point's drives are the tip's
            forced = np.zeros_like(tip_drives)
            forced[:, :, len(DRIVES):] = tip_drives[:, :, [DRIVES.index("f0"), DRIVES.index("m0")]]
            if np.all(at == g):             # at the tip: its point takes them
                points = [(g, points[0][1], tip_drives + forced)]
            else:
                first = at < g
                if first.any() and not first.all():
                    raise ValueError("the probe must lie on the same side of the tip throughout a batch")
                self.tip = int(first.all())
                points.insert(1 - self.tip, (at, np.zeros((n, 2, 2), dtype), forced))
        self.two = len(points) > 1 or split or bool(np.any(g != 1.0))
        self.points = points if self.two else []
        bounds = [np.zeros_like(g)] + [p[0] for p in self.points] + [np.ones_like(g)]
        self.starts = bounds[:-1]
        self.lengths = tuple(b - a for a, b in zip(bounds[:-1], bounds[1:]))
        self.short = [np.abs(self.beta * ell) <= pieces.KD_SERIES_LIMIT for ell in self.lengths]
        # (segment, t, d ell/d gamma, d t/d gamma) of the ends the rows use: each segment's start and
        # end (the tip moves the segments about it: d/d gamma is +1 on its left, -1 on its right)
        slopes = [1.0, -1.0] if len(self.lengths) == 2 and self.tip == 0 else [0.0] * len(self.lengths)
        self.ends = [end for j, ell in enumerate(self.lengths)
                     for end in ((j, np.zeros_like(g), slopes[j], 0.0), (j, ell, slopes[j], slopes[j]))]
        count = len(self.ends)
        rows, take = self._shared_rows([args[0], args[8]] + ([np.asarray(probe)] if probe is not None else []))
        pick = (lambda x: x) if rows is None else (lambda x: x[rows])      # noqa: E731
        uc = self.uc if rows is None else np.ones(len(rows), self.uc.dtype)
        stacked = _Segment(np.concatenate([pick(self.beta)] * count), np.concatenate([pick(t) for _, t, _, _ in self.ends]),
                           np.concatenate([pick(self.lengths[j]) for j, _, _, _ in self.ends]),
                           np.concatenate([pick(self.short[j]) for j, _, _, _ in self.ends]),
                           np.concatenate([uc] * count))
        self.at = stacked.parts(count, take, None if rows is None else self.uc)
        self.A, self.b = self._assemble(points, [(e.E, e.P) for e in self.at])

    def _shared_rows(self, args):
        """Members whose segments are the same (the same ``beta`` and points, other parameters
        varying: a grid of springs): one row per distinct set and each member's row among them,
        ``(rows, take)``; ``(None, None)`` when too little is shared to gain."""
        small = np.broadcast_shapes(*(np.shape(a) for a in args))
        m, n = math.prod(small), self.beta.shape[0]
        if 2 * m > n:
            return None, None
        take = np.broadcast_to(np.arange(m).reshape(small), self.shape).reshape(-1)
        rows = np.empty(m, int)
        rows[take] = np.arange(n)
        return rows, take

    def _drive_block(self, G, first):
        """A point's drive columns ``G`` (n, 2, m) placed among :attr:`drives` from column ``first``."""
        G = G.reshape(G.shape[0], 2, -1)
        out = np.zeros(G.shape[:2] + (len(self.drives),), G.dtype)
        out[:, :, first:first + G.shape[-1]] = G
        return out

    @cached_property
    def jump_partials(self):
        return pieces.point_jump_partials(*self.point)

    @cached_property
    def c(self):
        """The segments' coefficients per drive (NaN where the system is singular: an undamped
        resonance met exactly, or a non-finite argument)."""
        return self._solved[0] if self.derivatives else _solve(self.A, self.b)

    @cached_property
    def inverse(self):
        """``A^-1``, from the same solve as :attr:`c` (derivatives are products with it)."""
        return self._solved[1]

    @cached_property
    def _solved(self):
        size, nd = self.A.shape[-1], self.b.shape[-1]
        out = _solve(self.A, np.concatenate([self.b, np.broadcast_to(np.eye(size), self.A.shape)], -1))
        return out[..., :nd], out[..., nd:]

    def _assemble(self, points, ends, dpoints=None, dends=None):
        """``A``, ``b`` from the points ``(position, J, G)`` and the segments' end values; with
        ``dpoints``, ``dends`` given, their derivative (the system is linear in each but for each
        point's ``J`` times the state there)."""
        values = dends or ends
        n, size = self.beta.shape[0], 4 * len(self.lengths)
        dtype = np.result_type(values[1][0], points[0][1], values[1][1])
        A = np.zeros((n, size, size), dtype=dtype)
        b = np.zeros((n, size, len(self.drives)), dtype=dtype)
        E0, P0 = values[0]
        A[:, 0:2, 0:4], b[:, 0:2, _Q0] = E0[:, 0:2], -P0[:, 0:2]         # clamp
        if dpoints is None:
            b[:, 0, _Y0] = 1.0                                           # moved with the base: u(0) = y0
        for i, (_, J, G) in enumerate(points):
            (El, Pl), (dEl, dPl) = ends[2 * i + 1], values[2 * i + 1]
            if dpoints is None:
                JE, JP = J @ El[:, 0:2], np.einsum("nij,nj->ni", J, Pl[:, 0:2])
            else:
                dJ, G = dpoints[i]
                JE = dJ @ El[:, 0:2] + J @ dEl[:, 0:2]
                JP = np.einsum("nij,nj->ni", dJ, Pl[:, 0:2]) + np.einsum("nij,nj->ni", J, dPl[:, 0:2])
            if not self.points:                 # the tip at the free end: its jump ends the lever
                A[:, 2:4, 0:4], b[:, 2:4], b[:, 2:4, _Q0] = dEl[:, 2:4] - JE, G, JP - dPl[:, 2:4]
                return A, b
            left, right, r = slice(4 * i, 4 * i + 4), slice(4 * i + 4, 4 * i + 8), 4 * i + 2
            Er, Pr = values[2 * i + 2]
            A[:, r:r + 2, left], A[:, r:r + 2, right] = dEl[:, 0:2], -Er[:, 0:2]        # u, u' continuous
            b[:, r:r + 2, _Q0] = (Pr - dPl)[:, 0:2]
            A[:, r + 2:r + 4, left], A[:, r + 2:r + 4, right] = dEl[:, 2:4] - JE, -Er[:, 2:4]  # moment, shear jump
            b[:, r + 2:r + 4] = G
            b[:, r + 2:r + 4, _Q0] = JP + Pr[:, 2:4] - dPl[:, 2:4]
        Ee, Pe = values[-1]
        A[:, -2:, -4:], b[:, -2:, _Q0] = Ee[:, 2:4], -Pe[:, 2:4]         # free end
        return A, b

    def _tip_partial(self, name):
        """``(dJ, dG)`` of the tip's point w.r.t. ``name`` (zeros for a parameter it does not hold)."""
        if name not in _POINT:
            n = self.beta.shape[0]
            return np.zeros((n, 2, 2), self.jump.dtype), np.zeros((n, 2, len(self.drives)), self.jump.dtype)
        d = _columns(self.jump_partials[name], self.beta.shape[0], self.jump.dtype)
        return d[:, :4].reshape(-1, 2, 2), self._drive_block(d[:, 4:], DRIVES.index("d1"))

    def _d_ends(self, name):
        """Derivatives of the points and of the ends' values w.r.t. ``name``."""
        dpoints = [self._tip_partial(name)]
        dends = []
        for (j, t, d_ell, d_t), seg in zip(self.ends, self.at):
            d = seg.derivative(name, self.beta, t, self.lengths[j], np.full_like(t, d_ell), np.full_like(t, d_t))
            if d is None:
                d = (np.zeros_like(seg.E), -seg.P / self.k[:, None] if name == "k" else np.zeros_like(seg.P))
            elif name == "sigma":
                d = (np.zeros_like(seg.E), np.zeros_like(seg.P))
            dends.append(d)
        return dpoints, dends

    def _tip_points(self):
        return self.points or [(self.gamma, self.jump[:, :4].reshape(-1, 2, 2),
                                self._drive_block(self.jump[:, 4:], DRIVES.index("d1")))]

    def d_system_matrix(self, name):
        """``dA`` w.r.t. ``name``."""
        dpoints, dends = self._d_ends(name)
        return self._assemble(self._tip_points(), [(e.E, e.P) for e in self.at], dpoints, dends)[0]

    def d_det_at_tip(self, adjugate, names):
        """``tr(adj(A) dA)`` for parameters of the tip point alone (``k`` among them: the jump is
        in units of the lever's stiffness): ``dA`` is ``-dJ`` times the tip's state, in the jump's
        rows and the first segment's columns only."""
        rows, E = self._jump_rows, self.at[1].E[:, 0:2]
        adj = adjugate[:, 0:4, rows]
        return [-np.einsum("nji,nij->n", adj, self._tip_partial(name)[0] @ E) for name in names]

    @property
    def _jump_rows(self):
        return slice(4, 6) if self.two else slice(2, 4)

    def _tip_state(self):
        """``[u, z1]`` at the tip per drive (2 x drives): what a change of the jump acts on."""
        E, P = self.at[1].E, self.at[1].P
        z = E[:, 0:2] @ self.c[:, 0:4]
        z[:, :, _Q0] += P[:, 0:2]
        return z

    def d_system(self, names):
        """``{name: dc}``, one solve for all.  A parameter of the tip point alone changes only the
        jump's rows of the system: there ``db - dA c = dG d + dJ [u, z1]``."""
        rhs, tip = [], None
        for name in names:
            if name in _POINT and name not in ("beta", "k"):
                tip = self._tip_state() if tip is None else tip
                dJ, dG = self._tip_partial(name)
                r = np.zeros_like(self.b, dtype=np.result_type(self.b, dJ))
                r[:, self._jump_rows] = dJ @ tip + dG
            else:
                dpoints, dends = self._d_ends(name)
                dA, db = self._assemble(self._tip_points(), [(e.E, e.P) for e in self.at], dpoints, dends)
                r = db - dA @ self.c
            rhs.append(r)
        if not rhs:
            return {}
        nd = self.b.shape[-1]
        dc = self.inverse @ np.concatenate(rhs, -1)
        return {name: dc[..., nd * i:nd * (i + 1)] for i, name in enumerate(names)}

    def reader(self, sigma):
        """The read-out at ``sigma``: its segment evaluation, which coefficients it uses, and how it
        moves with the tip."""
        sigma = np.broadcast_to(np.real(np.asarray(sigma, dtype=float)), self.shape).reshape(-1)
        index = sum((sigma > p[0]).astype(int) for p in self.points) if self.points else np.zeros(sigma.shape, int)
        pick = lambda values: np.choose(index, values)   # noqa: E731  (one per segment, chosen per member)
        t = sigma - pick(self.starts)
        ell, short = pick(self.lengths), pick(self.short)
        seg = _Segment(self.beta, t, ell, short, self.uc)
        return seg, t, ell, index, self._coefficients(index, self.c)

    @staticmethod
    def _coefficients(index, c):
        """The coefficients of the segment each member reads (``index``)."""
        rows = 4 * index[:, None] + np.arange(4)
        return np.take_along_axis(c, rows[:, :, None], axis=1)

    def state(self, reader, dc=None):
        seg, _, _, index, coefficients = reader
        if dc is not None:
            coefficients = self._coefficients(index, dc)
        z = seg.E @ coefficients
        if dc is None:
            z[:, :, _Q0] += seg.P
        return z

    def d_state(self, reader, name, dc):
        """``d z(sigma)/d name`` (flat, 4 components x the drives)."""
        seg, t, ell, index, coefficients = reader
        z = self.state(reader, dc)
        before = index == 0
        d = seg.derivative(name, self.beta, t, ell, np.where(before, 1.0, -1.0), np.where(before, 0.0, -1.0))
        if d is None:
            if name == "k":
                z[:, :, _Q0] -= seg.P / self.k[:, None]
            return z
        dE, dP = d
        z = z + dE @ coefficients
        z[:, :, _Q0] += dP
        return z

    def out(self, x):
        """Flat results back to the arguments' broadcast shape (batch first)."""
        return x.reshape(self.shape + x.shape[1:])


def _drive_columns(drives, known) -> list[int]:
    unknown = [d for d in drives if d not in known]
    if unknown:
        raise ValueError(f"unknown drive {unknown[0]!r}: one of {', '.join(known)}")
    return [known.index(d) for d in drives]


_REORDERED = [2, 3, 0, 1]
"""A short segment's unknowns (its state at the start) with the moment and shear first."""


class _WrittenOut:
    """The lever read at ``sigma`` without assembling the system: each segment's rows at its outer
    end eliminated, as in :func:`_transferred`, and the tip's rows solved (2 x 2 or 4 x 4).

    A segment's end rows ``E[rows] c + P[rows] q0 = h`` (the clamp's ``u, z1``, ``h`` the base's
    ``y0``; beyond a set-back tip, the free end's moment and shear, ``h = 0``) read ``[Gp, Gf]`` on
    its coefficients, so ``c = [b0 - B u, u]``, ``B = Gp^-1 Gf``, ``b0 = Gp^-1 (h - P[rows] q0)``:
    two unknowns ``u`` per segment, its state anywhere ``z = R u + w`` (``R = E[:, 2:] - E[:, :2] B``,
    ``w`` from ``b0`` and the load).  ``Gp`` is ``I`` at the clamp in either basis; at the free end
    the bounded basis' ``cos, sin`` columns (a rotation) and, the short members' columns reordered
    (:data:`_REORDERED`), the field matrix's last two: well conditioned, where inverting the whole
    basis at the segment's start is not (its ``e^{s - s_end}`` column is ``e^{-beta l}`` there).

    With the tip at the end its rows ``X(z) = G d`` (``X(V) = V[2:] - J V[:2]``) leave the 2 x 2
    ``X(R) x = G d - X(w)``; set back, the states either side of the tip (``z_l = R_l x + w_l``,
    ``z_r = R_r y + w_r``: continuity, then the jump) the 4 x 4 ``[T(R_l), -R_r] [x; y] = [0; G d] -
    T(w_l) + w_r``, ``T(V) = [V[:2], X(V)]`` (:meth:`_across`); each solved by :func:`_small_inverse`.
    The segments are evaluated at their ends and the spot in one stack.  Inside, arrays keep the
    members last (rows, columns, members), so that a product of the tiny matrices is a few products
    of whole arrays (:func:`_product`); the results (:attr:`z`, :meth:`partials`) have the interface
    of :class:`_Lever`'s read-outs (batch first, flat; one column per drive asked, of :data:`DRIVES`);
    NaN where the system is singular, as there.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> general = _Lever(*args)
    >>> want = general.state(general.reader(0.95))[:, :2]
    >>> bool(np.allclose(_WrittenOut(args[0], 0.95, *args[1:]).z, want, rtol=1e-13, atol=0))
    True
    """

    def __init__(self, beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=DRIVES):
        args = [np.asarray(a) for a in (beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)]
        self.shape = np.broadcast_shapes(*(a.shape for a in args))
        n = math.prod(self.shape)
        flat = [a if a.ndim == 0 else np.broadcast_to(a, self.shape).reshape(-1) for a in args]
        beta, sigma, g = (np.broadcast_to(a, (n,)) for a in (flat[0], np.real(flat[1]), np.real(flat[9])))
        self.beta, self.k, self.L = beta.astype(np.result_type(beta, float)), flat[2], flat[7]
        self.point = (self.beta, *flat[2:9], flat[10])
        # one right-hand side per drive asked (of DRIVES): the load's and the base's columns as slices
        self.drives = tuple(drives)
        _drive_columns(drives, DRIVES)      # an unknown drive raises
        self._q0, self._y0 = (slice(drives.index(d), drives.index(d) + 1) if d in drives else slice(0, 0)
                              for d in ("q0", "y0"))
        self._tip = {DRIVES.index(d): j for j, d in enumerate(drives) if d in DRIVES[:4]}   # the jump's G columns
        self.two = bool(np.any(g != 1.0))
        self.before = sigma <= g if self.two else np.ones(n, bool)
        # (t, segment length) of the clamp, the tip from the left, [the tip from the right, the free
        # end,] and the spot
        at = [(np.zeros(n), g), (g, g)] + ([(np.zeros(n), 1.0 - g), (1.0 - g, 1.0 - g)] if self.two else [])
        spot = (np.where(self.before, sigma, sigma - g), np.where(self.before, g, 1.0 - g))
        # the batch each read point takes: a spot where the tip or the free end is takes theirs
        self.batch = list(range(len(at)))
        self.batch.append(next((b for b, (t, ell) in enumerate(at)
                                if np.array_equal(t, spot[0]) and np.array_equal(ell, spot[1])), len(at)))
        if self.batch[-1] == len(at):
            at.append(spot)
        self.t, self.ell = (np.concatenate(x).astype(float) for x in zip(*at))
        self.count = len(self.batch)
        stacked = np.tile(self.beta, len(at))
        short = np.abs(stacked * self.ell) <= pieces.KD_SERIES_LIMIT
        self.seg = _Segment(stacked, self.t, self.ell, short, np.ones(len(stacked)))
        if self.two:
            beyond = short & np.concatenate([np.zeros(2 * n, bool), np.ones(2 * n, bool), ~self.before][:len(at) - 2])
            self.seg.rows[beyond] = self.seg.rows[beyond][:, :, _REORDERED]
        self.uc = pieces.load_constant(self.beta, self.k, self.L) + 0 * self.beta
        self.E = self._batches(_members_last(self.seg.E))
        self.P = [self.uc * P for P in self._batches(_members_last(self.seg.P))]
        jump = _rows(pieces.point_jump(*self.point), n)
        self.J = jump[:4].reshape(2, 2, n)
        self.G = np.zeros((2, len(drives), n), jump.dtype)
        self.G[:, list(self._tip.values())] = jump[4:].reshape(2, 4, n)[:, list(self._tip)]
        # (batch, rows) eliminated per segment: the clamp's u, z1; the free end's moment and shear
        self.ends = [(0, slice(0, 2))] + ([(3, slice(2, 4))] if self.two else [])
        self.eliminated = [self._eliminate(*end, base=j == 0) for j, end in enumerate(self.ends)]
        R, w = self._per_unknown(1, 0)
        M, r = self._across(R), -self._across(w)
        r[-2:] += self.G                    # the jump's rows
        if self.two:
            R, w = self._per_unknown(2, 1)
            M, r = np.concatenate([M, -R], 1), r + w
        with np.errstate(all="ignore"):
            self.inverse = _small_inverse(M)
            self.u = np.split(_product(self.inverse, r), len(self.ends))
        self._c = {}
        self.c_spot = self._on_spot_segment(self.coefficients)
        self.z = np.moveaxis(self._state(-1, self.c_spot), -1, 0)

    def coefficients(self, j):
        """Segment ``j``'s coefficients per drive, ``[b0 - B u, u]`` (once: the values need only the
        spot's segment)."""
        if j not in self._c:
            _, B, b0 = self.eliminated[j]
            self._c[j] = np.concatenate([b0 - _product(B, self.u[j]), self.u[j]])
        return self._c[j]

    def _batches(self, x):
        """``x``, stacked over the batches along its last axis, split per read point (views)."""
        n = self.beta.shape[0]
        return [x[..., i * n:(i + 1) * n] for i in self.batch]

    def _eliminate(self, batch, rows, base):
        """``(Gp^-1, B, b0)`` of a segment from its end rows; ``base``: the clamp's, moved by ``y0``,
        where ``Gp = I`` (``Gp^-1`` None: nothing to solve)."""
        E, P = self.E[batch][rows], self.P[batch][rows]
        b0 = np.zeros((2, len(self.drives), P.shape[-1]), np.result_type(E, P))
        if base:
            b0[:, self._q0], b0[0, self._y0] = -P[:, None], 1.0
            return None, E[:, 2:], b0
        inverse = _small_inverse(E[:, :2])
        b0[:, self._q0] = -_product(inverse, P[:, None])
        return inverse, _product(inverse, E[:, 2:]), b0

    def _per_unknown(self, batch, segment):
        """``(R, w)`` at ``batch`` of ``segment``: its state ``z = R u + w`` per its unknowns ``u``."""
        E, (_, B, b0) = self.E[batch], self.eliminated[segment]
        w = _product(E[:, :2], b0)
        w[:, self._q0] += self.P[batch][:, None]
        return E[:, 2:] - _product(E[:, :2], B), w

    def _across(self, V):
        """What the tip's rows ask of a state ``V`` left of it: the jump's ``X(V) = V[2:] - J V[:2]``,
        after continuity's ``V[:2]`` when a segment lies beyond."""
        X = V[2:] - _product(self.J, V[:2])
        return np.concatenate([V[:2], X]) if self.two else X

    def _on_spot_segment(self, f):
        """``f(j)`` of the segment ``j`` the spot lies on, per member."""
        if self.before.all() or not self.before.any():
            return f(0 if self.before.all() else 1)
        return np.where(self.before, f(0), f(1))

    def _state(self, batch, c):
        """``[u, z1]`` per drive at ``batch`` from its segment's coefficients ``c``."""
        z = _product(self.E[batch][:2], c)
        z[:, self._q0] += self.P[batch][:2, None]
        return z

    def partials(self, names):
        """``{name: d [u, z1](sigma) / d name}`` per drive (``names`` of :data:`SPOT_JACOBIAN_PARAMETERS`
        but ``gamma``; batch first).  The states' change at fixed coefficients, ``e = dE c + dP q0``, less
        the eliminated rows' share (``E[:, :2] Gp^-1 e_end[rows]``), is ``dw``, their change at fixed
        unknowns; the tip's rows then move the unknowns by ``inverse ([0; dG d + dJ z_l[:2]] -
        T(dw_l) + dw_r)``."""
        n, count = self.beta.shape[0], self.count
        spot = slice(self.batch[-1] * n, (self.batch[-1] + 1) * n)
        coefficients = [self.coefficients(j) for j in np.arange(count - 1) // 2] + [self.c_spot]
        moved, at_spot = [], []
        for name in names:
            e = [None] * count
            if name == "beta":
                dE, dP = (_members_last(x) for x in self.seg.derivative(name, np.tile(self.beta, len(self.t) // n),
                                                                          self.t, self.ell, 1.0, 0.0))
                e = [_product(E, c) for E, c in zip(self._batches(dE), coefficients)]
                for changed, P in zip(e, self._batches(dP)):
                    changed[:, self._q0] += (self.uc * P)[:, None]
            elif name == "sigma":       # the spot alone moves
                dE, dP = (_members_last(x) for x in _Part(self.seg, spot).derivative(name, self.beta, None, None,
                                                                                     1.0, 0.0))
                e[-1] = _product(dE, coefficients[-1])
                e[-1][:, self._q0] += (self.uc * dP)[:, None]
            elif name == "k":           # through the load constant: P is in units of 1/k
                e = [np.zeros_like(c) for c in coefficients]
                for changed, P in zip(e, self.P):
                    changed[:, self._q0] = (-P / self.k)[:, None]
            q = (self._jump_moved(pieces.point_jump_partials(*self.point, wrt=(name,))[name]) if name in _POINT
                 else np.zeros_like(self.G))
            if self.two:
                q = np.concatenate([np.zeros_like(q), q])
            if e[0] is not None:
                left, right, e[-1] = self._at_fixed_unknowns(e)
                q -= self._across(left)
                if self.two:
                    q += right
            moved.append(q)
            at_spot.append(0.0 if e[-1] is None else e[-1][:2])
        # the spot's state per unit of the moved rows: R inverse (R = E[:, 2:] - E[:, :2] B of its segment)
        E, inverse = self.E[-1][:2], np.split(self.inverse, len(self.ends))
        spot_per_row = self._on_spot_segment(
            lambda j: _product(E[:, 2:] - _product(E[:, :2], self.eliminated[j][1]), inverse[j]))
        return {name: np.moveaxis(_product(spot_per_row, q) + w, -1, 0) for name, q, w in zip(names, moved, at_spot)}

    def _jump_moved(self, d):
        """``dJ z_tip + dG d`` of a partial ``d`` of the jump's twelve entries (:func:`pieces.point_jump`),
        its zero entries skipped (most are: each parameter enters a few)."""
        q = np.zeros_like(self.G)
        for i, v in enumerate(d):
            if np.ndim(v) == 0 and v == 0:
                continue
            if i < 4:
                q[i // 2] += v * self.z_tip[i % 2]
            elif (i - 4) % 4 in self._tip:
                q[(i - 4) // 4, self._tip[(i - 4) % 4]] += v
        return q

    def _at_fixed_unknowns(self, e):
        """``dw`` at the tip (either side) and the spot from the changes ``e`` at fixed coefficients
        (per batch): less the eliminated rows' share, ``E[:, :2] Gp^-1 e_end[rows]``, of the segment
        each lies on; ``(dw_l, dw_r or None, dw at the spot)``."""
        fixed = [e[batch][rows] if inverse is None else _product(inverse, e[batch][rows])
                 for (batch, rows), (inverse, _, _) in zip(self.ends, self.eliminated)]
        share = lambda i, j: e[i] - _product(self.E[i][:, :2], fixed[j])      # noqa: E731
        return share(1, 0), share(2, 1) if self.two else None, self._on_spot_segment(lambda j: share(-1, j))

    @cached_property
    def z_tip(self):
        return self._state(1, self.coefficients(0))

    out = _Lever.out


def _members_last(x):
    """A batch-first array with its members last, contiguous (the products below then stream)."""
    return np.ascontiguousarray(np.moveaxis(x, 0, -1))


def _product(A, B):
    """``A @ B`` per member, members last (``A`` (i, j, n), ``B`` (j, k, n)): ``j`` products of whole
    arrays, where NumPy's batched product of tiny matrices costs several times more.

    Examples
    --------
    >>> A, B = np.random.default_rng(2).normal(size=(2, 3, 2, 5))
    >>> bool(np.allclose(_product(A, B[:2, :]), np.einsum("ijn,jkn->ikn", A, B[:2, :])))
    True
    """
    out = A[:, 0, None] * B[None, 0]
    for j in range(1, A.shape[1]):
        out += A[:, j, None] * B[None, j]
    return out


def _small_inverse(M):
    """``M^-1`` per member (members last, ``M`` (m, m, n)): 2 x 2 by the adjugate, larger by LAPACK;
    NaN where ``M`` is singular.

    Examples
    --------
    >>> M = np.random.default_rng(1).normal(size=(2, 2, 3))
    >>> bool(np.allclose(_product(_small_inverse(M), M), np.eye(2)[:, :, None], rtol=0, atol=1e-13))
    True
    """
    if M.shape[0] != 2:
        return _members_last(_solve(np.moveaxis(M, -1, 0)))
    det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    return np.array([[M[1, 1], -M[0, 1]], [-M[1, 0], M[0, 0]]]) / np.where(det == 0, np.nan, det)


_KEPT_SIZE = 1 << 14
"""Batches up to this size are kept (some megabytes; a map's block is not held after its fit)."""


class _LastReadOut:
    """``_WrittenOut(*args, drives)``, the last one again when the arguments are the same to the bit: a
    least-squares fit asks for the values at a point, then for their partials at the same point, which
    need the same solution.

    >>> args = (np.linspace(1, 3, 4), 0.8, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> read = _LastReadOut()
    >>> read(*args) is read(*args), read(*args) is read(args[0] + 1e-9, *args[1:])
    (True, False)
    """

    def __init__(self):
        self.key, self.lever = None, None

    def __call__(self, *args, drives=DRIVES) -> _WrittenOut:
        arrays = [np.asarray(a) for a in args]
        key = (tuple(drives),) + tuple((a.dtype.str, a.shape, a.tobytes()) for a in arrays)
        if self.lever is not None and self.key == key:
            return self.lever
        lever = _WrittenOut(*arrays, drives=tuple(drives))
        if lever.beta.size <= _KEPT_SIZE:
            self.key, self.lever = key, lever
        return lever


_read_out = _LastReadOut()
"""The NumPy read-out of :func:`response` and :func:`slope_and_jacobian` (one kept, module-wide)."""


KERNELS = True
"""Whether read-outs without a probe run the compiled kernel (:mod:`pfmdyn.composed_kernels`); False:
the NumPy forms (:class:`_WrittenOut`, :class:`_Lever`), the reference the tests hold it to."""


class _Compiled:
    """The read-out of :mod:`pfmdyn.composed_kernels` with :class:`_WrittenOut`'s interface: ``z`` and
    :meth:`partials` (batch first, flat; one column per drive asked), the partials computed with the
    values when ``names`` are given.

    Examples
    --------
    >>> args = (2.5, 0.95, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> bool(np.allclose(_Compiled(*args).z, _WrittenOut(*args).z, rtol=1e-13, atol=0))
    True
    """

    def __init__(self, beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=DRIVES, names=()):
        from . import composed_kernels as kernels

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
        two = bool(np.any(g != 1.0)) or "gamma" in names
        jump, djump = np.empty((n, 12), complex), np.empty((len(names), n, 12), complex)
        kernels.tip_point(beta, k, kvv, kll, kvl, H, L, mu, rho_g,
                          np.array([_POINT.index(p) if p in _POINT else -1 for p in names], np.int64), jump, djump)
        # the load's constant by NumPy's powers: the q0 column's cancellations amplify their last digits
        uc = pieces.load_constant(beta, k, L)
        codes = {"beta": kernels.BETA, "sigma": kernels.SIGMA, "k": kernels.K, "gamma": kernels.GAMMA}
        kinds = np.array([codes.get(p, kernels.TIP) for p in names], np.int64)
        z, dz = np.empty((n, 2, len(DRIVES)), complex), np.empty((n, len(names), 2, len(DRIVES)), complex)
        use = _drive_columns(drives, DRIVES)
        kernels.read_out(beta, sigma, g, uc, k, jump, djump, kinds, two, np.array(use, np.int64), z, dz)
        z, dz = z[..., use], dz[..., use]
        self.z = z.real if real else z
        dz = dz.real if real else dz
        self._partials = {name: dz[:, i] for i, name in enumerate(names)}

    def partials(self, names):
        return {name: self._partials[name] for name in names}

    out = _Lever.out


def _written_out(names=(), probe=None) -> bool:
    """Whether a read-out is written out (:class:`_WrittenOut`, no assembly): all but a probe's and
    the partial w.r.t. ``gamma``, which the assembled system gives."""
    return probe is None and "gamma" not in names


def response(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=TIP_DRIVES, probe=None):
    """Slope ``u'(x_s)`` and deflection ``u(x_s)`` per unit drive: two tuples over ``drives``
    (of :data:`DRIVES`, and of :data:`PROBE_DRIVES` at ``x = probe L`` when ``probe`` is given).
    The deflection is absolute: driven by the base (``y0``), the deflection relative to the base
    is this minus one.

    Examples
    --------
    >>> slopes, deflections = response(2.5, 1.0, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> [f"{v:.8g}" for v in slopes]
    ['7346.2326', '5310.5162', '66.641964', '-0.016021027']
    >>> [round(float(v), 9) for v in response(1e-3, 0.7, 2.0, 0.0, 0.0, 0.0, 1e-5, 2e-4, 0.0, 1.0, 0.0, ("y0",))[1]]
    [1.0]
    """
    if probe is None and KERNELS:
        lever = _Compiled(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=drives)
        z = lever.z
    elif _written_out(probe=probe):
        lever = _read_out(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=drives)
        z = lever.z
    else:
        beta, sigma = np.broadcast_arrays(np.asarray(beta), np.asarray(sigma, dtype=float))
        lever = _Lever(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, probe=probe)
        z = lever.state(lever.reader(sigma))[:, :, _drive_columns(drives, lever.drives)]
    theta = (lever.beta / lever.L)[:, None] * z[:, 1]
    # a copy: the kept read-out (:func:`_read_out`) must not change with what a caller does to it
    return tuple(np.moveaxis(lever.out(theta), -1, 0)), tuple(np.moveaxis(lever.out(z[:, 0].copy()), -1, 0))


def slope(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=TIP_DRIVES):
    """Slope ``u'(sigma L)`` per unit drive (a tuple of arrays over ``drives``, by default ``d1, d2, f0, q0``).

    Examples
    --------
    >>> [f"{v:.8g}" for v in slope(2.5, 0.8, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)]
    ['7446.7015', '3613.9492', '70.728402', '-0.01440258']
    """
    return response(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives)[0]


def deflection(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=TIP_DRIVES):
    """Deflection ``u(sigma L)`` per unit drive (a tuple of arrays over ``drives``; absolute).

    Examples
    --------
    >>> [f"{v:.7g}" for v in deflection(2.5, 0.8, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)]
    ['0.9396194', '0.04499747', '0.00966206', '1.391756e-06']
    """
    return response(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives)[1]


def slope_and_jacobian(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, wrt=SPOT_JACOBIAN_PARAMETERS,
                       drives=TIP_DRIVES):
    """:func:`slope` and its partials w.r.t. :data:`SPOT_JACOBIAN_PARAMETERS` (None where not in ``wrt``).

    Returns
    -------
    values : tuple of ndarray, as :func:`slope`
    jacobian : ``jacobian[i][j]``, the derivative of ``values[i]`` w.r.t. ``SPOT_JACOBIAN_PARAMETERS[j]``

    Examples
    --------
    >>> values, jacobian = slope_and_jacobian(2.5, 0.8, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05,
    ...                                       wrt=('sigma',))
    >>> [f"{v:.8g}" for v in [row[1] for row in jacobian]]
    ['-1968.7118', '15554.443', '-48.327618', '-0.042736975']
    """
    names = [p for p in SPOT_JACOBIAN_PARAMETERS if p in wrt]
    use = _drive_columns(drives, DRIVES)
    if KERNELS:      # every partial, gamma's too
        lever = _Compiled(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=drives, names=tuple(names))
        use = list(range(len(drives)))
        z1, dz = lever.z[:, 1], lever.partials(names)
    elif _written_out(names):
        lever = _read_out(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=drives)
        use = list(range(len(drives)))
        z1, dz = lever.z[:, 1], lever.partials(names)
    else:
        beta, sigma = np.broadcast_arrays(np.asarray(beta), np.asarray(sigma, dtype=float))
        lever = _Lever(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, split="gamma" in names, derivatives=True)
        reader = lever.reader(sigma)
        z1 = lever.state(reader)[:, 1]
        dc = lever.d_system([p for p in names if p != "sigma"])
        dz = {name: lever.d_state(reader, name, dc.get(name, np.zeros_like(lever.c))) for name in names}
    scale = (lever.beta / lever.L)[:, None]
    columns = {}
    for name in names:
        d = scale * dz[name][:, 1]
        columns[name] = lever.out(d + z1 / lever.L[..., None] if name == "beta" else d)
    values = tuple(np.moveaxis(lever.out(scale * z1), -1, 0)[use])
    jac = tuple(tuple(columns[p][..., i] if p in columns else None for p in SPOT_JACOBIAN_PARAMETERS)
                for i in use)
    return values, jac


def _scaled_det(lever):
    """``det A`` times a factor free of zeros that makes it one function of ``beta`` across the bases
    (a short segment's unknowns are its state, a long one's the bounded basis' coefficients) and
    across the one- and two-segment systems; ``d log(factor)/d beta``, ``/d gamma``; the factor."""
    scale, d_beta, d_gamma = (1.0 if lever.two else _ONE_SEGMENT), 0.0, 0.0
    for short, ell, side in zip(lever.short, lever.lengths, (1.0, -1.0)):
        scale = scale * np.where(short, np.exp(-lever.beta * ell), 1.0 / _BOUNDED_AT_START)
        d_beta = d_beta + np.where(short, -ell, 0.0)
        d_gamma = d_gamma + np.where(short, -side * lever.beta, 0.0)
    return _clamped_det(lever.A) * scale, d_beta, d_gamma, scale


def _clamped_det(A):
    """``det A`` by the Schur complement of the clamp's rows: in either basis they read
    ``[I, B]`` on the first segment's unknowns, so ``det A = det(A22 - A21 B)``."""
    return _det(A[:, 2:, 2:] - A[:, 2:, 0:2] @ A[:, 0:2, 2:])


def _by_basis(s, short, long):
    """The arrays (frequencies last) ``short(s)`` gives where ``|s| <= 1`` (the Krylov-Duncan field
    matrix) and ``long(s)`` elsewhere (the bounded basis), as the assembled system chooses (``s`` flat)."""
    is_short = np.abs(s) <= pieces.KD_SERIES_LIMIT
    if is_short.all() or not is_short.any():
        return (short if is_short.all() else long)(s)
    # the bounded basis is finite at any s: everywhere, then the short members overwritten
    out = [np.array(x, np.result_type(s, float)) for x in long(s)]
    for o, x in zip(out, short(s[is_short])):
        o[..., is_short] = x
    return out


def _short_from_clamp(s, derivative=False):
    """A short segment from the clamp: its state at the end per unit of the two unknowns the clamp
    leaves, ``R[m, c]``: its unknowns are its state at the clamp, which zeroes the first two, so ``R``
    is the field matrix's last two columns; and its factor in :func:`_scaled_det`.  With
    ``derivative``, also ``d R/d s`` and ``d log(factor)/d s``."""
    s_1, t, u, v = pieces.krylov_duncan(s)
    K = np.array((s_1 + 1.0, t, u, v))
    out = K[_CIRCULANT[:4, 2:]], np.exp(-s)
    return out + (K[_CIRCULANT[1:, 2:]], np.full(len(s), -1.0)) if derivative else out


def _long_from_clamp(s, derivative=False):
    """:func:`_short_from_clamp` in the bounded basis: the clamp's rows read ``[I, B]``, so
    ``R = E[:, 2:] - E[:, :2] B``; ``s`` moves the segment's end and, in the basis' ``e^{s - s_end}``
    column, its start (``B``'s second column)."""
    rows = np.array(pieces.bounded_basis(s, s)[:20 if derivative else 16]).reshape(-1, 4, len(s))
    at_clamp = pieces.bounded_basis(0.0, s)
    B = np.empty((4, len(s)), np.result_type(s, float))     # contiguous per entry: the products stream
    for i, j in enumerate((2, 3, 6, 7)):
        B[i] = at_clamp[j]
    B = B.reshape(2, 2, -1)
    clamped = lambda E: E[:, 2:] - E[:, 0, None] * B[0] - E[:, 1, None] * B[1]  # noqa: E731
    E = rows[:4]
    out = clamped(E), np.full(len(s), 1.0 / _BOUNDED_AT_START)
    if not derivative:
        return out
    dE = rows[1:].copy()
    dE[:, 3] -= E[:, 3]
    dR = clamped(dE)
    dR[:, 1] += E[:, 0] * B[0, 1] + E[:, 1] * B[1, 1]
    return out + (dR, np.zeros(len(s)))


def _across_tip(R, J):
    """Rows 2, 3 of the state beyond the tip per clamp unknown, ``R[2:] - J R[:2]`` (nested lists)."""
    return [[R[m, c] - J[2 * m - 4] * R[0, c] - J[2 * m - 3] * R[1, c] for c in (0, 1)] for m in (2, 3)]


_PAIRS = np.array([(i, j) for i in range(4) for j in range(i + 1, 4)])
"""Index pairs of the 2 x 2 minors; reversed, each pair's complement."""
_SIGNS = (-1.0) ** (_PAIRS.sum(1)[:, None] + _PAIRS.sum(1)[None, :])


def _minors(X, rows, cols):
    """``det X[r][:, c]`` for the index pairs ``r`` in ``rows``, ``c`` in ``cols`` (X stacked, frequencies last)."""
    r, c = rows[:, None], cols[None, :]
    return X[r[..., 0], c[..., 0]] * X[r[..., 1], c[..., 1]] - X[r[..., 0], c[..., 1]] * X[r[..., 1], c[..., 0]]


def _short_to_free_end(s):
    """A short segment ending free: the weights ``v[K]`` of the minors of the state it starts from
    (rows ``K``, :data:`_PAIRS`, of two states) in the system's determinant, the minors of the free
    end's moment and shear rows of the field matrix (its unknowns are that state: Cauchy-Binet);
    and its factor in :func:`_scaled_det`."""
    s_1, t, u, v = pieces.krylov_duncan(s)
    G = np.array((s_1 + 1.0, t, u, v))[_CIRCULANT[2:4]]
    return _minors(G, _PAIRS[:1], _PAIRS)[0], np.exp(-s)


def _long_to_free_end(s):
    """:func:`_short_to_free_end` in the bounded basis: the segment's unknowns eliminated, the
    determinant is ``det(G E^-1 T) det E`` (``E`` its rows at the start, ``G`` the free end's); by
    Cauchy-Binet and Jacobi's complementary minors it is ``sum g_I (-1)^(I + K) det E[K', I'] t_K``:
    bounded terms, where ``G E^-1`` grows as ``e^s`` in both rows (and their 2 x 2 determinant
    would cancel)."""
    E = np.array(pieces.bounded_basis(np.zeros_like(s), s)[:16] + pieces.bounded_basis(s, s)[8:16]).reshape(6, 4, -1)
    g = _minors(E[4:], _PAIRS[:1], _PAIRS)[0]
    others = _PAIRS[::-1]
    return np.einsum("in,kin->kn", g, _SIGNS[..., None] * _minors(E[:4], others, others)), \
        np.full(len(s), 1.0 / _BOUNDED_AT_START)


def _transferred(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g):
    """:func:`characteristic` without assembling the system.  The segment from the clamp gives the
    tip's state per unit of the two unknowns the clamp leaves, ``R`` (4 x 2); the tip's jump ``J``
    maps it across, ``T = R`` but for rows 2, 3, ``R[2:] - J R[:2]``.  With the tip at the end the
    determinant is ``det T[2:]`` (the Schur complement of the clamp's rows); with a segment beyond,
    ``sum_K v[K] det T[K]`` over the row pairs ``K`` (:func:`_long_to_free_end`).  Times the
    segments' factors, written out over the arguments' broadcast shape; the segments depend on
    ``beta`` and ``gamma`` alone: evaluated once for a grid of springs.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> lever = _Lever(*args)           # the assembled system it stands for
    >>> f"{_transferred(*args) / _scaled_det(lever)[0][0]:.12f}"
    '1.000000000000'
    """
    beta, g = np.asarray(beta), np.real(np.asarray(gamma))
    if g.ndim and (g == g.flat[0]).all():           # one tip position: the segments once per beta
        g = g.flat[0]
    s = beta * g
    R, factor = (x.reshape(x.shape[:-1] + s.shape) for x in _by_basis(s.reshape(-1), _short_from_clamp,
                                                                        _long_from_clamp))
    T = [[R[0, 0], R[0, 1]], [R[1, 0], R[1, 1]]] + _across_tip(R, pieces.point_jump(beta, k, kvv, kll, kvl, H, L, mu,
                                                                                        rho_g))
    if not _tip_at_end(g):
        s = beta * (1.0 - g)
        v, beyond = _by_basis(s.reshape(-1), _short_to_free_end, _long_to_free_end)
        v, factor = v.reshape((6,) + s.shape), factor * beyond.reshape(s.shape)
        return sum(v[K] * (T[i][0] * T[j][1] - T[i][1] * T[j][0]) for K, (i, j) in enumerate(_PAIRS)) * factor
    return (T[2][0] * T[3][1] - T[2][1] * T[3][0]) * factor


def characteristic(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g):
    """The composed lever's characteristic: its zeros in ``beta`` are the resonances.

    The determinant of the assembled system, scaled (by ``e^{-beta l}`` per short segment) so that it
    is one analytic function of ``beta`` whichever basis each segment uses; formed without assembling
    the system (:func:`_transferred`).

    Examples
    --------
    >>> from scipy.optimize import brentq
    >>> f = lambda b: characteristic(b, 2.0, 0.0, 0.0, 0.0, 1e-5, 2e-4, 0.0, 1.0, 0.0)
    >>> round(brentq(f, 1.5, 2.5), 10)          # the free lever's first root
    1.8751040687
    """
    if KERNELS:
        return _compiled_characteristic(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)
    return _shaped(_transferred(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g), gamma)


def _compiled_characteristic(*args):
    """:func:`characteristic` by the compiled kernel (:func:`pfmdyn.composed_kernels.characteristic`,
    :func:`_transferred` step for step) for one lever or a column of levers against a row of ``beta``
    (other shapes: :func:`_transferred`).

    >>> args = (np.linspace(0.5, 30.0, 7), 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> bool(np.allclose(_compiled_characteristic(*args), _transferred(*args), rtol=1e-13, atol=0))
    True
    """
    from . import composed_kernels as kernels

    arrays = [np.asarray(a) for a in args]
    dtype = np.result_type(*arrays, float)
    if all(a.ndim == 0 for a in arrays[1:]):        # one lever: its parameters once
        params, shape = np.array([[a.item() for a in arrays[1:]]], dtype), arrays[0].shape
    elif arrays[0].ndim == 1 and all(a.shape in ((), (a.size, 1)) for a in arrays[1:]):
        # levers as a column against a row of beta (a start grid's)
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        params = np.stack([np.broadcast_to(a, shape[:1] + (1,))[:, 0] for a in arrays[1:]], -1).astype(dtype)
    else:
        return _shaped(_transferred(*args), args[8])
    out = np.empty((len(params), arrays[0].size), dtype)
    # beta copied: writable (a read-only view compiles again) and flat
    kernels.characteristic(np.array(arrays[0], dtype).reshape(-1), params, out)
    return out.reshape(shape)


def _tip_at_end(gamma) -> bool:
    """Whether the tip is at the free end throughout: one segment."""
    return bool(np.all(np.asarray(gamma) == 1.0))


def _shaped(out, gamma):
    """``out`` as an array of the arguments' broadcast shape (``gamma`` may be wider than the rest)."""
    shape = np.broadcast_shapes(np.shape(out), np.shape(gamma))
    return np.asarray(out) if np.shape(out) == shape else np.broadcast_to(out, shape).copy()


def _tip_at_end_and_partials(beta, k, kvv, kll, kvl, H, L, mu, rho_g, names):
    """:func:`_transferred` with the tip at the end (``det T[2:]`` times the segment's factor) and its
    partials ``{name: value}`` w.r.t. ``names`` (of :data:`JACOBIAN_PARAMETERS` but ``gamma``), by the
    product rule: the tip's parameters move ``J`` alone, ``beta`` also the segment and its factor.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.05)
    >>> det, partials = _tip_at_end_and_partials(*args, ["beta", "kvv"])
    >>> step = 1e-6
    >>> up, down = (_tip_at_end_and_partials(2.5 + h, *args[1:], [])[0] for h in (step, -step))
    >>> f"{partials['beta'] / ((up - down) / (2 * step)):.6f}"
    '1.000000'
    """
    beta = np.asarray(beta)
    R, factor, dR, d_log = (x.reshape(x.shape[:-1] + beta.shape) for x in _by_basis(
        beta.reshape(-1), lambda s: _short_from_clamp(s, True), lambda s: _long_from_clamp(s, True)))
    point = (beta, k, kvv, kll, kvl, H, L, mu, rho_g)
    J, dJ = pieces.point_jump(*point), pieces.point_jump_partials(*point, wrt=names)
    T = _across_tip(R, J)
    det = T[0][0] * T[1][1] - T[0][1] * T[1][0]
    partials = {}
    for name in names:
        moved = _across_tip(np.concatenate([R[:2], np.zeros_like(R[2:])]), dJ[name])   # -dJ R[:2]
        if name == "beta":
            moved = [[a + b for a, b in zip(*rows)] for rows in zip(moved, _across_tip(dR, J))]
        d = moved[0][0] * T[1][1] + T[0][0] * moved[1][1] - moved[0][1] * T[1][0] - T[0][1] * moved[1][0]
        partials[name] = (d + det * d_log if name == "beta" else d) * factor
    return det * factor, partials


def _compiled_tip_at_end(beta, k, kvv, kll, kvl, H, L, mu, rho_g, names):
    """:func:`_tip_at_end_and_partials` of one lever by the compiled kernel
    (:func:`pfmdyn.composed_kernels.tip_at_end_and_partials`).

    >>> args = (np.array([2.5, 7.0]), 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.05, ["beta", "kvv", "mu"])
    >>> (det, d), (want, d_want) = _compiled_tip_at_end(*args), _tip_at_end_and_partials(*args)
    >>> bool(np.allclose(det, want, rtol=1e-13, atol=0) and all(np.allclose(d[p], d_want[p], rtol=1e-12, atol=0) for p in d))
    True
    """
    from . import composed_kernels as kernels

    beta = np.asarray(beta)
    dtype = np.result_type(beta, k, kvv, kll, kvl, mu, rho_g, float)
    flat = np.array(beta.reshape(-1), dtype)       # writable and C-ordered: one specialisation to compile
    point = (flat, k, kvv, kll, kvl, H, L, mu, rho_g)
    jump = _columns(pieces.point_jump(*point), len(flat), dtype)
    partials = pieces.point_jump_partials(*point, wrt=names)
    djump = np.ascontiguousarray(np.stack([_columns(partials[p], len(flat), dtype) for p in names])) if names \
        else np.zeros((0, len(flat), 12), dtype)
    out, d = np.empty(len(flat), dtype), np.empty((len(names), len(flat)), dtype)
    kernels.tip_at_end_and_partials(flat, jump, djump, names.index("beta") if "beta" in names else -1, out, d)
    return out.reshape(beta.shape), {p: d[i].reshape(beta.shape) for i, p in enumerate(names)}


def characteristic_and_jacobian(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, wrt=JACOBIAN_PARAMETERS):
    """:func:`characteristic` and its partials w.r.t. :data:`JACOBIAN_PARAMETERS` (None where not in ``wrt``).

    At a zero only their ratios matter: a resonance moves with ``p`` as ``d beta/d p = -D_p / D_beta``.

    Examples
    --------
    >>> value, partials = characteristic_and_jacobian(1.8751040687, 2.0, 0.0, 0.0, 0.0, 1e-5, 2e-4, 0.0, 1.0, 0.0)
    >>> round(float(-partials[5] / partials[0]), 6)     # d beta1 / d mu of a free lever: -beta1
    -1.875104
    """
    if "gamma" not in wrt and _tip_at_end(gamma):
        tip_at_end = _compiled_tip_at_end if KERNELS and all(np.ndim(a) == 0 for a in (k, kvv, kll, kvl, H, L, mu, rho_g)) \
            else _tip_at_end_and_partials
        det, partials = tip_at_end(beta, k, kvv, kll, kvl, H, L, mu, rho_g, [p for p in JACOBIAN_PARAMETERS if p in wrt])
        return _shaped(det, gamma), tuple(_shaped(partials[p], gamma) if p in partials else None
                                          for p in JACOBIAN_PARAMETERS)
    lever = _Lever(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, split="gamma" in wrt)
    det, d_beta, d_gamma, scale = _scaled_det(lever)
    # Jacobi's formula d det = tr(adj(A) dA), the adjugate from the SVD: finite at a resonance,
    # where A is singular and its inverse is not.
    adjugate = _adjugate(lever.A) * scale[:, None, None]
    at_tip = [p for p in JACOBIAN_PARAMETERS if p in wrt and p in _POINT and p != "beta"]
    partials = dict(zip(at_tip, lever.d_det_at_tip(adjugate, at_tip)))
    for name in (p for p in JACOBIAN_PARAMETERS if p in wrt and p not in partials):
        d = np.einsum("nij,nji->n", adjugate, lever.d_system_matrix(name))
        partials[name] = d + det * (d_beta if name == "beta" else d_gamma if name == "gamma" else 0.0)
    return lever.out(det), tuple(lever.out(partials[p]) if p in partials else None for p in JACOBIAN_PARAMETERS)


def _det(A):
    with np.errstate(all="ignore"):
        return np.linalg.det(A)


def _adjugate(A):
    """``adj(A) = det(A) A^-1`` batched, from the SVD ``A = U diag(s) V^H``: ``det(U) det(V^H)
    V diag(prod_{j != i} s_j) U^H``, finite where ``A`` is singular."""
    u, sv, vh = np.linalg.svd(A)
    n = sv.shape[-1]
    others = np.stack([np.prod(np.delete(sv, i, axis=-1), axis=-1) for i in range(n)], -1)
    phase = np.linalg.det(u) * np.linalg.det(vh)
    return phase[:, None, None] * np.conj(np.swapaxes(vh, -1, -2)) @ (others[..., :, None] * np.conj(np.swapaxes(u, -1, -2)))


def _one_segment_factor() -> float:
    """``det`` of the two-segment system with a zero-length second segment over the one-segment
    ``det`` (a fixed sign: the second segment's unknowns are its state, eliminated by permutation)."""
    args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-5, 2e-4, 0.1, 1.0, 0.05)
    ratio = float(np.linalg.det(_Lever(*args, split=True).A)[0] / np.linalg.det(_Lever(*args).A)[0])
    return round(ratio)


_ONE_SEGMENT = _one_segment_factor()


class Reading:
    """Where an engine reads the lever: at the free end (``at_end``: arguments as the
    characteristic's) or at a laser spot (``at_spot``: ``sigma`` after ``beta``).  One forward
    model, :func:`slope_and_jacobian`, behind both.

    Examples
    --------
    >>> args = (2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> bool(at_end.slope(2.5, *args)[0] == at_spot.slope(2.5, 1.0, *args)[0])
    True
    """

    def __init__(self, spot: bool):
        self.spot = spot
        self.JACOBIAN_PARAMETERS = SPOT_JACOBIAN_PARAMETERS if spot else JACOBIAN_PARAMETERS

    def _split(self, beta, args):
        return (args[0], args[1:]) if self.spot else (1.0, args)

    def slope(self, beta, *args):
        sigma, params = self._split(beta, args)
        return slope(beta, sigma, *params)

    def slope_and_jacobian(self, beta, *args, wrt=None):
        sigma, params = self._split(beta, args)
        wrt = self.JACOBIAN_PARAMETERS if wrt is None else wrt
        values, jac = slope_and_jacobian(beta, sigma, *params, wrt=wrt)
        keep = [SPOT_JACOBIAN_PARAMETERS.index(p) for p in self.JACOBIAN_PARAMETERS]
        return values, tuple(tuple(row[j] for j in keep) for row in jac)


at_end, at_spot = Reading(False), Reading(True)
