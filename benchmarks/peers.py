"""Side by side with the tools band-excitation users run: BGlib's SHO guess and fit, sidpy's
``SidpyFitterRefactor``, ``pfmdyn map --model sho`` and pfmdyn's beam fit, on the same USID files.

Two files written with pyUSID, as BE users' files are: a ``side`` x ``side`` map of a lever
(k = 2 N/m, L = 225 um, H = 10 um, f1 = 75 kHz, Q = 80) in contact, k1 drawn per pixel from 16
values log-spaced over 100-800 N/m, complex noise of 1 % of each pixel's peak:

* ``one band``: ``bins`` frequencies around the first contact resonance (k2 = 0);
* ``two bands``: ``bins / 2`` frequencies around each of the first two contact resonances,
  k2 = 0.5 k1 (the beam fit then fits k2; the SHO tools see one resonance per band, and BGlib
  and sidpy, which fit one SHO over the whole frequency vector, only the first).

The spectra come from the finite-element beam of ``tests/fe_beam.py``, not from pfmdyn's model.
Per tool: pixels per second on one core (BLAS limited to one thread, Dask synchronous, BGlib
``cores=1``), at scale (pfmdyn's compiled kernels loaded before the clock starts, the beam's by a
run on the sample first; each pfmdyn row includes its run's set-up, Dask and the Zarr output), and
its ratio to BGlib's guess + fit in the same run.  BGlib and both pfmdyn fits fit the whole map;
sidpy, the slowest, fits its first ``sample`` x ``sample`` pixels (the pixels are drawn
independently, so any of them are a fair sample), named in the table.  Accuracy:

* SHO tools: the fraction of pixels whose frequency is within 2e-4 and Q within 3 % of the best
  SHO description of the noise-free spectrum (a least-squares SHO fit to it, by SciPy, per
  distinct k1), for the first band; and k1 by today's BE route, the SHO frequency of the first
  contact mode through ``pfmdyn stiffness`` (:func:`pfmdyn.analysis.stiffness.contact_stiffness`);
* the beam fit: k1 itself.  k1 is scored by its median relative error and the fraction of
  pixels within 2 % of the truth.

Peers are optional: ``pip install 'pfmdyn[peers]'``, then ``pip install --no-deps -U
"numpy_groupies>=0.9.22"`` (bglib 0.0.6 pins 0.9.7, which fails on NumPy >= 1.24).  Two more
workarounds are applied here: pyUSID 0.0.12 calls ``np.product`` (gone in NumPy 2: aliased to
``np.prod``), and on NumPy >= 2.4 BGlib's fit write-back fails on SciPy's shape-(1,) residual
(its ``least_squares`` is wrapped to return it as a scalar).  A missing peer is skipped and named.

    python benchmarks/peers.py [--side 128] [--bins 128] [--sample 32]

The results go to ``benchmarks/results/peers.md`` (:mod:`recording`).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import os
import shutil
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.optimize
from threadpoolctl import threadpool_limits

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from fe_beam import FEBeam  # noqa: E402
from recording import recorded  # noqa: E402

K, L, F1, H, Q = 2.0, 225e-6, 75e3, 10e-6, 80.0
NOISE = 0.01


def hand_sho(f, amplitude, f0, q):
    """BGlib's SHO, typed from its documentation (complex amplitude A e^{i phi})."""
    return amplitude * f0**2 / (f**2 - 1j * f * f0 / q - f0**2)


def best_sho(f, y):
    """Least-squares SHO of a noise-free spectrum (SciPy, from the peak): (f0, Q)."""
    peak = int(np.argmax(np.abs(y)))
    half = np.abs(y) > np.abs(y[peak]) / np.sqrt(2)
    q0 = f[peak] / max(np.ptp(f[half]), f[1] - f[0])
    scale = np.abs(y[peak]) / q0

    def residual(p):
        r = hand_sho(f, (p[0] + 1j * p[1]) * scale, f[peak] * np.exp(p[2]), q0 * np.exp(p[3])) - y
        return np.concatenate([r.real, r.imag]) / np.abs(y[peak])

    amplitude = -1j * y[peak] / q0 / scale          # at f = f0 BGlib's form is i Q A
    fit = scipy.optimize.least_squares(residual, [amplitude.real, amplitude.imag, 0.0, 0.0], method="lm",
                                       xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=20000)
    return f[peak] * np.exp(fit.x[2]), q0 * np.exp(fit.x[3])


def make_map(side, bins, two_bands, rng):
    """Spectra (positions, n_freq), frequencies, true k1 per pixel, best SHO (f0, Q) per pixel
    (first band), the free resonance of the FE lever."""
    values = np.geomspace(100.0, 800.0, 16)
    index = rng.integers(0, len(values), side * side)
    beams = [FEBeam(K, L, F1, H, k1=v, k2=0.5 * v if two_bands else 0.0, Q=Q, n_elements=60) for v in values]
    modes = np.array([b.contact_resonances(2) for b in beams])
    if two_bands:
        f = np.concatenate([np.linspace(0.9 * modes[:, m].min(), 1.1 * modes[:, m].max(), bins // 2) for m in (0, 1)])
    else:
        f = np.linspace(0.9 * modes[:, 0].min(), 1.1 * modes[:, 0].max(), bins)
    clean = np.stack([2e-3 * np.exp(0.3j) * b.slope(f)[:, 0] for b in beams])
    first = slice(0, bins // 2) if two_bands else slice(None)
    best = np.array([best_sho(f[first], c[first]) for c in clean])
    y = clean[index]
    y = y + NOISE * np.abs(y).max(axis=1, keepdims=True) * (rng.standard_normal(y.shape)
                                                           + 1j * rng.standard_normal(y.shape)) / np.sqrt(2)
    free = float(FEBeam(K, L, F1, H, n_elements=60).free_resonances(1)[0])
    return y, f, values[index], best[index], free


def write_usid(path, usid, y, f, side):
    import h5py
    with h5py.File(path, "w") as h5:
        usid.hdf_utils.write_main_dataset(
            h5.create_group("Measurement_000/Channel_000"), y, "Raw_Data", "Piezoresponse", "V",
            [usid.Dimension("X", "m", np.arange(side) * 1e-7), usid.Dimension("Y", "m", np.arange(side) * 1e-7)],
            [usid.Dimension("Frequency", "Hz", f)])


def _import_usid():
    if not hasattr(np, "product"):
        np.product = np.prod          # pyUSID 0.0.12 on NumPy 2
    import pyUSID
    return pyUSID


class Clock:
    """Wall-clock and CPU seconds from its creation (every tool runs in this process, on one core:
    on a shared machine the CPU seconds do not count the time others took)."""

    def __init__(self):
        self.wall, self.cpu = time.perf_counter(), time.process_time()

    def read(self) -> tuple[float, float]:
        return time.perf_counter() - self.wall, time.process_time() - self.cpu


def rates(pixels, seconds) -> tuple[float, float]:
    """Pixels per second of wall clock and of CPU."""
    return pixels / seconds[0], pixels / seconds[1]


def run_bglib(path, usid):
    """BGlib's complex-Gaussian guess, then its fit; (clock of the guess, clock of guess and fit, fit
    table), each clock a :class:`Clock`."""
    import h5py
    import BGlib.be.analysis.fitter as bg_fitter
    from BGlib.be.analysis import BESHOfitter
    from BGlib.be.analysis.be_sho_fitter import SHOGuessFunc
    solver = scipy.optimize.least_squares

    def scalar_residual(*args, **kwargs):     # NumPy >= 2.4: BGlib writes 1 - result.fun into a scalar field
        result = solver(*args, **kwargs)
        result.fun = float(np.ravel(result.fun)[0])
        return result

    bg_fitter.least_squares = scalar_residual
    with h5py.File(path, "r+") as h5, contextlib.redirect_stdout(io.StringIO()):
        main = usid.hdf_utils.find_dataset(h5, "Raw_Data")[0]
        fitter = BESHOfitter(main, cores=1, verbose=False)
        fitter.set_up_guess(guess_func=SHOGuessFunc.complex_gaussian, num_points=5)
        start = Clock()
        fitter.do_guess(override=True)
        guessed = start.read()
        fitter.set_up_fit()
        fit = fitter.do_fit(override=True)[()]
    return guessed, start.read(), fit


def run_sidpy(y, f, side):
    """sidpy's SidpyFitterRefactor (bounded, trf) with BGlib's SHO model and guess for it."""
    import dask
    import sidpy
    from BGlib.be.analysis.utils.sidpy_sho_fitter import SHO_fit_flattened, SHOestimateGuess
    from sidpy.proc.fitter_refactor import SidpyFitterRefactor
    data = sidpy.Dataset.from_array(y.reshape(side, side, -1))
    for axis, name in ((0, "y"), (1, "x")):
        data.set_dimension(axis, sidpy.Dimension(np.arange(side), name=name, units="px", quantity=name,
                                                 dimension_type="spatial"))
    data.set_dimension(2, sidpy.Dimension(f, name="frequency", units="Hz", quantity="Frequency",
                                          dimension_type="spectral"))
    with dask.config.set(scheduler="synchronous"), contextlib.redirect_stdout(io.StringIO()):
        fitter = SidpyFitterRefactor(data, SHO_fit_flattened, SHOestimateGuess, ind_dims=(2,),
                                     lower_bounds=[0.0, 0.0, 0.0, -np.inf], upper_bounds=[np.inf] * 4)
        fitter.setup_calc()
        start = Clock()
        result = fitter.do_fit(use_kmeans=False)
        elapsed = start.read()
    params = np.asarray(result[0] if isinstance(result, (list, tuple)) else result).reshape(-1, 4)
    return elapsed, params


def run_pfmdyn(path, out, sho, free, two_bands, warm=None):
    """``pfmdyn map`` on one core (its default block size); (:class:`Clock`, result).  ``warm``: a smaller
    map of the same kind run first, off the clock (the beam's compiled kernels loaded or compiled)."""
    from pfmdyn.maps import open_result
    from pfmdyn.maps.driver import open_map, run_map
    from pfmdyn.maps.sho import fit_sho_block
    overrides = {"spring_constant": K, "length": L, "tip_height": H, "free_resonance": free}
    if not two_bands:       # one band cannot tell k2 from k1: held at the lever's k2 = 0
        overrides["k2"] = 0.0
    source = open_map(str(path), overrides, sho=sho)
    if sho:     # start-up excluded: the compiled kernel loaded from numba's cache once per process
        fit_sho_block(source.model, np.ones((1, len(source.model.frequency_hz)), complex))
    if warm is not None:
        run_map(open_map(str(warm), overrides, sho=sho), str(out) + "_warm", scheduler="sync")
    start = Clock()
    run_map(source, str(out), scheduler="sync")
    return start.read(), open_result(str(out))


def sho_scores(f0, q, best, k1_true, free):
    """Fraction right (frequency 2e-4, Q 3 %), and k1 by the SHO route: median error, fraction within 2 %."""
    from pfmdyn.analysis.stiffness import contact_stiffness
    right = (np.abs(f0 / best[:, 0] - 1) < 2e-4) & (np.abs(q / best[:, 1] - 1) < 0.03)
    k1 = np.asarray(contact_stiffness(np.where(f0 > 0, f0, np.nan), free, K, out_of_range="nan").k1)
    return float(np.mean(right)), *k1_scores(k1, k1_true)


def k1_scores(k1, k1_true):
    error = np.abs(np.asarray(k1, float) / k1_true - 1)
    error = np.where(np.isfinite(error), error, np.inf)
    return float(np.median(error)), float(np.mean(error < 0.02))


def bench(name, two_bands, args, peers, tmp):
    rng = np.random.default_rng(2006 + two_bands)
    y, f, k1_true, best, free = make_map(args.side, args.bins, two_bands, rng)
    n = len(y)
    side_s = min(args.sample, args.side)
    n_s = side_s * side_s          # the sample: the first pixels, drawn like all others
    usid = peers["pyUSID"]
    paths = {"map": tmp / f"{name}.h5", "sample": tmp / f"{name}_sample.h5"}
    write_usid(paths["map"], usid, y, f, args.side)
    write_usid(paths["sample"], usid, y[:n_s], f, side_s)
    whole, sample = f"{args.side} x {args.side}", f"{side_s} x {side_s}"
    rows = []
    if "BGlib" in peers:
        copy = tmp / f"{name}_bglib.h5"
        shutil.copyfile(paths["map"], copy)
        t_guess, t_fit, fit = run_bglib(copy, usid)
        f0, q = fit["Frequency [Hz]"][:, 0], fit["Quality Factor"][:, 0]
        rows.append(("BGlib guess + fit", whole, *rates(n, t_fit), *sho_scores(f0, q, best, k1_true, free)))
        rows.append(("  of which guess", whole, *rates(n, t_guess), None, None, None))
    if "sidpy" in peers:
        elapsed, params = run_sidpy(y[:n_s], f, side_s)
        rows.append(("sidpy SidpyFitterRefactor", sample, *rates(n_s, elapsed),
                     *sho_scores(params[:, 1], params[:, 2], best[:n_s], k1_true[:n_s], free)))
    elapsed, result = run_pfmdyn(paths["map"], tmp / f"{name}_sho", True, free, two_bands)
    f0, q = (result[v].values.reshape(n, -1)[:, 0] for v in ("measured_resonance", "measured_quality_factor"))
    rows.append(("pfmdyn map --model sho", whole, *rates(n, elapsed), *sho_scores(f0, q, best, k1_true, free)))
    elapsed, result = run_pfmdyn(paths["map"], tmp / f"{name}_beam", False, free, two_bands, warm=paths["sample"])
    rows.append(("pfmdyn map (beam, elastic)", whole, *rates(n, elapsed), None,
                 *k1_scores(result["k1"].values.ravel(), k1_true)))
    return rows


def table(name, rows, side, bins):
    reference = rows[0][2:4] if rows[0][0].startswith("BGlib") else None
    lines = [f"### {name} ({side} x {side} pixels, {bins} frequencies)", "",
             "| tool | pixels fitted | pixels/s per core | ratio to BGlib guess + fit | pixels per CPU s | ratio "
             "| f and Q right | k1 median error | k1 within 2 % |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for tool, pixels, rate, cpu_rate, right, median, within in rows:
        cells = [tool, pixels, f"{rate:.0f}", f"{rate / reference[0]:.2f}" if reference else "-",
                 f"{cpu_rate:.0f}", f"{cpu_rate / reference[1]:.2f}" if reference else "-",
                 "-" if right is None else f"{100 * right:.1f} %",
                 "-" if median is None else f"{100 * median:.2f} %", "-" if within is None else f"{100 * within:.1f} %"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=128)
    parser.add_argument("--bins", type=int, default=128)
    parser.add_argument("--sample", type=int, default=32, help="side of the sample the slower tools fit")
    args = parser.parse_args()
    peers, skipped = {}, []
    for name in ("pyUSID", "BGlib", "sidpy"):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                peers[name] = _import_usid() if name == "pyUSID" else __import__(name)
        except Exception as exc:        # any import failure of a peer skips it (e.g. numpy_groupies 0.9.7)
            skipped.append(f"{name} ({type(exc).__name__}: {' '.join(str(exc).split())[:100]})")
    if "pyUSID" not in peers:
        sys.exit("benchmarks/peers.py writes its inputs with pyUSID: pip install 'pfmdyn[peers]'")
    if "BGlib" not in peers:
        peers.pop("sidpy", None)        # sidpy's SHO model and guess are BGlib's
    import numpy
    import scipy
    versions = ", ".join(f"{m.__name__} {getattr(m, '__version__', '?')}" for m in (numpy, scipy, *peers.values()))
    with recorded("peers"), threadpool_limits(1), tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        print(f"{versions}; one core per tool.\n")
        print("Skipped: " + ("; ".join(skipped) if skipped else "none") + ".\n")
        for name, two in (("one band", False), ("two bands", True)):
            print(table(name, bench(name.replace(" ", "_"), two, args, peers, Path(tmp)), args.side, args.bins) + "\n",
                  flush=True)
        print("f and Q right: frequency within 2e-4 and Q within 3 % of the least-squares SHO of the noise-free\n"
              "spectrum (first band). k1 for the SHO tools: their first-band frequency through pfmdyn stiffness\n"
              "(k2 = 0), today's BE route; for the beam fit: its own k1. With two bands the lever has k2 = 0.5 k1,\n"
              "which that route cannot see; BGlib and sidpy fit one SHO over both bands.\n"
              "Rates are per core on a machine that may be shared (see the load above): compare the ratios; each\n"
              "pfmdyn row includes its run's set-up (Dask, Zarr output). Pixels per CPU s: per second of this\n"
              "process's CPU time (every tool runs in it, on one core), which other work on the machine does not\n"
              "lengthen; the ratio beside it is to BGlib's.")
        if hasattr(os, "getloadavg"):
            print(f"Load average at the end: {'/'.join(f'{x:.1f}' for x in os.getloadavg())}.")


if __name__ == "__main__":
    main()
