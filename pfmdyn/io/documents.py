"""The JSON document of each command, built from the result it computed (:mod:`pfmdyn.io.results`).

The library's results stay what they are (dicts its tests and plots read); here each becomes the one
envelope with one record per number, under the names of :mod:`pfmdyn.names` and its ``GROUPS``.  One
function per document kind; the kinds' schemas are ``pfmdyn/schemas/COMMAND.KIND.json``.
"""
from __future__ import annotations

import math

from ..constants import RESONANCE_RELATIVE_UNCERTAINTY
from ..names import NAMES
from .results import document, quantity

__all__ = ["record", "records_of", "lever_records", "discrepancy_report", "sweep_fit", "sweep_comparison", "thermal_fit",
           "calibration", "stiffness", "map_summary", "resonances", "spot", "roots", "inspection", "branches",
           "diagram", "deconvolution"]

RENAMED = {"viscous_width_hz": "viscous_width", "eta": "contact_damping"}
"""A discrepancy parameter's old key -> its name (the old keys held a unit or a symbol)."""

DERIVED = {"viscous_width", "contact_damping", "added_mass"}
"""Parameters computed from fitted ones (their stderr propagated, or none)."""


def record(name: str, entry: dict, status: str = "fitted") -> dict:
    """A library parameter entry (``{value, stderr, unit}`` with ``determined``, ``given``, ``undetermined``,
    ``note`` or ``why``) as the record of ``name``: a value whose uncertainty exceeds it is undetermined,
    one held with a ``note`` is ``held``, a width not given is ``assumed``.

    >>> record("k2", {"value": 3.0, "stderr": 9.0, "unit": "N/m", "determined": False})["why"]
    'the data do not determine it: 3 +- 9 N/m'
    >>> record("width", {"value": 1e-5, "stderr": None, "unit": "m", "given": False, "why": "assumed L/10"})["status"]
    'assumed'
    """
    value, stderr, why = entry.get("value"), entry.get("stderr"), entry.get("why")
    if entry.get("undetermined") or entry.get("determined") is False or value is None:
        # the estimate the data leave undetermined is said, not lost
        unit = "" if NAMES[name].unit == "1" else f" {NAMES[name].unit}"
        shown = "" if value is None else f": {value:.3g}" + (f" +- {stderr:.3g}" if stderr is not None else "") + unit
        return quantity(name, None, status="undetermined",
                        why=why or entry.get("note") or f"the data do not determine it{shown}")
    if entry.get("note"):
        return quantity(name, value, stderr, status="held", why=entry["note"])
    if "given" in entry:
        return quantity(name, value, stderr, status="given") if entry["given"] else \
            quantity(name, value, stderr, status="assumed", why=why or "not given")
    return quantity(name, value, stderr, status="derived" if name in DERIVED else status)


def records_of(parameters: dict) -> dict:
    """Every parameter entry of a fit as its record, under its name.

    >>> sorted(records_of({"eta": {"value": 1e-6, "stderr": None, "unit": "N s/m"}}))
    ['contact_damping']
    """
    return {RENAMED.get(key, key): record(RENAMED.get(key, key), entry) for key, entry in parameters.items()}


def lever_records(values: dict, given=(), from_file=(), assumed: dict | None = None) -> dict:
    """The lever's records: ``values`` (name -> number; None skipped) ``given`` on the command line, read
    ``from_file`` or ``assumed`` (name -> why); any other value is the default, ``assumed``.

    >>> lever_records({"spring_constant": 2.0, "width": 3e-5}, given=["spring_constant"],
    ...               assumed={"width": "L/10"})["width"]["status"]
    'assumed'
    """
    assumed = assumed or {}
    out = {}
    for name, value in values.items():
        if value is None or name not in NAMES:
            continue
        if name in given:
            out[name] = quantity(name, value, status="given")
        elif name in assumed:
            out[name] = quantity(name, value, status="assumed", why=assumed[name])
        elif name in from_file:
            out[name] = quantity(name, value, status="file", why="read from the input file")
        else:
            out[name] = quantity(name, value, status="assumed", why="the default: " + (
                NAMES[name].default_why or "no flag, not in the file"))
    return out


def _statistics(report: dict) -> dict:
    return {"points": quantity("points", report["data_values"], status="derived"),
            "fitted_parameters": quantity("fitted_parameters", report["fitted_parameters"], status="derived"),
            "degrees_of_freedom": quantity("degrees_of_freedom", report["dof"], status="derived")}


def _unexplained(entry: dict | None) -> tuple[dict | None, list[str]]:
    """What a fit leaves unexplained: its gap, the band holding most of the misfit (or where it is, as a note),
    the largest residual, the share of the baseline's misfit; what was not named, as notes.

    >>> records, notes = _unexplained({"gap": 4.9, "share": 0.12, "where": "Q of free mode 1"})
    >>> sorted(records), notes
    (['gap', 'unexplained_share'], ['unexplained: the misfit is at Q of free mode 1'])
    """
    if not entry:
        return None, []
    out, notes = {"gap": quantity("gap", entry["gap"], status="derived")}, []
    where = entry.get("where")
    if isinstance(where, (list, tuple)):
        out["band"] = quantity("band", list(where), status="derived", dims=["bound"])
    elif where:
        notes.append(f"unexplained: the misfit is at {where}")
    for key, name in (("largest_residual", "largest_residual"), ("share", "unexplained_share")):
        if entry.get(key) is not None:
            out[name] = quantity(name, entry[key], status="derived")
    if entry.get("implausible"):
        notes.append(f"unexplained: implausible values of the effects that would explain it: {entry['implausible']}")
    if entry.get("small_share"):
        notes.append("unexplained: not named, each under the share the others leave: " + ", ".join(
            f"{e} ({v:.1%})" for e, v in entry["small_share"].items()))
    return out, notes


def _worst_region(entry: dict | None) -> dict | None:
    """Where the final fit's gap is largest (:func:`pfmdyn.discrepancy.regions.worst_region`) as records.

    >>> r = _worst_region({"region": "band 1-2 kHz", "band_hz": [1e3, 2e3], "values": 40, "gap": 3.2})
    >>> r["region"]["value"], r["gap"]["value"], r["band"]["dims"]
    ('band 1-2 kHz', 3.2, ['bound'])
    """
    if not entry:
        return None
    return {"region": quantity("region", entry["region"], status="derived"),
            "band": quantity("band", [float(b) for b in entry["band_hz"]], status="derived", dims=["bound"]),
            "points": quantity("points", entry["values"], status="derived"),
            "gap": quantity("gap", entry["gap"], status="derived")}


def _misfit(report: dict) -> tuple[dict, list[str]]:
    """What a fit leaves unexplained (:func:`_unexplained`) and where its gap is largest (:func:`_worst_region`):
    the records of its ``fit``, and notes.

    >>> records, notes = _misfit({"worst_region": {"region": "rest", "band_hz": [1, 2], "values": 9, "gap": 1.1}})
    >>> list(records), notes
    (['worst_region'], [])
    """
    unexplained, notes = _unexplained(report.get("unexplained"))
    out = {"unexplained": unexplained} if unexplained else {}
    if report.get("worst_region"):
        out["worst_region"] = _worst_region(report["worst_region"])
    return out, notes


def _mass_solutions(parameters: dict) -> list[dict]:
    """Each position of an added mass that explains the shifts as well, with its own mass and gap (the first
    is the result), when the modes cannot tell them apart (e.g. mirror positions about a node)."""
    found = next((p["solutions"] for p in (parameters.get("added_mass_position") or {}, parameters.get("added_mass") or {})
                  if p.get("solutions")), [])
    return [{"added_mass_position": quantity("added_mass_position", s["added_mass_position"], status="derived"),
             "added_mass": quantity("added_mass", s["added_mass"], status="derived"),
             "gap": quantity("gap", s["gap"], status="derived")} for s in found]


def _step(step: dict) -> dict:
    """One step of the effect-by-effect search (added or removed effect, gaps, BIC gained, parameters)."""
    out = {}
    if step.get("effect"):
        out["effect"] = quantity("effect", step["effect"], status="derived")
    for key in ("gap_before", "gap_after"):
        if step.get(key) is not None:
            out[key] = quantity(key, step[key], status="derived")
    if step.get("criterion_gain") is not None:
        out["delta_bic"] = quantity("delta_bic", step["criterion_gain"], status="derived")
    out.update(records_of(step.get("parameters") or {}))
    return out


def _step_note(i: int, step: dict) -> str:
    what = f"added {step['effect']}" if step.get("effect") else f"removed {step.get('removed') or 'nothing'}"
    located = step.get("located") or {}
    where = f" ({located['signature']})" if located.get("signature") else ""
    return f"step {i}: {what}{where}" + (f", gap {step['gap_before']:.4g} -> {step['gap_after']:.4g}"
                                         if step.get("gap_after") is not None else "")


def discrepancy_report(report: dict, kind: str, source: dict, lever: dict, rows=None) -> dict:
    """The document of ``pfmdyn discrepancy`` on a spectrum (``kind`` ``spectrum``) or a resonance table
    (``resonances``, its ``rows`` the table's ``(condition, mode)``): the final model's parameters and what
    each effect explains in ``results``, the baseline and the steps in ``fit``.

    >>> doc = discrepancy_report({"missing_effects": [], "gap_before": 1.0, "gap_after": 1.0,
    ...     "explained_share": 0.0, "effect_shares": {}, "data_values": 9, "fitted_parameters": 2, "dof": 7,
    ...     "baseline_fitted_parameters": 2, "damping_mechanisms": [], "unexplained": None, "criterion": "BIC",
    ...     "steps": [], "parameters": {"k1": {"value": 0.3, "stderr": 1e-4, "unit": "N/m", "determined": True}},
    ...     "baseline_parameters": {}, "fit_report": "[[Model]] baseline"}, "resonances", {"path": "t.csv"}, {})
    >>> doc["missing_effects"], doc["results"]["k1"]["status"], doc["fit"]["gap_after"]["value"]
    ([], 'fitted', 1.0)
    """
    results = records_of(report["parameters"])
    results["explained_share"] = quantity("explained_share", report["explained_share"], status="derived")
    shares = report.get("effect_shares") or {}
    if shares:
        effects = list(shares)
        results["effect"] = quantity("effect", effects, status="derived", dims=["effect"])
        for key, name in (("share", "effect_share"), ("gap_without", "gap_without"), ("share_of_rest", "share_of_rest")):
            results[name] = quantity(name, [shares[e].get(key) for e in effects], status="derived", dims=["effect"])
    results["damping_mechanisms"] = quantity("damping_mechanisms", list(report.get("damping_mechanisms") or []),
                                             status="derived", dims=["damping_mechanisms"])
    if report.get("damping_mechanisms_indistinguishable_from"):
        results["equivalent_damping_mechanisms"] = quantity(
            "equivalent_damping_mechanisms", list(report["damping_mechanisms_indistinguishable_from"]), status="derived",
            dims=["equivalent_damping_mechanisms"])
    if rows is not None:
        results["condition"] = quantity("condition", [c for c, _ in rows], status="file", why="the table's rows",
                                        dims=["row"])
        results["mode"] = quantity("mode", [m for _, m in rows], status="file", why="the table's rows", dims=["row"])
        results["measured_resonance"] = quantity("measured_resonance", report["measured_hz"], status="file",
                                                 why="the table's rows", dims=["row"])
        inputs = report.get("uncertainty_inputs") or {}
        assumed = inputs.get("resonance_frequencies", {}).get("assumed")
        results["resonance_uncertainty"] = quantity(
            "resonance_uncertainty", report["frequency_uncertainty_hz"], status="assumed" if assumed else "file",
            why=f"{RESONANCE_RELATIVE_UNCERTAINTY:.1%} of each frequency: the table gives none" if assumed else "the table's metadata", dims=["row"])
        results["predicted_resonance"] = quantity("predicted_resonance", report["predicted_hz"], status="derived",
                                                  dims=["row"])
        results["baseline_resonance"] = quantity("baseline_resonance", report["baseline_hz"], status="derived",
                                                 dims=["row"])
        if "measured_quality_factor" in report:
            results["measured_quality_factor"] = quantity(
                "measured_quality_factor", report["measured_quality_factor"], status="file",
                why="the table's quality_factor column", dims=["row_with_q"])
            results["predicted_quality_factor"] = quantity(
                "predicted_quality_factor", report["predicted_quality_factor"], status="derived", dims=["row_with_q"])
            results["quality_factor_uncertainty"] = quantity(
                "quality_factor_uncertainty", report["quality_factor_relative_uncertainty"], status="assumed",
                why="no uncertainty of Q in the table")
    medium = report.get("medium")
    if medium:
        results["medium"] = {
            "medium": quantity("medium", medium["medium"], status="given"),
            "width": quantity("width", medium["width"], status="given"),
            "predicted_quality_factor": quantity("predicted_quality_factor", medium["predicted_quality_factor"],
                                                 status="derived"),
            "measured_quality_factor": quantity("measured_quality_factor", medium["fitted_quality_factor"],
                                                status="derived")
            if medium.get("fitted_quality_factor") is not None else
            quantity("measured_quality_factor", None, why="no free-mode damping fitted")}
    fit = {"gap_before": quantity("gap_before", report["gap_before"], status="derived"),
           "gap_after": quantity("gap_after", report["gap_after"], status="derived"),
           **_statistics(report),
           "baseline": {"fitted_parameters": quantity("fitted_parameters", report["baseline_fitted_parameters"],
                                                      status="derived"),
                        **records_of(report.get("baseline_parameters") or {})},
           "steps": [_step(s) for s in report.get("steps") or []]}
    if report.get("noise_sigma") is not None:
        fit["noise"] = quantity("noise", report["noise_sigma"], status="derived")
    if report.get("frequency_stride"):
        fit["frequency_stride"] = quantity("frequency_stride", report["frequency_stride"], status="derived")
    misfit, notes = _misfit(report)
    fit.update(misfit)
    notes.insert(0, f"criterion: {report['criterion']}")
    if report.get("gap_definition"):
        notes.append(f"gap: {report['gap_definition']}")
    notes += [_step_note(i, s) for i, s in enumerate(report.get("steps") or [], 1)]
    notes += [f"{name}: {why}" for name, why in (report.get("spring_rule") or {}).items()]
    notes += [f"{name}: {why}" for name, why in (report.get("untestable_effects") or {}).items()]
    budget = (report["parameters"].get("k1") or {}).get("budget")
    if budget and report["parameters"]["k1"].get("value"):
        k1 = abs(report["parameters"]["k1"]["value"])
        fit["budget"] = {"uncertainty_source": quantity("uncertainty_source", list(budget), status="derived",
                                                        dims=["uncertainty_source"]),
                         "relative_uncertainty": quantity("relative_uncertainty", [v / k1 for v in budget.values()],
                                                          status="derived", dims=["uncertainty_source"])}
    words = {source: entry["words"] for source, entry in (report.get("uncertainty_inputs") or {}).items()}
    notes += [f"{name}'s uncertainty by input: " + ", ".join(f"{words.get(s, s)} {v:.3g} {p['unit']}" for s, v in
                                                                p["budget"].items())
              for name, p in report["parameters"].items() if p.get("budget")]
    notes.append(report["fit_report"])
    return document("discrepancy", kind, source, lever, results, fit, notes,
                    missing_effects=report["missing_effects"])


def _instrument(fit: dict) -> tuple[dict, list[str]]:
    """What the instrument's fit recorded (records of status ``file``) and one note per comparison."""
    recorded = {name: quantity(name, value, status="file", why="the instrument's own fit, recorded in the file")
                for name, value in (fit.get("instrument_fit") or {}).items() if name in NAMES}
    notes = []
    for c in fit.get("instrument_comparison") or []:
        unit = NAMES[c["name"]].unit
        unit = "" if unit == "1" else f" {unit}"
        notes.append(f"{c['name']}: ours {c['ours']:.6g}{unit}, the instrument's {c['instrument']:.6g}{unit} "
                     f"(relative difference {c['relative_difference']:+.2g}; "
                     f"{'disagrees' if c['disagrees'] else 'agrees'} within {c['tolerance']:.3g}{unit})"
                     + (f": {c['why']}" if c.get("why") else ""))
    disagree = [c["name"] for c in fit.get("instrument_comparison") or [] if c["disagrees"]]
    if fit.get("instrument_comparison"):
        recorded["disagrees"] = quantity("disagrees", disagree, status="derived", dims=["disagrees"])
    return recorded, notes


def _assumed(fit: dict) -> dict:
    """The lever's values a sweep or tune fit assumed, name -> why (from its ``assumed`` sentences)."""
    out = {}
    for sentence in fit.get("assumed") or []:
        name = sentence.split(" ", 1)[0]
        if name in NAMES:
            out[name] = sentence
    return out


def _free_lever(fit: dict, given) -> dict:
    """The lever of a sweep or tune fit: spring constant, length, medium, temperature (when used)."""
    values = {name: fit.get(name) for name in ("spring_constant", "length", "medium", "temperature")}
    return lever_records(values, given=given, from_file=fit.get("from_file") or (), assumed=_assumed(fit))


def _fit_records(fit: dict) -> tuple[dict, list[str]]:
    """A sweep's or a tune's own fit: its gap, points, band, what it leaves unexplained, its noise, what the
    instrument's own fit recorded; and notes comparing the two."""
    out = {"gap": quantity("gap", fit["gap"], status="derived"),
           "points": quantity("points", fit["points"], status="file", why="the data's frequencies")}
    if fit.get("band_hz"):
        out["band"] = quantity("band", list(fit["band_hz"]), status="derived", dims=["bound"])
    out.update(_misfit(fit)[0])      # a sweep's or tune's misfit is a band: no note
    out["noise"] = quantity("noise", fit["noise"], status="derived")
    out["instrument"], notes = _instrument(fit)
    return out, notes


OVERDAMPED = "the first mode in the medium is overdamped: no damped resonance, no Q"
"""Why a sweep's or a tune's lever has no first-mode Q."""


def _sweep_results(fit: dict) -> dict:
    """The lever a sweep or tune fit found: its parameters, vacuum resonance and the Q it predicts."""
    results = records_of(fit["parameters"])
    if "width" in (fit.get("from_file") or ()) and results["width"]["status"] == "given":
        results["width"] = quantity("width", results["width"]["value"], status="file", why="read from the input file")
    errors = fit.get("uncertainties", {})
    results["vacuum_resonance"] = derived("vacuum_resonance", fit["vacuum_resonance"], errors.get("vacuum_resonance"))
    q = fit["quality_factor"]
    results["free_quality_factor"] = derived("free_quality_factor", q, errors.get("quality_factor")) \
        if math.isfinite(q) else quantity("free_quality_factor", None, status="undetermined", why=OVERDAMPED)
    return results


def derived(name: str, value, error: dict | None) -> dict:
    """The record of a derived ``value`` with its ``error`` (``{"stderr"[, "why"]}``): undetermined, with the
    error's why, where the fit's covariance does not give the stderr (a value without its uncertainty is
    not reported as known).

    >>> derived("white_floor", 1e-13, {"stderr": 2e-15})["stderr"], derived("white_floor", 1e-13, {"stderr": None, "why": "x"})["status"]
    (2e-15, 'undetermined')
    """
    if error is not None and error.get("stderr") is None:
        return quantity(name, None, status="undetermined", why=error["why"])
    return quantity(name, value, None if error is None else error["stderr"], status="derived")


def sweep_fit(fit: dict, given=()) -> dict:
    """The document of ``pfmdyn discrepancy`` on one drive sweep (kind ``sweep``): the lever in its fluid,
    the detector's gain and background, against what the instrument's own fit recorded.

    >>> fit = {"path": "s.txt", "instrument": "Cytomass", "points": 160, "medium": "water at 20 C",
    ...        "spring_constant": 8.0, "length": 1e-4, "vacuum_resonance": 7.5e4, "quality_factor": 6.8,
    ...        "peak_hz": 7.1e4, "gap": 1.05, "noise": 1e-4, "unexplained": None, "from_file": ["amplitude_peak"],
    ...        "assumed": ["medium water at 20 C (none in the file)"], "amplitude_only": False, "phase_reversed": False,
    ...        "parameters": {"free_resonance": {"value": 7.2e4, "stderr": 16.7, "unit": "Hz"}},
    ...        "gain": {"value": [1e-9, 9e-8], "unit": "V/rad"}, "background": {"value": [[1e-3, 2e-3]], "unit": "V"},
    ...        "instrument_fit": {"amplitude_peak": 7.1e4}, "instrument_comparison": []}
    >>> doc = sweep_fit(fit, given=["spring_constant", "length"])
    >>> doc["results"]["gain"]["value"], doc["lever"]["medium"]["status"], doc["missing_effects"]
    ({'real': 1e-09, 'imag': 9e-08}, 'assumed', [])
    """
    results = _sweep_results(fit)
    results["amplitude_peak"] = derived("amplitude_peak", fit["peak_hz"], fit.get("uncertainties", {}).get("peak_hz"))
    results["gain"] = quantity("gain", _complex(fit["gain"]["value"]), _complex(fit["gain"].get("stderr")),
                               status="fitted")
    results["background"] = quantity("background", _complex(fit["background"]["value"]),
                                     _complex(fit["background"].get("stderr")), status="fitted", dims=["coefficient"])
    results["amplitude_only"] = quantity("amplitude_only", bool(fit["amplitude_only"]), status="file",
                                         why="the columns of the file")
    results["phase_reversed"] = quantity("phase_reversed", bool(fit["phase_reversed"]), status="derived")
    out, notes = _fit_records(fit)
    notes.append(f"gain in {fit['gain']['unit']}, background in {fit['background']['unit']}, added to the "
                 f"{fit['background'].get('adds_to', 'response')}")
    return document("discrepancy", "sweep", {"path": str(fit["path"]), "instrument": fit.get("instrument")},
                    _free_lever(fit, given), results, out, notes, missing_effects=[])


def _complex(pairs):
    """``[re, im]`` (or a list of them) as a complex number (or list); None stays None, as does a pair
    with a part None (not determined)."""
    if pairs is None:
        return None
    if pairs and isinstance(pairs[0], (list, tuple)):
        items = [_complex(p) for p in pairs]
        return None if None in items else items
    return None if None in pairs else complex(*pairs)


def sweep_comparison(out: dict, given=()) -> dict:
    """The document of ``pfmdyn discrepancy`` on a drive sweep and its reference (kind ``comparison``): what changed
    between two drive sweeps under ``missing_effects`` (``added_mass``, or none), the reference's own fit
    under ``fit.reference``.

    >>> reference = {"path": "b.txt", "points": 10, "spring_constant": 8.0, "length": 1e-4, "vacuum_resonance": 7.5e4,
    ...     "quality_factor": 6.8, "peak_hz": 7.1e4, "gap": 1.0, "noise": 1e-4, "amplitude_only": False,
    ...     "phase_reversed": False, "parameters": {}, "gain": {"value": [1.0, 0.0], "unit": "V/rad"},
    ...     "background": {"value": [[0.0, 0.0]], "unit": "V"}}
    >>> out = {"path": "a.txt", "reference": "b.txt", "effect": "nothing", "parameters": {}, "lever_mass": 1e-10,
    ...        "resonance_before": 7.2e4, "resonance_after": 7.2e4, "gap_before": 1.0, "gap_after": 1.0, "noise": 1e-4,
    ...        "gain_after": [1.0, 0.0], "background_after": [[0.0, 0.0]], "steps": [], "reference_fit": reference}
    >>> sweep_comparison(out)["missing_effects"]
    []
    """
    results = records_of(out["parameters"])
    results["lever_mass"] = derived("lever_mass", out["lever_mass"], out.get("uncertainties", {}).get("lever_mass"))
    results["free_resonance"] = quantity("free_resonance", [out["resonance_before"], out["resonance_after"]],
                                         out.get("resonance_stderr"), status="fitted", dims=["sweep"])
    results["gain"] = quantity("gain", _complex(out["gain_after"]), _complex(out.get("gain_after_stderr")),
                               status="fitted")
    results["background"] = quantity("background", _complex(out["background_after"]),
                                     _complex(out.get("background_after_stderr")), status="fitted",
                                     dims=["coefficient"])
    recorded, notes = _instrument(out)
    reference = sweep_fit(out["reference_fit"], given)
    fit = {"gap_before": quantity("gap_before", out["gap_before"], status="derived"),
           "gap_after": quantity("gap_after", out["gap_after"], status="derived"),
           "noise": quantity("noise", out["noise"], status="derived"),
           "instrument": recorded,
           "steps": [{"effect": quantity("effect", s["effect"], status="derived"),
                      "fitted_parameters": quantity("fitted_parameters", s["parameters"], status="derived"),
                      "chi_square": quantity("chi_square", s["chi2"], status="derived"),
                      "bic": quantity("bic", s["bic"], status="derived"),
                      "gap": quantity("gap", s["gap"], status="derived")} for s in out["steps"]],
           "reference": {**reference["results"], **reference["fit"]}}
    fit.update(_misfit(out)[0])
    solutions = _mass_solutions(out["parameters"])
    if solutions:
        fit["solutions"] = solutions
    notes = [*out.get("notes", []), *notes, "free_resonance: the first free resonance in the reference and in the data (dims sweep)"]
    if out.get("nuisances"):
        notes.append("refitted besides the named effect: " + ", ".join(out["nuisances"]))
    effect = out["effect"]
    missing = [] if effect == "nothing" else [effect]
    lever = _free_lever(out["reference_fit"], given)
    return document("discrepancy", "comparison", {"path": str(out["path"]), "reference": str(out["reference"])},
                    lever, results, fit, notes, missing_effects=missing)


def thermal_fit(fit: dict, given=()) -> dict:
    """The document of ``pfmdyn discrepancy`` on a thermal tune (kind ``thermal``): the lever in its fluid at
    its temperature, the detection's scale against the equipartition theorem.

    >>> fit = {"path": "t.nid", "points": 6955, "band_hz": [5e4, 3e5], "medium": "air at 40 C", "temperature": 313.15,
    ...        "spring_constant": 27.1, "length": 2.25e-4, "vacuum_resonance": 1.8e5, "quality_factor": 398.0,
    ...        "parameters": {}, "detection_scale": 1.7, "white_floor": 1e-13, "unit": "m/sqrt(Hz)", "noise": 0.016,
    ...        "gap": 1.35, "from_file": ["medium", "temperature"], "assumed": []}
    >>> doc = thermal_fit(fit, given=["length"])
    >>> doc["lever"]["temperature"]["status"], doc["results"]["free_quality_factor"]["value"]
    ('file', 398.0)
    """
    results = _sweep_results(fit)
    errors = fit.get("uncertainties", {})
    for name in ("detection_scale", "white_floor", "matching_spring_constant"):
        if name in fit:
            results[name] = derived(name, fit[name], errors.get(name))
    out, notes = _fit_records(fit)
    notes.append(f"the spectrum in {fit['unit']}; the fit's residual and noise are of its logarithm")
    return document("discrepancy", "thermal", {"path": str(fit["path"])}, _free_lever(fit, given), results, out,
                    notes, missing_effects=[])



def _budget(estimate: dict, name: str, dim: str) -> dict:
    """A spring constant (``name``) and its relative uncertainty budget by source, or why it is undetermined."""
    value = estimate["spring_constant"]
    if value is None or not math.isfinite(value):
        return {name: quantity(name, None, why=estimate["reason"] or "not determined")}
    sources = estimate["sources"]
    return {name: quantity(name, value, estimate["spring_constant_stderr"], status="derived"),
            "budget": {"uncertainty_source": quantity("uncertainty_source", list(sources), status="derived",
                                                      dims=[dim]),
                       "relative_uncertainty": quantity("relative_uncertainty", list(sources.values()),
                                                        status="derived", dims=[dim])}}


def calibration(doc: dict, path, given=()) -> dict:
    """The document of ``pfmdyn calibrate`` (kind ``thermal_tune``): the first mode fitted on the tune, the
    spring constant by the thermal method and by Sader's, each with its budget, whether they agree.

    >>> nan = float("nan")
    >>> d = calibration({"free_resonance": 1.8e5, "free_resonance_stderr": 9.0, "free_quality_factor": 440.0,
    ...     "free_quality_factor_stderr": 20.0, "thermal": {"spring_constant": 2.0, "spring_constant_stderr": 0.1,
    ...     "sources": {"fit": 0.05}, "reason": ""}, "sader": {"spring_constant": nan, "spring_constant_stderr": nan,
    ...     "sources": {}, "reason": "needs the lever's length and width"}, "consistent": None, "reconcile": [],
    ...     "assumptions": [], "inputs": {"temperature": 300.0, "medium": "air at 27 C"}, "instrument": {},
    ...     "from_file": [], "instrument_comparison": []}, "t.csv", given=["temperature"])
    >>> d["results"]["sader_spring_constant"]["status"], d["fit"]["thermal"]["budget"]["relative_uncertainty"]["value"]
    ('undetermined', [0.05])
    """
    results = {"free_resonance": quantity("free_resonance", doc["free_resonance"], doc["free_resonance_stderr"]),
               "free_quality_factor": quantity("free_quality_factor", doc["free_quality_factor"],
                                               doc["free_quality_factor_stderr"])}
    fit = {}
    for method, name in (("thermal", "thermal_spring_constant"), ("sader", "sader_spring_constant")):
        records = _budget(doc[method], name, f"{method}_budget")
        results[name] = records.pop(name)
        fit[method] = records
    results["consistent"] = quantity("consistent", doc["consistent"], status="derived") \
        if doc["consistent"] is not None else quantity("consistent", None, why="one estimate is undetermined")
    if doc["reconcile"]:
        fit["reconcile"] = {
            "input_name": quantity("input_name", [r["input"] for r in doc["reconcile"]], status="derived",
                                   dims=["input_name"]),
            "correction_factor": quantity("correction_factor", [r["factor"] for r in doc["reconcile"]],
                                          status="derived", dims=["input_name"])}
    instrument = dict(doc["instrument"])
    if "environment" in instrument:
        instrument["medium"] = instrument.pop("environment")
    recorded, notes = _instrument({"instrument_fit": instrument,
                                   "instrument_comparison": doc["instrument_comparison"]})
    if "sader_spring_constant_of_its_fit" in instrument:
        recorded["sader_spring_constant"] = quantity("sader_spring_constant",
                                                     instrument["sader_spring_constant_of_its_fit"], status="derived")
    fit["instrument"] = recorded
    assumed = {a.split(" ", 1)[0]: a for a in doc["assumptions"] if a.split(" ", 1)[0] in NAMES}
    lever = lever_records(doc["inputs"], given=given, from_file=doc["from_file"],
                          assumed={name: assumed.get(name, "the default") for name in doc["inputs"]
                                   if name not in given and name not in doc["from_file"]})
    notes += [f"reconciled by {r['input']} x {r['factor']:.4g}: {r['why']}"
              for r in doc["reconcile"]]
    notes += [f"assumed: {a}" for a in doc["assumptions"]]
    return document("calibrate", "thermal_tune", {"path": str(path)}, lever, results, fit, notes)


def _solution(s: dict, lever: dict, k2_policy: str) -> dict:
    """One solution of the inverse problem: the unknowns solved (stderr propagated), the rest held or tied."""
    unknowns = s["unknowns"]
    out = {"k1": quantity("k1", s["k1"], s.get("k1_stderr"), status="derived")}
    if "k2" in unknowns:
        out["k2"] = quantity("k2", s["k2"], s.get("k2_stderr"), status="derived")
    elif s["k2"] is not None:
        out["k2"] = quantity("k2", s["k2"], status="tied", why=k2_policy)
    else:
        out["k2"] = quantity("k2", None, why=k2_policy)
    out["tip_position"] = quantity("tip_position", s["tip_position"], s.get("tip_position_stderr"), status="derived") \
        if "tip_position" in unknowns else quantity("tip_position", s["tip_position"], status="held",
                                                    why="the lever's tip position, not solved for")
    out["residual_beta"] = quantity("residual_beta", s["residual_beta"], status="derived")
    if s.get("k1_by_mode"):
        out["k1_by_mode"] = quantity("k1_by_mode", s["k1_by_mode"], status="derived", dims=["mode"])
    if s.get("reduced_modulus") is not None:
        out["reduced_modulus"] = quantity("reduced_modulus", s["reduced_modulus"], s["reduced_modulus_stderr"],
                                          status="derived")
    return out


def stiffness(doc: dict, path=None, given=(), from_file=(), assumed: dict | None = None) -> dict:
    """The document of ``pfmdyn stiffness`` (kind ``contact_resonance``): k1 (with k2 or the tip position)
    solved from the contact resonances, each uncertainty's budget, every solution when not unique.

    >>> d = stiffness({"k1": 109.7, "k1_stderr": 0.0, "k2": None, "tip_position": 1.0, "unknowns": ["k1"],
    ...     "residual_beta": 0.0, "k1_over_k": 54.9, "unique": True, "k2_policy": "k2 left out", "proof": [],
    ...     "notes": [], "solutions": [{"k1": 109.7, "k2": None, "tip_position": 1.0, "unknowns": ["k1"],
    ...     "k1_stderr": 0.0, "residual_beta": 0.0}], "inputs": {"spring_constant": 2.0, "free_resonance": 7.5e4,
    ...     "contact_hz": [3e5], "modes": [1], "contact_uncertainty": 0.0}}, given=["spring_constant"])
    >>> d["results"]["k1"]["value"], d["results"]["k2"]["status"], d["results"]["contact_resonance"]["dims"]
    (109.7, 'undetermined', ['mode'])
    """
    inputs = dict(doc["inputs"])
    contact, modes = inputs.pop("contact_hz"), inputs.pop("modes")
    assumed = {**{name: "the default" for name in inputs
                  if name.endswith("_uncertainty") and name not in (*given, *from_file)},
               **(assumed or {})}
    per_mode = {name: inputs.pop(name) for name in list(inputs) if isinstance(inputs[name], list)}
    lever = lever_records({k: v for k, v in inputs.items() if not isinstance(v, str)}, given=given,
                          from_file=from_file, assumed=assumed)
    for name, value in per_mode.items():          # one per contact resonance (an assumed relative one)
        lever[name] = quantity(name, value, status="assumed" if name in assumed else "given",
                               why=assumed.get(name), dims=["mode"])
    if isinstance(inputs.get("medium"), str):
        lever["medium"] = quantity("medium", inputs["medium"], status="given" if "medium" in given else "assumed",
                                   **({} if "medium" in given else {"why": "the default"}))
    status = "file" if "contact_resonance" in from_file else "given"
    why = {"why": "read from the input file"} if status == "file" else {}
    results = {"contact_resonance": quantity("contact_resonance", contact, status=status, dims=["mode"], **why),
               "mode": quantity("mode", modes, status=status, dims=["mode"], **why)}
    solutions = [_solution(s, lever, doc["k2_policy"]) for s in doc["solutions"]]
    if doc["unique"]:
        results.update(solutions[0])
        results["k1_over_k"] = quantity("k1_over_k", doc["k1_over_k"], doc.get("k1_over_k_stderr"), status="derived")
        budget = (doc["solutions"][0].get("stderr_sources") or {})
        k1 = doc["k1"]
        shares = {source: parts["k1"] / k1 for source, parts in budget.items() if parts.get("k1", 0) > 0}
    else:
        why_not = f"not unique: {len(solutions)} solution(s) explain the resonances (fit.solutions)"
        results.update({name: quantity(name, None, why=why_not) for name in ("k1", "k2", "tip_position")})
        shares = {}
    results["unique"] = quantity("unique", bool(doc["unique"]), status="derived")
    fit = {"solutions": solutions}
    if shares:
        fit["budget"] = {"uncertainty_source": quantity("uncertainty_source", list(shares), status="derived",
                                                        dims=["uncertainty_source"]),
                         "relative_uncertainty": quantity("relative_uncertainty", list(shares.values()),
                                                          status="derived", dims=["uncertainty_source"])}
    notes = [f"k2 policy: {doc['k2_policy']}", *(f"why: {p}" for p in doc["proof"]), *doc["notes"]]
    return document("stiffness", "contact_resonance", {"path": None if path is None else str(path)}, lever,
                    results, fit, notes)


def _derived(name: str, value, why: str) -> dict:
    """A number derived from others, or undetermined (``why``) when it is None or not finite.

    >>> _derived("median_k1", float("nan"), "no pixel")["status"]
    'undetermined'
    """
    if value is None or not math.isfinite(value):
        return quantity(name, None, why=why)
    return quantity(name, value, status="derived")


MAP_RESULTS = ("explained_fraction", "at_bound_fraction", "median_gap", "median_k1", "median_nulling_bias")
"""What a map's summary says of its pixels (:func:`map_summary`)."""


def map_summary(summary: dict, path, shape, given: dict | None = None, settings=(), assumed: dict | None = None) -> dict:
    """The document of ``pfmdyn map`` (kind ``map``: the model fitted pixel by pixel; the maps themselves
    are in ``source.store``, Zarr in xarray's convention): the run's statistics, its ``settings``
    (sentences, kept as notes).  ``given``: the lever's values given on the command line; ``assumed``: name ->
    (value, why) of those it took by default; ``summary["why"]``, when there, says why a statistic no pixel
    determines is undetermined.

    >>> d = map_summary({"explained_fraction": 1.0, "median_k1": 109.8, "out": "o/maps.zarr"}, "cr.h5", (4, 5),
    ...                 assumed={"tip_height": (13e-6, "a typical PFM probe's")})
    >>> d["source"]["store"], d["results"]["median_k1"]["unit"], d["results"]["pixels"]["value"]
    ('o/maps.zarr', 'N/m', [4, 5])
    >>> d["lever"]["tip_height"]["status"]
    'assumed'
    """
    def statistic(name, value):
        return _derived(name, value, summary.get("why")
                        or "no pixel of the map determines it (none fitted by this run, or none explained)")

    results = {"pixels": quantity("pixels", list(shape), status="file", why="the map's shape", dims=["axis"])}
    results.update({name: statistic(name, summary[name]) for name in MAP_RESULTS if name in summary})
    fit = {name: statistic(name, summary[name])
           for name in ("blocks_run", "blocks_done", "blocks_total", "pixels_fitted") if name in summary}
    if "pixels_per_s" in summary:
        fit["pixels_per_second"] = statistic("pixels_per_second", summary["pixels_per_s"])
    notes = ([f"model: {summary['model']}"] if "model" in summary else []) + list(settings) + (
        [summary[key] for key in ("left_out", "assumed") if summary.get(key)])
    assumed = assumed or {}
    lever = lever_records({**{name: value for name, (value, _) in assumed.items()}, **(given or {})},
                          given=list(given or {}), assumed={name: why for name, (_, why) in assumed.items()})
    return document("map", "map", {"path": str(path), "store": str(summary["out"])}, lever, results, fit, notes)


def _probe(values: dict, given=(), from_file=(), k2_policy: str | None = None, k1_uncertainty: float = 0.0) -> dict:
    """The lever (and contact) a computation took: given, from a file, or the defaults; k2, when not given,
    tied to k1 by ``k2_policy``; a given k1 with the standard uncertainty ``k1_uncertainty`` it was given with.

    >>> _probe({"spring_constant": 2.0, "k1": 300.0}, ["spring_constant", "k1"], k1_uncertainty=20.0)["k1"]
    {'value': 300.0, 'stderr': 20.0, 'unit': 'N/m', 'status': 'given'}
    """
    values = {k: v for k, v in values.items() if k != "k1_uncertainty"}
    out = lever_records({k: v for k, v in values.items() if isinstance(v, (int, float)) and not isinstance(v, bool)},
                        given=given, from_file=from_file)
    if k2_policy and "k2" in out and "k2" not in given:
        out["k2"] = quantity("k2", out["k2"]["value"], status="tied", why=k2_policy)
    if k1_uncertainty and "k1" in out:
        out["k1"]["stderr"] = float(k1_uncertainty)
    return out


def _mode_records(d: dict, prefix: str) -> dict:
    """The modes of one condition (``free`` or ``contact``) of :meth:`Resonances.to_dict`."""
    stderr = d.get(f"{prefix}_stderr")
    if stderr is not None and not any(u != 0 for u in stderr):
        stderr = None
    modes = {"resonance": quantity("resonance", d[f"{prefix}_hz"], stderr, status="derived", dims=["mode"]),
             "resonance_interval": quantity("resonance_interval", d[f"{prefix}_intervals_hz"], status="derived",
                                            dims=["mode", "bound"])}
    if d.get(f"{prefix}_complete_below_hz") is not None:
        modes["complete_below"] = quantity("complete_below", d[f"{prefix}_complete_below_hz"], status="derived")
    if f"{prefix}_q" in d:
        modes["predicted_quality_factor"] = quantity("predicted_quality_factor", d[f"{prefix}_q"], status="derived",
                                                     dims=["mode"])
        modes["damped_resonance"] = quantity("damped_resonance", d[f"{prefix}_damped_hz"], status="derived",
                                             dims=["mode"])
        modes["amplitude_peak"] = quantity("amplitude_peak", d[f"{prefix}_peak_hz"], status="derived", dims=["mode"])
    return modes


def resonances(d: dict, given=()) -> dict:
    """The document of ``pfmdyn resonances`` (kind ``modes``): each condition's modes under ``free`` and
    ``contact`` (dims mode), certified or not; an undamped mode's Q is infinite (``"inf"`` in the list).

    >>> doc = resonances({"spring_constant": 2.0, "free_resonance": 7e4, "length": 2e-4, "certified": True,
    ...     "free_hz": [7e4], "free_intervals_hz": [[6.9e4, 7.1e4]], "free_complete_below_hz": 7.2e4,
    ...     "contact_hz": [], "contact_intervals_hz": [], "contact_complete_below_hz": None}, ["spring_constant"])
    >>> doc["results"]["free"]["resonance"]["value"], doc["lever"]["length"]["status"]
    ([70000.0], 'assumed')
    """
    results = {"certified": quantity("certified", bool(d["certified"]), status="derived")}
    notes = [] if d["certified"] else [f"not certified: {d['reason']}"]
    if d["certified"]:
        for prefix in ("free", "contact"):
            results[prefix] = _mode_records(d, prefix)
            for i, why in enumerate(d.get(f"{prefix}_undetermined") or [], 1):
                if why:
                    notes.append(f"{prefix} mode {i}: {why}")
    if d.get("k2_policy"):
        notes.append(f"k2 policy: {d['k2_policy']}")
    if d.get("medium_note"):
        notes.append(d["medium_note"])
    return document("resonances", "modes", {}, _probe(d, given, k2_policy=d.get("k2_policy"), k1_uncertainty=d.get("k1_uncertainty", 0.0)),
                    results, None, notes)


def _complex_record(name: str, z: dict | None, why: str, stderr: float | None = None) -> dict:
    return quantity(name, complex(z["re"], z["im"]), stderr, status="derived") if z else quantity(name, None, why=why)


def spot(d: dict, given=(), from_file=(), path=None) -> dict:
    """The document of ``pfmdyn spot`` (kind ``spot``): blind spots, the slope ratio along the lever
    (dims position), the sensitivities and calibration factors (complex) at the lever's spot.

    >>> d = {"drive_frequency": 1e5, "beta": 2.24, "blind_spot": [0.62], "blind_spot_intervals": [[0.61, 0.63]],
    ...      "certified": True, "q0_to_d1_slope_ratio": {"spot_position": [0.5, 1.0], "re": [1e-5, 2e-5], "im": [0, 0]},
    ...      "free_sensitivity": 0.67, "contact_sensitivity": 0.74, "calibration_factor": {"re": 0.86, "im": 0.0},
    ...      "paper_calibration_factor": {"re": 0.78, "im": 0.0}, "d_eff_error_per_volt": None,
    ...      "d_eff_error_per_volt_undetermined": "needs the lever width", "lever": {"spring_constant": 2.0},
    ...      "k1": 100.0, "k2": 82.4}
    >>> doc = spot(d, given=["spring_constant", "k1"])
    >>> doc["results"]["d_eff_error_per_volt"]["why"], doc["results"]["calibration_factor"]["value"]
    ('needs the lever width', {'real': 0.86, 'imag': 0.0})
    >>> spot({**d, "stderr": {"blind_spot": [float("nan")]}})["notes"][-1]
    'blind_spot: uncertainty undetermined (a blind spot appears or goes within the assumed inputs)'
    """
    ratio = d["q0_to_d1_slope_ratio"]
    stderr = {name: value for name, value in d.get("stderr", {}).items()
              if not (name == "blind_spot" and any(math.isnan(v) for v in value))}
    results = {
        "drive_frequency": (quantity("drive_frequency", d["drive_frequency"], status="file",
                                     why="the drive frequency the file records") if d.get("frequency_from_file")
                            else quantity("drive_frequency", d["drive_frequency"], status="given")),
        "beta": quantity("beta", d["beta"], status="derived"),
        "blind_spot": quantity("blind_spot", d["blind_spot"], stderr.get("blind_spot"), status="derived",
                               dims=["blind_spot"]),
        "blind_spot_interval": quantity("blind_spot_interval", d["blind_spot_intervals"], status="derived",
                                        dims=["blind_spot", "bound"]),
        "certified": quantity("certified", bool(d["certified"]), status="derived"),
        "spot_position": quantity("spot_position", ratio["spot_position"], status="derived", dims=["position"]),
        "slope_ratio": quantity("slope_ratio", [complex(a, b) for a, b in zip(ratio["re"], ratio["im"])],
                                status="derived", dims=["position"]),
        "free_sensitivity": quantity("free_sensitivity", d["free_sensitivity"], status="derived"),
        "contact_sensitivity": quantity("contact_sensitivity", d["contact_sensitivity"],
                                        stderr.get("contact_sensitivity"), status="derived"),
        "calibration_factor": _complex_record("calibration_factor", d["calibration_factor"], "undetermined",
                                              stderr.get("calibration_factor")),
        "paper_calibration_factor": _complex_record("paper_calibration_factor", d["paper_calibration_factor"],
                                                    "undetermined", stderr.get("paper_calibration_factor")),
        "d_eff_error_per_volt": _complex_record("d_eff_error_per_volt", d["d_eff_error_per_volt"],
                                                d.get("d_eff_error_per_volt_undetermined", "undetermined"),
                                                stderr.get("d_eff_error_per_volt"))}
    lever = _probe({**d["lever"], "k1": d["k1"], "k2": d["k2"]}, given, from_file, d.get("k2_policy"),
                   d.get("k1_uncertainty", 0.0))
    notes = [f"k2 policy: {d['k2_policy']}"] if d.get("k2_policy") else []
    notes += [f"not certified: {d['reason']}"] if not d["certified"] else []
    if "blind_spot" in d.get("stderr", {}) and "blind_spot" not in stderr:
        notes.append("blind_spot: uncertainty undetermined (a blind spot appears or goes within the assumed inputs)")
    return document("spot", "spot", {"path": None if path is None else str(path)}, lever, results, None, notes)


def roots(d: dict) -> dict:
    """The document of ``pfmdyn roots`` (kind ``roots``): the family's roots as decimal strings (exact
    digits), certified enclosures, the family's parameters (exact decimal strings).

    >>> roots({"family": "free", "parameters": {}, "roots": ["1.8751"], "intervals": [["1.87510", "1.87511"]],
    ...        "certified": True})["results"]["root"]["value"]
    ['1.8751']
    """
    results = {"root": quantity("root", d["roots"], status="derived", dims=["root"]),
               "root_interval": quantity("root_interval", d["intervals"], status="derived", dims=["root", "bound"]),
               "certified": quantity("certified", bool(d["certified"]), status="derived")}
    notes = [f"family: {d['family']}"] + [f"parameter {k} = {v}" for k, v in d["parameters"].items()]
    notes += [] if d["certified"] else [f"not certified: {d['reason']}"]
    return document("roots", "roots", {}, None, results, None, notes)


def inspection(d: dict) -> dict:
    """The document of ``pfmdyn inspect`` (kind ``file``): what an instrument file holds, each value a
    record of status ``file``; its channels and what it lacks as notes.

    >>> doc = inspection({"path": "t.nid", "kind": "thermal spectrum", "instrument": "Nanosurf (NID)", "channels": [],
    ...                   "fields": {"free_resonance": {"value": 1.8e5, "unit": "Hz"}}, "missing": ["length"], "notes": []})
    >>> doc["results"]["free_resonance"]["status"], doc["notes"]
    ('file', ['not in the file: length'])
    """
    results = {name: quantity(name, r["value"], status="file", why="read from the input file")
               for name, r in d["fields"].items()}
    notes = [f"channel {c['name']}: {c.get('unit') or 'no unit'}, shape {tuple(c.get('shape') or ())}"
             + (f", stored values x {c['scale']:g}" if c.get("scale", 1) != 1 else "") for c in d.get("channels") or []]
    if d.get("missing"):
        notes.append("not in the file: " + ", ".join(d["missing"]))
    notes += list(d.get("notes") or [])
    return document("inspect", "file", {"path": str(d["path"]), "instrument": d.get("instrument"),
                                        "file_kind": d.get("kind")}, None, results, None, notes)


BRANCH_NAMES = {"k1_over_k": "k1_over_k", "k2_ratio": "k2_ratio", "k2t_HL": "lateral_k2_ratio"}
"""A family's swept parameter (:data:`pfmdyn.roots.branches.SWEPT`) -> its name."""


def branches(family: str, swept: str, stiffness, roots, ratio, crossovers, fixed: dict, given=()) -> dict:
    """The document of ``pfmdyn branches`` (kind ``branches``): each mode's root and frequency ratio along
    the swept stiffness (dims: the swept name, mode), where each branch crosses over; ``fixed``: the
    family's parameters held, those not ``given`` by their default.

    >>> doc = branches("indentation", "k1_over_k", [1.0, 10.0], [[2.0], [3.0]], [[1.1], [2.6]],
    ...                ([5.8], [2.9]), {})
    >>> doc["results"]["root"]["dims"], doc["results"]["crossover"]["value"], doc["notes"]
    (['k1_over_k', 'mode'], [5.8], ['family: indentation'])
    """
    name = BRANCH_NAMES[swept]
    modes = list(range(1, len(crossovers[0]) + 1))
    results = {name: quantity(name, list(stiffness), status="given", dims=[name]),
               "mode": quantity("mode", modes, status="given", dims=["mode"]),
               "root": quantity("root", roots, status="derived", dims=[name, "mode"]),
               "frequency_ratio": quantity("frequency_ratio", ratio, status="derived", dims=[name, "mode"]),
               "crossover": quantity("crossover", list(crossovers[0]), status="derived", dims=["mode"]),
               "crossover_root": quantity("crossover_root", list(crossovers[1]), status="derived", dims=["mode"])}
    results.update(lever_records({BRANCH_NAMES[key]: float(value) for key, value in fixed.items()},
                                 given=[BRANCH_NAMES[key] for key in given]))
    return document("branches", "branches", {}, None, results, None, [f"family: {family}"])


def diagram(response, lever: dict, given=(), assumed: dict | None = None, notes=()) -> dict:
    """The document of ``pfmdyn diagram`` (kind ``diagram``): the response's three parts per frequency
    (dims frequency), from which the whole frequency-bias map follows,
    ``A = piezo_response + (local + nonlocal_electrostatic_response) (V_dc - V_surf)``, on the biases
    ``tip_bias`` (dims bias); ``lever``: name -> value, ``given`` or ``assumed`` (name -> why).

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> r = SimpleNamespace(frequency_hz=np.array([1e5]), bias_v=np.array([-1.0, 1.0]), surface_potential_v=0.0,
    ...                     piezo_coefficient=np.array([1e-12 + 0j]), local_coefficient=np.array([2e-12j]),
    ...                     nonlocal_coefficient=np.array([-3e-12 + 0j]))
    >>> doc = diagram(r, {"k1": 100.0, "quality_factor": float("inf")}, given=["k1"],
    ...               assumed={"quality_factor": "lossless, as in the paper"})
    >>> doc["results"]["piezo_response"]["value"], doc["lever"]["quality_factor"]["status"]
    ({'real': [1e-12], 'imag': [0.0]}, 'unbounded')
    """
    per = {"status": "derived", "dims": ["frequency"]}
    results = {"frequency": quantity("frequency", response.frequency_hz, status="given", dims=["frequency"]),
               "tip_bias": quantity("tip_bias", response.bias_v, status="given", dims=["bias"]),
               **{name: quantity(name, getattr(response, part), **per) for name, part in (
                   ("piezo_response", "piezo_coefficient"), ("local_electrostatic_response", "local_coefficient"),
                   ("nonlocal_electrostatic_response", "nonlocal_coefficient"))}}
    return document("diagram", "diagram", {}, lever_records(lever, given=given, assumed=assumed), results, None,
                    notes)


def deconvolution(result, quality, path, surface=None, unit: str = "a.u.", lever: dict | None = None, given=(),
                  out=None) -> dict:
    """The document of ``pfmdyn deconvolve`` (kind ``deconvolution``): the straight line in the bias fitted
    at each frequency (Eq. 41; dims frequency, in the data's ``unit``), its nulling bias and the tip-quality
    indicator (``quality``: :func:`pfmdyn.analysis.deconvolve.tip_quality`); with a lever (``surface``) the
    true surface displacement at the spot, undetermined ranges as notes.  The per-point residuals stay in
    ``error_map.csv`` (``source.out``).  ``given``: the flags given (``surface_potential`` among them when it
    was; else it is the default, assumed).

    >>> from pfmdyn.analysis.deconvolve import deconvolve, tip_quality
    >>> fit = deconvolve([1e5] * 3, [-1.0, 0.0, 1.0], [1, 2, 3], surface_potential_v=0.0)
    >>> doc = deconvolution(fit, tip_quality(fit.v_null, fit.v_null_se), "d.csv", unit="pm")
    >>> doc["results"]["measured_d_eff"]["value"], doc["results"]["electrostatic_slope"]["dims"], doc["notes"][0]
    ({'real': [2.0], 'imag': [0.0]}, ['frequency'], 'data in pm')
    """
    per = {"status": "fitted", "dims": ["frequency"]}
    results = {"frequency": quantity("frequency", result.frequency_hz, status="file", why="the data's frequencies",
                                     dims=["frequency"]),
               "biases": quantity("biases", result.n_bias, status="file", why="the data's biases",
                                  dims=["frequency"]),
               "electrostatic_slope": quantity("electrostatic_slope", result.g_elec, result.g_elec_se, **per),
               "intercept": quantity("intercept", result.intercept, **per),
               "measured_d_eff": quantity("measured_d_eff", result.d_eff, result.d_eff_se, **per),
               "nulling_bias": quantity("nulling_bias", result.v_null, result.v_null_se, **per),
               **{name: _derived(name, value, "no frequency determines the nulling bias")
                  for name, value in (("mean_nulling_bias", quality.mean_v), ("nulling_bias_spread", quality.spread_v))}}
    notes = [f"data in {unit}"]
    if surface is not None:
        derived = {"status": "derived", "dims": ["frequency"]}
        results.update({
            "calibration_factor": quantity("calibration_factor", surface.calibration_factor, **derived),
            "surface_d_eff": quantity("surface_d_eff", surface.d_eff, surface.d_eff_se, **derived),
            "surface_electrostatic_slope": quantity("surface_electrostatic_slope", surface.g_elec, **derived)})
        if surface.d_eff_error_per_volt is not None:
            results["d_eff_error_per_volt"] = quantity("d_eff_error_per_volt", surface.d_eff_error_per_volt,
                                                       **derived)
        notes += [f"undetermined {low:.6g}-{high:.6g} Hz: {why}" for low, high, why in surface.undetermined]
    lever = lever_records({"surface_potential": result.surface_potential_v, **(lever or {})},
                          given=given)
    return document("deconvolve", "deconvolution", {"path": str(path), "out": None if out is None else str(out)},
                    lever, results, None, notes)
