"""The report of ``pfmdyn discrepancy`` (both data kinds): a :class:`DiscrepancyReport` with the
JSON-ready fields (``to_dict()``), the summary text (``report()``) and the fits behind it."""
from __future__ import annotations

import math

import numpy as np

from ..digits import rounded
from ..fitting.result import Result
from . import select
from .effects import public_name
from .plausible import describe
from .regions import gap_text, worst_region

__all__ = ["DiscrepancyReport", "degrees", "parameters", "report", "summary", "medium_comparison"]


class DiscrepancyReport(Result):
    """What ``pfmdyn discrepancy`` found: the fields of its JSON report (read as a mapping or by
    ``to_dict()``), the summary text (``report()``) and ``fits``, the baseline and final
    :class:`pfmdyn.discrepancy.model.FitResult` (None when not kept).

    >>> r = DiscrepancyReport({"missing_effects": ["damping"]}, fits=None)
    >>> r["missing_effects"], r.fits
    (['damping'], None)
    """

    def report(self) -> str:
        """The summary the command prints (:func:`summary`)."""
        return summary(self)


def degrees(fit) -> dict:
    """Data values, fitted parameters and their difference ``dof`` of a fit.

    Data values the model reproduces by construction (``fit.extra["by_construction"]``: a
    table's free mode 1, which sets the frequency scale) test nothing and are not counted;
    a complex spectrum value counts twice (real and imaginary part), as do its complex
    linear coefficients.

    >>> from types import SimpleNamespace as S
    >>> degrees(S(n=4, k=3, extra={"by_construction": 1}))
    {'data_values': 3, 'fitted_parameters': 3, 'dof': 0}
    """
    n = fit.n - getattr(fit, "extra", {}).get("by_construction", 0)
    return {"data_values": n, "fitted_parameters": fit.k, "dof": n - fit.k}


def parameters(fit) -> dict:
    """A fit's parameters, each held one (``fit.extra["held"]``) with the reason as ``note``.

    >>> from types import SimpleNamespace as S
    >>> fit = S(parameters=lambda: {"k2": {"value": None}}, extra={"held": {"k2": "tied to k1"}})
    >>> parameters(fit)["k2"]["note"]
    'tied to k1'
    """
    out = fit.parameters()
    for name, note in getattr(fit, "extra", {}).get("held", {}).items():
        if name in out:
            out[name] = dict(out[name], note=note)
    return out


def report(result: dict, frequency_hz=None, resonances=(), **extra) -> DiscrepancyReport:
    """The report of a loop result (both data kinds), with its baseline and final fits; with the
    spectrum's ``frequency_hz`` (one per residual) also the final fit's ``worst_region`` among
    its bands and ``resonances`` (:func:`pfmdyn.discrepancy.regions.worst_region`)."""
    baseline, final = result["baseline"], result["final"]
    if frequency_hz is not None:
        extra["worst_region"] = worst_region(frequency_hz, np.abs(final.residual / final.sigma) ** 2, resonances)
    steps = [dict(s, effect=public_name(s["effect"]) if s["effect"] else None) for s in result["steps"]]
    out = {"missing_effects": final.model.public_effects, "gap_before": baseline.gap, "gap_after": final.gap,
           "explained_share": select.share(baseline.gap, baseline.gap, final.gap), "effect_shares": result["shares"],
           **degrees(final), "baseline_fitted_parameters": baseline.k,
           "damping_mechanisms": final.model.damping_mechanisms, "unexplained": result["unexplained"],
           "criterion": select.CRITERION, "steps": steps, "parameters": parameters(final),
           "baseline_parameters": parameters(baseline), "fit_report": final.report()}
    out.update(extra)
    return DiscrepancyReport(out, fits=(baseline, final))


def summary(report) -> str:
    """Readable multi-line summary of a report."""
    mech = report.get("damping_mechanisms") or []
    tied = report.get("damping_mechanisms_indistinguishable_from") or []
    detail = ", ".join(mech) + (f"; {' or '.join(tied)} fit the data as well" if tied else "")
    shares = report.get("effect_shares") or {}
    named = [e + (f" ({detail})" if e == "damping" and mech else "")
             + (f" [{_share_text(shares[e])}]" if e in shares else "") for e in report["missing_effects"]]
    lines = [f"baseline gap {report['gap_before']:.2f} -> final gap {report['gap_after']:.2f} "
             f"(1 = noise level); missing effects: {', '.join(named) or 'none'}",
             f"{report['data_values']} data values, {report['fitted_parameters']} fitted parameters: "
             f"{report['dof']} degree(s) of freedom left"]
    if report.get("worst_region"):
        lines.insert(1, "final " + gap_text(report["gap_after"], report["worst_region"]))
    for i, s in enumerate(report["steps"], 1):
        if "removed" in s:
            lines.append(f"step {i}: {s['decision']}")
            continue
        loc = s["located"]
        where = (f"residual in {loc['band_hz'][0] / 1e3:.1f}-{loc['band_hz'][1] / 1e3:.1f} kHz"
                 if "band_hz" in loc else f"largest residual at {loc['worst']}")
        head = f"step {i}: {where}, signature '{loc['signature']}'"
        if s["effect"] is None:
            lines.append(f"{head}; {s['decision']}")
        else:
            lines.append(f"{head}; added {s['effect']} (delta BIC {s['criterion_gain']:.1f}, "
                         f"gap {s['gap_before']:.2f} -> {s['gap_after']:.2f})")
    if report.get("unexplained"):
        where = report["unexplained"]["where"]
        place = (f"at {where[0] / 1e3:.4g}-{where[1] / 1e3:.4g} kHz" if isinstance(where, (list, tuple))
                 else f"at {where}")
        left = report["unexplained"].get("share")
        lines.append(f"no effect of the library explains the residual {place} "
                     f"(gap {report['unexplained']['gap']:.3g} x noise"
                     + (f", {left:.1%} of the baseline misfit" if left is not None else "") + ")")
        if report["unexplained"].get("implausible"):
            lines.append(describe(report["unexplained"]["implausible"]))
        if report["unexplained"].get("small_share"):
            lines.append(f"not named, under {select.MIN_SHARE:.0%} of the misfit the others leave: " + ", ".join(
                f"{e} ({v:.1%})" for e, v in report["unexplained"]["small_share"].items()))
    for name, why in (report.get("untestable_effects") or {}).items():
        lines.append(f"{name}: {why}")
    for name, p in report["parameters"].items():
        if p["value"] is None:      # e.g. springs from a table of free modes only
            lines.append(f"  {name} not determined by these data" + (f": {p['note']}" if p.get("note") else ""))
        else:
            err = "" if p["stderr"] is None else f" +- {p['stderr']:.2g}"
            note = "" if p.get("determined", True) else " (not determined by these data)"
            value = rounded(p["value"], p["stderr"] or 0.0) if p["stderr"] else f"{p['value']:.5g}"
            lines.append(f"  {name} = {value}{err} {p['unit']}{note}".rstrip())
            if p.get("budget") and p["value"]:
                words = report.get("uncertainty_inputs") or {}
                lines.append(f"    {name}'s uncertainty, input by input: " + ", ".join(
                    f"{words.get(source, {}).get('words', source)} {100 * v / abs(p['value']):.2g}%"
                    for source, v in sorted(p["budget"].items(), key=lambda kv: -kv[1])))
    return "\n".join(lines)


def _share_text(share: dict) -> str:
    """An effect's share of the misfit, as the summary states it.

    >>> _share_text({"share": 0.012, "share_of_rest": 0.99, "gap_without": 9.0})
    '1.2% of the misfit, 99.0% of what the others leave'
    """
    text = f"{share['share']:.1%} of the misfit"
    return text + (f", {share['share_of_rest']:.1%} of what the others leave"
                   if share["share_of_rest"] > share["share"] + 0.001 else "")


def medium_comparison(report: dict, lever) -> dict:
    """The first free mode's Q the fitted damping gives beside the one ``lever``'s medium predicts
    (Sader's load on a lever of that width, :mod:`pfmdyn.medium`; the exact damped root of
    :func:`pfmdyn.analysis.resonances.resonances`).  The fitted losses add at ``f1``: ``1/Q`` of
    internal friction, the viscous ``g``, the fluid's ``fluid_loss``; a contact dashpot damps no
    free mode.  ``fitted`` is None when the fit holds no free-mode damping.

    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.medium import Medium
    >>> lever = Cantilever(27.0, 1.798e5, 225e-6, width=40e-6, medium=Medium.air(313.15))
    >>> out = medium_comparison({"parameters": {"fluid_loss": {"value": 1 / 440}}}, lever)
    >>> round(out["predicted_quality_factor"]), out["fitted_quality_factor"]
    (474, 440.0)
    """
    from ..analysis.resonances import resonances

    p = report.get("parameters", {})
    value = lambda name: (p.get(name) or {}).get("value") or 0.0     # noqa: E731
    q = value("quality_factor")
    loss = (1.0 / q if q and math.isfinite(q) else 0.0) + value("viscous_loss") + value("fluid_loss")
    predicted = resonances(lever, None, modes=1).free.q[0]
    return {"medium": lever.medium.name, "width": lever.width, "predicted_quality_factor": float(predicted),
            "fitted_quality_factor": round(1.0 / loss, 10) if loss else None}
