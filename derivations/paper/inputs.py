"""The paper's inputs, once: Table 1, the tip and contact numbers of Sections III-IV, constants.

Decimal strings as printed (exact: ``sympy.Rational`` and ``mpmath.mpf`` read them without
rounding).  Numeric code reads the same values as floats from ``generated/paper_inputs.py``,
written from this module by ``pfmdyn codegen``.
"""
from __future__ import annotations

__all__ = ["TABLE1", "TIP_HEIGHT", "CONTACT_K1", "K1_OVER_K2", "D_EFF_FIG", "TIP1_CONTACT", "TIP1_FREE",
           "TIP2_FREE", "TIP2_GEOMETRY",
           "TIP1_CONTACT_PM", "TIP1_FREE_PM", "TIP2_FREE_PM", "EPSILON_0", "SILICON_DENSITY", "SILICON_E", "NUMERIC"]

TABLE1 = {"A": {"w": "24e-6", "h": "8e-6", "L": "224e-6", "k": "45"},
          "B": {"w": "24e-6", "h": "3e-6", "L": "224e-6", "k": "2.4"},
          "C": {"w": "24e-6", "h": "1.05e-6", "L": "224e-6", "k": "0.1"}}
"""Table 1: width ``w``, thickness ``h``, length ``L`` (m) and spring constant ``k`` (N/m)."""
TIP_HEIGHT = "15e-6"            # H (m), Section IV.2
CONTACT_K1 = "1000"             # N/m, Section IV.2
K1_OVER_K2 = "0.85"             # Section III.1
D_EFF_FIG = "5e-12"             # m/V, Section IV.2 / Figs. 6-7

# Section VI.1: measured resonances (kHz) of tip 1 (Co-Cr) and tip 2 (Nanosensors), and tip 2's
# geometry as supplied (h is the thickness; f1 its first free resonance, Hz).
TIP1_CONTACT = ("407.95", "1075.020")
TIP1_FREE = ("63.2", "368.33", "1031.70")
TIP2_FREE = ("54.55", "346.73", "980.55")
TIP2_GEOMETRY = {"h": "3e-6", "w": "24e-6", "L": "223e-6", "k": "2.4", "f1": "54.55e3"}
# The uncertainties (kHz) printed with those resonances ("407.95 +- 0.3 kHz", ...).
TIP1_CONTACT_PM = ("0.3", "0.15")
TIP1_FREE_PM = ("0.4", "0.3", "0.2")
TIP2_FREE_PM = ("0.04", "0.05", "0.1")

EPSILON_0 = "8.8541878128e-12"
"""Vacuum permittivity, F/m (CODATA 2018)."""
# Silicon, the material of the cantilevers in Table 1 (not given in the paper): the Young's
# modulus spans the crystal directions; density of crystalline Si.
SILICON_DENSITY = "2330"        # kg/m**3
SILICON_E = ("130e9", "188e9")  # Pa

NUMERIC = {"TABLE1": TABLE1, "TIP_HEIGHT": TIP_HEIGHT, "CONTACT_K1": CONTACT_K1,
           "D_EFF_FIG": D_EFF_FIG, "EPSILON_0": EPSILON_0, "SILICON_DENSITY": SILICON_DENSITY,
           "TIP1_CONTACT_KHZ": TIP1_CONTACT, "TIP1_FREE_KHZ": TIP1_FREE, "TIP2_FREE_KHZ": TIP2_FREE,
           "TIP2_GEOMETRY": TIP2_GEOMETRY}
"""The inputs numeric code uses, as written to ``generated/paper_inputs.py`` (as floats)."""
