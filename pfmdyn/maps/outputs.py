"""The per-pixel maps a beam map fit writes: each one's unit and meaning, what a model must hold
(damping mechanisms, a bias axis) to write it, and how the fit reports it.
"""
from __future__ import annotations

from . import bias as bias_axis

__all__ = ["ALWAYS", "SCALED", "quantities"]

# name -> (unit, description) of the per-pixel output arrays
_QUANTITIES = {
    "k1": ("N/m", "vertical contact stiffness"),
    "k1_stderr": ("N/m", "standard error of k1: the fit's and, as pfmdyn stiffness states them, the tip "
                  "height's share (k2 tied or held; attribute tip_height_uncertainty) and, with k2 tied by an "
                  "assumed Poisson's ratio, the tie's (Poisson 0.2-0.4)"),
    "k2": ("N/m", "longitudinal contact stiffness (two or more bands; else NaN)"),
    "k2_stderr": ("N/m", "standard error of k2"),
    "quality_factor": ("1", "quality factor Q of the beam loss 1/Q (internal friction)"),
    "quality_factor_stderr": ("1", "standard error of Q"),
    "viscous_loss": ("1", "viscous drag g = c / (rho S omega1): 1/Q of free mode 1 under drag alone"),
    "viscous_loss_stderr": ("1", "standard error of viscous_loss"),
    "contact_loss": ("1", "contact dashpot x = omega1 eta / k1: loss tangent of the contact at f1"),
    "contact_loss_stderr": ("1", "standard error of contact_loss"),
    "amplitude": ("response units per unit d1",
                  "d_eff amplitude |c| (first band; with biases the response at V = V_surf: intercept + V_surf slope)"),
    "amplitude_stderr": ("response units per unit d1", "standard error of amplitude"),
    "phase": ("rad", "d_eff phase arg c (first band)"),
    **bias_axis.QUANTITIES, **bias_axis.DISTRIBUTED, **bias_axis.SURFACE,
    "gap": ("1", "noise-normalised RMS residual sqrt(mean |y - model|^2) / sigma: 1 = fitted to the noise "
                 "(sigma from the pixel's spectra, pfmdyn.fitting.noise, as pfmdyn discrepancy)"),
    "at_bound": ("1", "1 where a fitted parameter sits at its bound: the model cannot reach the data there, "
                      "so nothing is reported for the pixel"),
    "explained": ("1", "1 where the model explains the pixel (gap below the threshold, default 2, no parameter at "
                       "a bound), else 0"),
}
_REQUIRES = {"viscous_loss": {"viscous"}, "viscous_loss_stderr": {"viscous"},
             "contact_loss": {"contact"}, "contact_loss_stderr": {"contact"},
             **dict.fromkeys(bias_axis.QUANTITIES, {"bias"}), **dict.fromkeys(bias_axis.DISTRIBUTED, {"distributed"}),
             **dict.fromkeys(bias_axis.SURFACE, {"distributed", "bias"})}
"""What a model must hold (mechanisms, a bias axis) to write a quantity (others: always)."""


def quantities(mechanisms=("internal",), bias: bool = False) -> dict[str, tuple[str, str]]:
    """Output arrays (name -> (unit, description)) of a model with these damping mechanisms
    (and the electrostatic maps when the map has a ``bias`` axis).

    >>> list(quantities(("internal", "viscous")))[4:8]
    ['quality_factor', 'quality_factor_stderr', 'viscous_loss', 'viscous_loss_stderr']
    >>> [name for name in quantities(bias=True) if "bias" in name]
    ['nulling_bias', 'nulling_bias_stderr']
    """
    have = set(mechanisms) | ({"bias"} if bias else set())
    return {name: v for name, v in _QUANTITIES.items() if _REQUIRES.get(name, set()) <= have}


ALWAYS = {"gap", "at_bound", "explained", "cost"}
"""Outputs reported at every pixel, also where the fit sits at a bound."""


SCALED = {"amplitude", "amplitude_stderr", "electrostatic", "electrostatic_stderr"}
"""Linear maps in response units (the fit works on spectra scaled to unit norm)."""
