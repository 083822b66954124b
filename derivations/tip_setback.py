"""Tip set back from the free end: tip at ``x = gamma L``, beam free beyond it, slope read at L.

Equation: Eq. 2, ``u0'''' = kappa**4 u0 + q0/EI``, on two segments, ``0 < x < gamma L``
(clamped at 0, Eq. 3) and ``gamma L < x < L`` (free at L: ``u0''(L) = u0'''(L) = 0``).  At
the tip ``x = a = gamma L`` the displacement and slope are continuous and the tip loads
make the moment and the shear jump (left minus right)::

    EI [u0''(a-) - u0''(a+)]   = H F_l + J omega**2 u0'(a)           (Eq. 4a moved to a)
    EI [u0'''(a-) - u0'''(a+)] = -(F_v + f0 + m_t omega**2 u0(a))   (Eq. 4b moved to a)

With nothing beyond the tip (``a = L``) these are Eq. 4a,b.  The moment jump is the
external couple on the beam at ``a``, counter-clockwise positive (the sense in which
``u0'`` grows: an end couple ``C`` on a cantilever gives ``EI u0''(L) = C``).  ``H F_l``
is the couple of the longitudinal spring force acting ``H`` below the neutral axis;
``J omega**2 u0'(a)`` is the couple returned by the tip body, which resists angular
acceleration (``J = m_t r_g**2``, :func:`derivations.tip_mass.rotary_inertia`): it enters
the moment as the point mass enters the shear, and ``rho_g = r_g / L = 0`` is the
solution without it.  The spring forces are those of
:mod:`derivations.tilt`, ``F = -K (w - d)`` with ``K = [[kvv, kvl], [kvl, kll]]`` in beam
axes (``kvv = k1``, ``kll = k2``, ``kvl = 0`` without tilt), and the tip-mass term is that of
:mod:`derivations.tip_mass`, ``m_t omega**2 = mu k beta**4 / 3``, with the rotary term
``J omega**2 = mu k beta**4 L**2 rho_g**2 / 3``.  So the one
solution carries every geometric effect of the discrepancy library and they compose:
set-back alone is ``mu = 0``, ``kvl = 0``; a point-mass tip is ``rho_g = 0``; the paper's
model is additionally ``gamma = 1``.

Solver: eight constants, reduced to two by transfer matrices.  The field matrix
``F(l)`` maps the state ``[u, u', u'', u''']`` of the homogeneous equation over a length
``l``; it is ``Phi(l) Phi(0)**-1`` with ``Phi`` the fundamental matrix of
:func:`derivations.beam.general_solution`.  The constant particular solution
``u_p = -q0 / (EI kappa**4)`` carries the load.  The clamp fixes two state components at
0, the free end gives two equations for the unknown ``u''(0)``, ``u'''(0)``: a 2x2
Cramer system.  Results are polynomials in the atoms of ``a = gamma beta`` and
``b = eta beta`` (``eta = 1 - gamma``), put in a canonical normal form
(``sin**2 = 1 - cos**2`` and ``sinh**2 = cosh**2 - 1`` for each argument).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .beam import EI, H, L, beta, d1, d2, f0, general_solution, kappa, q0, x
from .tilt import kll, kvl, kvv
from .tip_mass import inertial_stiffness, rho_g, rotary_inertia  # noqa: F401 (rho_g: codegen's symbol)
from .trig import atoms, from_atoms, normal_form, to_atoms

__all__ = ["gamma", "eta", "ATOMS_A", "ATOMS_B", "field_matrix", "SetbackSolution", "solve", "to_functions", "DRIVES"]

gamma, eta = sp.symbols("gamma eta", positive=True)
"""Tip position ``a = gamma L`` and overhang ``eta = 1 - gamma`` (fractions of L)."""

ATOMS_A, ATOMS_B = atoms("a"), atoms("b")
"""Atoms (cos, sin, cosh, sinh) of ``a = gamma beta`` and of ``b = eta beta``."""

DRIVES = (d1, d2, f0, q0)


@lru_cache(maxsize=None)
def field_matrix(fraction: sp.Symbol, at=None) -> sp.Matrix:
    """State transfer matrix over ``fraction * L`` of the unloaded beam, in atoms.

    ``at``: the atoms of ``fraction * beta`` (default: :data:`ATOMS_A` for ``gamma``, else
    :data:`ATOMS_B`).

    >>> F = field_matrix(gamma)
    >>> F.subs({ATOMS_A[0]: 1, ATOMS_A[1]: 0, ATOMS_A[2]: 1, ATOMS_A[3]: 0})   # zero length
    Matrix([
    [1, 0, 0, 0],
    [0, 1, 0, 0],
    [0, 0, 1, 0],
    [0, 0, 0, 1]])
    """
    u, consts = general_solution()
    u = u.subs(q0, 0)
    phi = sp.Matrix([[sp.diff(u, x, n).diff(c) for c in consts] for n in range(4)])
    at = at or (ATOMS_A if fraction == gamma else ATOMS_B)
    at_l = to_atoms(phi.subs(x, fraction * L), beta * fraction, at)
    F = at_l * phi.subs(x, 0).inv()
    return F.applyfunc(lambda e: normal_form(sp.cancel(e), at))


@dataclass(frozen=True)
class SetbackSolution:
    """``theta = u0'(L)`` and ``u0(L)`` as ``numerator[drive] / denominator``, in atoms.

    Parameters carried: ``k, kvv, kll, kvl, H, L, mu, rho_g`` and ``beta``; ``gamma`` enters only
    through the atoms of ``a = gamma beta`` and ``b = (1 - gamma) beta``.
    """

    denominator: sp.Expr
    slope: dict
    deflection: dict
    clamp: tuple = ()
    """``(det, {drive: numerators of u''(0), u'''(0) over det})``, unreduced: the clamp state,
    from which :mod:`derivations.detection` reads the beam anywhere (every tip term flows in)."""

    def theta(self, drive: sp.Symbol) -> sp.Expr:
        """Tip slope at L per unit ``drive``, in atoms."""
        return self.slope[drive] / self.denominator


def _reduce(exprs: list[sp.Expr], sets=(ATOMS_A, ATOMS_B)) -> list[sp.Expr]:
    """Normal forms over one monomial denominator, common monomial and integer content removed.

    ``sets``: the atom sets the expressions are polynomials in.

    Only monomial factors are removed: the normalisation is fixed but arbitrary (compare
    by ratio), as in :func:`derivations.beam.solve_tip_problem`.
    """
    terms = [t for e in exprs for t in sp.Add.make_args(sp.expand(e))]
    common = sp.lcm_list([t.as_numer_denom()[1] for t in terms])
    nums = [normal_form(sp.expand(e * common), *sets) for e in exprs]
    gens = sorted(set().union(*[n.free_symbols for n in nums]), key=str)
    polys = [sp.Poly(n, *gens) for n in nums]
    nonzero = [p for p in polys if not p.is_zero]
    lowest = [min(m[i] for p in nonzero for m in p.monoms()) for i in range(len(gens))]
    content = sp.gcd_list([p.content() for p in nonzero])
    factor = content * sp.Mul(*[g**e for g, e in zip(gens, lowest)])
    out = [sp.expand(n / factor) for n in nums]
    lead = sp.Poly(out[0], *gens).LC()
    return [-e for e in out] if lead < 0 else out


@lru_cache(maxsize=None)
def solve() -> SetbackSolution:
    """Solve the two-segment problem by transfer matrices and 2x2 Cramer (see module).

    >>> sol = solve()
    >>> sorted(map(str, sol.slope))
    ['d1', 'd2', 'f0', 'q0']
    """
    m0, v0, u_p = sp.symbols("m0 v0 u_p")
    z_a = field_matrix(gamma) * sp.Matrix([-u_p, 0, m0, v0])
    u_a, slope_a = z_a[0] + u_p, z_a[1]
    force_v = -(kvv * (u_a - d1) + kvl * (H * slope_a - d2))
    force_l = -(kvl * (u_a - d1) + kll * (H * slope_a - d2))
    total = force_v + f0 + inertial_stiffness() * u_a
    couple = H * force_l + rotary_inertia() * slope_a
    z_b = sp.Matrix([z_a[0], z_a[1], z_a[2] - couple / EI, z_a[3] + total / EI])
    z_l = (field_matrix(eta) * z_b).applyfunc(sp.expand)
    # Cramer on the free-end equations z_l[2] = z_l[3] = 0 (linear in m0, v0), then
    # theta = z_l[1] and u(L) = z_l[0] + u_p with m0, v0 replaced, all times det.
    (a, b), (c, d) = [[sp.expand(z_l[i].coeff(s)) for s in (m0, v0)] for i in (2, 3)]
    e = [sp.expand(-z_l[i].subs({m0: 0, v0: 0})) for i in (2, 3)]
    det = sp.expand(a * d - b * c)
    m0_det, v0_det = sp.expand(e[0] * d - b * e[1]), sp.expand(a * e[1] - c * e[0])

    def times_det(expr):
        lin = [sp.expand(expr.coeff(s)) for s in (m0, v0)]
        rest = sp.expand(expr.subs({m0: 0, v0: 0}))
        return sp.expand(lin[0] * m0_det + lin[1] * v0_det + rest * det)

    # The load acts through u_p = -q0 / (EI kappa**4) only.
    load = {u_p: -q0 / (EI * kappa**4)}
    slope_l = sp.expand(times_det(z_l[1]).subs(load))
    defl_l = sp.expand(times_det(z_l[0] + u_p).subs(load))
    outputs = [det] + [slope_l.coeff(dr) for dr in DRIVES] + [defl_l.coeff(dr) for dr in DRIVES]
    reduced = _reduce(outputs)
    clamp = {dr: tuple(sp.expand(e.subs(load)).coeff(dr) for e in (m0_det, v0_det)) for dr in DRIVES}
    return SetbackSolution(reduced[0], dict(zip(DRIVES, reduced[1:5])),
                           dict(zip(DRIVES, reduced[5:9])), (det, clamp))


def to_functions(expr: sp.Expr) -> sp.Expr:
    """Replace the atoms by cos, sin, cosh, sinh of ``gamma beta`` and ``(1 - gamma) beta``.

    >>> to_functions(ATOMS_B[0])
    cos(beta*(1 - gamma))
    """
    return from_atoms(from_atoms(expr, beta * gamma, ATOMS_A), beta * (1 - gamma), ATOMS_B)
