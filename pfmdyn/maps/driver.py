"""Run the per-pixel fit over a whole map on Dask and stream the maps to Zarr, resumably.

The map is cut into pixel blocks (``block`` x ``block`` pixels, all frequencies).  Each block is
one Dask task that reads its spectra, fits them with :func:`pfmdyn.maps.fit.fit_block` and writes
its region of every output array in ``OUT/maps.zarr``; a per-block flag array ``done`` (one chunk
per block, so concurrent workers never rewrite each other's flags) is set last, so a rerun after
an interruption skips finished blocks.  Nothing holds the whole map in memory: a task holds one
block of spectra, the driver only the ``(ny, nx)`` maps of its summary.

The default local run uses a pool of worker *processes*, one per core, each limited to one BLAS
thread: the beam fit is NumPy work on modest arrays, which threads sharing the GIL do not scale.
The SHO fit is compiled and releases the GIL (:mod:`pfmdyn.maps.sho_kernel`): its default local
run fits the blocks one after the other in this process, each block's spectra shared among
threads, one per core (no process to start, nothing to pickle).
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

from ..errors import UserError
from ..fitting.workers import exit_with_parent, pool as _pool
from .fit import fit_block
from .outputs import quantities
from .spec import MECHANISMS, model_name
from .readers import MapInput, open_map, read_block
from .readers import require as _require
from .result import MapResult
from .sho import RENAMED, band_centres, fit_sho_block, is_sho
from .store import (DIMENSIONS, consolidate, create_maps, open_group, rename_map, set_attributes, write_coordinates,
                    write_regions)

__all__ = ["MapInput", "check_scheduler", "earlier_run", "exit_with_parent", "open_map", "run_map"]

def _blocks(shape, block):
    ny, nx = shape
    return [(by, bx) for by in range(math.ceil(ny / block)) for bx in range(math.ceil(nx / block))]


def _process(source: MapInput, out: str, by: int, bx: int, block: int, options: dict) -> int:
    ys, xs = slice(by * block, (by + 1) * block), slice(bx * block, (bx + 1) * block)
    response = read_block(source, ys, xs)
    fit = fit_sho_block if is_sho(source.model) else fit_block
    result = fit(source.model, response, **options)      # NaN or empty pixels come back masked
    write_regions(out, (ys, xs), {name: result[name] for name in source.model.outputs})
    open_group(out, mode="r+")["done"][by, bx] = 1      # last: a block is done once all its maps are
    return response.shape[0] * response.shape[1]


def _output(out, source: MapInput, block: int, selection=None, surface_potential_v=None):
    group = open_group(out, mode="a")
    ny, nx = source.shape
    grid = (math.ceil(ny / block), math.ceil(nx / block))
    model = source.model
    sho = is_sho(model)
    if sho:
        settings = {"model": "sho", "band_hz": band_centres(model)}
    else:
        geometry = {name: getattr(model.lever, name) for name in ("spring_constant", "free_resonance", "length",
                                                                 "tip_height", "tip_position", "tip_mass_ratio",
                                                                 "tip_gyration_radius", "tilt")}
        settings = {"model": model_name(model.mechanisms), **geometry, "k2_policy": model.describe_k2(),
                    "tip_height_uncertainty": model.tip_height_uncertainty, "assumed": source.assumed,
                    "surface_potential_v": surface_potential_v}
    steps, dims = (model.step_shape, model.dims) if sho else ((), ("y", "x"))
    if "done" in group:     # an interrupted run: only the same map of the same model may continue it
        if group["done"].shape != grid:
            raise UserError(f"{out}: holds a map of another shape or block size; choose another output", quantity="out")
        for key, value in settings.items():
            if group.attrs.get(key, value) != value:
                raise UserError(f"{out}: holds a map with {key} {group.attrs[key]}, not {value}; choose another output",
                                quantity="out")
    maps = {name: {"shape": (ny, nx, *steps), "chunks": (block, block, *steps), "units": unit, "long_name": text,
                   "dims": dims} for name, (unit, text) in model.outputs.items()}
    renamed = {old: new for old, new in RENAMED.items() if old in group} if sho else {}
    if renamed:       # an SHO map begun before its Q or resonance was renamed
        for old, new in renamed.items():
            rename_map(group, old, new, long_name=maps[new]["long_name"])
        consolidate(out)
        group = open_group(out, mode="a")       # its listing as it now is
    maps["done"] = {"shape": grid, "chunks": (1, 1), "fill_value": 0, "dtype": "u1", "dims": ("block_y", "block_x"),
                    "units": "1", "long_name": "1 where the block's maps are written (a rerun skips it)"}
    create_maps(out, {name: arguments for name, arguments in maps.items() if name not in group})
    if DIMENSIONS not in group["done"].attrs:       # a map begun before the store named its dimensions
        for name, arguments in maps.items():
            set_attributes(group[name], {DIMENSIONS: list(arguments["dims"]), "units": arguments["units"],
                                         "long_name": arguments["long_name"]})
    attrs = {"source": os.path.abspath(source.path), "block": block, **settings}
    if model.bias_v is not None:
        attrs["bias_v"] = [float(v) for v in model.bias_v]
    if selection is not None:
        attrs["model_selection"] = selection
    set_attributes(group, attrs)
    write_coordinates(group, {dim: size for dim, size in zip(dims, (ny, nx, *steps)) if dim not in group},
                      attrs.get("bias_v"), settings.get("band_hz"))
    consolidate(out)        # last: the metadata xarray reads in one request
    return group


SPECTRA_PER_BLOCK = 16384
"""An SHO map's blocks hold about this many spectra (pixels x bias steps x bands): each block costs
a read and a write of every map, tens of milliseconds, and its fit about 0.3 s per core (32 MB of
spectra of 128 bins)."""

BEAM_SPECTRA_PER_BLOCK = 4096
"""A beam map's blocks hold about this many spectra (pixels x bias steps): a block's read and
write of ~25 maps cost tens of milliseconds, a third of the fit of 256 pixels (16 x 16 blocks ran
at 2,800 pixels per CPU second on a 128 x 128 map, 64 x 64 at 4,300); a block of 4096 pixels fits
in about a second per core."""


def default_block(model, shape) -> int:
    """Pixels per block side: the largest power of two whose square holds at most
    :data:`SPECTRA_PER_BLOCK` spectra for the SHO (no larger than the map),
    :data:`BEAM_SPECTRA_PER_BLOCK` for the beam model (no more than half the map's larger side,
    so that a pool of workers has four blocks or more to share).

    >>> from pfmdyn.maps.sho import SHOMapModel
    >>> default_block(SHOMapModel(np.linspace(3e5, 3.2e5, 128)), (512, 512))
    128
    >>> default_block(SHOMapModel(np.linspace(3e5, 3.2e5, 128), np.linspace(-5, 5, 64)), (256, 256))
    16
    >>> from pfmdyn import Cantilever
    >>> from pfmdyn.maps.beam import BeamMapModel
    >>> lever = Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6)
    >>> default_block(BeamMapModel(lever, np.linspace(3e5, 4e5, 128)), (128, 128))
    64
    >>> default_block(BeamMapModel(lever, np.linspace(3e5, 4e5, 128), bias_v=np.linspace(-5, 5, 16)), (128, 128))
    16
    >>> default_block(BeamMapModel(lever, np.linspace(3e5, 4e5, 128)), (16, 16))
    8
    """
    sho = is_sho(model)
    per_pixel = math.prod(model.step_shape) if sho else len(model.bias_v) if model.bias_v is not None else 1
    budget = SPECTRA_PER_BLOCK if sho else BEAM_SPECTRA_PER_BLOCK
    side = 2 ** int(math.log2(math.sqrt(budget / per_pixel))) if per_pixel <= budget else 1
    if sho:
        return min(side, max(shape))
    return min(side, 2 ** int(math.log2(max(max(shape) // 2, 1))))


def run_map(source: MapInput, out_dir: str, *, block: int | None = None, scheduler: str | None = None,
            workers: int | None = None, max_blocks: int | None = None, progress=None,
            selection: list | None = None, **options) -> MapResult:
    """Fit every pixel of ``source`` and write ``out_dir/maps.zarr``; returns a summary.

    ``scheduler``: None or ``"processes"`` (local pool of ``workers`` processes, default one per
    core, see :func:`_pool`; None for an SHO model: the blocks in turn, each on ``workers``
    threads), ``"threads"``,
    ``"sync"`` (one core, in this process), or ``tcp://HOST:PORT`` (a running
    ``dask.distributed`` scheduler).  Blocks flagged done in an existing output are skipped;
    ``max_blocks`` stops after that many (the next run continues).  ``selection`` (the rows
    of an automatic model choice) is stored in the Zarr attributes; ``options`` go to
    :func:`pfmdyn.maps.fit.fit_block` (:func:`pfmdyn.maps.sho.fit_sho_block` for an SHO model).
    ``progress``: None, or a callable ``progress(blocks_done, blocks_total, pixels_fitted)``
    called before the first block and after each (the command draws its bar from it).

    ``block``: pixels per block side; None: an interrupted run's, else :func:`default_block`.

    Returns a :class:`pfmdyn.maps.result.MapResult`: blocks and pixels fitted, pixels per second,
    the model, the fraction of pixels explained and the median gap over the whole map.
    """
    dask = _require("dask")
    import dask.delayed  # noqa: F401  (submodule import)
    out = os.path.join(out_dir, "maps.zarr")
    made = [path for path in (out_dir, out) if not os.path.exists(path)]
    block = block or earlier_run(out).get("block") or default_block(source.model, source.shape)
    try:
        os.makedirs(out_dir, exist_ok=True)
        group = _output(out, source, block, selection, options.get("surface_potential_v"))
        done = np.asarray(group["done"][...])
        todo = [b for b in _blocks(source.shape, block) if not done[b]][:max_blocks]
        if scheduler is None and is_sho(source.model):
            scheduler, options = "sync", {**options, "threads": workers or os.cpu_count() or 1}
        tasks = [dask.delayed(_process, pure=False)(source, out, by, bx, block, options,
                                                    dask_key_name=f"pfmdyn-block-{by}-{bx}") for by, bx in todo]
        start = time.perf_counter()
        pixels = _compute(tasks, scheduler, workers, progress, int(done.sum()), done.size)
        elapsed = time.perf_counter() - start
    except BaseException as exc:
        _forget(made, out)
        if isinstance(exc, OSError):      # out_dir not writable, a file in its place, a full disk
            raise UserError(f"cannot write {out}: {exc.strerror or exc}") from None
        raise
    gap = np.asarray(group["gap"][...])
    extra = {"median_nulling_bias": _statistic(group["nulling_bias"][...])} if "nulling_bias" in group else {}
    if "at_bound" in group:
        extra["at_bound_fraction"] = _statistic(group["at_bound"][...], np.nanmean) if np.isfinite(gap).any() else 0.0
    return MapResult({**extra, "blocks_run": len(todo), "blocks_done": int(np.sum(group["done"][...])),
                      "blocks_total": done.size, "pixels_fitted": pixels,
                      "pixels_per_s": pixels / elapsed if elapsed > 0 and pixels else float("nan"),
                      "model": group.attrs["model"], "explained_fraction": _statistic(group["explained"][...], np.nanmean),
                      "median_gap": _statistic(gap), "out": out}, shape=tuple(source.shape))


def earlier_run(out: str) -> dict:
    """The attributes of the map output ``out`` an earlier run left (empty when there is none);
    a file, or a damaged Zarr group, in its place is one line asking for another output.

    >>> import tempfile
    >>> earlier_run(tempfile.mkdtemp() + "/maps.zarr")
    {}
    """
    if not os.path.exists(out):
        return {}
    try:
        group = _require("zarr").open_group(out, mode="r")
        if "done" in group:
            np.asarray(group["done"][...])          # the flags a rerun continues from
        return dict(group.attrs)
    except UserError:       # zarr not installed: already one line
        raise
    except (OSError, ValueError, KeyError) as exc:    # zarr: not a group, unreadable metadata
        raise UserError(f"{out}: not a map output a run can continue ({type(exc).__name__}: "
                        f"{' '.join(str(exc).split())[:80]}); choose another output", quantity="out") from None


def _forget(made: list[str], out: str) -> None:
    """After a failed run, remove what it created (``made``: the output directory, ``maps.zarr``)
    unless a block finished there: a run that fitted nothing leaves nothing behind, one that
    fitted some blocks keeps them for the rerun."""
    import shutil
    try:
        if out in made and np.any(_require("zarr").open_group(out, mode="r")["done"][...]):
            return
    except UserError:       # zarr not installed: already one line
        raise
    except (OSError, KeyError, ValueError):     # not even the flags were written
        pass
    for path in reversed(made):
        shutil.rmtree(path, ignore_errors=True)


def _statistic(values, how=np.nanmedian) -> float:
    """``how`` (a NaN-skipping median or mean) over the pixels holding a value: fitted or masked
    (``explained`` 0) pixels of finished blocks; NaN before any block is done."""
    values = np.asarray(values)
    return float(how(values)) if np.isfinite(values).any() else float("nan")


def check_scheduler(scheduler: str | None) -> None:
    """Raise a one-line error unless ``scheduler`` is one :func:`run_map` accepts.

    >>> check_scheduler("tcp://127.0.0.1:8786")
    """
    if scheduler not in (None, "processes", "threads", "sync") and "://" not in scheduler:
        raise UserError(f"unknown scheduler {scheduler!r}: use processes, threads, sync or tcp://HOST:PORT")


def _compute(tasks, scheduler, workers, progress, already, total):
    """Run the block tasks, telling ``progress`` (if given) the blocks done of the whole map and the pixels fitted."""
    check_scheduler(scheduler)
    kwargs = {"scheduler": scheduler or "processes"}
    if kwargs["scheduler"] in ("processes", "threads"):
        kwargs["num_workers"] = max(1, min(workers or os.cpu_count() or 1, len(tasks)))
    pool = _pool(kwargs["num_workers"]) if kwargs["scheduler"] == "processes" and tasks else None
    if pool is not None:
        kwargs.update(pool=pool, chunksize=1)   # one block per message: blocks are large
    pixels, blocks = 0, already
    report = progress or (lambda *counts: None)
    report(blocks, total, pixels)

    def tick(result):
        nonlocal pixels, blocks
        pixels, blocks = pixels + result, blocks + 1
        report(blocks, total, pixels)

    from concurrent.futures.process import BrokenProcessPool
    try:
        if "://" in kwargs["scheduler"]:
            distributed = _require("distributed")
            with distributed.Client(scheduler) as client:
                try:
                    for future in distributed.as_completed(client.compute(tasks)):
                        tick(future.result())
                except distributed.KilledWorker as exc:     # a block whose workers keep dying
                    raise UserError(f"{exc.args[0] if exc.args else 'a block'} killed every worker that ran it "
                                    "(out of memory?); finished blocks are kept: rerun to resume") from None
        elif tasks:
            import dask
            from dask.callbacks import Callback

            class _Bar(Callback):   # runs in this process whatever the local scheduler
                def _posttask(self, key, result, dsk, state, worker_id):
                    if isinstance(result, int):
                        tick(result)

            with _Bar():
                dask.compute(*tasks, **kwargs)
    except BrokenProcessPool:
        raise UserError("a worker process was killed (a signal, or out of memory); finished blocks are kept: "
                        "rerun the same command to resume") from None
    finally:
        if pool is not None:
            pool.shutdown()
    return pixels
