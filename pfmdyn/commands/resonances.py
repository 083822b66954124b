"""``pfmdyn resonances``: where a probe's free and contact resonances are, certified.

Example: ``pfmdyn resonances --spring-constant 2.5 --free-resonance 5e4 --length 200e-6
--tip-height 10e-6 --k1 260 --k2-over-k1 0.85 --tip-mass-ratio 0.14 --tip-gyration-radius 2.5e-6
--tilt 11.5 --quality-factor 300 --json r.json``.  Tilt in degrees, positive when the free end is
nearer the sample than the clamp (the usual mounting).  See :mod:`pfmdyn.analysis.resonances`.
"""
from __future__ import annotations

from ..errors import UserError
from . import flags
from .roots import positive_int

__all__ = ["add_arguments", "run"]

ONE_LEVER = True
"""One lever at a few points: the NumPy forms of the lever (:func:`pfmdyn.commands.flags.lever_forms`)."""


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn resonances``: the probe's flags, ``--modes``, ``--json``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4",
    ...               "--tilt", "12"]).tilt
    '12'
    """
    parser.epilog = ("tilt: degrees, positive when the free end is nearer the sample than the clamp "
                     "(the usual mounting, 10-15 deg). No k2 and no k2 policy: k2 tied to k1 by Mindlin at Poisson's "
                     "ratio 0.3, as in pfmdyn stiffness, spot and map. No --tip-height: a typical PFM probe's, "
                     "13 um, as those commands assume.")
    flags.add_lever(parser, required=("spring_constant", "free_resonance", "length"))
    flags.add_contact(parser)
    flags.add(parser, ("k1_uncertainty",))
    flags.add_damping(parser)
    parser.add_argument("--modes", default="3", help="number of modes of each condition (default 3)")
    flags.add_json(parser)


def run(args) -> int:
    """Compute, print the table, write JSON if asked; 1 when a proof fails."""
    from ..analysis.resonances import resonances
    from ..io.results import check_writable

    check_writable(args.json)
    modes = positive_int(args.modes, "--modes", 50)
    assumed = {}
    lever = flags.cantilever(args, assumed=assumed)
    contact = flags.contact(args)
    k1_uncertainty = flags.given(args, ("k1_uncertainty",)).get("k1_uncertainty", 0.0)
    if contact.k1 is None and (contact.k2 is not None or contact.k2_over_k1 is not None
                               or contact.poisson is not None or contact.contact_loss or k1_uncertainty):
        raise UserError("a contact needs --k1")
    policy = {}
    if contact.k1 is not None:
        contact, words = contact.policy(lever)
        policy = {"k2_policy": words}
    result = resonances(lever, contact if contact.k1 is not None else None, modes)
    stderr, shares = None, {}
    if contact.k1 is not None and result.certified:
        from ..analysis.resonances import contact_spread
        from ..analysis.stiffness_report import assumed_variations
        stderr, shares = contact_spread(lever, contact, modes, assumed_variations(lever, flags.contact(args), contact,
                                                                                  assumed, k1_uncertainty))
    if lever.medium is not None:
        print(flags.medium_line(lever.medium, args))
    if assumed and contact.k1 is not None:
        print(flags.assumed_line(assumed, lever))
    print(result.report(stderr))
    moved = [words for name, words in (("tip_height_uncertainty", "tip height"), ("k2_policy_uncertainty",
                                                                                   "k2 policy"), ("k1_uncertainty", "k1"))
             if any(u != 0 for u in shares.get(name, ()))]
    if moved:
        print("contact resonances +- their standard uncertainty (their damped and peak frequencies move with them) over "
              "the inputs assumed or without one of their own, "
              f"each moved by its own: {', '.join(moved)}" + ("" if k1_uncertainty else " (k1 as given, exact)"))
    if policy:
        print(f"k2 policy: {policy['k2_policy']}")
    if args.json:
        from ..io import documents

        given = flags.given_names(args, (*flags.NAMES,))
        flags.write_json(args.json, documents.resonances({**result.to_dict(), **policy, "contact_stderr": stderr,
                                                          "k1_uncertainty": k1_uncertainty},
                                                         given))
    return 0 if result.certified else 1
