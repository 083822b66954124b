"""Doctest examples of the generated functions, computed at generation time.

Every generated function carries a short example: a call at a stored point (:data:`POINT`)
and its values, evaluated here from the SymPy expression in mpmath (30 digits), never
typed by hand and never by running the generated code.  The values are shown to
:data:`DIGITS` significant digits, fewer when a value lies so close to a rounding boundary
that the generated code's last-bit error could flip the last digit shown.
"""
from __future__ import annotations

import mpmath as mp
import sympy as sp

__all__ = ["beta1_free", "POINT", "DIGITS", "value", "arguments", "evaluate", "derivative", "formatted", "Example"]

DIGITS = 8
"""Significant digits shown."""

_MARGIN = mp.mpf("1e-9")
"""Relative error allowed to the generated code before a shown digit may change."""

DEFAULT = 0.5
"""Example value of an argument :data:`POINT` does not name (checked to give finite values)."""

POINT = {
    # Dimensionless frequency of the transfer modules and the characteristic functions.
    "beta": 2.5, "z": 2.5, "r": 1.5,
    # Lever and tip (SI): spring constant, length, tip height, width, thickness, silicon.
    "k": 2.0, "L": 2e-4, "H": 1e-5, "width": 3e-5, "thickness": 3e-6,
    "youngs_modulus": 1.69e11, "density": 2330.0, "mu": 0.1, "gamma": 0.9,
    # Tip's radius of gyration over L; detection spot position over L.
    "rho_g": 0.05, "sigma": 0.8,
    # Contact (SI): springs, their beam-frame form at alpha = 0.2 rad, torsion, Hertz.
    "k1": 100.0, "k2": 50.0, "kvv": 98.0, "kll": 52.0, "kvl": 9.0, "alpha": 0.2, "k2t": 1e9,
    "tip_radius": 2.5e-8, "load": 1e-8, "nu": 0.3,
    # Dimensionless parameters of the characteristic functions.
    "k1_over_k": 50.0, "k2_ratio": 0.5, "k2t_HL": 2.0,
    # Damping: internal 1/Q, viscous, contact loss tangent.
    "inv_q": 0.01, "g": 0.02, "x": 0.03,
    # Electrostatics and domain contrast (SI).
    "epsilon_0": 8.8541878128e-12, "V_ac": 1.0, "dV": 0.5,
    "b_re": 1.0, "b_im": 0.5, "c_re": -0.2, "c_im": 0.1,
    "d_eff": 5e-11, "d_el": 2e-11, "psi": 0.3, "phi": 0.3, "pr_plus": 4e-11, "pr_minus": 6e-11,
    "g_elec": 2e-11, "v_dc": 1.5, "v_av": 0.2,
    # Relations of derivations/formulas.py: a mode at f (Hz) of a lever with f1, its shifts;
    # losses; a thermal peak; a complex root in units of f1.
    "frequency": 3e5, "free_resonance": 7e4, "d_beta": 0.01, "d_beta1": -0.002,
    "viscous_loss": 0.02, "contact_loss": 0.03,
    "f": 7.2e4, "f0": 7e4, "q": 150.0, "amplitude": 1e-12, "white": 1e-14, "root_re": 1.0, "root_im": 0.005,
    # The SHO of band-excitation tools (Hz): a resonance just below that frequency.
    "resonance_frequency": 2.99e5, "quality_factor": 50.0,
    # Two-frequency oscillator: drives (Hz) about 3e5 and inverse signals of an SHO there (Q 80, D 1).
    "f1": 2.97e5, "f2": 3.05e5, "z1_re": 0.0199, "z1_im": 0.0124, "z2_re": -0.0336, "z2_im": 0.0127,
    # A fluid's Reynolds number rho omega b^2/(4 eta): a lever in water near 10 kHz.
    "reynolds": 1.0,
}
"""Argument name -> its value in the examples (``beta1``: the first free root, derived)."""


def beta1_free(dps: int = 30) -> str:
    """First root of ``1 + cos(beta) cosh(beta)`` (free cantilever), to ``dps`` digits.

    >>> beta1_free(12)
    '1.87510406871'
    """
    with mp.workdps(dps + 10):
        root = mp.findroot(lambda b: mp.cos(b) + mp.sech(b), 1.875)
        return mp.nstr(root, dps, strip_zeros=False)


def value(name: str) -> float:
    """The example value of argument ``name``.

    >>> value("k"), value("beta1")
    (2.0, 1.8751040687)
    """
    if name == "beta1":
        return float(beta1_free(11))
    return POINT.get(name, DEFAULT)


def arguments(names) -> str:
    """The call's argument list at the stored point.

    >>> arguments(["beta", "k", "L"])
    '2.5, 2.0, 0.0002'
    """
    return ", ".join(repr(value(n)) for n in names)


def evaluate(expr: sp.Expr, symbols, dps: int = 30):
    """``expr`` at the stored point of ``symbols`` (an mpmath number).

    >>> b = sp.Symbol("beta")
    >>> mp.nstr(evaluate(sp.cos(b), [b]), 12)
    '-0.801143615547'
    """
    with mp.workdps(dps):
        f = sp.lambdify(list(symbols), expr, "mpmath")
        return f(*[mp.mpf(value(str(s))) for s in symbols])


def derivative(expr: sp.Expr, symbols, wrt: sp.Symbol, dps: int = 30):
    """``d expr / d wrt`` at the stored point (mpmath differentiation of the SymPy expression).

    >>> b = sp.Symbol("beta")
    >>> mp.nstr(derivative(b**3, [b], b), 12)
    '18.75'
    """
    with mp.workdps(dps + 10):
        f = sp.lambdify(list(symbols), expr, "mpmath")
        at = [mp.mpf(value(str(s))) for s in symbols]
        i = list(symbols).index(wrt)
        result = mp.diff(lambda t: f(*at[:i], t, *at[i + 1:]), at[i])
    with mp.workdps(dps):
        return +result


def _shown(v, digits: int) -> str:
    if isinstance(v, mp.mpc) and v.imag != 0:
        return format(complex(v), f".{digits}g")
    return format(float(mp.re(v)), f".{digits}g")


def _stable(v, digits: int) -> bool:
    """The shown text does not change within the error margin."""
    parts = [mp.re(v), mp.im(v)] if isinstance(v, mp.mpc) else [v]
    for i, part in enumerate(parts):
        for sign in (-1, 1):
            moved = list(parts)
            moved[i] = part * (1 + sign * _MARGIN)
            w = mp.mpc(*moved) if len(parts) == 2 else moved[0]
            if _shown(w, digits) != _shown(v, digits):
                return False
    return True


def formatted(values) -> tuple[int, list[str]]:
    """The digits shown and each value's text; raises on values that are not finite.

    >>> formatted([mp.mpf(1) / 3, mp.mpc(0, 2)])
    (8, ['0.33333333', '0+2j'])
    """
    for v in values:
        if not mp.isfinite(v):
            raise ValueError(f"example value {v} is not finite: choose another point in {__name__}.POINT")
    digits = DIGITS
    while digits > 4 and not all(_stable(v, digits) for v in values):
        digits -= 1
    return digits, [_shown(v, digits) for v in values]


class Example:
    """Doctest lines: pairs ``(statement, expected output)`` for the template."""

    def __init__(self):
        self.lines: list[tuple[str, str]] = []

    def tuple_of(self, call: str, values, target: str = "") -> "Example":
        """A call returning a tuple of numbers, shown as their formatted texts.

        >>> Example().tuple_of("f(1.0)", [mp.mpf(2)]).lines
        [('[f"{v:.8g}" for v in f(1.0)]', "['2']")]
        """
        digits, texts = formatted(values)
        self.lines.append((f'[f"{{v:.{digits}g}}" for v in {target or call}]', repr(texts)))
        return self

    def number(self, call: str, v) -> "Example":
        """A call returning one number.

        >>> Example().number("f(1.0)", mp.mpf(2) / 3).lines
        [('f"{f(1.0):.8g}"', "'0.66666667'")]
        """
        digits, (text,) = formatted([v])
        self.lines.append((f'f"{{{call}:.{digits}g}}"', repr(text)))
        return self

    def statement(self, code: str, output: str = "") -> "Example":
        """Any statement and its output (empty: none)."""
        self.lines.append((code, output))
        return self
