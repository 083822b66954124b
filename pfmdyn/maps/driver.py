"""Run the per-pixel fit over a whole map on Dask and stream the maps to Zarr, resumably.

The map is cut into pixel blocks (``block`` x ``block`` pixels, all frequencies).  Each block is
one Dask task that reads its spectra, fits them with :func:`pfmdyn.maps.fit.fit_block` and writes
its region of every output array in ``OUT/maps.zarr``; a per-block flag array ``done`` is set last,
so a rerun after an interruption skips finished blocks.  Nothing holds the whole map in memory.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from ..errors import UserError
from .fit import MECHANISMS, fit_block, quantities
from .readers import MapInput, open_map, read_block
from .readers import require as _require

__all__ = ["MapInput", "open_map", "run_map", "read_maps"]

def _blocks(shape, block):
    ny, nx = shape
    return [(by, bx) for by in range(math.ceil(ny / block)) for bx in range(math.ceil(nx / block))]


def _process(source: MapInput, out: str, by: int, bx: int, block: int, options: dict) -> int:
    zarr = _require("zarr")
    ys, xs = slice(by * block, (by + 1) * block), slice(bx * block, (bx + 1) * block)
    response = read_block(source, ys, xs)
    if not np.all(np.isfinite(response)):
        raise UserError(f"{source.path}: response holds NaN or inf in block ({by}, {bx})")
    result = fit_block(source.model, response, **options)
    group = zarr.open_group(out, mode="r+")
    for name in quantities(source.model.mechanisms):
        group[name][ys, xs] = result[name]
    group["done"][by, bx] = 1
    return response.shape[0] * response.shape[1]


def _output(out, source: MapInput, block: int):
    zarr = _require("zarr")
    group = zarr.open_group(out, mode="a")
    ny, nx = source.shape
    grid = (math.ceil(ny / block), math.ceil(nx / block))
    if "done" in group and group["done"].shape != grid:
        raise UserError(f"{out}: holds a map of another shape or block size; choose another --out")
    for name, (unit, text) in quantities(source.model.mechanisms).items():
        if name not in group:
            arr = group.full(name, shape=(ny, nx), chunks=(block, block), dtype="f8", fill_value=np.nan)
            arr.attrs.update(units=unit, description=text)
    if "done" not in group:
        group.zeros("done", shape=grid, chunks=grid, dtype="u1")
    group.attrs.update(source=os.path.abspath(source.path), block=block)
    return group


def run_map(source: MapInput, out_dir: str, *, block: int = 16, scheduler: str | None = None,
            progress: bool = True, **options) -> dict:
    """Fit every pixel of ``source`` and write ``out_dir/maps.zarr``; returns a summary.

    ``scheduler``: None (Dask's local threaded scheduler on all cores), ``"sync"`` (one thread),
    or ``tcp://HOST:PORT`` (a running ``dask.distributed`` scheduler).  Blocks flagged done in an
    existing output are skipped.
    """
    dask = _require("dask")
    import dask.delayed  # noqa: F401  (submodule import)
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, "maps.zarr")
    group = _output(out, source, block)
    done = np.asarray(group["done"][...])
    todo = [b for b in _blocks(source.shape, block) if not done[b]]
    tasks = [dask.delayed(_process)(source, out, by, bx, block, options) for by, bx in todo]
    start = time.perf_counter()
    pixels = _compute(tasks, scheduler, progress, len(_blocks(source.shape, block)) - len(todo))
    elapsed = time.perf_counter() - start
    gap = np.asarray(group["gap"][...])
    summary = {"blocks_run": len(todo), "pixels_fitted": pixels,
               "pixels_per_s": pixels / elapsed if elapsed > 0 and pixels else float("nan"),
               "explained_fraction": float(np.nanmean(group["explained"][...])),
               "median_gap": float(np.nanmedian(gap)), "out": out}
    return summary


def _compute(tasks, scheduler, progress, already):
    """Run the block tasks, with a tqdm bar of blocks done and pixels per second."""
    from tqdm.auto import tqdm
    bar = tqdm(total=len(tasks) + already, initial=already, unit="block", disable=not progress)
    pixels = 0
    if scheduler and "://" in scheduler:
        distributed = _require("distributed")
        with distributed.Client(scheduler) as client:
            for future in distributed.as_completed(client.compute(tasks)):
                pixels += future.result()
                bar.update(1)
                bar.set_postfix(pixels_per_s=f"{pixels / max(bar.format_dict['elapsed'], 1e-9):.0f}")
    else:
        import dask
        from dask.callbacks import Callback

        class _Bar(Callback):
            def _posttask(self, key, result, dsk, state, worker_id):
                nonlocal pixels
                if isinstance(result, int):
                    pixels += result
                    bar.update(1)
                    bar.set_postfix(pixels_per_s=f"{pixels / max(bar.format_dict['elapsed'], 1e-9):.0f}")

        with _Bar():
            dask.compute(*tasks, scheduler="sync" if scheduler == "sync" else "threads")
    bar.close()
    return pixels


def read_maps(out: str) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The fitted maps of ``out`` (a ``maps.zarr`` directory) and their units."""
    group = _require("zarr").open_group(out, mode="r")
    maps = {name: np.asarray(group[name][...]) for name in quantities(MECHANISMS) if name in group}
    return maps, {name: group[name].attrs.get("units", "") for name in maps}
