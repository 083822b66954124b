"""The one vocabulary of pfmdyn: each physical quantity under one name, one unit, one flag.

The same name is the Python attribute (:class:`pfmdyn.Cantilever`, :class:`pfmdyn.Contact`),
the key of a metadata line in a CSV file, of a JSON report and of a Zarr attribute, and, with
dashes, the command-line flag (``tip_position`` <-> ``--tip-position``).  Values are SI
(tilt in degrees).  Older spellings found in files (``spring_constant_n_per_m``, ``f1``) are
read as :attr:`Quantity.aliases` of the name; nothing writes them.

The README's table of names is :func:`markdown_table` (a test keeps the two equal).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .constants import ROOM_TEMPERATURE, TIP_HEIGHT, TIP_HEIGHT_SPREAD
from .errors import UserError

__all__ = ["Quantity", "QUANTITIES", "NAMES", "LEVER", "CONTACT", "DAMPING", "MEASURED", "CALIBRATION", "GROUPS", "canonical", "flag",
           "checked", "fill_defaults", "markdown_table"]


@dataclass(frozen=True)
class Quantity:
    """One physical quantity: its name, unit, meaning and the values a real probe can have.

    ``low``/``high`` bound plausible values (a value outside is a typo or a unit slip);
    ``open_low`` excludes ``low`` itself (a length cannot be 0, a tip mass can).
    """

    name: str
    symbol: str
    unit: str
    meaning: str
    low: float
    high: float
    open_low: bool = True
    aliases: tuple[str, ...] = ()
    option: bool = True
    """False for a value that files and reports hold but no command takes as a flag (what an
    instrument measured: a contact resonance, a mode's Q, its drive settings)."""
    label: str = ""
    """What reports and messages call it in a few words (default: the name with spaces)."""
    default: float | None = None
    """The value assumed when neither a flag nor a file gives one (reports mark it assumed)."""
    default_why: str = ""
    """Why :attr:`default` is what it is, in a few words (reports say it beside the assumed value)."""

    def __post_init__(self):
        if not self.label:
            object.__setattr__(self, "label", self.name.replace("_", " "))

    @property
    def flag(self) -> str:
        """The command-line flag: ``--`` and the name with dashes."""
        return "--" + self.name.replace("_", "-")


def _report(name, symbol, unit, meaning) -> Quantity:
    """A quantity reports hold and no command takes (no range to check: any finite value)."""
    return Quantity(name, symbol, unit, meaning, -math.inf, math.inf, open_low=False, option=False)


QUANTITIES: tuple[Quantity, ...] = (
    # The lever, its tip and the detection point.
    Quantity("spring_constant", "k", "N/m", "lever spring constant 3 EI / L^3", 1e-4, 1e4,
             aliases=("spring_constant_n_per_m", "k", "k_n_per_m")),
    Quantity("free_resonance", "f1", "Hz", "first free flexural resonance, as measured (with the tip)",
             500.0, 1e8, aliases=("free_resonance_hz", "f1", "f1_hz")),
    Quantity("length", "L", "m", "lever length, clamp to free end", 1e-6, 1e-2, aliases=("length_m",),
             label="lever length"),
    Quantity("width", "w", "m", "lever width", 1e-7, 1e-2, aliases=("width_m",), label="lever width"),
    Quantity("thickness", "t", "m", "lever thickness (geometry input)", 1e-8, 1e-3, aliases=("thickness_m",)),
    Quantity("density", "rho", "kg/m^3", "lever material density (geometry input)", 100.0, 3e4),
    Quantity("tip_height", "H", "m", "tip height, the lever arm of the lateral contact force", 1e-8, 1e-3,
             aliases=("tip_height_m",), default=TIP_HEIGHT,
             default_why=f"a typical PFM probe's, {TIP_HEIGHT * 1e6:g} +/- {TIP_HEIGHT_SPREAD * 1e6:g} um: datasheets "
             "give 10-17 um, no file records it"),
    Quantity("tip_position", "x_tip/L", "1", "where the tip sits along the lever (1: at the free end)",
             0.0, 1.0, aliases=("gamma",)),
    Quantity("tip_mass_ratio", "m_tip/(rho S L)", "1", "tip mass over the lever's mass", 0.0, 100.0,
             open_low=False, aliases=("mu",)),
    Quantity("tip_gyration_radius", "r_g", "m", "tip's radius of gyration about the lever axis "
             "(rotary inertia J = m_tip r_g^2)", 0.0, 1e-3, open_low=False),
    Quantity("tilt", "alpha", "deg", "lever inclination; positive when the free end is nearer the sample "
             "than the clamp (the usual mounting, 10-15 deg)", -45.0, 45.0, open_low=False),
    Quantity("spot_position", "x_s/L", "1", "detection (laser) spot along the lever (1: at the free end)",
             0.0, 1.0),
    # The contact.
    Quantity("k1", "k1", "N/m", "vertical contact stiffness", 0.0, 1e9, open_low=False),
    Quantity("k2", "k2", "N/m", "lateral (longitudinal) contact stiffness", 0.0, 1e9, open_low=False),
    Quantity("k2_over_k1", "k2/k1", "1", "k2 policy: k2 tied to k1 at this ratio", 0.0, 100.0,
             open_low=False),
    # An isotropic solid has -1 < nu <= 1/2 (auxetic samples below 0); the Mindlin ratio holds over all of it.
    Quantity("poisson", "nu", "1", "k2 policy: k2/k1 of a Hertz-Mindlin contact on a sample of this "
             "Poisson's ratio", -1.0, 0.5, aliases=("poisson_ratio",)),
    Quantity("k1_uncertainty", "u(k1)", "N/m", "standard uncertainty of a given k1 (e.g. pfmdyn stiffness's): the "
             "results move by it (default 0: k1 as given, exact)", 0.0, 1e9, open_low=False),
    # What the contact-resonance analysis takes besides the probe (``pfmdyn stiffness``, contact maps).
    Quantity("contact_uncertainty", "u(f_c)", "Hz", "standard uncertainty of each contact resonance frequency",
             0.0, 1e9, open_low=False, aliases=("contact_uncertainty_hz",)),
    Quantity("free_resonance_uncertainty", "u(f1)", "Hz", "standard uncertainty of the free resonance", 0.0, 1e8,
             open_low=False),
    Quantity("spring_constant_uncertainty", "u(k)", "N/m", "standard uncertainty of the spring constant", 0.0, 1e4,
             open_low=False),
    Quantity("tip_height_uncertainty", "u(H)", "m", "standard uncertainty of the tip height (default 10 per cent of "
             "a given one, the spread of PFM probes' datasheets for the assumed one)", 0.0, 1e-3, open_low=False,
             default=TIP_HEIGHT_SPREAD, default_why="of the assumed tip height, the spread of PFM probes' datasheets"),
    Quantity("tip_radius", "R", "m", "tip apex radius of the Hertz contact (for the reduced modulus E*)", 1e-10, 1e-3,
             aliases=("tip_radius_m",)),
    Quantity("normal_load", "P", "N", "normal load on the tip of the Hertz contact (for the reduced modulus E*)",
             0.0, 1.0, aliases=("load_n",)),
    # Damping.
    Quantity("quality_factor", "Q", "1", "internal friction: complex modulus E (1 + i/Q)", 0.1, 1e9,
             aliases=("Q",)),
    Quantity("viscous_loss", "g", "1", "viscous drag c/(rho S omega1): 1/Q of free mode 1 under drag alone",
             0.0, 100.0, open_low=False),
    Quantity("contact_loss", "x", "1", "contact dashpot omega1 eta/k1: loss tangent of the contact at f1",
             0.0, 1e4, open_low=False),
    Quantity("fluid_loss", "g_f", "1", "a fluid's drag at high Reynolds number: half-power width at f1 over f1, "
             "growing as sqrt(f)", 0.0, 100.0, open_low=False, option=False),
    # Calibration of the free lever (``pfmdyn calibrate``): the fluid, the detector, nominal sizes' tolerances.
    Quantity("temperature", "T", "K", "temperature of the lever and the fluid around it", 1.0, 2000.0,
             aliases=("temperature_k",), default=ROOM_TEMPERATURE,
             default_why="room temperature"),
    Quantity("medium", "medium", "1", "fluid around the lever: air, water (at the temperature) or DENSITY,VISCOSITY "
             "(kg/m^3,Pa s)", 0.0, 0.0),
    Quantity("invols", "InvOLS", "m/V", "inverse optical lever sensitivity: static deflection per detector volt",
             1e-12, 1e-3, aliases=("invols_m_per_v",)),
    Quantity("length_uncertainty", "u(L)", "m", "standard uncertainty of a nominal length (default 2 per cent of it)",
             0.0, 1e-2, open_low=False),
    Quantity("width_uncertainty", "u(w)", "m", "standard uncertainty of a nominal width (default 5 per cent of it)",
             0.0, 1e-2, open_low=False),
    # What changed between two drive sweeps (``pfmdyn discrepancy AFTER --reference BEFORE``).
    Quantity("added_mass_position", "x_m/L", "1", "where a point mass added to the free lever sits "
             "(1: at the free end)", 0.0, 1.0),
    Quantity("added_mass", "m_add", "kg", "point mass added to the free lever (a cell), explained from two "
             "drive sweeps", 0.0, 1.0, open_low=False, option=False),
    # What an instrument measured and its settings (instrument files, ``pfmdyn inspect``).
    Quantity("free_quality_factor", "Q_free", "1", "measured Q of the first free resonance (thermal tune fit)",
             0.1, 1e9, option=False, label="free Q"),
    Quantity("amplitude_peak", "f_peak", "Hz", "drive frequency of the largest response amplitude (a drive "
             "sweep's peak; below the resonance when the damping is heavy)", 500.0, 1e8, option=False),
    Quantity("contact_resonance", "f_c", "Hz", "measured first contact resonance (tune fit)", 500.0, 1e9,
             aliases=("contact_resonance_hz",), option=False),
    Quantity("contact_quality_factor", "Q_c", "1", "measured Q of the first contact resonance (tune fit)",
             0.1, 1e9, option=False, label="contact Q"),
    Quantity("drive_frequency", "f_drive", "Hz", "frequency the instrument drove at", 0.0, 1e10,
             aliases=("drive_frequency_hz",)),
    Quantity("tip_bias", "V_tip", "V", "DC bias on the tip", -1e4, 1e4, open_low=False,
             aliases=("tip_bias_v",), option=False),
    # Dual AC resonance tracking (DART) images: the drive, and the maps ``pfmdyn map`` makes of them.
    Quantity("drive_amplitude", "V_ac", "V", "AC drive on the tip, zero-to-peak (DART: DriveAmplitude)", 0.0, 1e3),
    Quantity("frequency_width", "df", "Hz", "DART: spacing f2 - f1 of the two drive frequencies about the tracked "
             "centre (DFRTFrequencyWidth)", 0.0, 1e9),
    Quantity("d_eff", "d_eff", "m/V", "effective piezoelectric coefficient: surface displacement along k1 per tip "
             "volt, signed (> 0: toward the lever in phase with the bias)", -1.0, 1.0, open_low=False),
    Quantity("channel_noise", "sigma", "1", "relative noise of each lock-in signal (circular, complex), estimated "
             "from the image", 0.0, 100.0, open_low=False, option=False),
    Quantity("oscillator_k1", "k1_pm", "N/m", "point-mass contact stiffness k ((f_c/f1)^2 - 1) of the oscillator's "
             "resonance", -1e9, 1e9, option=False, label="point-mass k1"),
    Quantity("oscillator_k1_error", "k1_pm/k1 - 1", "1", "relative difference of the point-mass k1 from the lever's",
             -1e9, 1e9, option=False, label="point-mass k1 error"),
    Quantity("oscillator_d_eff", "d_eff,osc", "m/V", "d_eff read through the oscillator: its static gain as the "
             "point-mass lever's k1/(k + k1), signed by its drive phase", -1.0, 1.0, option=False,
             label="oscillator d_eff"),
    Quantity("oscillator_d_eff_error", "d_eff,osc/d_eff - 1", "1", "relative difference of the oscillator's d_eff "
             "from the lever's (-2: the sign flipped)", -1e9, 1e9, option=False, label="oscillator d_eff error"),
    Quantity("real_drive", "real", "1", "1 where a DART pixel's drive is taken at its domain's phase (one of two per "
             "image: in phase or in antiphase with the bias, but for the lock-ins' offset and a background): its "
             "phases' sum fits the contact beside their ratio; 0 where that misfits by over five standard deviations "
             "(the ratio's contact alone)", 0.0, 1.0,
             open_low=False, option=False),
    # The electrostatic drive of vertical PFM (``pfmdyn diagram``, ``deconvolve``, ``map``).
    Quantity("surface_potential", "V_surf", "V", "surface potential of the sample: the electrostatic drives scale "
             "with V_dc - V_surf", -1e3, 1e3, open_low=False, default=0.0,
             default_why="none measured: d_eff is then the response's part that does not scale with the DC bias"),
    Quantity("local_force", "F_loc", "N/V", "local electrostatic force on the tip per volt of V_ac per volt of "
             "V_dc - V_surf (0 as in Fig. 6; 1.4e-8 or 7e-10 as in Fig. 7)", -1.0, 1.0, open_low=False),
    _report("determined_fraction", "determined", "1", "fraction of a DART image's pixels both inversions determine"),
    # What the reports hold besides the lever and the contact (keys of the JSON documents, pfmdyn.io.results).
    *(_report(name, symbol, unit, meaning) for name, symbol, unit, meaning in (
        # spectra and resonances
        ("resonance", "f_n", "Hz", "a resonance frequency (one per mode: dims mode or row)"),
        ("measured_resonance", "f_meas", "Hz", "a resonance frequency as measured (a table's row, a fit to data, an SHO map)"),
        ("predicted_resonance", "f_model", "Hz", "a resonance frequency of the final model"),
        ("predicted_quality_factor", "Q_model", "1", "a mode's Q the model predicts (all damping together)"),
        ("baseline_resonance", "f_base", "Hz", "a resonance frequency of the paper's model fitted before any effect"),
        ("resonance_uncertainty", "u(f)", "Hz", "standard uncertainty of a measured resonance frequency"),
        ("measured_quality_factor", "Q_meas", "1", "a mode's Q as measured (a table's row, a tune or sweep fit, an "
         "SHO map): the half-power width over the frequency, all damping together"),
        ("quality_factor_uncertainty", "u(Q)/Q", "1", "relative standard uncertainty of a measured Q"),
        ("resonance_interval", "[f_lo, f_hi]", "Hz", "certified enclosure of a resonance frequency"),
        ("complete_below", "f_complete", "Hz", "every resonance below this frequency is listed (certified)"),
        ("condition", "condition", "1", "free or contact: the boundary condition of a mode"),
        ("mode", "n", "1", "mode number (1: the first)"),
        ("certified", "certified", "1", "true when interval arithmetic proves the values"),
        ("vacuum_resonance", "f_vac", "Hz", "first free resonance the lever would have in vacuum"),
        ("viscous_width", "Delta f", "Hz", "half-power width viscous drag gives every peak"),
        ("contact_damping", "eta", "N s/m", "contact dashpot beside k1"),
        ("lever_mass", "m_lever", "kg", "the lever's mass rho S L"),
        ("added_mass_ratio", "m_add/m_lever", "1", "added mass over the lever's mass"),
        ("band", "[f_lo, f_hi]", "Hz", "frequency band of the data analysed (or of a misfit)"),
        ("points", "N", "1", "number of data values (complex values count twice)"),
        ("frequency_stride", "stride", "1", "one frequency in this many analysed (a long file thinned)"),
        ("disagrees", "disagrees", "1", "the quantities whose value differs from the instrument's by more than three of "
         "our standard uncertainties"),
        # drive sweeps and thermal tunes
        ("gain", "G", "data/rad", "detector gain: signal (in the data's unit, the notes say which) per lever slope"),
        ("background", "b", "data", "additive background of a sweep, in the data's unit (constant and linear "
         "coefficients)"),
        ("amplitude_only", "amplitude only", "1", "true when the sweep holds no phase"),
        ("phase_reversed", "phase reversed", "1", "true when the instrument's phase runs the other way"),
        ("detection_scale", "s_det", "1", "measured over predicted thermal spectrum: the detection's calibration"),
        ("white_floor", "S_white", "m/sqrt(Hz)", "white noise floor of a thermal spectrum"),
        ("matching_spring_constant", "k_det", "N/m", "the spring constant at which a thermal tune's detection_scale is 1"),
        # calibration
        ("thermal_spring_constant", "k_th", "N/m", "spring constant from the thermal tune (equipartition)"),
        ("sader_spring_constant", "k_Sader", "N/m", "spring constant from Sader's hydrodynamic method"),
        ("relative_uncertainty", "u_r", "1", "a relative standard uncertainty (a budget's share)"),
        ("uncertainty_source", "source", "1", "what a share of an uncertainty budget comes from"),
        ("input_name", "input", "1", "an input of a calculation, by its name"),
        ("consistent", "consistent", "1", "true when the two spring constants agree within their uncertainties"),
        ("correction_factor", "factor", "1", "the factor an input would need for the methods to agree"),
        # contact stiffness from contact resonances (pfmdyn stiffness)
        ("k1_over_k", "k1/k", "1", "contact stiffness over the lever's spring constant"),
        ("k1_by_mode", "k1_n", "N/m", "k1 from each contact mode alone (dims mode)"),
        ("reduced_modulus", "E*", "Pa", "reduced modulus of a Hertz contact from k1"),
        ("residual_beta", "r_beta", "1", "largest residual of the characteristic equations at the solution"),
        ("unique", "unique", "1", "true when exactly one solution explains the resonances under what was stated"),
        # maps (pfmdyn map, pfmdyn stiffness on a contact-frequency map)
        ("pixels", "ny, nx", "1", "the map's size in pixels (dims axis: y, x)"),
        ("explained_fraction", "explained", "1", "fraction of pixels the model explains (gap at or below the threshold)"),
        ("at_bound_fraction", "at bound", "1", "fraction of pixels with a parameter at a bound (left unexplained)"),
        ("median_gap", "median gap", "1", "median of the map's gap"),
        ("median_k1", "median k1", "N/m", "median of the map's k1"),
        ("median_nulling_bias", "median V_null", "V", "median of the map's nulling bias"),
        ("blocks_run", "blocks run", "1", "blocks fitted by this run"),
        ("blocks_done", "blocks done", "1", "blocks done, this run and earlier ones"),
        ("blocks_total", "blocks", "1", "blocks of the map"),
        ("pixels_fitted", "pixels fitted", "1", "pixels fitted by this run"),
        ("pixels_per_second", "pixels/s", "1/s", "pixels fitted per second of this run"),
        # modes, spot, roots (pfmdyn resonances, spot, roots)
        ("frequency", "f", "Hz", "the frequency analysed"),
        ("damped_resonance", "f_d", "Hz", "a damped mode's frequency (the real part of its complex root)"),
        ("beta", "beta", "1", "dimensionless wavenumber of the lever at a frequency (beta^4 ~ f)"),
        ("blind_spot", "x_blind/L", "1", "spot positions where the vertical signal vanishes"),
        ("blind_spot_interval", "[x_lo, x_hi]/L", "1", "certified enclosure of a blind spot"),
        ("slope_ratio", "theta_q0/theta_d1", "m^2/N", "slope per surface charge over slope per d1 along the lever"),
        ("free_sensitivity", "S_free", "1", "optical-lever sensitivity of the free lever at the spot (per tip height)"),
        ("contact_sensitivity", "S_contact", "1", "optical-lever sensitivity in contact at the spot (per tip height)"),
        ("calibration_factor", "C", "1", "contact over free sensitivity: the factor a free-lever calibration misses"),
        ("paper_calibration_factor", "C_paper", "1", "the calibration factor of the paper's lever (spot at the end)"),
        ("d_eff_error_per_volt", "delta d_eff", "m/V^2", "error of d_eff per volt of V_dc - V_surf from the "
         "distributed electrostatic load"),
        ("root", "z_n", "1", "a root of a characteristic equation (decimal strings where digits are asked: roots)"),
        ("root_interval", "[z_lo, z_hi]", "1", "certified enclosure of a root (decimal strings)"),
        # resonance branches against contact stiffness (pfmdyn branches)
        ("k2_ratio", "k2 H^2/(k L^2)", "1", "normalised longitudinal contact stiffness"),
        ("lateral_k2_ratio", "H^2 k2 L/c_T", "1", "normalised lateral contact stiffness (torsion)"),
        ("frequency_ratio", "f_n/f_1", "1", "a resonance frequency over the first free one"),
        ("crossover", "s_n", "1", "normalised stiffness where a branch passes midway between its soft and stiff "
         "limits"),
        ("crossover_root", "z_n,mid", "1", "the root midway between a branch's soft and stiff limits"),
        # frequency-bias diagrams and their deconvolution (pfmdyn diagram, deconvolve)
        ("piezo_response", "A_piezo", "m/V", "electromechanical response per volt of V_ac (bias independent)"),
        ("local_electrostatic_response", "A_el/dV", "m/V^2", "response to the local electrostatic force per volt "
         "of V_ac per volt of V_dc - V_surf"),
        ("nonlocal_electrostatic_response", "A_nl/dV", "m/V^2", "response to the distributed (non-local) "
         "electrostatic load per volt of V_ac per volt of V_dc - V_surf"),
        ("biases", "n_V", "1", "number of DC biases measured at a frequency"),
        ("measured_d_eff", "d_eff,meas", "data", "d_eff of the signal as measured: the fitted line b + c V at "
         "V_surf (Eq. 41), in the data's unit"),
        ("electrostatic_slope", "G_elec", "data/V", "electrostatic part of the signal per volt of DC bias: the "
         "slope c of Eq. 41, in the data's unit"),
        ("intercept", "b", "data", "the fitted line of Eq. 41 at zero DC bias, in the data's unit"),
        ("nulling_bias", "V_null", "V", "DC bias at which the fitted response is smallest"),
        ("mean_nulling_bias", "mean V_null", "V", "weighted mean of the nulling bias over frequency"),
        ("nulling_bias_spread", "spread V_null", "V", "spread of the nulling bias over frequency: the tip-quality "
         "indicator (near 0 with V_null ~ V_surf: electrostatic-dominated or worn tip)"),
        ("surface_d_eff", "d_eff/C", "data", "measured d_eff as the true surface displacement at the spot (over "
         "the calibration factor)"),
        ("surface_electrostatic_slope", "G_elec/C", "data/V", "G_elec as the true surface displacement at the "
         "spot (over the calibration factor)"),
        # the discrepancy model's fit
        ("gap", "gap", "1", "sqrt(mean |residual / noise|^2): 1 when the residual is noise"),
        ("region", "region", "1", "a region of the data by name: a resonance's half-power band, a band, the rest"),
        ("gap_before", "gap_0", "1", "gap of the model without the named effects (the paper's, or the reference's)"),
        ("gap_after", "gap_1", "1", "gap of the final model"),
        ("gap_without", "gap_-e", "1", "gap of the final model with one effect left out"),
        ("explained_share", "share", "1", "share of the baseline's misfit the named effects explain"),
        ("effect_share", "share_e", "1", "share of the explained misfit that an effect's own removal loses"),
        ("share_of_rest", "share_e|rest", "1", "share of the misfit an effect explains after the others"),
        ("chi_square", "chi2", "1", "sum of squared residuals over their noise"),
        ("bic", "BIC", "1", "Bayesian information criterion, chi2 + k ln n (noise known)"),
        ("delta_bic", "Delta BIC", "1", "BIC gained by adding an effect"),
        ("fitted_parameters", "k", "1", "number of parameters fitted"),
        ("degrees_of_freedom", "dof", "1", "data values less fitted parameters"),
        ("noise", "sigma", "data", "noise of the data in the data's own unit (RMS, estimated from the data)"),
        ("largest_residual", "max |r|", "1", "the largest residual over the largest measured value"),
        ("unexplained_share", "share_left", "1", "share of the baseline's misfit the final model leaves"),
        ("effect", "effect", "1", "an effect's name (missing_effects' vocabulary)"),
        ("damping_mechanisms", "damping", "1", "the damping mechanisms the final model holds"),
        ("equivalent_damping_mechanisms", "damping'", "1", "other damping mechanisms that fit the data as well"),
    )),
)

NAMES: dict[str, Quantity] = {q.name: q for q in QUANTITIES}

LEVER = ("spring_constant", "free_resonance", "length", "width", "tip_height", "tip_position",
         "tip_mass_ratio", "tip_gyration_radius", "tilt", "spot_position")
"""Names describing the probe (:class:`pfmdyn.Cantilever`)."""
CONTACT = ("k1", "k2", "k2_over_k1", "poisson")
"""Names describing the contact (:class:`pfmdyn.Contact`)."""
DAMPING = ("quality_factor", "viscous_loss", "contact_loss")
"""The three damping mechanisms: internal friction, viscous drag, contact dashpot."""
CALIBRATION = ("temperature", "medium", "invols", "length_uncertainty", "width_uncertainty")
"""What calibrating the free lever takes besides its size: the fluid and its temperature, the detector."""
MEASURED = ("free_quality_factor", "contact_resonance", "contact_quality_factor", "drive_frequency", "tip_bias")
"""What an instrument file may hold besides the lever: measured resonances, their Q, the drive settings."""

_ALIASES = {alias.lower(): q.name for q in QUANTITIES for alias in (q.name, *q.aliases)}


GROUPS = {
    "baseline": "the paper's model fitted before any effect (its parameters and fit)",
    "steps": "the effects added (or removed) one at a time, in order: what each changed",
    "reference": "the fit of the reference measurement (the sweep before the change)",
    "instrument": "what the instrument's own fit recorded in the file, beside our value",
    "medium": "the first free mode's Q the fluid predicts beside the fitted damping",
    "unexplained": "what the final model leaves: the band holding most of the misfit",
    "worst_region": "the region of the data where the final model's gap is largest, and that gap",
    "thermal": "the spring constant from the thermal tune, with its uncertainty budget",
    "sader": "the spring constant from Sader's method, with its uncertainty budget",
    "budget": "relative standard uncertainties by source",
    "reconcile": "what would make the two methods agree: the input and its factor",
    "solutions": "every solution of the inverse problem (the first is the result)",
    "free": "free modes (the lever not in contact)",
    "contact": "contact modes (the tip on the sample)",
}
"""The names of groups of records in the JSON documents (every other key is a quantity's name)."""


def canonical(key: str) -> str | None:
    """The name of a quantity from any spelling a file may use (None: not a quantity).

    >>> canonical("spring_constant_n_per_m"), canonical("Tip_Position"), canonical("colour")
    ('spring_constant', 'tip_position', None)
    """
    return _ALIASES.get(str(key).strip().lower())


def flag(name: str) -> str:
    """The command-line flag of a name.

    >>> flag("tip_mass_ratio")
    '--tip-mass-ratio'
    """
    return NAMES[name].flag


def checked(name: str, value, where: str = "") -> float:
    """``value`` as a float, or a :class:`UserError` naming ``where`` when no probe can have it.

    >>> checked("length", "225e-6")
    0.000225
    >>> checked("length", 0.0, "lever.csv")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: lever.csv: length must be in (1e-06, 0.01] m, got 0.0
    """
    q = NAMES[name]
    prefix = f"{where}: " if where else ""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise UserError(f"{prefix}{name} must be a number, got {value!r}") from None
    inside = (number > q.low if q.open_low else number >= q.low) and number <= q.high
    if not (math.isfinite(number) and inside):
        interval = f"{'(' if q.open_low else '['}{q.low:g}, {q.high:g}]"
        unit = "" if q.unit == "1" else f" {q.unit}"
        raise UserError(f"{prefix}{name} must be in {interval}{unit}, got {value}")
    return number


def fill_defaults(values: dict, names=LEVER) -> dict[str, str]:
    """Put into ``values`` (name -> SI) the default (:attr:`Quantity.default`) of each of
    ``names`` that neither a flag nor the file gave; returns name -> why, what reports say of each.
    Every command that builds a lever takes its defaults here, so one k1 means one contact in all.

    >>> values = {"length": 2e-4}
    >>> why = fill_defaults(values); values["tip_height"], why["tip_height"].split(",")[0]
    (1.3e-05, "a typical PFM probe's")
    """
    out = {}
    for name in names:
        q = NAMES[name]
        if values.get(name) is None and q.default is not None:
            values[name] = q.default
            out[name] = q.default_why
    return out


def markdown_table() -> str:
    """The README's table: one row per quantity (name, flag or ``(files)``, unit, meaning).

    >>> markdown_table().splitlines()[2]
    '| `spring_constant` | `--spring-constant` | N/m | lever spring constant 3 EI / L^3 |'
    """
    rows = ["| name (Python, JSON, file, Zarr) | flag | unit | meaning |", "|---|---|---|---|"]
    rows += [f"| `{q.name}` | {f'`{q.flag}`' if q.option else '(files)' if q.low > -math.inf else '(reports)'} | "
             f"{q.unit} | {q.meaning} |" for q in QUANTITIES]
    return "\n".join(rows)
