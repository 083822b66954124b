"""``pfmdyn map``: the elastic-contact beam model fitted at every pixel of a band-excitation map.

::

    pfmdyn map scan.h5 --out result/                       # Dask local scheduler, all cores
    pfmdyn map scan.h5 --out result/ --scheduler tcp://host:8786
    pfmdyn map be_usid.h5 --out result/ --spring-constant 2 --length 225e-6   # pycroscopy USID
    pfmdyn map be_usid.h5 --out result/ --model sho        # BGlib's SHO, result/be_usid.h5 in BGlib's layout
    pfmdyn map dart.ibw --out result/ --tip-height 12e-6 --plot figures/ --json -     # an Asylum DART image

The input holds ``response`` (ny, nx, n_freq, complex; or (ny, nx, n_bias, n_freq) with
``bias_v``, which adds maps of the electrostatic term and the nulling bias), ``frequency_hz`` and
the cantilever metadata as root attributes; ``result/maps.zarr`` gets one (ny, nx) array per quantity with its
units in the attributes.  A contact-resonance frequency map (``contact_frequency_hz``, (ny, nx))
becomes a k1 map through :func:`pfmdyn.analysis.stiffness.contact_stiffness`.  An Asylum DART
image (``.ibw``, :mod:`pfmdyn.io.dart`) becomes maps of the contact resonance and Q (the
two-frequency oscillator's through the lever's response at each pixel's drives), k1, the contact loss
(each pixel's contact fitted with its alike neighbours', ``--pool``) and the signed d_eff (the lever),
and of how far the oscillator is from the lever (:mod:`pfmdyn.maps.dart`).  Rerunning an interrupted command resumes where it stopped.
A USID input also gets its fit in BGlib's layout (:mod:`pfmdyn.maps.usid`): in a copy of the input
in ``result/`` (default) or, with ``--usid-inplace``, in the input file itself.
"""
from __future__ import annotations

import argparse

import dataclasses
import math

from ..errors import UserError, listed
from ..fitting.noise import GAP_LIMIT
from ..names import NAMES, checked, flag
from . import flags

__all__ = ["add_arguments", "run", "write_summary"]

_LEVER = ("spring_constant", "free_resonance", "length", "tip_height", "tip_position", "tip_mass_ratio",
          "tip_gyration_radius", "tilt", "spot_position")
_CONTACT = ("k2", "k2_over_k1", "poisson")
"""The probe's flags (:mod:`pfmdyn.commands.flags`): they override the file's metadata."""
_SPREAD = ("tip_height_uncertainty",)
"""The assumed inputs' spreads k1's standard error takes (flags over the defaults)."""
_DART = ("drive_amplitude", "frequency_width")
"""A DART image's settings, over its note's."""


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn map``."""
    parser.add_argument("data", metavar="INPUT", help="map file: HDF5 (.h5) or Zarr directory with response (ny, nx[, n_bias], n_freq), "
                                     "frequency_hz[, bias_v]; or USID BE/BEPS HDF5; or contact_frequency_hz (ny, nx); "
                                     "or an Asylum DART image (.ibw, dual AC resonance tracking)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory (gets maps.zarr)")
    parser.add_argument("--model", default="auto",
                        help="per-pixel model: 'elastic' (elastic contact, k1, internal friction 1/Q, complex d_eff "
                             "per band, and k2 when the frequencies hold two or more contact-mode bands) plus damping "
                             "mechanisms '+viscous' (drag) and/or '+contact' (dashpot), and '+distributed' (the "
                             "electrostatic load along the lever, beside the local one at the tip); 'auto' (default) "
                             "chooses them "
                             "on 16 pixels spread over the map (BIC + gap rule of pfmdyn discrepancy) and reports it; "
                             "'sho': BGlib's simple harmonic oscillator per spectrum and band (resonance frequency, Q, "
                             "amplitude, phase; no lever metadata needed)")
    parser.add_argument("--usid-inplace", action="store_true",
                        help="USID input: write the results group into the input file (as BGlib does) instead of a "
                             "copy of it in --out")
    parser.add_argument("--block", type=int, default=None,
                        help="pixels per block side (default: an interrupted run's; else as many pixels as hold about 4k "
                             "spectra, 16k for --model sho)")
    parser.add_argument("--scheduler", default=None,
                        help="'processes' (default: one worker process per core), 'threads', 'sync' (one core), "
                             "or tcp://HOST:PORT of a dask.distributed scheduler")
    parser.add_argument("--workers", type=int, default=None, help="local worker processes, or for --model sho threads (default: all cores)")
    parser.add_argument("--max-blocks", type=int, default=None,
                        help="stop after this many blocks (rerun the same command to continue)")
    parser.add_argument("--start-quality-factor", type=float, default=100.0, metavar="Q",
                        help="the fit's starting Q of the contact mode, not a lever's internal friction (default 100)")
    parser.add_argument("--quality-factor", dest="start_quality_factor", type=float, help=argparse.SUPPRESS)   # old
    parser.add_argument("--gap-threshold", type=float, default=GAP_LIMIT,
                        help="noise-normalised RMS residual (1 = fitted to the noise, as in pfmdyn discrepancy) above "
                             f"which a pixel is marked unexplained (default {GAP_LIMIT:g})")
    flags.add(parser, ("surface_potential",), defaults={"surface_potential": (
        None, "fitted with +distributed, else 0, the intercept; for maps with a bias axis d_eff is the response at "
              "this bias, the electrostatic term and the nulling bias do not depend on it")})
    parser.add_argument("--pool", type=int, default=5, metavar="R",
                        help="DART images: fit each pixel's contact (k1, contact loss, hence the contact resonance and "
                             "Q) to its own and its alike neighbours' signals within R pixels (default 5; 0: each "
                             "pixel alone)")
    parser.add_argument("--phase-offset", type=float, default=0.0, metavar="DEG",
                        help="DART images: the lock-ins' phase offset (degrees), taken off Phase1 and Phase2 (default "
                             "0); the run reports the offset the image's drives show, modulo 180 degrees")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--plot", metavar="DIR", help="also write DIR/NAME.png for each map")
    parser.add_argument("--png", action="store_true", help=argparse.SUPPRESS)   # the old spelling: --plot OUT
    flags.add_json(parser, "the run's summary")
    flags.add_lever(parser, _LEVER)
    flags.add_contact(parser, _CONTACT)
    flags.add(parser, _SPREAD)
    flags.add(parser, _DART)


def _mechanisms(args, source, fit_options):
    """Mechanisms from --model (and the selection rows when auto): auto reuses an
    interrupted run's choice, else selects on pixels spread over the map."""
    import os
    from ..maps.spec import model_name, parse_model
    if args.model != "auto":
        return parse_model(args.model), None
    from ..maps.driver import earlier_run
    if "model" in (attrs := earlier_run(os.path.join(args.out, "maps.zarr"))):
        print(f"model (auto, as chosen by the interrupted run): {attrs['model']}")
        return parse_model(attrs["model"]), attrs.get("model_selection")
    from ..maps.select import choose_model
    mechanisms, rows = choose_model(source, **fit_options)
    print(f"model (auto, on pixels spread over the map): {model_name(mechanisms)}; " + ", ".join(
        f"{r['model']} BIC {r['bic']:.1f} gap {r['gap']:.3g}" for r in rows))
    return mechanisms, rows


def _progress_bar(enabled: bool, unit: str = "block"):
    """A tqdm bar of blocks (or ``unit``) done (of the whole map) with pixels per second, as a
    :func:`pfmdyn.maps.driver.run_map` progress callback (None when disabled) and its closer."""
    if not enabled:
        return None, lambda: None
    from tqdm.auto import tqdm
    state = {}

    def report(done, total, pixels):
        if "bar" not in state:
            state["bar"] = tqdm(total=total, initial=done, unit=unit)
            return
        bar = state["bar"]
        bar.update(done - bar.n)
        bar.set_postfix(pixels_per_s=f"{pixels / max(bar.format_dict['elapsed'], 1e-9):.0f}")

    return report, lambda: state["bar"].close() if "bar" in state else None


def run(args) -> int:
    """Fit the map and print a summary line."""
    import os
    from ..io.results import check_writable
    from ..maps.driver import check_scheduler, open_map, run_map
    check_writable(args.json)
    checked("quality_factor", args.start_quality_factor, "--start-quality-factor")
    for name in ("block", "gap_threshold", "workers", "max_blocks"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UserError(f"--{name.replace('_', '-')} must be positive, got {value}")
    check_scheduler(args.scheduler)
    if args.model not in ("auto", "sho"):
        from ..maps.spec import parse_model
        parse_model(args.model)         # checked whatever the input, as every flag
    overrides = flags.given(args, _LEVER + _CONTACT + _SPREAD + ("width",))
    dart_settings = flags.given(args, _DART)        # checked whatever the input, as every flag
    if args.medium:             # the fluid around the lever: its load enters the beam model
        overrides["medium"] = flags.medium_from_args(args)
    from ..io.kinds import CONTACT_MAP_KINDS, file_kind
    from ..maps.contact import contact_map, describe
    if file_kind(args.data) in CONTACT_MAP_KINDS:
        if args.medium:
            raise UserError(f"{args.data}: a map of contact resonances is inverted by the paper's lever in vacuum; "
                            "for a lever in a medium use pfmdyn stiffness")
        unused = [flag(name) for name in overrides if name not in ("spring_constant", "free_resonance")]
        unused += ["--model"] * (args.model != "auto")
        if unused:      # a value given is a value meant: not dropped in silence
            raise UserError(f"{args.data}: a contact-frequency map is read on the paper's lever with k2 = 0 (the "
                            f"tip at the free end), which {listed(unused)} would not enter: drop "
                            + ("it" if len(unused) == 1 else "them"))
        summary = contact_map(args.data, args.out, overrides)
        print(describe(summary))
        _draw(args)         # a figure of k1 and its error (--plot was ignored here)
        write_summary(args.json, args.out, args.data, summary, overrides)
        return 0
    if file_kind(args.data) == "asylum":
        if args.medium:
            raise UserError(f"{args.data}: a DART image is inverted on the lever in vacuum (or air); a medium's load "
                            "is not in this inversion")
        return _dart(args, overrides, dart_settings)
    sho = args.model == "sho"
    source = open_map(args.data, overrides, sho=sho)
    if args.usid_inplace and source.layout != "usid":
        raise UserError(f"{args.data}: --usid-inplace needs a USID input (this file has the plain layout)")
    copy = os.path.join(args.out, os.path.basename(args.data))
    if source.layout == "usid" and not args.usid_inplace and os.path.exists(copy) and os.path.samefile(copy, args.data):
        raise UserError(f"{args.data}: --out is the input's folder, where the copy with the fit would replace the "
                        "input; choose another --out, or --usid-inplace to write into the input")
    surface_potential = flags.given(args, ("surface_potential",)).get("surface_potential")
    if args.medium:
        print(flags.medium_line(overrides["medium"], args))
    if source.assumed:
        print(flags.assumed_line(source.assumed, source.model.lever))
    n_bands = len(source.model.bands)
    biases = source.model.bias_v
    if sho:
        fit_options, rows = {"gap_threshold": args.gap_threshold}, None
        print(f"fitting: an SHO per spectrum and band ({n_bands} band{'s' if n_bands > 1 else ''}"
              + (f", {len(biases)} biases" if biases is not None else "") + ")")
    else:
        fit_options = {"q0": args.start_quality_factor, "gap_threshold": args.gap_threshold,
                       "surface_potential_v": surface_potential}
        mechanisms, rows = _mechanisms(args, source, fit_options)
        source = dataclasses.replace(source, model=dataclasses.replace(source.model, mechanisms=mechanisms))
        print(f"fitting: k1 ({source.model.describe_k2()}), "
              f"complex d_eff per band ({n_bands} band{'s' if n_bands > 1 else ''})"
              + (f", electrostatic term and nulling bias ({len(biases)} biases, {min(biases):g} to {max(biases):g} V)"
                 if biases is not None else ""))
    progress, close = _progress_bar(flags.progress_shown(args))
    try:
        s = run_map(source, args.out, block=args.block, scheduler=args.scheduler, workers=args.workers,
                    max_blocks=args.max_blocks, progress=progress, selection=rows, **fit_options)
    finally:
        close()
    _draw(args)
    written = ""
    if source.layout == "usid":
        from ..maps.usid import write_usid
        target = args.data if args.usid_inplace else copy
        written = f"; {'SHO' if sho else 'beam'} fit in BGlib's layout: {target}:{write_usid(source, s['out'], target)}"
    print(s.report() + written)
    assumed = {name: (getattr(source.model.lever, name), why) for name, why in source.assumed.items()}
    write_summary(args.json, args.out, args.data, s.to_dict(), overrides, s.shape, assumed)
    return 0


def _draw(args, dart: bool = False) -> None:
    """``--plot DIR`` (or the old ``--png``, into ``--out``): a PNG of each map in the store (with ``dart``, the
    DART summary figure too)."""
    import os
    folder = args.plot or (args.out if args.png else None)
    if not folder:
        return
    from ..maps import open_result
    from ..plots.maps import plot_dart, plot_maps
    os.makedirs(folder, exist_ok=True)
    result = open_result(args.out)
    for name, figure in {**plot_maps(result), **({"dart": plot_dart(result)} if dart else {})}.items():
        figure.savefig(os.path.join(folder, f"{name}.png"), dpi=100)


def write_summary(json_path, out, data, summary: dict, overrides: dict, shape=None, assumed: dict | None = None) -> None:
    """``--json``: the summary document (:func:`pfmdyn.io.documents.map_summary`) of a run on ``data`` into
    ``out``; ``assumed``: name -> (value, why) of the lever's defaults taken."""
    if json_path:
        from ..io import documents
        from ..maps import open_result

        shape = shape or tuple(open_result(out)[["k1"]]["k1"].shape)
        given = {name: value for name, value in overrides.items() if name != "medium"}
        flags.write_json(json_path, documents.map_summary(summary, data, shape, given, assumed=assumed))


def _check_note(path, entries: dict) -> None:
    """Each value a DART image's note gave (name -> (value, status, ...)) within what a probe can have, a
    bad one named by the file and its key (it said 'quality_factor must be in ...', naming neither).

    >>> _check_note("d.ibw", {"quality_factor": (-5.0, "file", "ThermalQ"), "length": (2e-4, "given")})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: d.ibw, ThermalQ in the note: quality_factor must be in (0.1, 1e+09], got -5.0
    """
    from ..io.asylum import NOTE_KEYS
    from ..io.dart import DART_KEYS

    keys = {**NOTE_KEYS, **DART_KEYS, "quality_factor": NOTE_KEYS["free_quality_factor"]}
    for name, (value, status, *_) in entries.items():
        if status == "file" and name in NAMES:
            checked(name, value, f"{path}, {keys.get(name, name)} in the note")


def _dart(args, overrides: dict, given: dict) -> int:
    """A DART image: the lever from the note and the flags, every pixel inverted both ways, the maps
    written (and drawn, and summarised in JSON)."""
    import os

    import numpy as np
    from .. import Cantilever, Contact
    from ..io.dart import read_dart
    from ..maps.dart import document, drive_axis, invert, write_dart
    image = read_dart(args.data)
    found = {name: (value, "file", f"the note of {os.path.basename(args.data)}")
             for name, value in image.fields.items() if name in _LEVER}
    found.update({name: (value, "given") for name, value in overrides.items() if name in _LEVER})
    if "free_quality_factor" in image.fields:
        found["quality_factor"] = (image.fields["free_quality_factor"], "file",
                                   "the free lever's ThermalQ, taken as its internal friction")
    else:
        found["quality_factor"] = (math.inf, "assumed", "no ThermalQ in the note: the lever lossless")
    settings = {name: (value, "file", "the note") for name, value in image.settings.items() if name in _DART}
    _check_note(args.data, {**found, **settings})
    settings.update({name: (value, "given") for name, value in given.items()})
    values = {name: entry[0] for name, entry in found.items()}
    flags.require(values, ("spring_constant", "free_resonance", "length"), args.data)
    flags.require({name: entry[0] for name, entry in settings.items()}, _DART, args.data)
    for name, why in flags.fill_defaults(values, _LEVER).items():
        found[name] = (values[name], "assumed", why)
        print(flags.assumed_line({name: why}, Cantilever.from_values(values)))
    lever = Cantilever.from_values(values)
    if "tip_height_uncertainty" in overrides:
        found["tip_height_uncertainty"] = (overrides["tip_height_uncertainty"], "given")
    else:
        from ..analysis.stiffness_report import tip_height_spread
        assumed = found["tip_height"][1] == "assumed"
        found["tip_height_uncertainty"] = (tip_height_spread(lever.tip_height, assumed), "assumed", (
            NAMES["tip_height_uncertainty"].default_why if assumed else "10 % of the tip height, the datasheets' "
            "tolerance") + ": its share is in k1_stderr")
    contact, k2_policy = Contact(**{name: overrides[name] for name in _CONTACT if name in overrides}).policy(lever)
    if contact.k2_of(1.0) or lever.tilt:
        from ..analysis.contact_resonance import require_tip_height
        require_tip_height(lever, "k2 or a tilt")
    ny, nx = image.centre.shape
    print(f"DART image: {ny} lines x {nx} points ({image.direction}); lever k {lever.spring_constant:.4g} N/m, "
          f"f1 {lever.free_resonance:.6g} Hz, Q {lever.quality_factor:.4g}; drive {settings['drive_amplitude'][0]:g} V, "
          f"df {settings['frequency_width'][0]:.6g} Hz; {k2_policy}")
    for note in image.notes:
        print(note)
    print(flags.taken_line({name: entry[0] for name, entry in {**found, **settings}.items() if entry[1] == "file"
                            and name in NAMES}, ()))
    f1, f2 = image.frequencies(settings["frequency_width"][0])
    # a lag less by the offset: s = A exp(-i (phi - offset))
    s1, s2 = (s * np.exp(1j * math.radians(args.phase_offset)) for s in image.signals)
    report, close = _progress_bar(flags.progress_shown(args), unit="pixel")
    try:
        maps, sigma = invert(f1, f2, s1, s2, lever, contact, settings["drive_amplitude"][0], pool=args.pool,
                             progress=None if report is None else lambda done, total: report(done, total, done),
                             tip_height_uncertainty=found["tip_height_uncertainty"][0])
    finally:
        close()
    axis = drive_axis(lever, contact, f1, s1, maps["k1"], maps["contact_loss"])
    left = 90.0 if axis == -90.0 else -axis         # a drive's argument -a is a lag a, as the phases
    phases = f"phases: {args.phase_offset:g} deg taken off both (--phase-offset); the offset left, from the domains' drives: "
    if math.isfinite(left):
        phases += f"{left:+.1f} deg (mod 180)" + ("; beyond 45 deg d_eff's sign may be flipped: set --phase-offset"
                                                  if abs(left) > 45 else "")
    else:
        phases, left = phases + "undetermined (no pixel determined)", None
    print(phases)
    out = os.path.join(args.out, "maps.zarr")
    write_dart(out, maps, {"model": "dart", "source": str(args.data), "channel_noise": sigma, "k2_policy": k2_policy,
                           "pool_radius": args.pool, "phase_offset_deg": args.phase_offset,
                           "phase_offset_left_deg": left, "tip_height": lever.tip_height,
                           "tip_height_uncertainty": found["tip_height_uncertainty"][0],
                           "assumed": {name: entry[2] for name, entry in found.items() if entry[1] == "assumed"}})
    _draw(args, dart=True)
    doc = document(maps, sigma, found, settings, str(args.data), out, k2_policy, args.pool, phases)
    ok = maps["determined"].astype(bool)
    if ok.any():
        median = {name: record["value"] for name, record in doc["results"].items()}

        def pm(name, scale=1.0):        # the median and the median pixel's uncertainty, to the digits it leaves
            from ..digits import plus_minus
            return plus_minus(doc["results"][name]["value"] * scale, (doc["results"][name]["stderr"] or 0.0) * scale)
        print(f"DART: {ok.sum()}/{ok.size} pixels determined, noise {100 * sigma:.2g} %; medians (+- the median "
              f"pixel's uncertainty): contact resonance {pm('contact_resonance')} Hz, Q {pm('contact_quality_factor')}, "
              f"k1 {pm('k1')} N/m, contact loss {pm('contact_loss')}, |d_eff| {pm('d_eff', 1e12)} pm/V; the "
              f"oscillator's point-mass k1 {100 * median['oscillator_k1_error']:+.1f} %, its d_eff "
              f"{100 * median['oscillator_d_eff_error']:+.1f} %; maps in {out}")
    else:
        noise = f"noise {100 * sigma:.2g} %" if math.isfinite(sigma) else "noise undetermined"
        print(f"DART: no pixel determined (of {ok.size}; {noise}): the two drives' amplitudes and "
              f"phases fix no contact anywhere (both drives on one side of the peak, or no resonance between them); "
              f"maps (undetermined) in {out}")
    flags.write_json(args.json, doc)
    return 0
