"""``pfmdyn discrepancy``: name the effects missing from the paper's model, as JSON (and PNG)."""
from __future__ import annotations

import argparse
import math
from contextlib import contextmanager

import numpy as np

from ..errors import UserError, listed
from ..io import documents
from . import flags


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``pfmdyn discrepancy``.

    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["d.csv", "--json", "o.json"]).json
    'o.json'
    """
    parser.add_argument("data", metavar="INPUT", help="CSV (metadata lines, then a spectrum or resonances table) or an "
                        "instrument file (.ibw, .nid, .h5/.hdf5, drive sweep .txt/.dat/.nid, thermal tune)")
    flags.add_json(parser, "the full report")
    parser.add_argument("--plot", metavar="PATH", help="write the figure (.png, .pdf, .svg): data, baseline, final model, "
                        "residuals")
    group = parser.add_argument_group("the lever (each overrides the file's metadata)")
    flags.add(group, OVERRIDES)
    flags.add(group, ("medium", "temperature"), defaults={"medium": (
        None, "the file's; else water for a drive sweep, air for a thermal tune, none (vacuum) for a spectrum or a "
              "resonance table")})
    parser.add_argument("--vertical-only", action="store_true",
                        help="start from the model without k2 (adds lateral_stiffness to the library)")
    parser.add_argument("--workers", type=int, default=None,
                        help="worker processes for a spectrum's fits, on Linux (default: all cores, up to its candidates; the report "
                             "is the same with any number)")
    sweeps = parser.add_argument_group("drive sweeps (.txt/.dat/.nid) and thermal tunes: the free lever in a fluid, "
                                       "driven at its base or by thermal noise")
    sweeps.add_argument("--reference", metavar="BEFORE",
                        help="the drive sweep before the change: lever, fluid, gain and background calibrated on it, "
                             "DATA explained from them (an added mass, a gain or background change, or nothing)")
    flags.add(sweeps, ("added_mass_position",))


def resonance_rows(data, report: dict) -> str:
    """A resonance table's rows as measured (the file's, the instrument's fits) beside the final model's.

    >>> from types import SimpleNamespace as NS
    >>> data = NS(condition=np.array(["free", "contact"]), mode=np.array([1, 1]), quality_factor=np.array([138.6, np.nan]))
    >>> print(resonance_rows(data, {"measured_hz": [72969.0, 368990.0], "predicted_hz": [72969.0, 368992.05],
    ...                             "frequency_uncertainty_hz": [73.0, 369.0], "predicted_quality_factor": [155.71]}))
    condition  mode       measured (Hz)    model (Hz)  measured Q  model Q
    free          1         72969 +- 73         72969       138.6    155.7
    contact       1       368990 +- 369        368992           -        -
    """
    q = data.quality_factor if data.quality_factor is not None else np.full(len(data.mode), np.nan)
    with_q = ~np.isnan(q)
    model_q = np.full(len(q), np.nan)
    model_q[with_q] = [np.nan if v is None else v for v in report.get("predicted_quality_factor", [])]
    lines = [f"{'condition':9}  mode  {'measured (Hz)':>18}  {'model (Hz)':>12}  {'measured Q':>10}  {'model Q':>7}"]
    for c, m, f, sigma, p, qm, qp in zip(data.condition, data.mode, report["measured_hz"],
                                          report["frequency_uncertainty_hz"], report["predicted_hz"], q, model_q):
        measured = f"{f:.6g} +- {sigma:.3g}"
        lines.append(f"{c:9}  {m:4d}  {measured:>18}  {p:>12.6g}  {_q(qm):>10}  {_q(qp):>7}")
    return "\n".join(lines)


def _q(value: float) -> str:
    return "-" if np.isnan(value) else f"{value:.4g}"


OVERRIDES = ("spring_constant", "length", "width", "tip_height", "free_resonance")
"""The lever's quantities a file's metadata may hold and the command line may override."""


def _analyse(data, args, assumed: dict):
    """The analysis, its progress shown on a terminal only (a log or a pipe gets the report alone); a resonance
    table's with the tip height's uncertainty in each parameter's (the assumed one's spread, else 10 %)."""
    from ..discrepancy.resonances import analyse_resonances
    from ..discrepancy.select import TIME_BUDGET_S
    from ..discrepancy.spectrum import analyse
    from ..io.tables import SpectrumData

    options = dict(vertical_only=args.vertical_only, progress=flags.progress_shown(args), time_budget_s=TIME_BUDGET_S)
    if isinstance(data, SpectrumData):
        return analyse(data, workers=args.workers, **options)
    spread = flags.assumed_tip_height_uncertainty(data.metadata.tip_height, assumed)
    return analyse_resonances(data, tip_height_uncertainty=spread, **options)


def _rows_taken(data) -> str:
    """A resonance table's rows as the 'from the file' line names them.

    >>> import numpy as np
    >>> from pfmdyn.io.discrepancy_data import ResonanceData
    >>> _rows_taken(ResonanceData(None, np.array([1, 1]), np.array(["free", "contact"]), np.array([72969.0, 368990.0]),
    ...                           quality_factor=np.array([138.63, np.nan])))
    'free mode 1 72969 Hz (Q 138.63), contact mode 1 368990 Hz'
    """
    qs = data.quality_factor if data.quality_factor is not None else [math.nan] * len(data.mode)
    return ", ".join(f"{c} mode {m} {f:.6g} Hz" + (f" (Q {q:.6g})" if not math.isnan(q) else "")
                     for c, m, f, q in zip(data.condition, data.mode, data.frequency_hz, qs))


def _lever_in_medium(data, args):
    """The data's lever (its measured free resonance) in ``--medium``: it needs the width."""
    found = {name: getattr(data.metadata, name) for name in ("spring_constant", "length", "width", "free_resonance")}
    return flags.cantilever(args, {k: v for k, v in found.items() if v is not None})


def _sweeps(args) -> int:
    """A drive sweep fitted as a spectrum, or explained from ``--reference`` (:mod:`pfmdyn.discrepancy.sweep`)."""
    from ..discrepancy.inputs import is_sweep, read_sweep
    from ..discrepancy.reference import compare_sweeps
    from ..discrepancy.sweep import fit_sweep
    from ..plots.sweep import plot_sweep

    if args.reference and not is_sweep(args.reference):
        raise UserError(f"{args.reference}: --reference must be a drive sweep (.txt/.dat with a sweep table, .nid frequency sweep)")
    _refuse_unused(args, "a drive sweep")
    values = flags.given(args, ("spring_constant", "length", "width", "added_mass_position"))
    flags.require(values, ("spring_constant", "length"), args.data)
    after = read_sweep(args.data)
    before = read_sweep(args.reference) if args.reference else None
    found = {"medium": (before or after).medium} if (before or after).medium else None
    medium = flags.medium_from_args(args, found, default="water")
    print(flags.medium_line(medium, args, found))
    for table in filter(None, (before, after)):         # what the reader made of each file (units, left out)
        for note in table.notes:
            print(f"note: {table.path}: {note}")
    with _fitting(args.data, "the spring constant and length"):
        fit = _provenance(fit_sweep(before or after, values["spring_constant"], values["length"], medium,
                                    values.get("width")), args, medium, found)
        result = _provenance(compare_sweeps(after, fit, values.get("added_mass_position")), args, medium, found) \
            if before else fit
    if before:
        print(fit.report())
    given = flags.given_names(args, (*OVERRIDES, "medium", "temperature"))
    doc = documents.sweep_comparison(result.to_dict(), given) if before else documents.sweep_fit(result.to_dict(), given)
    return _emit(args, result, doc, lambda: plot_sweep(fit, before, result, after) if before else plot_sweep(fit, after))


def _thermal(args) -> int:
    """A thermal tune fitted as a thermally driven spectrum (:mod:`pfmdyn.discrepancy.thermal`)."""
    from ..discrepancy.thermal import fit_thermal
    from ..io.instruments import read_instrument
    from ..io.thermal_tune import read_thermal_tune
    from ..plots.sweep import plot_thermal

    _refuse_unused(args, "a thermal tune")
    tune = read_thermal_tune(args.data)
    lever = read_instrument(args.data).fields       # what the file says of the lever; the flags win
    values = {**{k: lever[k] for k in ("spring_constant", "length", "width") if k in lever},
              **flags.given(args, ("spring_constant", "length", "width"))}
    flags.require(values, ("spring_constant", "length"), args.data)
    found = {"medium": tune.conditions.get("environment"), "temperature": tune.conditions.get("temperature")}
    found = {k: v for k, v in found.items() if v is not None}
    medium = flags.medium_from_args(args, found, default="air")
    temperature = flags.temperature(args, found)[0]
    print(flags.medium_line(medium, args, found, thermal=True))
    taken = [k for k in ("spring_constant", "length", "width") if k in lever and k not in flags.given(args, OVERRIDES)]
    with _fitting(args.data, "the spring constant and length"):
        fit = _provenance(fit_thermal(tune, values["spring_constant"], values["length"], medium, temperature,
                                      values.get("width")), args, medium, found, taken)
    doc = documents.thermal_fit(fit.to_dict(), flags.given_names(args, (*OVERRIDES, "medium", "temperature")))
    return _emit(args, fit, doc, lambda: plot_thermal(fit))


def _refuse_unused(args, what: str) -> None:
    """A free lever's spectrum (``what``) has no tip and no contact: a tip height, a free resonance (fitted) or
    --vertical-only would be dropped in silence; a value given is a value meant.

    >>> _refuse_unused(argparse.Namespace(data="s.txt", tip_height="1e-5", free_resonance=None, vertical_only=False),
    ...                "a drive sweep")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: s.txt: a drive sweep is fitted as the free lever (its resonance fitted, no tip in contact), which --tip-height would not enter: drop it
    """
    unused = [flags.NAMES[name].flag for name in ("tip_height", "free_resonance") if getattr(args, name) is not None]
    unused += ["--vertical-only"] * bool(args.vertical_only)
    if unused:
        raise UserError(f"{args.data}: {what} is fitted as the free lever (its resonance fitted, no tip in contact), "
                        f"which {listed(unused)} would not enter: drop {'it' if len(unused) == 1 else 'them'}")


def _provenance(result, args, medium, found: dict | None, taken=()):
    """``result`` with what came from the file added to its ``from_file`` (the lever's ``taken`` values, the
    medium and temperature ``found`` and not overridden) and the medium and temperature it assumed marked
    ``assumed``."""
    found = found or {}
    from_file = [*result["from_file"], *taken]
    assumed = list(result["assumed"])
    if getattr(args, "medium", None) is None:
        if found.get("medium"):
            from_file.append("medium")
        else:
            assumed.append(f"medium {medium.name} (none in the file: give {flags.NAMES['medium'].flag})")
    kelvin, source = flags.temperature(args, found)
    if source == "from the file":
        from_file.append("temperature")
    elif source != "given" and (medium.temperature is not None or "temperature" in result):
        assumed.append(f"temperature {kelvin:g} K ({source})")
    return result.updated(from_file=sorted(set(from_file)), assumed=list(dict.fromkeys(assumed)))


@contextmanager
def _fitting(where, check: str):
    """The fits run with one BLAS thread (they multiply tall, narrow matrices: threads only add overhead,
    about 1.5x on a shared machine); data that read correctly but defeat the numerics end in one line."""
    import numpy as np
    from threadpoolctl import threadpool_limits

    try:
        with threadpool_limits(1, user_api="blas"):
            yield
    except UserError:
        raise
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        raise UserError(f"{where}: the fit failed ({type(exc).__name__}: {exc}); check {check}") from None


def _check_something_to_compare(data, where) -> None:
    """A resonance table of the first free resonance alone, without its Q, holds nothing the model could miss:
    that resonance sets the lever's scale (the report said 'gap 0.00, missing effects: none').

    >>> import numpy as np
    >>> from types import SimpleNamespace as NS
    >>> _check_something_to_compare(NS(mode=np.array([1]), condition=np.array(["free"]), quality_factor=None), "t.csv")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: t.csv: only the first free resonance, which sets the lever's scale, and no Q: nothing to compare with the model (give contact resonances, higher free modes or a spectrum; a map is pfmdyn map's)
    """
    import numpy as np

    if getattr(data, "kind", None) == "spectrum" or not hasattr(data, "mode"):
        return
    scale_only = np.all((data.mode == 1) & (data.condition == "free"))
    q = data.quality_factor
    if scale_only and (q is None or not np.isfinite(np.asarray(q, float)).any()):
        raise UserError(f"{where}: only the first free resonance, which sets the lever's scale, and no Q: nothing to "
                        "compare with the model (give contact resonances, higher free modes or a spectrum; a map is "
                        "pfmdyn map's)")


def _emit(args, result, doc, figure) -> int:
    """Print a free lever's result, write its JSON ``doc`` and (``--plot``) the ``figure()`` it makes."""
    print(result.report())
    flags.write_json(args.json, doc)
    if args.plot:
        flags.save_figure(figure(), args.plot)
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``pfmdyn discrepancy``; returns the exit status."""
    from ..discrepancy import spectrum
    from ..discrepancy.inputs import is_sweep, is_thermal_tune, read
    from ..discrepancy.report import medium_comparison
    from ..io.record import MissingFieldError
    from ..io.results import check_writable
    from ..io.tables import SpectrumData, ignored_note

    check_writable(args.json)
    check_writable(args.plot, figure=True)
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers must be positive, got {args.workers}")
    if is_sweep(args.data) or args.reference:
        return _sweeps(args)
    if flags.given(args, ("added_mass_position",)):     # checked, then refused: it would be ignored
        raise UserError("--added-mass-position is for a drive sweep compared with --reference")
    if is_thermal_tune(args.data):
        return _thermal(args)
    overrides, assumed = flags.given(args, OVERRIDES), {}
    try:
        data = read(args.data, overrides)
    except MissingFieldError as exc:        # no instrument file records a tip height: the default, as every command
        missing = (exc.field,) if isinstance(exc.field, str) else exc.field
        if "tip_height" not in missing:
            raise
        assumed = flags.fill_defaults(overrides, ("tip_height",))
        if "length" in missing:         # only the assumed tip height over it acts, as in stiffness
            flags.assume_length(overrides, assumed)
        data = read(args.data, overrides)       # what else is missing, without the tip height
    _check_something_to_compare(data, args.data)
    if ignored_note(data):
        print(f"note: {args.data}: {ignored_note(data)}")
    if assumed:
        print(flags.assumed_line(assumed, data.metadata))
    given = flags.given_names(args, OVERRIDES)
    found = {name: getattr(data.metadata, name) for name in OVERRIDES        # f1 said once, as the free row's
             if getattr(data.metadata, name, None) is not None and name not in assumed
             and not (name == "free_resonance" and not isinstance(data, SpectrumData)
                      and data.metadata.free_resonance in data.frequency_hz[(data.condition == "free") & (data.mode == 1)])}
    print(flags.taken_line(found, given, [f"{len(data.frequency_hz)} spectrum rows" if isinstance(data, SpectrumData)
                                          else _rows_taken(data)]))
    stride = 1
    if isinstance(data, SpectrumData):
        rows = len(data.frequency_hz)
        data, stride = spectrum.thin(data)
    with _fitting(args.data, "the metadata (spring constant, length, tip height, free resonance)"):
        report = _analyse(data, args, assumed)
    if stride > 1:
        report = report.updated(frequency_stride=stride)
    if args.medium:
        report = report.updated(medium=medium_comparison(report.to_dict(), _lever_in_medium(data, args)))
    print(report.report())
    if not isinstance(data, SpectrumData):
        print(resonance_rows(data, report.to_dict()))
    if args.medium:
        m = report.to_dict()["medium"]
        fitted = "no free-mode damping fitted" if m["fitted_quality_factor"] is None else \
            f"the fitted damping gives Q {m['fitted_quality_factor']:.4g}"
        print(f"{flags.medium_line(flags.medium_from_args(args), args)}: predicts the first free mode's Q {m['predicted_quality_factor']:.4g} "
              f"(lever width {m['width']:g} m); {fitted}")
    if stride > 1:
        print(f"note: {rows} rows; one frequency in {stride} analysed (at most {spectrum.MAX_ROWS} rows)")
    lever = documents.lever_records({name: getattr(data.metadata, name, None) for name in OVERRIDES}, given=given,
                                    from_file=OVERRIDES, assumed=assumed)
    rows = None if isinstance(data, SpectrumData) else [(str(c), int(m)) for c, m in zip(data.condition, data.mode)]
    flags.write_json(args.json, documents.discrepancy_report(
        report.to_dict(), "spectrum" if rows is None else "resonances", {"path": str(args.data)}, lever, rows))
    if args.plot:
        # The path was checked before the analysis; a figure matplotlib then cannot save is one line.
        from ..plots.discrepancy import plot_resonance_report, plot_spectrum_report
        plot = plot_spectrum_report if isinstance(data, SpectrumData) else plot_resonance_report
        flags.save_figure(plot(data, report), args.plot)
    return 0
