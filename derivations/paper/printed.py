"""Printed equations and numbers of Jesse, Baddorf & Kalinin (2006), as SymPy objects.

Each entry is keyed by its claim id (``../shared/claims.yaml``; ids verbatim) and holds
the paper's statement exactly as printed, typos included.  These expressions are only
ever compared with the derivations; no result of pfmdyn is computed from them.

Symbols are shared with :mod:`derivations.beam` and :mod:`derivations.torsion` so that a
printed form and its derived counterpart can be compared directly.
"""
from __future__ import annotations

import sympy as sp

from ..beam import H, L, beta as b, d1, d2, f0, k, k1, k2, kappa, q0
from ..sliding_friction import f_l
from ..torsion import d3, f_lat, k2t, xi
from .inputs import (CONTACT_K1, D_EFF_FIG, K1_OVER_K2, TABLE1, TIP1_CONTACT, TIP1_FREE,  # noqa: F401 (P.TABLE1, ...)
                     TIP2_FREE, TIP2_GEOMETRY, TIP_HEIGHT)

c, s, ch, sh = sp.cos(b), sp.sin(b), sp.cosh(b), sp.sinh(b)

# --- Section III.2, Eqs. 5-10: the general elastic-contact solution -----------------------
A_v = 3 * b**4 * k1 * k * L * s * sh                                            # Eq. 6
A_l = 3 * b**2 * H * k2 * (3 * k1 + ch * (-3 * k1 * c + b**3 * k * s) + b**3 * k * c * sh)  # Eq. 7
A_e = 3 * b**4 * k * L * s * sh                                                 # Eq. 8
A_q = 3 * L**2 * (3 * k1 * (c - ch) - k * b**3 * s + (k * b**3 + 3 * k1 * s) * sh)  # Eq. 9
N = b**2 * (9 * H**2 * k1 * k2 + b**4 * k**2 * L**2
            + ch * ((-9 * H**2 * k1 * k2 + b**4 * k**2 * L**2) * c
                    + 3 * b * k * (k1 * L**2 + H**2 * k2 * b**2) * s)
            + 3 * b * k * (-k1 * L**2 + H**2 * k2 * b**2) * c * sh)            # Eq. 10
ELASTIC = {d1: A_v, d2: A_l, f0: A_e, q0: A_q}

# Eqs. 11-14: beta -> 0 limits of A_x/N, exact form and the paper's approximation.
_den = 4 * k * (k + k1) * L**2 + 3 * H**2 * k2 * (4 * k + k1)
LOW_FREQUENCY = {
    d1: (6 * k1 * k * L / _den, 6 * k * L / (4 * k * L**2 + 3 * H**2 * k2)),
    d2: (3 * H * k2 * (4 * k + k1) / _den, 3 * H * k2 / (4 * k * L**2 + 3 * H**2 * k2)),
    f0: (6 * k * L / _den, 6 * k * L / (k1 * (4 * k * L**2 + 3 * H**2 * k2))),
    q0: ((8 * k - k1) * L**2 / (16 * k * (k + k1) * L**2 + 12 * H**2 * k2 * (4 * k + k1)),
         L**2 / (4 * (4 * k * L**2 + 3 * H**2 * k2))),
}

# Eqs. 15-18: high-frequency exponents of |A_x/N| in omega (A_v/N also proportional to k1).
HIGH_FREQUENCY_EXPONENT = {d1: sp.Integer(-1), d2: sp.Rational(-1, 2), f0: sp.Integer(-1),
                           q0: sp.Rational(-3, 2)}

# --- Section III.3: supported and free cantilevers ------------------------------------------
theta_nlc = 3 * q0 / (k * b**3) * (c - ch + s * sh) / (ch * s - c * sh)          # Eq. 20
pinned_roots = ("3.927", "7.067", "10.21")
pinned_static_theta = q0 / (16 * k)
pinned_static_A = q0 * L / (24 * k)
theta_f = -(-3 * L * q0 * s + 3 * (L * q0 + b * f0 * s) * sh) / (k * b**3 * L * (1 + ch * c))  # Eq. 22
free_static_theta = q0 / (2 * k) + 3 * f0 / (2 * k * L)
free_static_A = q0 * L / (3 * k) + f0 / k
nonlocal_free_to_supported = 8
free_roots = ("1.875", "4.694", "7.855")
contact_to_free_ratio = "4.4"

# --- Section III.4: frictionless contact and sliding friction -------------------------------
FRICTIONLESS = {
    d1: 3 * b**4 * k1 * k * s * sh,                                             # Eq. 23a
    d2: sp.Integer(0),                                                          # Eq. 23b
    f0: 3 * b**4 * k * s * sh,                                                  # Eq. 23c
    q0: 3 * L * (3 * k1 * (c - ch) - k * b**3 * s + (k * b**3 + 3 * k1 * s) * sh),  # Eq. 23d
}
N_frictionless = b**3 * k * L * (b**3 * k + ch * (b**3 * k * c + 3 * b * k1 * s) - 3 * k1 * c * sh)  # 23f
theta_p_stiff = ((3 * L * q0 * (c - ch) + (d1 * k * b**4 + L * q0) * s * sh)
                 / (b**3 * k * L * (ch * s - c * sh)))                          # Eq. 24
theta_friction = 3 * f_l * H * (ch * s + c * sh) / (b * k * L**2 * (1 + c * ch))  # Eq. 26

# --- Section III.5: piezoelectric nanoindentation ----------------------------------------
u_indentation = (3 * (f0 + d1 * k1) * (c * ch - 1)
                 / (b**3 * k + ch * (3 * k1 * s - b**3 * k * c) - 3 * k1 * c * sh))  # Eq. 27
theta_indentation = (3 * b * (f0 + d1 * k1) * s * sh
                     / (L * (b**3 * k + ch * (b**3 * k * c + 3 * k1 * s) - 3 * k1 * c * sh)))  # Eq. 28
indentation_static = 3 * (f0 + d1 * k1) / ((2 * k1 + 2 * k) * L)
stiff_static_theta, stiff_static_A = 3 * d1 / (2 * L), d1
free_static_theta_28, free_static_A_28 = -3 * f0 / (2 * k * L), -f0 / k
nonpiezo_static_theta, nonpiezo_static_A = -3 * f0 / (2 * k1 * L), -f0 / k1
theta_stiff_dynamic = -d1 * kappa * s * sh / (ch * s - c * sh)                   # Eq. 29

# --- Section III.6: torsion ------------------------------------------------------------------
torsion_elastic = d3 * k2t * sp.sin(xi * L) / (xi * sp.cos(xi * L) + H * k2t * sp.sin(xi * L))  # Eq. 33
torsion_stiff_limit, torsion_free_limit = d3 / H, sp.Integer(0)
torsion_force = f_lat * sp.tan(xi * L) / xi                                     # Eq. 35
n = sp.Symbol("n", positive=True, integer=True)
torsion_force_roots = (2 * n - 1) * sp.pi / L                                   # xi_n as printed

# --- Printed parameters used in Sections IV-VI -------------------------------------------------
# TABLE1, TIP_HEIGHT, CONTACT_K1, K1_OVER_K2, D_EFF_FIG: see paper/inputs.py (imported above).

# --- Section III.1: contact mechanics numbers --------------------------------------------------
hertz_coefficient = "1.82"
PIEZO_INDENTATION = {"C1": "403e9", "C3": "15.4", "R": "50e-9", "P": "100e-9"}   # SI
piezo_depth_angstrom = "3.01"
piezo_k1 = ("993", "63.3")                   # k1 = (993 - 63.3 V) N/m
lateral_ratio_formula = "2*(1 - nu)/(1 - 2*nu)"   # printed as k1/k2
lateral_ratio_value = "0.85"
F_loc, A_el_pm = "1.4e-8", "14"              # N/V, pm/V (with k1 = 1000 N/m)

# --- Section VI.1: measured resonances (kHz) and printed ratios ---------------------------------
# (the measured resonances and tip 2's geometry are inputs: derivations/paper/inputs.py)
TIP1_CONTACT_RATIO, TIP1_CONTACT_THEORY = "2.63", "3.24"
TIP1_FREE_RATIOS = ("5.83", "16.32")         # w2/w1, w3/w1
TIP2_FREE_RATIOS = ("6.35", "17.97")
FREE_THEORY_RATIOS = ("6.23", "17.55")

# --- Section IV.1: cantilever (non-local) contribution ------------------------------------------
eps0, S_area, V_ac, dV, w_c = sp.symbols("epsilon0 S V_ac DeltaV w", positive=True)
q0_cap = eps0 * S_area * V_ac * dV / (2 * L * H**2)                       # first harmonic, per length
A_nl = -L * w_c * eps0 * V_ac * dV / (48 * k * H**2)
PR_eq36_extra = L * w_c * eps0 * V_ac * dV / (48 * k * H**2)              # PR = d_eff + this
KEFF_INPUTS = {"d_eff": "50e-12", "dV": "5", "L": "225e-6", "w": "30e-6", "H": "15e-6"}
keff_printed = "0.55"
# --- Section IV.2 / Fig. 7 --------------------------------------------------------------------
LOCAL_FORCE_TEXT = "14e-9"                # N/V, Section IV.2
LOCAL_FORCE_CAPTION = ("14", "0.7")       # N/V, caption of Fig. 7

# --- Section IV.3: domain contrast (Eqs. 37-40) -------------------------------------------------
d_eff, d_el, psi, phi = sp.symbols("d_eff d_el psi phi", positive=True)
PR_plus_amp = sp.sqrt(d_eff**2 + d_el**2 + d_eff * d_el * sp.cos(phi))
PR_minus_amp = sp.sqrt(d_eff**2 + d_el**2 - d_eff * d_el * sp.cos(phi))
tan_phase = (2 * d_el * (PR_minus_amp - PR_plus_amp) * sp.sin(psi)
             / (d_el**2 * (1 - sp.cos(2 * psi)) + 2 * PR_plus_amp * PR_minus_amp))
small_el_amp = (d_eff + d_el * sp.cos(phi), d_eff - d_el * sp.cos(phi))
small_el_phase = sp.pi - sp.sin(2 * psi) * d_el**2 / d_eff**2                # Eq. 40
small_piezo_amp = (d_el + d_eff * sp.cos(phi), d_el - d_eff * sp.cos(phi))
small_piezo_phase = 2 * sp.sin(2 * psi) * d_eff / (d_el * (sp.cos(2 * psi) - 3))
# --- Section VI.4, Eq. 41 ---------------------------------------------------------------------
G_t, d_t, V_dc, V_surf, b_fit, c_fit = sp.symbols("G_elec d_efft V_dc V_surf b c", real=True)
eq41_G, eq41_d = c_fit, b_fit + c_fit * V_surf
