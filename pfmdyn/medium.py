"""The fluid around the lever: a viscous :class:`Medium` and the load it puts on a vibrating lever.

The load per unit length is Sader's ``(pi/4) rho omega**2 b**2 Gamma(Re)``, ``Re = rho omega b**2/(4 eta)``
(Sader 1998, J. Appl. Phys. 84, 64; derived and checked in ``derivations/hydrodynamics.py``, claims
``calibrate.*``).  ``Gamma = Omega(log10 Re) Gamma_circ(Re)``: the exact circular-cylinder function (generated
``formulas.circular_hydrodynamic_function``) times Sader's *fitted* rectangular correction (generated
``formulas.rectangular_correction_*``), which he states accurate to 0.1 % for ``1e-6 <= Re <= 1e4``;
outside that range :func:`hydrodynamic_function` is NaN (undetermined), never extrapolated.

Sign convention.  :func:`hydrodynamic_function` is Sader's (time ``exp(-i omega t)``, loss ``Gamma_i > 0``),
so its numbers are the published ones.  pfmdyn's time dependence is ``exp(+i omega t)``
(``derivations/damping.py``: viscous drag is ``beta**4 (1 - i g/r)``), so :func:`load_ratio` is its complex
conjugate over the lever's mass per length: a lever in the fluid has ``beta_fluid**4 = beta**4 (1 +
load_ratio)``, real part added mass, imaginary part (negative) the loss; its first mode has
``Q = (1 + Re load) / (-Im load) > 0``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constants import ROOM_TEMPERATURE
from .errors import UserError
from .generated import formulas

__all__ = ["Medium", "reynolds_number", "hydrodynamic_function", "load_ratio", "mass_per_length", "VALID_REYNOLDS"]

VALID_REYNOLDS = (1e-6, 1e4)
"""Where Sader's rectangular correction was fitted (his stated range)."""

# Dry air as an ideal gas at one standard atmosphere (molar mass of dry air, CODATA gas constant).
_ATMOSPHERE, _AIR_MOLAR_MASS, _GAS_CONSTANT = 101325.0, 0.0289647, 8.314462618
# Sutherland's law for air (White, Viscous Fluid Flow, 3rd ed., Table 1-2): mu0 at T0, constant S.
_SUTHERLAND = (1.716e-5, 273.15, 110.4)
# Water density: Tanaka et al. 2001, Metrologia 38, 301 (CIPM, 0-40 C): a1..a5 in C, C, C^2, C, kg/m^3.
_TANAKA = (-3.983035, 301.797, 522528.9, 69.34881, 999.974950)
# Water viscosity: Vogel's equation mu = A 10^(B/(T - C)) (A Pa s, B and C in K), within 2.5 % over 0-100 C.
_VOGEL = (2.414e-5, 247.8, 140.0)
# Where each is that phase at one atmosphere: air a gas well above its condensation (~80 K) and where
# Sutherland's law holds; water liquid between its melting and boiling points.
_PHASES = {"air": (150.0, 2000.0, "a gas"), "water": (273.15, 373.15, "liquid")}


@dataclass(frozen=True)
class Medium:
    """A Newtonian fluid: ``density`` (kg/m^3) and dynamic ``viscosity`` (Pa s); ``name`` for reports.

    >>> Medium(1000.0, 1e-3).kinematic_viscosity
    1e-06
    """

    density: float
    viscosity: float
    name: str = "fluid"
    temperature: float | None = None
    """K, for air and water (their properties follow it); None for a fluid given by its numbers."""

    def __post_init__(self):
        if not (math.isfinite(self.density) and math.isfinite(self.viscosity) and self.density > 0
                and self.viscosity > 0):
            raise UserError(f"a medium needs a positive density and viscosity, got {self.density}, {self.viscosity}")

    @property
    def kinematic_viscosity(self) -> float:
        """``eta / rho`` (m^2/s)."""
        return self.viscosity / self.density

    @classmethod
    def air(cls, temperature: float = ROOM_TEMPERATURE) -> "Medium":
        """Dry air at one atmosphere and ``temperature`` (K): ideal gas, Sutherland's viscosity.

        >>> m = Medium.air(313.15); round(m.density, 3), round(m.viscosity * 1e5, 3)
        (1.127, 1.907)
        """
        t = _in_phase("air", temperature)
        mu0, t0, s = _SUTHERLAND
        return cls(_ATMOSPHERE * _AIR_MOLAR_MASS / (_GAS_CONSTANT * t), mu0 * (t / t0)**1.5 * (t0 + s) / (t + s),
                   f"air at {t - 273.15:g} C", t)

    @classmethod
    def water(cls, temperature: float = ROOM_TEMPERATURE) -> "Medium":
        """Pure water at ``temperature`` (K, 273.15-373.15): Tanaka's density (fitted 0-40 C, used to 100 C),
        Vogel's viscosity.

        >>> m = Medium.water(298.15); round(m.density, 2), round(m.viscosity * 1e3, 3)
        (997.05, 0.89)
        """
        t = _in_phase("water", temperature)
        a1, a2, a3, a4, a5 = _TANAKA
        c = t - 273.15
        density = a5 * (1 - (c + a1)**2 * (c + a2) / (a3 * (c + a4)))
        a, b, c0 = _VOGEL
        return cls(density, a * 10**(b / (t - c0)), f"water at {c:g} C", t)

    @classmethod
    def parse(cls, text: str, temperature: float = ROOM_TEMPERATURE) -> "Medium":
        """``air``, ``water`` (at ``temperature``, K) or ``DENSITY,VISCOSITY`` (kg/m^3, Pa s).

        >>> Medium.parse("1.2,1.8e-5").density, Medium.parse("Water").name
        (1.2, 'water at 20 C')
        >>> Medium.parse("oil")
        Traceback (most recent call last):
        ...
        pfmdyn.errors.UserError: medium must be air, water or DENSITY,VISCOSITY (kg/m^3,Pa s), got 'oil'
        """
        word = str(text).strip().lower()
        if word in ("air", "water"):
            return getattr(cls, word)(temperature)
        parts = word.split(",")
        try:
            density, viscosity = (float(p) for p in parts)
        except ValueError:
            raise UserError(f"medium must be air, water or DENSITY,VISCOSITY (kg/m^3,Pa s), got {text!r}") from None
        return cls(density, viscosity, f"fluid of {density:g} kg/m^3, {viscosity:g} Pa s")


def _in_phase(word: str, temperature) -> float:
    """``temperature`` (K) checked against the phase of ``word`` (air, water) at one atmosphere; a value
    that reads as degrees Celsius (its kelvin in the range) is named so.

    >>> _in_phase("air", "313.15")
    313.15
    >>> _in_phase("air", 25)
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: air is a gas at temperatures from 150 to 2000 K (one atmosphere), got 25 K: did you mean 298.15 K (25 C)?
    """
    low, high, phase = _PHASES[word]
    try:
        t = float(temperature)
    except (TypeError, ValueError):
        t = math.nan
    if not low <= t <= high:
        got = f"{t:g} K" if math.isfinite(t) else repr(temperature)
        hint = f": did you mean {t + 273.15:g} K ({t:g} C)?" if low <= t + 273.15 <= high else ""
        raise UserError(f"{word} is {phase} at temperatures from {low:g} to {high:g} K (one atmosphere), "
                        f"got {got}{hint}", quantity="temperature")
    return t


def reynolds_number(medium: Medium, frequency_hz, width: float):
    """``Re = rho omega b**2 / (4 eta)`` of a lever of width ``b`` (m) at ``frequency_hz``.

    >>> round(float(reynolds_number(Medium(1000.0, 1e-3), 1e4, 4e-5)), 4)
    25.1327
    """
    f = np.asarray(frequency_hz)
    f = f.astype(complex if np.iscomplexobj(f) else float)
    return medium.density * 2 * np.pi * f * width**2 / (4 * medium.viscosity)


def hydrodynamic_function(reynolds):
    """Sader's ``Gamma(Re)`` of a thin rectangular beam (his convention, ``Gamma_i > 0``); NaN outside
    :data:`VALID_REYNOLDS`.

    >>> g = hydrodynamic_function(1.0); round(g.real, 4), round(g.imag, 4)
    (3.734, 4.0746)
    """
    # the conjugate of the analytic continuation pfmdyn's time convention uses, on real Re
    out = np.conj(_conjugate_function(np.asarray(reynolds, dtype=float)))
    return complex(out) if out.ndim == 0 else out


def load_ratio(medium: Medium, frequency_hz, width: float, mass_per_length: float):
    """The fluid's load over the lever's inertia, pfmdyn's convention: ``beta_fluid**4 = beta**4 (1 + load)``,
    ``load = pi rho b**2 conj(Gamma(Re)) / (4 m)`` with ``m = rho_c h b`` (kg/m); real part added mass,
    imaginary part (negative: ``exp(+i omega t)``) the loss.

    >>> r = load_ratio(Medium.air(313.15), 1.8e5, 4e-5, 3.9e-7)
    >>> round(r.real, 5), round(r.imag, 5), round((1 + r.real) / -r.imag)    # the first mode's Q
    (0.00577, -0.00209, 481)
    """
    out = np.pi * medium.density * width**2 * _conjugate_function(reynolds_number(medium, frequency_hz, width))
    out = out / (4 * mass_per_length)
    return complex(out) if np.ndim(out) == 0 else out


def _conjugate_function(reynolds):
    """``conj(Gamma(Re))`` for real ``Re``, continued analytically to complex ``Re`` (a damped mode's
    frequency): ``i`` turned to ``-i`` in the circular function, the correction's real coefficients
    kept (both generated).  NaN where ``Re.real`` is outside :data:`VALID_REYNOLDS`."""
    re = np.asarray(reynolds, dtype=complex)
    inside = (re.real >= VALID_REYNOLDS[0]) & (re.real <= VALID_REYNOLDS[1])
    safe = np.where(inside, re, 1.0)
    circular = formulas.circular_hydrodynamic_function(safe)
    tau = np.log10(safe)
    omega = formulas.rectangular_correction_real(tau) - 1j * formulas.rectangular_correction_imag(tau)
    return np.where(inside, omega * circular, np.nan + 1j * np.nan)


def mass_per_length(spring_constant: float, length: float, free_resonance: float) -> float:
    """``rho_c h b = k beta1**4 / (3 L omega1**2)`` (kg/m) from the spring constant, the length and the first
    resonance *in vacuum* (Hz).

    >>> round(mass_per_length(27.0, 225e-6, 1.8e5) * 1e7, 4)
    3.866
    """
    return float(formulas.mass_per_length(spring_constant, length, free_resonance))
