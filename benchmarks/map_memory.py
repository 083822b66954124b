"""A map four times larger than the process may hold, through ``pfmdyn map`` chunk by chunk.

Writes a synthetic band-excitation map (plain Zarr layout, ``response`` chunked by 16 x 16 pixel
blocks) one row of chunks at a time, so this script never holds it either.  Then runs
``pfmdyn map`` on it in a subprocess whose address space is limited (``RLIMIT_AS``, inherited by
the worker processes) to what the same command needs on a tiny map plus a quarter of the map's
size (a control shows that limit refuses the whole map at once), and prints each process's peak
RSS against the data size.

    python benchmarks/map_memory.py [--mib 256] [--n-freq 256]

Results: ``benchmarks/results/map_memory.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import zarr

from pfmdyn import Cantilever
from pfmdyn.maps.beam import BeamMapModel
from recording import recorded

K, L, F1, H = 2.0, 225e-6, 75e3, 10e-6
BLOCK = 16

# Runs `pfmdyn map` under an address-space limit; prints peak RSS (MiB) of this process and of
# its largest worker (forked from it), and VmPeak.
_RUNNER = """
import json, resource, sys
limit = int(sys.argv[1])
if limit:
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
from pfmdyn.cli import main
code = main(["map", *sys.argv[2:]])
status = {line.split(":")[0]: line.split()[1] for line in open("/proc/self/status") if line.startswith("Vm")}
# VmHWM, not ru_maxrss: the latter keeps the launching process's peak across exec
print(json.dumps({"code": code, "rss_self": int(status["VmHWM"]) / 1024,
                  "rss_workers": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024,
                  "vm_peak": int(status["VmPeak"]) / 1024}))
"""


# Control: with the modules `pfmdyn map` imports, the same limit refuses the whole map at once.
_LOAD_WHOLE = """
import resource, sys
limit = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
import dask, h5py, tqdm, zarr
import pfmdyn.cli, pfmdyn.maps.driver, pfmdyn.maps.select
try:
    zarr.open_group(sys.argv[2], mode="r")["response"][...]
    print("held")
except MemoryError:
    print("MemoryError")
"""


def write_map(path, ny, nx, n_freq, rng):
    """Synthetic spectra (k1 150-1500 N/m, Q 60, 1 % noise) written one row of blocks at a time."""
    f = np.linspace(2.2e5, 4.2e5, n_freq)
    model = BeamMapModel(Cantilever(K, F1, L, tip_height=H), f)
    group = zarr.open_group(path, mode="w")
    response = group.create_dataset("response", shape=(ny, nx, n_freq), chunks=(BLOCK, BLOCK, n_freq),
                                    dtype="c16", compressor=None)
    group["frequency_hz"] = f
    group.attrs.update(spring_constant=K, length=L, tip_height=H, free_resonance=F1)
    for y0 in range(0, ny, BLOCK):
        k1 = rng.uniform(150, 1500, BLOCK * nx)
        y = 1e-3 * model.shape_functions(k1, np.full(k1.size, 60.0))
        y += 1e-5 * np.abs(y).max() / 1e-3 * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
        response[y0:y0 + BLOCK] = y.reshape(BLOCK, nx, n_freq)


def run(path, out, limit, *extra):
    result = subprocess.run([sys.executable, "-c", _RUNNER, str(limit), str(path), "--out", str(out),
                             "--model", "elastic", "--no-progress", *extra],
                            capture_output=True, text=True)
    if result.returncode != 0 or not result.stdout.strip():
        return {"code": result.returncode, "error": result.stderr.strip().splitlines()[-1:]}
    lines = result.stdout.strip().splitlines()
    return {**json.loads(lines[-1]), "summary": lines[-2]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mib", type=float, default=256, help="map size (MiB of complex128 spectra)")
    parser.add_argument("--n-freq", type=int, default=256)
    args = parser.parse_args()
    rng = np.random.default_rng(2)
    pixel_bytes = 16 * args.n_freq
    side = max(BLOCK, int(np.sqrt(args.mib * 2**20 / pixel_bytes)) // BLOCK * BLOCK)
    data_mib = side * side * pixel_bytes / 2**20
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        write_map(os.path.join(tmp, "tiny.zarr"), BLOCK, BLOCK, args.n_freq, rng)
        write_map(os.path.join(tmp, "big.zarr"), side, side, args.n_freq, rng)
        print(f"wrote a {side} x {side} x {args.n_freq} map: {data_mib:.0f} MiB of spectra "
              f"({time.perf_counter() - t:.0f} s)", flush=True)
        tiny = run(os.path.join(tmp, "tiny.zarr"), os.path.join(tmp, "tiny_out"), 0)
        limit = int((tiny["vm_peak"] + data_mib / 4) * 2**20)
        print(f"tiny map: VmPeak {tiny['vm_peak']:.0f} MiB, peak RSS {tiny['rss_self']:.0f} MiB "
              f"(workers {tiny['rss_workers']:.0f} MiB); limit for the big map: VmPeak + data/4 = "
              f"{limit / 2**20:.0f} MiB", flush=True)
        control = subprocess.run([sys.executable, "-c", _LOAD_WHOLE, str(limit), os.path.join(tmp, "big.zarr")],
                                 capture_output=True, text=True).stdout.strip()
        print(f"control, loading the whole map under that limit: {control or 'failed'}", flush=True)
        t = time.perf_counter()
        big = run(os.path.join(tmp, "big.zarr"), os.path.join(tmp, "big_out"), limit)
        seconds = time.perf_counter() - t
    if big["code"] != 0:
        print(f"FAILED under the limit: {big}")
        return 1
    print(big["summary"])
    print(f"big map under RLIMIT_AS {limit / 2**20:.0f} MiB: done in {seconds:.0f} s; data {data_mib:.0f} MiB, "
          f"peak RSS {big['rss_self']:.0f} MiB (driver), {big['rss_workers']:.0f} MiB (largest worker); "
          f"growth over the tiny map {max(big['rss_self'], big['rss_workers']) - max(tiny['rss_self'], tiny['rss_workers']):.0f} MiB"
          f" = {(max(big['rss_self'], big['rss_workers']) - max(tiny['rss_self'], tiny['rss_workers'])) / data_mib:.3f} x data")
    return 0


if __name__ == "__main__":
    with recorded("map_memory"):
        status = main()
    sys.exit(status)
