"""Renderer of ``generated/lever_pieces.py``: the lever's derived pieces (:mod:`derivations.pieces`).

Each piece is small: the segment's field matrix (Krylov-Duncan functions, a series in ``s**4``
for ``|s| <= 1`` and closed in any math namespace for ball arithmetic), the bounded basis, the
load's constant particular solution and the tip point's jump with its partial derivatives.
:mod:`pfmdyn.composed` assembles them.
"""
from __future__ import annotations

import sympy as sp

from .. import pieces
from ..beam import H, L, beta, k
from ..tilt import kll, kvl, kvv
from ..tip_mass import mu, rho_g
from . import examples, templates
from .examples import Example
from .printing import code, cse_lines, header, source_hash

__all__ = ["render", "SERIES_TERMS", "POINT_PARAMETERS", "POINT_JACOBIAN"]

SERIES_TERMS = 8
"""Terms of each Krylov-Duncan series in ``s**4``: the first left out is below 1e-30 at ``|s| = 1``."""
POINT_PARAMETERS = (beta, k, kvv, kll, kvl, H, L, mu, rho_g)
POINT_JACOBIAN = (beta, k, kvv, kll, kvl, mu, rho_g)


def krylov_duncan() -> list[sp.Expr]:
    """``K_j = F[0][j]``, with the check that ``F[n][j] = K[(j - n) % 4]`` (a circulant)."""
    F = pieces.unit_state()
    K = [F[0, j] for j in range(4)]
    assert all(sp.simplify(F[n, j] - K[(j - n) % 4]) == 0 for n in range(4) for j in range(4))
    return K


def _series(expr: sp.Expr, j: int) -> tuple[float, ...]:
    """Coefficients of ``poly`` in ``expr = s**j * poly(s**4)`` (the Taylor series), lowest first."""
    poly = sp.series(expr, pieces.s, 0, 4 * SERIES_TERMS + j).removeO()
    coeffs = [poly.coeff(pieces.s, 4 * i + j) for i in range(SERIES_TERMS)]
    assert sp.expand(poly - sum(c * pieces.s**(4 * i + j) for i, c in enumerate(coeffs))) == 0
    return tuple(float(c) for c in coeffs)


def krylov_duncan_weights(K: list[sp.Expr]) -> list[tuple[int, ...]]:
    """``2 K_j`` as integer weights of ``cosh s, sinh s, cos s, sin s`` (checked to be exact)."""
    basis = (sp.cosh(pieces.s), sp.sinh(pieces.s), sp.cos(pieces.s), sp.sin(pieces.s))
    out = []
    for k in K:
        twice = sp.expand(2 * k)
        weights = tuple(int(twice.coeff(b)) for b in basis)
        assert sp.expand(twice - sum(w * b for w, b in zip(weights, basis))) == 0
        out.append(weights)
    return out


def _in_namespace(expr: sp.Expr) -> str:
    """``expr`` in cos, sin, exp of a math namespace ``m`` (python-flint or mpmath)."""
    e, f = sp.symbols("_e _f")          # exp(s), exp(-s)
    expr = expr.subs({sp.cosh(pieces.s): (e + f) / 2, sp.sinh(pieces.s): (e - f) / 2})
    # integer coefficients over 4: exact on python-flint's rational series too
    text = code(sp.expand(4 * expr)).replace("np.", "m.").replace("_e", "m.exp(s)").replace("_f", "(1 / m.exp(s))")
    return f"({text}) / 4"


def render() -> str:
    """Text of ``generated/lever_pieces.py``."""
    K = krylov_duncan()
    s_minus = [_series(K[0] - 1, 4)] + [_series(K[j], j) for j in (1, 2, 3)]
    B = pieces.bounded_basis()
    J, G = pieces.point_jump()
    jump = list(J) + list(G)
    partials = {str(p): [sp.simplify(e.diff(p)) for e in jump] for p in POINT_JACOBIAN}
    at = examples.arguments(map(str, POINT_PARAMETERS))
    point_example = Example().tuple_of(f"point_jump({at})",
                                       [examples.evaluate(e, POINT_PARAMETERS) for e in jump[:4]],
                                       target=f"point_jump({at})[:4]")
    kd = [K[0] - 1, *K[1:]]
    half = {pieces.s: sp.Rational(1, 2)}
    kd_example = Example().tuple_of("krylov_duncan(0.5)", [sp.N(e.subs(half), 30) for e in kd])
    closed_example = Example().statement("import mpmath").tuple_of(
        "", [sp.N(e.subs(half), 30) for e in K],
        target="map(float, krylov_duncan_closed(mpmath.mpf(0.5), mpmath))")
    sources = [*K, *B, *jump, pieces.load_constant()]
    return templates.render(
        "lever_pieces.py.jinja",
        header=header("derivations/pieces.py: unit_state(), bounded_basis(), load_constant(), point_jump()",
                      source_hash(sources)),
        series=s_minus, closed=[_in_namespace(e) for e in K], weights=krylov_duncan_weights(K),
        bounded=cse_lines(list(B)),
        load=code(pieces.load_constant()), parameters=[str(p) for p in POINT_PARAMETERS],
        # the partials' powers of beta as products: compiled (pfmdyn.composed.kernels.tip_point), a complex
        # power is a general pow, some hundred times a product
        jump=cse_lines(jump), partials={p: [code(e, {beta}) for e in v] for p, v in partials.items()},
        point_example=point_example, kd_example=kd_example, closed_example=closed_example)
