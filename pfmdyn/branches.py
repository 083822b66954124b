"""``pfmdyn branches``: resonance branches against normalised contact stiffness (Figs. 4b, 4e, 5c).

Every branch family's characteristic function is affine in its swept stiffness ``s``:
``f(z; s) = f0(z) + s f1(z)``.  So the soft limit (``s -> 0``) has the roots of ``f0`` and
the stiff limit (``s -> oo``) the roots of ``f1``; both are computed certified by
:mod:`pfmdyn.roots`.  Branch ``n`` rises from soft root ``n`` to stiff root ``n``, and the
sweep brackets it there: ``f = s f1`` at the soft root and ``f = f0`` at the stiff root, whose
signs are checked to differ, so each bracket holds a root for every ``s > 0``.  The sweep
itself is double precision: vectorised Illinois (regula falsi) steps on all stiffness
values and modes at once.  The crossover of a branch is the stiffness at which it passes
midway between its limits; affinity gives it in closed form, ``s = -f0(z_mid)/f1(z_mid)``.

Families and the reading of the paper's figures:

* ``indentation`` (Fig. 4b, Eq. 28; ``frictionless`` is the same equation): ``k1_over_k``
  swept; free cantilever (Eq. 22) -> supported end (Eq. 20).
* ``elastic`` (Fig. 4e, longitudinal coupling, case 4c): ``k2_ratio`` swept with the
  vertical spring held at ``--k1-over-k`` (default 0, the figure's longitudinal spring
  alone); with k1 = 0: free cantilever -> tip slope held (``tan z = -tanh z``).
* ``torsion-elastic`` (Fig. 5c, Eq. 33): ``k2t_HL`` swept; clamped-free torsion
  ``(2n-1) pi/2`` -> clamped-clamped ``n pi``.

The y axis is the resonance frequency over the first free resonance: ``(z/z1)**2`` for
flexure (omega ~ beta**2) and ``z/z1`` for torsion (omega ~ xi).
"""
from __future__ import annotations

import csv
from functools import lru_cache

import numpy as np

from .errors import UserError
from .generated import characteristic
from .roots import CertificationError, certify, characteristic_function
from .roots_cli import parse_parameters, positive_int

__all__ = ["SWEPT", "LABELS", "add_arguments", "branch_limits", "sweep", "crossovers", "plot", "write_csv", "run"]

SWEPT = {"indentation": "k1_over_k", "frictionless": "k1_over_k", "elastic": "k2_ratio", "torsion-elastic": "k2t_HL"}
"""Branch family -> the stiffness parameter swept along the x axis."""

LABELS = {
    "k1_over_k": ("normalised vertical contact stiffness $k_1/k$", "soft limit: free end", "stiff limit: supported end"),
    "k2_ratio": ("normalised longitudinal contact stiffness $k_2H^2/(kL^2)$", "soft limit: free end",
                 "stiff limit: tip slope held"),
    "k2t_HL": ("normalised lateral contact stiffness $H^2k_2L/c_T$", "soft limit: free torsion",
               "stiff limit: clamped torsion"),
}
"""Swept parameter -> (x-axis label, soft-limit label, stiff-limit label)."""

_FIGURE = {"indentation": "Fig. 4b", "frictionless": "Fig. 4b", "elastic": "Fig. 4e", "torsion-elastic": "Fig. 5c"}


def _split(family: str, fixed: dict):
    """Exact callables (``fmpq`` parameters) for ``f0`` and ``f1`` of ``f = f0 + s f1``."""
    name = SWEPT[family]
    f_soft = characteristic_function(family, **fixed, **{name: 0})
    # f1 = (f(S) - f(0))/S holds exactly for any S; a huge S makes the ball radii of the
    # terms free of s (which cancel only in exact arithmetic) negligible in the difference.
    big = 2**64
    f_big = characteristic_function(family, **fixed, **{name: big})
    return f_soft, lambda z, m: (f_big(z, m) - f_soft(z, m)) / big


def branch_limits(family: str, modes: int, **fixed) -> tuple[np.ndarray, np.ndarray]:
    """Certified soft (``s = 0``) and stiff (``s -> oo``) limits of the first ``modes`` branches.

    >>> soft, stiff = branch_limits("indentation", 2)
    >>> soft.round(4).tolist(), stiff.round(4).tolist()
    ([1.8751, 4.6941], [3.9266, 7.0686])
    """
    return _limits(family, modes, tuple(sorted(fixed.items())))


@lru_cache(maxsize=32)
def _limits(family: str, modes: int, fixed: tuple) -> tuple[np.ndarray, np.ndarray]:
    # Cached: the sweep, the crossovers, the plot and the CSV all need the same limits.
    out = []
    for g in _split(family, dict(fixed)):
        flint_g = lambda s, g=g: g(s, characteristic.FLINT)    # noqa: E731 (binds g per limit)
        balls, _ = certify(flint_g, modes, 17, f_exact=flint_g)
        out.append(np.array([float(b.mid()) for b in balls]))
    return out[0], out[1]


def _numeric(family: str, fixed: dict):
    name, base = SWEPT[family], characteristic.FAMILIES[family]
    values = {k: float(v) for k, v in fixed.items()}
    return lambda z, s: base(z, np, **values, **{name: s})


def sweep(family: str, stiffness: np.ndarray, modes: int = 5, **fixed) -> np.ndarray:
    """Branch roots ``z[i, n]`` at ``stiffness[i]`` for modes ``n < modes``, double precision.

    >>> z = sweep("torsion-elastic", np.array([1e-6, 1.0, 1e6]), 2)
    >>> z.round(4).tolist()
    [[1.5708, 4.7124], [2.0288, 4.9132], [3.1416, 6.2832]]
    """
    soft, stiff = branch_limits(family, modes, **fixed)
    f = _numeric(family, fixed)
    s = np.asarray(stiffness, dtype=float)[:, None]
    a, b = np.broadcast_to(soft, (s.size, modes)).copy(), np.broadcast_to(stiff, (s.size, modes)).copy()
    with np.errstate(under="ignore"):       # exp(-z) underflows harmlessly at large z
        fa, fb = f(a, s), f(b, s)
        if np.any(np.sign(fa) * np.sign(fb) > 0):
            raise CertificationError(f"{family}: a branch is not bracketed by its soft and stiff limits")
        for _ in range(100):
            done = (np.abs(b - a) <= 4e-16 * np.abs(b)) | (fb == 0)
            if done.all():
                break
            step = np.where(done, 0.0, fb * (b - a) / np.where(done, 1.0, fb - fa))
            c = b - step
            fc = f(c, s)
            flip = np.sign(fc) * np.sign(fb) < 0
            # Illinois: keep the bracket; halve the stale end's value so it cannot stall.
            a, fa = np.where(flip, b, a), np.where(flip, fb, fa / 2)
            b, fb = np.where(done, b, c), np.where(done, fb, fc)
    return b


def crossovers(family: str, modes: int = 5, **fixed) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness at which each branch passes midway between its limits, and that midpoint.

    >>> s, z = crossovers("indentation", 3)
    >>> np.round(np.log10(s), 2).tolist()
    [0.77, 1.68, 2.24]
    """
    soft, stiff = branch_limits(family, modes, **fixed)
    f = _numeric(family, fixed)
    mid = (soft + stiff) / 2
    f0 = f(mid, 0.0)
    return -f0 / (f(mid, 1.0) - f0), mid


def _frequency(family: str, z: np.ndarray, z1: float) -> np.ndarray:
    return z / z1 if family.startswith("torsion") else (z / z1) ** 2


def write_csv(path: str, family: str, stiffness: np.ndarray, z: np.ndarray, z1: float) -> None:
    """One row per stiffness: the roots ``z_n`` and ``f_n/f_1(free)``.

    >>> import io, tempfile, os
    >>> d = tempfile.mkdtemp(); p = os.path.join(d, "b.csv")
    >>> write_csv(p, "indentation", np.array([1.0]), np.array([[2.0]]), 2.0)
    >>> open(p).read().splitlines()
    ['k1_over_k,z_1,f_1/f_free_1', '1,2,1']
    """
    freq = _frequency(family, z, z1)
    n = z.shape[1]
    with open(path, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow([SWEPT[family], *(f"z_{i}" for i in range(1, n + 1)), *(f"f_{i}/f_free_1" for i in range(1, n + 1))])
        for s, row, fr in zip(stiffness, z, freq):
            out.writerow([f"{s:.10g}", *(f"{v:.15g}" for v in row), *(f"{v:.12g}" for v in fr)])


def plot(path: str, family: str, stiffness: np.ndarray, z: np.ndarray, **fixed) -> None:
    """Branches on log axes with dashed limits and the crossovers joined by a dotted line.

    Built on :class:`matplotlib.figure.Figure` (no pyplot), like :mod:`pfmdyn.plotting`.

    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "b.png")
    >>> s = np.logspace(-3, 6, 20)
    >>> plot(p, "torsion-elastic", s, sweep("torsion-elastic", s, 2))
    >>> os.path.getsize(p) > 0
    True
    """
    from matplotlib.figure import Figure

    modes = z.shape[1]
    soft, stiff = branch_limits(family, modes, **fixed)
    s_cross, z_cross = crossovers(family, modes, **fixed)
    xlabel, soft_label, stiff_label = LABELS[SWEPT[family]]

    def freq(v):
        return _frequency(family, np.asarray(v), soft[0])

    fig = Figure(figsize=(8.4, 5.0), dpi=150, layout="constrained")
    ax = fig.add_subplot()
    colors = [f"C{i}" for i in range(modes)]
    for n in range(modes):
        ax.axhline(freq(soft[n]), color="0.55", ls="--", lw=0.9, label=soft_label if n == 0 else None)
        ax.axhline(freq(stiff[n]), color="0.15", ls="--", lw=0.9, label=stiff_label if n == 0 else None)
        ax.plot(stiffness, freq(z[:, n]), color=colors[n], lw=2, label=f"mode {n + 1}")
    inside = (s_cross >= stiffness[0]) & (s_cross <= stiffness[-1])
    ax.plot(s_cross[inside], freq(z_cross[inside]), "k:", lw=1.2)
    ax.plot(s_cross[inside], freq(z_cross[inside]), "o", mfc="white", mec="k", ms=6,
            label="crossover (midway free to stiff)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(stiffness[0], stiffness[-1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel("resonance frequency  $f_n / f_1^{\\mathrm{free}}$")
    fixed_text = "".join(f", {k} = {v}" for k, v in fixed.items())
    ax.set_title(f"{family}{fixed_text}: first {modes} resonance branches (cf. {_FIGURE[family]})", fontsize=10)
    ax.grid(True, which="major", color="0.9", lw=0.6)
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)    # keeps the branches clear
    fig.savefig(path)


def add_arguments(parser) -> None:
    """Arguments of ``pfmdyn branches``.

    >>> import argparse
    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["elastic", "--out", "b.png"]).points
    '400'
    """
    parser.add_argument("family", help=f"one of: {', '.join(SWEPT)}")
    parser.add_argument("--out", required=True, metavar="PATH.png", help="PNG file to write")
    parser.add_argument("--csv", default=None, metavar="PATH", help="also write the branches as CSV")
    parser.add_argument("--points", default="400", help="stiffness values on the log grid 1e-3..1e6 (default 400)")
    parser.add_argument("--modes", default="5", help="number of branches (default 5)")
    parser.add_argument("--k1-over-k", dest="k1_over_k", default=None,
                        help="elastic only: vertical stiffness k1/k held fixed (default 0)")


def run(args) -> int:
    """Sweep, then write the PNG (and CSV); prints the crossovers.

    >>> import argparse, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> run(argparse.Namespace(family="indentation", out=os.path.join(d, "b.png"), csv=None,
    ...                        points="50", modes="2", k1_over_k=None))
    indentation: crossover of mode 1 at k1_over_k = 5.82 (beta = 2.901)
    indentation: crossover of mode 2 at k1_over_k = 47.9 (beta = 5.881)
    0
    """
    if args.family not in SWEPT:
        raise UserError(f"no branches for {args.family!r}; choose from {', '.join(SWEPT)}")
    points, modes = positive_int(args.points, "--points"), positive_int(args.modes, "--modes")
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
    try:
        plot(args.out, args.family, stiffness, z, **fixed)
        if args.csv:
            write_csv(args.csv, args.family, stiffness, z, branch_limits(args.family, 1, **fixed)[0][0])
    except OSError as exc:
        raise UserError(f"cannot write output: {exc.strerror or exc}") from None
    return 0
