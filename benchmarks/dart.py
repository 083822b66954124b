"""Benchmark: DART images (dual AC resonance tracking) through ``pfmdyn map`` (issue 40).

Run ``python benchmarks/dart.py [IMAGES_PER_CLASS]`` (default 10).

1. Accuracy sweep: images of 24 x 24 pixels from the independent finite-element lever of
   ``tests/dart_image.py`` (k 1-40 N/m, L 120-300 um, internal Q 150-600; grains of k1 50-1500 N/m and
   contact loss 0.004-0.045; d_eff 2-20 pm/V in stripe domains of both signs; df 0.7-1.5 contact
   widths; tracking off by up to 30 % of a width; noise 0.5-2 %, circular complex and relative on each
   lock-in's signal), in three classes: k2 = 0.5 k1 at the lever's end, the spot at 0.73 L, lossy
   contacts (each grain's loss drawn for an oscillator Q of 25 +- 15 % at the peak, up to 0.1).  Each
   image is written as an Asylum ``.ibw`` and read by the command (``--pool`` at its default).  Per
   quantity, an image passes when 95 % of its pixels are within the tolerance of issue 40 (contact
   resonance 2e-4, contact Q 5 %, k1 3 %, d_eff 5 %, contact loss 10 %; d_eff's sign right on 99 %);
   reported as the images passing and the pixels within over all images.

   The truth of the contact resonance and Q (issue 40: "the two-frequency oscillator's of the exact
   response, or the exact complex pole's"): at each pixel, the oscillator through the exact
   (noise-free) signals at that pixel's own two drives; where none goes through them (a negative Q),
   the FE beam's damped complex pole.  The two readings differ by far more than 2e-4 (the table below
   gives the median), and the first moves with the tracking within a grain: the comparison is with
   the first.  A second table reads the same images pixel by pixel (``--pool 0``) beside the
   fraction of pixels an unbiased estimator at the Cramér-Rao bound of one pixel would put within 2e-4:
   the oscillator's (four numbers, four unknowns; its Jacobian at the exact signals, the image's noise)
   and the lever's knowing the drive real (three unknowns: ``k1``, contact loss, ``|d_eff|``), which
   ``pfmdyn map`` fits (``real_drive``).  A third table holds each pixel's stated standard error to the
   truth: the share of pixels within two of them, per quantity and class.
2. Speed: a 256 x 256 image, the library's inversion (:func:`pfmdyn.maps.dart.invert`) and the
   whole command (read, invert, write the store), on one core (NumPy without threads); target:
   seconds.

Results: ``benchmarks/results/dart.md``, written by each completed run.
"""
from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")      # one core: no BLAS threads
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy import special  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from dart_image import dart_case, write_ibw  # noqa: E402
from pfmdyn import Cantilever, Contact  # noqa: E402
from pfmdyn.cli import main  # noqa: E402
from pfmdyn.io.dart import read_dart  # noqa: E402
from pfmdyn.maps import open_result  # noqa: E402
from pfmdyn.maps.dart import POOL, deflection_signal, invert, oscillator, oscillator_sensitivity  # noqa: E402
from recording import recorded  # noqa: E402

TOLERANCES = {"contact_resonance": 2e-4, "contact_quality_factor": 0.05, "k1": 0.03, "d_eff": 0.05,
              "contact_loss": 0.10}
CLASSES = {"k2 = 0.5 k1": {}, "spot 0.73 L": {"spot": 0.73}, "lossy (Q ~ 25)": {"lossy": True}}


def _run(case, folder: Path, *extra):
    path = write_ibw(case, folder / "dart.ibw")
    lever = case.lever
    argv = ["map", str(path), "--out", str(folder / "out"), "--no-progress", "--tip-height", repr(lever["tip_height"]),
            "--spot-position", repr(lever["spot_position"]), "--k2-over-k1", repr(lever["k2_over_k1"]), *extra]
    with open(os.devnull, "w") as quiet:
        stdout, sys.stdout = sys.stdout, quiet
        try:
            code = main(argv)
        finally:
            sys.stdout = stdout
    assert code == 0, code
    return open_result(folder / "out")


def _bound(case) -> float:
    """The mean over the pixels of the chance that an unbiased per-pixel estimator at the Cramér-Rao bound
    lands within the contact resonance's tolerance (the exactly determined oscillator is that estimator)."""
    exact = case.exact
    spread = oscillator_sensitivity(exact["f1"], exact["f2"], exact["s1"], exact["s2"]).resonance
    sd = case.settings["noise"] * spread / case.truth["contact_resonance"]
    with np.errstate(all="ignore"):
        return float(np.nanmean(special.erf(TOLERANCES["contact_resonance"] / (np.sqrt(2) * sd))))


def _real_drive_bound(case) -> float:
    """As :func:`_bound`, for an estimator knowing the lever and that the drive is real (three unknowns, ``k1``,
    the contact loss and ``|d_eff|``, for four numbers; the lock-ins' offset known): the Jacobian of
    ``log s_j`` (real and imaginary parts, noise ``sigma**2 / 2`` each) through pfmdyn's lever at the true contact."""
    lever, contact = _lever(case)
    f = [case.exact[name].ravel() for name in ("f1", "f2")]
    k1, loss = case.truth["k1"].ravel(), case.truth["contact_loss"].ravel()
    h = 1e-6
    points = [(k1, loss), (k1 * np.exp(h), loss), (k1, loss + h)]
    signals = [[deflection_signal(lever, contact, fj, *point) for fj in f] for point in points]
    columns = [np.concatenate([np.log(moved[j] / signals[0][j]).view(float).reshape(-1, 2) / h for j in (0, 1)], -1)
               for moved in signals[1:]]
    jacobian = np.stack([*columns, np.tile([1.0, 0.0, 1.0, 0.0], (len(k1), 1))], -1)       # rows x (log k1, loss, log|d|)
    covariance = np.linalg.inv(np.einsum("nki,nkj->nij", jacobian, jacobian))[:, :2, :2] * case.settings["noise"] ** 2 / 2
    resonance = [oscillator(*f, *moved).resonance for moved in signals]
    gradient = np.stack([(moved - resonance[0]) / h for moved in resonance[1:]], -1)
    sd = np.sqrt(np.einsum("ni,nij,nj->n", gradient, covariance, gradient)) / case.truth["contact_resonance"].ravel()
    with np.errstate(all="ignore"):
        return float(np.nanmean(special.erf(TOLERANCES["contact_resonance"] / (np.sqrt(2) * sd))))


def _lever(case):
    """The case's lever and contact as pfmdyn's, as the command reads them from the note and the flags."""
    lever = case.lever
    return (Cantilever(lever["spring_constant"], lever["free_resonance"], lever["length"],
                       quality_factor=lever["quality_factor"], tip_height=lever["tip_height"],
                       spot_position=lever["spot_position"]), Contact(k2_over_k1=lever["k2_over_k1"]))


def accuracy(per_class: int) -> None:
    print(f"1. accuracy: {per_class} images of 24 x 24 per class; an image passes a quantity when 95 % of its "
          "pixels are within the tolerance; the truth of the contact resonance and Q: the oscillator through the "
          "exact signals at each pixel's drives (the FE beam's damped pole where none goes through them)")
    header = "| class | " + " | ".join(f"{name} ({tol:g})" for name, tol in TOLERANCES.items()) + " | d_eff sign (99 %) |"
    print(header)
    print("|" + "---|" * (len(TOLERANCES) + 2))
    alone, coverage = {}, {}
    for label, options in CLASSES.items():
        images = {name: 0 for name in [*TOLERANCES, "sign"]}
        pixels = {name: [] for name in images}
        coverage[label] = {name: {"within": [], "z": []} for name in TOLERANCES}
        alone[label] = {"images": 0, "pixels": [], "bound": [], "real": [], "quality": [], "pole": []}
        for seed in range(per_class):
            case = dart_case(1000 * (1 + list(CLASSES).index(label)) + seed, 24, 24, **options)
            with tempfile.TemporaryDirectory() as folder:
                maps = _run(case, Path(folder))
                per_pixel = _run(case, Path(folder), "--pool", "0")
            for name, tolerance in TOLERANCES.items():
                within = np.abs(maps[name].values / case.truth[name] - 1) < tolerance
                images[name] += within.mean() >= 0.95
                pixels[name].append(within.mean())
                with np.errstate(all="ignore"):
                    z = np.abs(maps[name].values - case.truth[name]) / maps[f"{name}_stderr"].values
                z = z[np.isfinite(maps[name].values)]
                coverage[label][name]["within"].append(np.mean(z <= 2))
                coverage[label][name]["z"].append(z)
            right = np.sign(maps["d_eff"].values) == np.sign(case.truth["d_eff"])
            images["sign"] += right.mean() >= 0.99
            pixels["sign"].append(right.mean())
            within = np.mean(np.abs(per_pixel["contact_resonance"].values / case.truth["contact_resonance"] - 1)
                             < TOLERANCES["contact_resonance"])
            row = alone[label]
            row["images"] += within >= 0.95
            row["pixels"].append(within)
            row["bound"].append(_bound(case))
            row["real"].append(_real_drive_bound(case))
            row["quality"].append(np.median(case.truth["contact_quality_factor"]))
            row["pole"].append(np.median(np.abs(case.exact["pole_resonance"] / case.truth["contact_resonance"] - 1)))
        print(f"| {label} | " + " | ".join(f"{images[n]}/{per_class} images, {100 * np.mean(pixels[n]):.1f} % pixels"
                                          for n in images) + " |")
    print("\neach pixel's stated standard error (--pool at its default) against the truth: the pixels within 2 stated "
          "sigma over all images (the least of an image), the median |error| / stderr (a normal's: 0.67) and the "
          "pixels whose stderr is NaN (counted as not within)")
    print("| class | " + " | ".join(TOLERANCES) + " |")
    print("|" + "---|" * (len(TOLERANCES) + 1))
    for label, row in coverage.items():
        print(f"| {label} | " + " | ".join(
            f"{100 * np.mean(row[n]['within']):.1f} % ({100 * np.min(row[n]['within']):.0f} %), "
            f"{np.nanmedian(np.concatenate(row[n]['z'])):.2f}, {np.mean(np.isnan(np.concatenate(row[n]['z']))):.1%} "
            "no stderr" for n in TOLERANCES) + " |")
    print("\ncontact_resonance pixel by pixel (--pool 0) against the one-pixel Cramér-Rao bounds: the oscillator's "
          "(four unknowns) and the lever's with a real drive (three)")
    print("| class | images' median contact Q | median abs(pole / truth - 1) | --pool 0: within 2e-4 | "
          "oscillator's bound: expected within 2e-4 | real drive's bound: expected within 2e-4 |")
    print("|---|---|---|---|---|---|")
    for label, row in alone.items():
        print(f"| {label} | {np.min(row['quality']):.0f}-{np.max(row['quality']):.0f} | "
              f"{np.median(row['pole']):.1e} | {row['images']}/{per_class} images, {100 * np.mean(row['pixels']):.1f} % "
              "pixels | " + " | ".join(f"{sum(b >= 0.95 for b in row[key])}/{per_class} images, "
                                       f"{100 * np.mean(row[key]):.1f} % pixels" for key in ("bound", "real")) + " |")


def speed() -> None:
    print("\n2. speed: a 256 x 256 image on one core")
    started = time.perf_counter()
    case = dart_case(7, 256, 256, spot=0.73, grains=12)
    print(f"generated by the finite-element lever in {time.perf_counter() - started:.0f} s")
    with tempfile.TemporaryDirectory() as folder:
        path = write_ibw(case, Path(folder) / "dart.ibw")
        image = read_dart(path)
        lever, contact = _lever(case)
        f1, f2 = image.frequencies(case.settings["frequency_width"])
        s1, s2 = image.signals
        times, cpu = {0: [], POOL: []}, {0: [], POOL: []}
        for _ in range(3):
            for pool in times:
                started, started_cpu = time.perf_counter(), time.process_time()
                maps, _ = invert(f1, f2, s1, s2, lever, contact, case.settings["drive_amplitude"], pool=pool)
                times[pool].append(time.perf_counter() - started)
                cpu[pool].append(time.process_time() - started_cpu)
        for pool in times:
            print(f"library inversion (pfmdyn.maps.dart.invert, pool={pool}), best of 3: {min(times[pool]):.2f} s wall, "
                  f"{min(cpu[pool]):.2f} s of CPU (the machine's load shares the core)")
        print(f"({maps['determined'].mean():.1%} of the pixels determined; k1 within 3 % on "
              f"{np.mean(np.abs(maps['k1'] / case.truth['k1'] - 1) < 0.03):.1%}, the contact resonance within 2e-4 on "
              f"{np.mean(np.abs(maps['contact_resonance'] / case.truth['contact_resonance'] - 1) < 2e-4):.1%})")
        started, started_cpu = time.perf_counter(), time.process_time()
        _run(case, Path(folder))
        print(f"whole command (read the .ibw, invert, write maps.zarr): {time.perf_counter() - started:.2f} s wall, "
              f"{time.process_time() - started_cpu:.2f} s of CPU")


if __name__ == "__main__":
    with recorded("dart"):
        accuracy(int(sys.argv[1]) if len(sys.argv) > 1 else 10)
        speed()
