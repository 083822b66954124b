"""``pfmdyn stiffness``: contact stiffness k1 (and k2) from contact resonances.

Numbers on the command line::

    pfmdyn stiffness --free 75e3 --contact 300e3 --spring-constant 2 --contact-uncertainty 100

or an instrument file (free and contact resonance and spring constant from its metadata;
command-line values win) or a pfmdyn resonance table (CSV, ``mode,condition,frequency_hz``)::

    pfmdyn stiffness scan.ibw --k2-ratio 0.05 --json k1.json

Two or more ``--contact`` values (with their ``--mode`` numbers) give k1 and k2.
A contact-resonance frequency map (DART or CR tracking: ``contact_frequency_hz`` (ny, nx) in an
HDF5 file or Zarr group, see :mod:`pfmdyn.maps.contact`) becomes a k1 map, vectorised::

    pfmdyn stiffness dart.h5 --out result/      # result/maps.zarr: k1, k1_stderr
``--reduced-modulus`` converts k1 to E* with the Hertz relation (``--tip-radius``, ``--load``).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import UserError

__all__ = ["add_arguments", "run", "gather"]


def _number(text, what: str, *, allow_zero: bool = False) -> float | None:
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise UserError(f"{what} must be a number, got {text!r}") from None
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise UserError(f"{what} must be {'non-negative' if allow_zero else 'positive'} and finite, got {text}")
    return value


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn stiffness``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["--contact", "3e5", "--contact", "9e5", "--mode", "1", "--mode", "2"]).contact
    ['3e5', '9e5']
    """
    parser.add_argument("file", nargs="?", default=None,
                        help="instrument file (.ibw, .h5, .nid) or resonance table (.csv); optional")
    parser.add_argument("--free", default=None, metavar="HZ", help="first free resonance f1 (Hz)")
    parser.add_argument("--contact", action="append", default=None, metavar="HZ",
                        help="contact resonance (Hz); repeat for several modes")
    parser.add_argument("--mode", action="append", default=None, metavar="N",
                        help="mode number of each --contact (default 1, 2, ...)")
    parser.add_argument("--spring-constant", default=None, metavar="N/m", help="cantilever spring constant k")
    parser.add_argument("--k2-ratio", default=None, metavar="X",
                        help="longitudinal contact stiffness k2 H^2/(k L^2) held fixed (one contact mode; default 0)")
    parser.add_argument("--k2-over-k1", default=None, metavar="X",
                        help="k2 grows with k1 as k2 = X k1 (needs --length and --tip-height or a file giving them)")
    parser.add_argument("--poisson", default=None, metavar="NU",
                        help="Mindlin coupling k2/k1 = 2(1-nu)/(2-nu) for a sample of Poisson's ratio NU")
    parser.add_argument("--contact-uncertainty", default=None, metavar="HZ", help="standard uncertainty of each contact frequency")
    parser.add_argument("--free-uncertainty", default=None, metavar="HZ", help="standard uncertainty of f1")
    parser.add_argument("--spring-constant-uncertainty", default=None, metavar="N/m", help="standard uncertainty of k")
    parser.add_argument("--length", default=None, metavar="M", help="lever length L (for k2 in N/m)")
    parser.add_argument("--tip-height", default=None, metavar="M", help="tip height H (for k2 in N/m)")
    parser.add_argument("--reduced-modulus", action="store_true", help="also give E* from k1 (Hertz contact)")
    parser.add_argument("--tip-radius", default=None, metavar="M", help="tip radius R (with --reduced-modulus)")
    parser.add_argument("--load", default=None, metavar="N", help="normal load P (with --reduced-modulus)")
    parser.add_argument("--json", default=None, metavar="PATH", help="also write the result as JSON")
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="for a contact-frequency map (contact_frequency_hz): write DIR/maps.zarr with k1")


def _from_file(path: str, overrides: dict) -> dict:
    """free, contacts, modes, k (and L, H when known) from an instrument file or a resonance table."""
    from ..io.instruments import read_instrument, required_field

    if Path(path).suffix.lower() == ".csv":
        from ..io.tables import ResonanceData, read
        data = read(path)
        if not isinstance(data, ResonanceData):
            raise UserError(f"{path}: a resonance table (mode, condition, frequency_hz) is needed, not a spectrum")
        contact = data.condition == "contact"
        if not contact.any():
            raise UserError(f"{path}: no contact resonance in the table")
        free = [f for m, c, f in zip(data.mode, data.condition, data.frequency_hz) if c == "free" and m == 1]
        meta = data.metadata
        return {"free": overrides.get("free_resonance_hz") or (free[0] if free else meta.f1),
                "contacts": data.frequency_hz[contact].tolist(), "modes": data.mode[contact].tolist(),
                "k": overrides.get("spring_constant_n_per_m") or meta.k, "L": meta.L, "H": meta.H}
    record = read_instrument(path)
    contact = record.fields.get("contact_resonance_hz")
    return {"free": required_field(record, "free_resonance_hz", overrides),
            "contacts": [contact] if contact else [], "modes": [1],
            "k": required_field(record, "spring_constant_n_per_m", overrides),
            "L": record.fields.get("length_m"), "H": record.fields.get("tip_height_m")}


def gather(args) -> dict:
    """The inputs from the file and the command line, checked (command line wins)."""
    free = _number(args.free, "--free")
    k = _number(args.spring_constant, "--spring-constant")
    contacts = [_number(c, "--contact") for c in args.contact or []]
    modes = [int(_number(m, "--mode")) for m in args.mode or []]
    if any(m != int(m) for m in (float(x) for x in args.mode or [])):
        raise UserError("--mode must be a whole number")
    inputs = {"free": free, "contacts": contacts, "k": k, "L": _number(args.length, "--length"),
              "H": _number(args.tip_height, "--tip-height")}
    if args.file:
        found = _from_file(args.file, {"free_resonance_hz": free, "spring_constant_n_per_m": k})
        for key in ("free", "k", "L", "H"):
            inputs[key] = inputs[key] or found[key]
        if not contacts:
            inputs["contacts"], modes = found["contacts"], modes or found["modes"]
    if not inputs["contacts"]:
        where = f" in {Path(args.file).name}" if args.file else ""
        raise UserError(f"no contact resonance{where}: give --contact HZ")
    for key, option in (("free", "--free"), ("k", "--spring-constant")):
        if inputs[key] is None:
            raise UserError(f"no {'free resonance' if key == 'free' else 'spring constant'}: give {option}")
    modes = modes or list(range(1, len(inputs["contacts"]) + 1))
    if len(modes) != len(inputs["contacts"]):
        raise UserError(f"{len(inputs['contacts'])} contact resonances but {len(modes)} --mode values")
    inputs["modes"] = modes
    return inputs


def _coupling(args) -> float | None:
    """k2/k1 from --k2-over-k1 or --poisson (Mindlin), or None."""
    from ..analysis.stiffness import mindlin_k2_over_k1

    if args.k2_over_k1 is not None and args.poisson is not None:
        raise UserError("give --k2-over-k1 or --poisson, not both")
    if args.poisson is not None:
        nu = _number(args.poisson, "--poisson", allow_zero=True)
        return mindlin_k2_over_k1(nu)
    return _number(args.k2_over_k1, "--k2-over-k1")


def _is_contact_map(path: str) -> bool:
    """True for an HDF5 file or Zarr directory holding a contact-frequency map."""
    import os
    if not (os.path.isdir(path) or Path(path).suffix.lower() in (".h5", ".hdf5")):
        return False
    from ..maps.contact import is_contact_map
    try:
        return is_contact_map(path)
    except UserError:       # not HDF5 or Zarr: the instrument readers say what it is
        return False


def _contact_map(args) -> int:
    """k1 at every pixel of a contact-frequency map (command-line values win over the file's)."""
    from ..maps.contact import contact_map, describe
    if not args.out:
        raise UserError(f"{args.file}: a contact-frequency map needs --out DIR (gets maps.zarr with k1)")
    if args.contact or args.k2_ratio or args.k2_over_k1 or args.poisson or args.reduced_modulus:
        raise UserError("a contact-frequency map takes its contact frequencies from the file, with k2 = 0: "
                        "drop --contact, --k2-ratio, --k2-over-k1, --poisson and --reduced-modulus")
    overrides = {key: _number(getattr(args, flag), option) for flag, key, option in (
        ("free", "free_resonance_hz", "--free"), ("spring_constant", "spring_constant_n_per_m", "--spring-constant"),
        ("contact_uncertainty", "contact_uncertainty_hz", "--contact-uncertainty")) if getattr(args, flag) is not None}
    if args.mode:
        if len(args.mode) != 1:
            raise UserError("a contact-frequency map has one mode: give --mode once")
        overrides["contact_mode"] = int(_number(args.mode[0], "--mode"))
    print(describe(contact_map(args.file, args.out, overrides)))
    return 0


def run(args) -> int:
    """Compute k1 (and k2), print them with the branch proof, write JSON if asked."""
    from ..analysis.stiffness import (coupled_contact_stiffness, contact_stiffness, k1_k2_from_modes, reduced_modulus,
                                      reduced_modulus_uncertainty)
    from ..io.results import write_json

    if args.file and _is_contact_map(args.file):
        return _contact_map(args)
    if args.out:
        raise UserError("--out is for a contact-frequency map (a file holding contact_frequency_hz)")
    inputs = gather(args)
    sig_c = _number(args.contact_uncertainty, "--contact-uncertainty", allow_zero=True) or 0.0
    sig_f = _number(args.free_uncertainty, "--free-uncertainty", allow_zero=True) or 0.0
    sig_k = _number(args.spring_constant_uncertainty, "--spring-constant-uncertainty", allow_zero=True) or 0.0
    k2_fixed = _number(args.k2_ratio, "--k2-ratio", allow_zero=True)
    free, k = inputs["free"], inputs["k"]
    coupling = _coupling(args)
    if coupling is not None:
        if len(inputs["contacts"]) != 1 or k2_fixed is not None:
            raise UserError("--k2-over-k1/--poisson take one contact mode and no --k2-ratio")
        for key, option in (("L", "--length"), ("H", "--tip-height")):
            if not inputs[key]:
                raise UserError(f"k2 = {coupling:g} k1 needs the lever length and tip height: give {option}")
        r = coupled_contact_stiffness(inputs["contacts"][0], free, k, k2_over_k1=coupling, length_m=inputs["L"],
                                      tip_height_m=inputs["H"], mode=inputs["modes"][0],
                                      contact_uncertainty_hz=sig_c, free_uncertainty_hz=sig_f)
        k1, dk1 = float(r.k1_n_per_m), float(np.hypot(r.k1_uncertainty_n_per_m, r.k1_over_k * sig_k))
        k2_ratio, dk2, proofs = coupling * k1 / k * (inputs["H"] / inputs["L"]) ** 2, 0.0, []
        coupled_note = (f"k2 = {coupling:g} k1 along the branch; certified limits f/f1 = {r.proof.soft_ratio:.6g} "
                        f"(free) and {r.proof.stiff_ratio:.6g} (clamped-clamped); one positive k1 (checked)")
    elif len(inputs["contacts"]) == 1:
        r = contact_stiffness(inputs["contacts"][0], free, k, mode=inputs["modes"][0], k2_ratio=k2_fixed or 0.0,
                              contact_uncertainty_hz=sig_c, free_uncertainty_hz=sig_f,
                              spring_constant_uncertainty=sig_k, certify_root=True)
        k1, dk1, k2_ratio, dk2, proofs = float(r.k1_n_per_m), float(r.k1_uncertainty_n_per_m), k2_fixed or 0.0, 0.0, [r.proof]
    else:
        if k2_fixed is not None:
            raise UserError("--k2-ratio is for one contact mode; with two or more, k2 is determined")
        r = k1_k2_from_modes(inputs["contacts"], inputs["modes"], free, k, contact_uncertainty_hz=sig_c,
                             free_uncertainty_hz=sig_f, spring_constant_uncertainty=sig_k)
        k1, dk1, k2_ratio, dk2, proofs = r.k1_n_per_m, r.k1_uncertainty_n_per_m, r.k2_ratio, r.k2_ratio_uncertainty, list(r.proofs)
    out = {"inputs": {"free_resonance_hz": free, "contact_resonance_hz": inputs["contacts"], "modes": inputs["modes"],
                      "spring_constant_n_per_m": k, "contact_uncertainty_hz": sig_c, "free_uncertainty_hz": sig_f},
           "k1_n_per_m": k1, "k1_uncertainty_n_per_m": dk1, "k1_over_k": k1 / k,
           "k2_ratio": k2_ratio, "k2_ratio_uncertainty": dk2,
           "branch_proof": [p.text() for p in proofs] or [coupled_note]}
    # Without frequency or spring-constant uncertainties there is nothing to propagate.
    spread = f" +/- {dk1:.2g}" if dk1 > 0 else " (no uncertainty given: --contact-uncertainty, --free-uncertainty)"
    lines = [f"k1 = {k1:.6g}{spread} N/m  (k1/k = {k1 / k:.6g})",
             f"k2 H^2/(k L^2) = {k2_ratio:.6g}" + (f" +/- {dk2:.2g}" if len(proofs) > 1 else
                                                  " (held fixed)" if proofs else " (follows k1)")]
    if inputs["L"] and inputs["H"]:
        out["k2_n_per_m"] = k2_ratio * k * inputs["L"] ** 2 / inputs["H"] ** 2
        lines.append(f"k2 = {out['k2_n_per_m']:.6g} N/m  (L = {inputs['L']:g} m, H = {inputs['H']:g} m)")
    if args.reduced_modulus:
        radius, load = _number(args.tip_radius, "--tip-radius"), _number(args.load, "--load")
        if radius is None or load is None:
            raise UserError("--reduced-modulus needs --tip-radius (m) and --load (N)")
        e_star = float(reduced_modulus(k1, radius, load))
        out.update(reduced_modulus_pa=e_star, reduced_modulus_uncertainty_pa=float(reduced_modulus_uncertainty(k1, dk1, radius, load)),
                   tip_radius_m=radius, load_n=load)
        lines.append(f"E* = {e_star:.6g} +/- {out['reduced_modulus_uncertainty_pa']:.2g} Pa  (Hertz, R = {radius:g} m, P = {load:g} N)")
    lines.extend("branch proof, " + text for text in out["branch_proof"])
    print("\n".join(lines))
    if args.json:
        write_json(args.json, out)
    return 0
