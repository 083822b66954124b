"""``pfmdyn calibrate``: the spring constant of a free lever from its thermal tune, thermal and Sader."""
from __future__ import annotations

import math

from ..errors import UserError
from ..io import documents
from . import flags

__all__ = ["add_arguments", "run", "report"]


def add_arguments(parser) -> None:
    """Options of ``pfmdyn calibrate`` (names and units: :mod:`pfmdyn.names`).

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> a = p.parse_args(["t.nid", "--length", "225e-6", "--width", "40e-6"]); a.file, a.medium, a.spot_position
    ('t.nid', None, None)
    """
    parser.add_argument("file", metavar="INPUT", help="thermal tune: Nanosurf .nid, or a CSV of frequency_hz and an ASD column "
                        "ending in _m_per_sqrthz or _v_per_sqrthz")
    flags.add(parser, ("length",))
    flags.add_medium_arguments(parser, medium="the file's, else air")
    flags.add(parser, ("invols", "spot_position", "tip_position", "length_uncertainty", "width_uncertainty"))
    flags.add_json(parser)
    parser.add_argument("--plot", metavar="PATH", help="write the spectrum with the fitted first mode (.png, .pdf, .svg)")


def _number(value, unit="N/m", digits=4) -> str:
    return f"{value:.{digits}g} {unit}" if value is not None and math.isfinite(value) else "undetermined"


def report(result) -> str:
    """The lines ``pfmdyn calibrate`` prints.

    >>> import numpy as np
    >>> from pfmdyn.analysis.calibrate import calibrate
    >>> from pfmdyn.generated import formulas
    >>> from pfmdyn.io.thermal_tune import ThermalTune
    >>> from pfmdyn.medium import Medium
    >>> f = np.linspace(0, 4e5, 8001)
    >>> tune = ThermalTune("t.csv", f, formulas.oscillator_asd(f, 1.8e5, 440.0, 1.03e-15, 3e-14), "m", {}, {})
    >>> print(report(calibrate(tune, medium=Medium.air(313.15), temperature=313.15)).splitlines()[2])
    Sader:   undetermined (needs the lever's length and width)
    """
    d, p = result.to_json(), result.peak
    inst = result.instrument
    lines = [f"first mode ({result.model}): f = {p.frequency_hz:.6g} +- {_number(p.frequency_uncertainty_hz, 'Hz', 2)}, "
             f"Q = {p.quality_factor:.4g} +- {_number(p.quality_factor_uncertainty, '', 2).strip()}"
             + (f"  (instrument: {inst['free_resonance']:.6g} Hz, Q {inst['free_quality_factor']:.4g})"
                if "free_resonance" in inst and "free_quality_factor" in inst else "")]
    for name, label in (("thermal", "thermal"), ("sader", "Sader")):
        e = d[name]
        if e["spring_constant"] is not None and math.isfinite(e["spring_constant"]):
            shares = ", ".join(f"{k} {v:.1%}" for k, v in e["sources"].items())
            lines.append(f"{label + ':':8} k = {_number(e['spring_constant'])} +- {_number(e['spring_constant_stderr'], '', 2)}"
                         f"N/m ({shares})")
        else:
            lines.append(f"{label + ':':8} undetermined ({e['reason']})")
    if "spring_constant" in inst:
        lines.append(f"instrument: k = {inst['spring_constant']:.4g} N/m"
                     + (f" at {inst['temperature'] - 273.15:g} C" if "temperature" in inst else "")
                     + (f" in {inst['environment']}" if "environment" in inst else "")
                     + (f"; Sader's formula on its own fit of the tune: {inst['sader_spring_constant_of_its_fit']:.4g} N/m"
                        if "sader_spring_constant_of_its_fit" in inst else ""))
    if d["consistent"] is None:
        lines.append("agreement: undetermined (one estimate is)")
    elif d["consistent"]:
        lines.append("agreement: thermal and Sader agree within twice their combined uncertainty")
    else:
        lines.append("agreement: thermal and Sader DISAGREE beyond twice their combined uncertainty; "
                     + ("each alone, within its plausible range, would reconcile them:" if d["reconcile"] else
                        "no single input within its plausible range reconciles them"))
        lines += [f"  {r['input']} x {r['factor']:.4g} ({r['why']})" for r in d["reconcile"]]
    lines += [f"assumed: {a}" for a in d["assumptions"]]
    return "\n".join(lines)


def _provenance(tune, result, args, temperature_source: str) -> dict:
    """What came from the file (``from_file``: the instrument's fit, the medium and temperature it names and
    no flag replaced) and its fit beside ours (``instrument_comparison``, tolerances from our uncertainties
    and the spectrum's bin)."""
    import numpy as np

    from ..discrepancy.sweep import compare_with_instrument

    p = result.peak
    taken = [name for name in tune.instrument if name in flags.NAMES]
    taken += ["medium"] if args.medium is None and tune.conditions.get("environment") else []
    taken += ["temperature"] if temperature_source == "from the file" else []
    ours = {"free_resonance": (p.frequency_hz, p.frequency_uncertainty_hz),
            "free_quality_factor": (p.quality_factor, p.quality_factor_uncertainty)}
    if result.thermal.determined:
        ours["spring_constant"] = (result.thermal.value, result.thermal.stderr)
    step = float(np.median(np.diff(np.sort(tune.frequency_hz))))
    comparison = compare_with_instrument(tune.instrument, ours, step)
    for c in comparison:
        if c["name"] == "spring_constant" and c["disagrees"]:
            c["why"] = spring_constant_difference(result, c["instrument"])
    return {"from_file": sorted(set(taken)), "instrument_comparison": comparison}


def spring_constant_difference(result, stated: float) -> str:
    """What could make the file's spring constant ``stated`` differ from our thermal one: the sensitivity the
    spectrum was converted with (k goes as its inverse square), or another method behind the file's number
    (Sader's formula on the instrument's own fit, when the lever's plan lets us compute it).

    >>> from types import SimpleNamespace as NS
    >>> r = NS(thermal=NS(value=9.05), instrument={"sader_spring_constant_of_its_fit": 25.15})
    >>> print(spring_constant_difference(r, 27.13))
    the file's k matches ours with the spectrum's InvOLS x 0.5776; it lies near Sader's formula on the instrument's own fit (25.15 N/m), so it may be a Sader calibration, not a thermal one
    """
    factor = math.sqrt(result.thermal.value / stated)
    text = f"the file's k matches ours with the spectrum's InvOLS x {factor:.4g}"
    sader = result.instrument.get("sader_spring_constant_of_its_fit")
    if sader is None:
        return text + f"; or it came from another method (give {flags.NAMES['length'].flag} and " \
                      f"{flags.NAMES['width'].flag} to compare with Sader's formula on the instrument's own fit)"
    if abs(sader - stated) < abs(result.thermal.value - stated):
        return text + f"; it lies near Sader's formula on the instrument's own fit ({sader:.4g} N/m), so it may be " \
                      "a Sader calibration, not a thermal one"
    return text


def run(args) -> int:
    """Read, calibrate, print, write what was asked."""
    from ..discrepancy.sweep import disagreement_lines
    from ..discrepancy.thermal import calibrate_tune
    from ..io.results import check_writable
    from ..io.thermal_tune import read_thermal_tune
    from ..medium import Medium

    check_writable(args.json)
    check_writable(args.plot, figure=True)
    values = flags.given(args, ("length", "width", "temperature", "invols", "spot_position", "tip_position",
                                "length_uncertainty", "width_uncertainty"))      # a bad flag before the file
    tune = read_thermal_tune(args.file)
    environment = tune.conditions.get("environment")
    if args.medium is None and environment not in (None, "air"):
        raise UserError(f"{args.file}: measured in {environment}: give {flags.NAMES['medium'].flag}")
    medium = flags.medium_from_args(args, tune.conditions)
    temperature, source = flags.temperature(args, tune.conditions)
    word = (args.medium or environment or "air").strip().lower()
    factory = getattr(Medium, word) if word in ("air", "water") else None
    result = calibrate_tune(tune, length=values.get("length"), width=values.get("width"), medium=medium,
                            temperature=temperature, invols=values.get("invols"),
                            spot_position=values.get("spot_position", 1.0),
                            tip_position=values.get("tip_position", 1.0),
                            length_uncertainty=values.get("length_uncertainty"),
                            width_uncertainty=values.get("width_uncertainty"), medium_factory=factory)
    if source.startswith("assumed"):
        result.assumptions.append(f"temperature {temperature:g} K (give {flags.NAMES['temperature'].flag})")
    if args.medium is None and environment is None:
        result.assumptions.append(f"medium {medium.name} (give --medium)")
    print(flags.medium_line(medium, args, tune.conditions, thermal=True))
    print(report(result))
    document = {**result.to_json(), **_provenance(tune, result, args, source)}
    for line in disagreement_lines(document["instrument_comparison"]):
        print(line.strip())
    print("from the file: " + (", ".join(document["from_file"]) or "the spectrum only"))
    given = flags.given_names(args, ("medium", "temperature", "length", "width", "spot_position", "tip_position"))
    flags.write_json(args.json, documents.calibration(document, args.file, given))
    if args.plot:
        from ..plots.calibrate import plot_calibration
        flags.save_figure(plot_calibration(tune, result), args.plot)
    return 0
