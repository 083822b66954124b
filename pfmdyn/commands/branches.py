"""``pfmdyn branches``: resonance branches against contact stiffness, as PNG (and CSV)."""
from __future__ import annotations

import argparse

import csv

from ..errors import UserError
from ..generated import families
from . import flags
from .roots import parse_parameters, positive_int


def write_csv(path: str, family: str, stiffness, z, z1: float) -> None:
    """One row per stiffness: the roots ``z_n`` and ``f_n/f_1(free)``.

    >>> import os, tempfile
    >>> import numpy as np
    >>> d = tempfile.mkdtemp(); p = os.path.join(d, "b.csv")
    >>> write_csv(p, "indentation", np.array([1.0]), np.array([[2.0]]), 2.0)
    >>> open(p).read().splitlines()
    ['k1_over_k,z_1,f_1/f_free_1', '1,2,1']
    """
    from ..roots.branches import SWEPT, frequency_ratio

    freq = frequency_ratio(family, z, z1)
    n = z.shape[1]
    with open(path, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow([SWEPT[family], *(f"z_{i}" for i in range(1, n + 1)), *(f"f_{i}/f_free_1" for i in range(1, n + 1))])
        for s, row, fr in zip(stiffness, z, freq):
            out.writerow([f"{s:.10g}", *(f"{v:.15g}" for v in row), *(f"{v:.12g}" for v in fr)])


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn branches``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["elastic", "--plot", "b.png"]).points
    '400'
    """
    parser.add_argument("family", help=f"one of: {', '.join(f.roots for f in families.FAMILIES if f.branch)}")
    parser.add_argument("--plot", metavar="PATH", help="the figure to write (.png, .pdf, .svg); required")
    parser.add_argument("--out", dest="plot", help=argparse.SUPPRESS)      # the old spelling, one release
    parser.add_argument("--csv", default=None, metavar="PATH", help="also write the branches as CSV")
    parser.add_argument("--points", default="400", help="stiffness values on the log grid 1e-3..1e6 (default 400)")
    parser.add_argument("--modes", default="5", help="number of branches (default 5)")
    parser.add_argument("--k1-over-k", dest="k1_over_k", default=None,
                        help="elastic only: vertical stiffness k1/k held fixed (default 0)")
    flags.add_json(parser, "the branches and crossovers")


def run(args) -> int:
    """Sweep, then write the PNG (and CSV); prints the crossovers.

    >>> import argparse, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> run(argparse.Namespace(family="indentation", plot=os.path.join(d, "b.png"), csv=None,
    ...                        points="50", modes="2", k1_over_k=None, json=None))
    indentation: crossover of mode 1 at k1_over_k = 5.82 (beta = 2.901)
    indentation: crossover of mode 2 at k1_over_k = 47.9 (beta = 5.881)
    0
    """
    import numpy as np

    from ..derivations.certify import CertificationError
    from ..io.results import check_writable
    from ..plots.branches import plot_branches
    from ..roots.branches import SWEPT, branch_limits, crossovers, frequency_ratio, sweep

    if not args.plot:
        raise UserError("give --plot PATH (the figure to write)")
    check_writable(args.plot, figure=True)
    check_writable(args.csv, args.json)
    if args.family not in SWEPT:
        raise UserError(f"no branches for {args.family!r}; choose from {', '.join(SWEPT)}")
    points, modes = positive_int(args.points, "--points", 100_000), positive_int(args.modes, "--modes", 50)
    if points < 2:
        raise UserError("--points must be at least 2")
    fixed = {}
    if args.family == "elastic":
        fixed = parse_parameters("elastic", {"k1_over_k": args.k1_over_k or "0", "k2_ratio": "0", "k2t_HL": None})
        del fixed["k2_ratio"]
    elif args.k1_over_k is not None:
        raise UserError(f"--k1-over-k is swept (or absent) for {args.family!r}; it is fixed only for 'elastic'")
    stiffness = np.logspace(-3, 6, points)
    try:
        z = sweep(args.family, stiffness, modes, **fixed)
    except CertificationError as exc:
        raise UserError(str(exc)) from None
    s_cross, z_cross = crossovers(args.family, modes, **fixed)
    var = "xi L" if args.family.startswith("torsion") else "beta"
    for n, (s, zc) in enumerate(zip(s_cross, z_cross), 1):
        print(f"{args.family}: crossover of mode {n} at {SWEPT[args.family]} = {s:.3g} ({var} = {zc:.4g})")
    z1 = branch_limits(args.family, 1, **fixed)[0][0]
    try:
        plot_branches(args.family, stiffness, z, **fixed).savefig(args.plot)
        if args.csv:
            write_csv(args.csv, args.family, stiffness, z, z1)
    except OSError as exc:
        raise UserError(f"cannot write output: {exc.strerror or exc}") from None
    if args.json:
        from ..io import documents

        flags.write_json(args.json, documents.branches(args.family, SWEPT[args.family], stiffness, z,
                                                       frequency_ratio(args.family, z, z1), (s_cross, z_cross), fixed,
                                                       given=["k1_over_k"] if args.k1_over_k is not None else []))
    return 0
