"""Frequency-bias response diagrams of vertical PFM (Section IV.2, Figs. 6 and 7).

The vertical signal is the measured height ``A = (2L/3) theta`` (Section III.2) per unit
``V_ac`` for frictionless contact (Eq. 23, ``k2 -> 0``: vertical coupling only, which is
what the text of IV.2 describes; Eq. 28, which the paper cites for Fig. 6, has no
distributed load, see ``generated/errata.md``, ``fig6.model_reference``).  Three drives add:

* electromechanical, ``d1 = d_eff V_ac`` (bias independent);
* local electrostatic, ``f0 = s F_loc dV V_ac`` on the tip;
* non-local electrostatic, ``q0 = s eps0 w dV V_ac / H**2`` per unit length of the cantilever
  (the first harmonic of the force ``s eps0 w (V_tip - V_surf)**2 / (2 H**2)``; Eq. 36 has an
  extra 1/2, erratum ``eq36.q0``),

with ``dV = V_dc - V_surf``.  Signs follow the project convention
(``pfmdyn.derivations.paper.convention``: ``u``, ``d1``, ``f0``, ``q0`` positive away from the
surface).  The capacitive force is attractive, so ``s = electrostatic_sign = -1`` by default;
``+1`` gives the paper's drives as printed (a repulsive force), for comparison.  Because
the bias enters linearly, the transfer coefficients are evaluated once per frequency and
the map is ``A(f, V) = P(f) + (G_loc(f) + G_nl(f)) dV``.

The paper reads the slope at the free end.  A lever with its laser spot elsewhere
(``Cantilever.spot_position``, ``x_s/L``; or any other departure from the paper's probe: a
set-back, heavy or tilted tip) is evaluated on the composed model read at the spot
(:meth:`pfmdyn.Cantilever.response`, :mod:`pfmdyn.composed`) with ``k2 = 0`` as in
Eq. 23, and its slope is turned into a height with the same ``2L/3`` the instrument would use.
The shares and the dominance do not depend on that factor; at a blind spot of the distributed
load (``pfmdyn spot``) the non-local part vanishes.

:func:`response_map` computes the map; :func:`pfmdyn.plots.diagram.plot_diagram` draws the
amplitude, phase, dominance (Fig. 6 b,d,f) and three-colour (Fig. 7) maps, and
:mod:`pfmdyn.commands.diagram` is the ``pfmdyn diagram`` subcommand.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..cantilever import Cantilever, Contact
from ..generated import formulas, paper_inputs

__all__ = ["EPSILON_0", "SILICON_DENSITY", "TABLE1", "ResponseMap", "table1_cantilever",
           "cantilever_from_spring_constant", "response_map", "nulling_bias",
           "low_frequency_crossover_bias"]

EPSILON_0 = paper_inputs.EPSILON_0
"""Vacuum permittivity, F/m."""
SILICON_DENSITY = paper_inputs.SILICON_DENSITY
"""kg/m**3."""
TABLE1 = {name: (c["w"], c["h"], c["L"], c["k"]) for name, c in paper_inputs.TABLE1.items()}
"""Table 1 of the paper: width, thickness, length (m), spring constant (N/m)."""
# Parameters of Section IV.2 (SI): tip height, d_eff, contact stiffness (F_loc is 0 in
# Fig. 6, 14 nN/V or 0.7 nN/V in Fig. 7, so it has no single default but 0).
PAPER_TIP_HEIGHT = paper_inputs.TIP_HEIGHT
PAPER_D_EFF = paper_inputs.D_EFF_FIG
PAPER_K1 = paper_inputs.CONTACT_K1


def cantilever_from_spring_constant(*, spring_constant, length, width, thickness,
                                    density=SILICON_DENSITY, quality_factor=math.inf) -> Cantilever:
    """Rectangular cantilever whose Young's modulus is chosen to reproduce ``spring_constant``.

    ``E = 4 k L**3 / (w h**3)`` (from ``k = E w h**3 / (4 L**3)``, Section III.2); the first
    free resonance then follows from the geometry and ``density``.  Table 1 prints ``k``
    and the geometry but no modulus; this keeps the printed ``k`` exact (the implied
    moduli, 162-167 GPa, are those of silicon).

    Parameters
    ----------
    spring_constant : float
        ``k`` in N/m (> 0).
    length, width, thickness : float
        ``L``, ``w``, ``h`` in m (> 0).
    density : float, optional
        kg/m**3, silicon by default.
    quality_factor : float, optional
        ``Q`` of the internal friction (complex modulus ``E (1 + i/Q)``, :class:`Cantilever`);
        ``inf`` (default) is the paper's lossless model.

    Returns
    -------
    Cantilever

    Examples
    --------
    >>> c = cantilever_from_spring_constant(spring_constant=45.0, length=224e-6,
    ...                                     width=24e-6, thickness=8e-6)
    >>> round(c.spring_constant, 6), round(c.free_resonance / 1e3, 1)   # N/m, kHz
    (45.0, 216.5)
    """
    for name, value in [("spring_constant", spring_constant), ("length", length),
                        ("width", width), ("thickness", thickness), ("density", density)]:
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    modulus = formulas.youngs_modulus_from_spring_constant(spring_constant, width, thickness, length)
    return Cantilever.from_geometry(length=length, width=width, thickness=thickness,
                                    youngs_modulus=modulus, density=density,
                                    quality_factor=quality_factor)


def table1_cantilever(name, *, quality_factor=math.inf) -> Cantilever:
    """Cantilever ``"A"``, ``"B"`` or ``"C"`` of Table 1 (silicon, printed ``k``).

    Examples
    --------
    >>> [round(table1_cantilever(n).free_resonance / 1e3, 1) for n in "ABC"]   # kHz
    [216.5, 81.6, 28.2]
    """
    if name not in TABLE1:
        raise ValueError(f"unknown cantilever {name!r}: choose one of {', '.join(TABLE1)}")
    width, thickness, length, k = TABLE1[name]
    return cantilever_from_spring_constant(spring_constant=k, length=length, width=width,
                                           thickness=thickness, quality_factor=quality_factor)


@dataclass(frozen=True)
class ResponseMap:
    """Vertical PFM response ``A`` per unit ``V_ac`` (m/V) on a frequency x bias grid.

    The per-frequency coefficients are stored; the 2-D components (shape
    ``(frequency.size, bias.size)``, complex) are computed on access.

    Attributes
    ----------
    frequency_hz, bias_v : ndarray
        Grid axes; ``bias_v`` is ``V_dc``.
    surface_potential_v : float
        ``V_surf``; the electrostatic drives scale with ``dV = V_dc - V_surf``.
    piezo_coefficient : ndarray
        Electromechanical ``A`` per ``V_ac`` (m/V), per frequency.
    local_coefficient, nonlocal_coefficient : ndarray
        Local and non-local electrostatic ``A`` per ``V_ac`` per volt of ``dV`` (m/V**2).
    """

    frequency_hz: np.ndarray
    bias_v: np.ndarray
    surface_potential_v: float
    piezo_coefficient: np.ndarray
    local_coefficient: np.ndarray
    nonlocal_coefficient: np.ndarray

    @property
    def _delta_v(self) -> np.ndarray:
        return (self.bias_v - self.surface_potential_v)[None, :]

    @property
    def piezo(self) -> np.ndarray:
        """Electromechanical part ``A_piezo`` (bias independent, broadcast to the grid)."""
        return np.broadcast_to(self.piezo_coefficient[:, None], (self.frequency_hz.size, self.bias_v.size))

    @property
    def local(self) -> np.ndarray:
        """Local electrostatic part ``A_el``."""
        return self.local_coefficient[:, None] * self._delta_v

    @property
    def nonlocal_(self) -> np.ndarray:
        """Non-local (cantilever buckling) part ``A_nl``; trailing ``_``: ``nonlocal`` is a keyword."""
        return self.nonlocal_coefficient[:, None] * self._delta_v

    @property
    def total(self) -> np.ndarray:
        """``A_piezo + A_el + A_nl``."""
        electrostatic = self.local_coefficient + self.nonlocal_coefficient
        return self.piezo_coefficient[:, None] + electrostatic[:, None] * self._delta_v

    def _magnitudes(self):
        """``|A_piezo|, |A_el|, |A_nl|`` as real outer products (no complex 2-D arrays: faster)."""
        delta = np.abs(self._delta_v)
        return (np.abs(self.piezo_coefficient)[:, None], np.abs(self.local_coefficient)[:, None] * delta,
                np.abs(self.nonlocal_coefficient)[:, None] * delta)

    def dominance(self) -> np.ndarray:
        """``|A_piezo| / (|A_piezo| + |A_nl|)`` (Fig. 6 b,d,f): 1 electromechanical, 0 non-local.

        The paper plots ``A_piezo/(A_piezo + A_nl)``; with complex (or sign-changing) parts
        that ratio is unbounded near the nulling bias, so magnitudes are used: the map
        then reads as the electromechanical share in [0, 1].  The local part is left out,
        as in Fig. 6.  NaN where both parts vanish.
        """
        piezo, _, nonlocal_ = self._magnitudes()
        with np.errstate(invalid="ignore"):
            return piezo / (piezo + nonlocal_)

    def shares(self) -> np.ndarray:
        """Shares ``|A_el|, |A_nl|, |A_piezo|`` over their sum, last axis (R, G, B) as in Fig. 7.

        NaN where all three parts vanish.
        """
        piezo, local, nonlocal_ = self._magnitudes()
        parts = np.broadcast_arrays(local, nonlocal_, piezo)   # R, G, B
        total = local + nonlocal_ + piezo
        out = np.empty(total.shape + (3,))
        with np.errstate(invalid="ignore"):
            for i, part in enumerate(parts):
                np.divide(part, total, out=out[..., i])
        return out


def _coefficients(cantilever, frequency_hz, *, width, k1, H, d_eff, local_force, electrostatic_sign=-1):
    """Per-frequency ``(frequency, P, G_loc, G_nl)``: A per V_ac, and per V_ac per volt of dV."""
    if electrostatic_sign not in (-1, 1):
        raise ValueError(f"electrostatic_sign must be -1 (attractive) or +1, got {electrostatic_sign!r}")
    if not isinstance(cantilever, Cantilever):
        raise TypeError(f"cantilever must be a Cantilever, got {type(cantilever).__name__}")
    for name, value in [("width", width), ("k1", k1), ("H", H)]:
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    for name, value in [("d_eff", d_eff), ("local_force", local_force)]:
        if not np.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
    frequency = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    if frequency.ndim != 1:
        raise ValueError("frequency_hz must be one-dimensional")
    if cantilever.is_paper_probe:
        t = cantilever.frictionless_response(frequency, k1=k1)
    else:       # read at the spot (or with the tip's extras): the composed model, k2 = 0 as in Eq. 23
        t = replace(cantilever, tip_height=H).response(frequency, Contact(k1=k1))
    to_height = formulas.height_per_slope(cantilever.length)   # A = 2 theta L / 3 (Section III.2)
    s = electrostatic_sign * to_height
    return (frequency, to_height * d_eff * t.vertical, s * local_force * t.local_force,
            s * formulas.capacitive_load_per_volt2(EPSILON_0, width, H) * t.distributed_load)


def response_map(cantilever, frequency_hz, bias_v, *, width, k1=PAPER_K1, H=PAPER_TIP_HEIGHT,
                 d_eff=PAPER_D_EFF, local_force=0.0, surface_potential_v=0.0,
                 electrostatic_sign=-1) -> ResponseMap:
    """Vertical PFM response per unit ``V_ac`` over frequency x bias (Figs. 6-7).

    Parameters
    ----------
    cantilever : Cantilever
        E.g. from :func:`table1_cantilever`; its ``quality_factor`` sets the losses and its
        ``spot_position`` where the slope is read (1, the free end, as in the paper; elsewhere
        the frequencies must lie where ``beta > 0.1``, above about 0.3 % of ``f1``).
    frequency_hz : array_like, 1-D
        Drive frequencies, Hz (> 0).
    bias_v : array_like, 1-D
        DC tip bias ``V_dc``, V.
    width : float
        Cantilever width ``w``, m (the non-local load is ``eps0 w dV V_ac / H**2``).
    k1 : float, optional
        Vertical contact stiffness, N/m (Section IV.2: 1000).
    H : float, optional
        Tip height = cantilever-surface separation, m (15 um); also the lever arm of a tilted
        lever's contact (the cantilever's own ``tip_height`` is replaced by it).
    d_eff : float, optional
        Effective piezoelectric coefficient, m/V (5 pm/V); the sign is the domain's.
    local_force : float, optional
        ``F_loc``, N/V: ``f0 = s F_loc dV V_ac`` (Fig. 7: 14 nN/V or 0.7 nN/V; Fig. 6: 0).
    surface_potential_v : float, optional
        ``V_surf``, V.
    electrostatic_sign : {-1, +1}, optional
        ``s``: -1 (default) for the attractive capacitive force of the project's convention,
        +1 for the drives as the paper prints them.

    Returns
    -------
    ResponseMap
        Coefficients per frequency; the bias enters linearly, so a 2000 x 2000 map costs
        2000 transfer evaluations plus one broadcast.

    Examples
    --------
    >>> c = table1_cantilever("A")
    >>> m = response_map(c, [1e3], [0.0, 10.0], width=24e-6)
    >>> round(float(abs(m.total[0, 0])) * 1e12, 3)   # pm/V: k1/(k + k1) d_eff at low frequency
    4.785
    >>> m.dominance()[0].round(3)
    array([1. , 0.8])
    >>> spot = replace(c, spot_position=0.7)            # the laser spot at 0.7 L
    >>> round(float(abs(response_map(spot, [1e3], [0.0], width=24e-6).total[0, 0])) * 1e12, 3)
    4.354
    """
    frequency, piezo, local, nonlocal_ = _coefficients(
        cantilever, frequency_hz, width=width, k1=k1, H=H, d_eff=d_eff, local_force=local_force,
        electrostatic_sign=electrostatic_sign)
    bias = np.atleast_1d(np.asarray(bias_v, dtype=float))
    if bias.ndim != 1 or not np.all(np.isfinite(bias)):
        raise ValueError("bias_v must be a finite one-dimensional array")
    if not np.isfinite(surface_potential_v):
        raise ValueError(f"surface_potential_v must be finite, got {surface_potential_v!r}")
    return ResponseMap(frequency, bias, float(surface_potential_v), piezo, local, nonlocal_)


def nulling_bias(cantilever, frequency_hz, *, width, k1=PAPER_K1, H=PAPER_TIP_HEIGHT,
                 d_eff=PAPER_D_EFF, local_force=0.0, surface_potential_v=0.0,
                 electrostatic_sign=-1) -> np.ndarray:
    """DC bias minimising ``|A|`` at each frequency (where the PFM signal is nulled).

    With ``A = P + G (V - V_surf)``, ``G = G_loc + G_nl``, the real ``V`` minimising
    ``|A|**2`` is ``V_null = V_surf - Re(P conj(G)) / |G|**2``.  Without losses ``P/G`` is
    real and ``A(V_null) = 0`` exactly; with losses ``|A(V_null)|`` is the residual
    ``|Im(P conj(G))| / |G|``.  NaN where ``G = 0`` (no electrostatic drive).

    Parameters are those of :func:`response_map`.

    Returns
    -------
    ndarray
        ``V_null`` per frequency, V.

    Examples
    --------
    >>> c = table1_cantilever("B")
    >>> v = nulling_bias(c, [1e3, 5e5], width=24e-6)
    >>> m = response_map(c, [1e3, 5e5], v, width=24e-6)
    >>> bool(abs(m.total[0, 0]) < 1e-9 * abs(m.piezo[0, 0]))
    True
    """
    _, piezo, local, nonlocal_ = _coefficients(
        cantilever, frequency_hz, width=width, k1=k1, H=H, d_eff=d_eff, local_force=local_force,
        electrostatic_sign=electrostatic_sign)
    g = local + nonlocal_
    # The response is piezo + g (V - V_surf): intercept piezo - g V_surf, slope g.
    with np.errstate(invalid="ignore", divide="ignore"):
        return surface_potential_v + formulas.nulling_bias(piezo.real, piezo.imag, g.real, g.imag)


def low_frequency_crossover_bias(cantilever, *, width, k1=PAPER_K1, H=PAPER_TIP_HEIGHT,
                                 d_eff=PAPER_D_EFF) -> float:
    """``|dV|`` at which ``|A_nl| = |A_piezo|`` far below the first contact resonance (Fig. 6 arrow).

    The ratio of the electromechanical coefficient to the non-local one per volt, taken from
    the generated transfer functions at a frequency ``1e-6 f1`` (their series branch: the
    static limit of Eq. 23).  For ``k1 >> k`` it grows in proportion to ``k``; it is
    infinite at ``k1 = 8k``, where the static non-local slope vanishes.  The paper's probe
    only: a lever read elsewhere than at its free end has no series branch to take the static
    limit from (ValueError; its static blind spot is ``pfmdyn spot``'s).

    Examples
    --------
    >>> [round(low_frequency_crossover_bias(table1_cantilever(n), width=24e-6), 3) for n in "ABC"]
    [39.883, 1.388, 0.057]
    """
    if not cantilever.is_paper_probe:
        raise ValueError("the static crossover bias is the paper's probe's (spot at the free end, massless "
                         "tip there, no tilt)")
    static = [1e-6 * cantilever.free_resonance]
    _, piezo, _, nonlocal_ = _coefficients(cantilever, static, width=width, k1=k1, H=H,
                                           d_eff=d_eff, local_force=0.0)
    with np.errstate(divide="ignore"):
        return float(np.abs(piezo[0]) / np.abs(nonlocal_[0]))


# --- plotting: Figure objects saved directly (Agg), no pyplot, so no GUI backend is selected
# and a notebook's pyplot state is left alone.  Bias is horizontal (V) and frequency vertical
# (kHz), as in the paper's measured diagrams (Figs. 8-10): the bias-independent resonance
# lines are horizontal and the linear-in-bias region opens as a V.


# --- command line -------------------------------------------------------------------------
