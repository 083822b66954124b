"""The map's results written back into a USID file, in BGlib's layout, so a band-excitation user's
pipeline (pycroscopy's viewers, loop fitters) reads them as its own.

Beside the main dataset (e.g. ``/Measurement_000/Channel_000/Raw_Data``) a results group:

* ``Raw_Data-SHO_Fit_NNN`` (``pfmdyn map`` with the model ``sho``), as BGlib's ``BESHOfitter`` writes it:
  ``Guess`` and ``Fit``, compound datasets with the fields of :data:`pfmdyn.maps.sho.FIELDS`
  (``'Amplitude [V]'``, ``'Frequency [Hz]'``, ``'Quality Factor'``, ``'Phase [rad]'``,
  ``'R2 Criterion'``), shaped (positions, spectroscopic steps): every spectroscopic row of the
  main dataset but ``Frequency``, at the steps' first columns, in the file's order (one
  ``Single_Step`` when only Frequency varies); with two or more frequency bands (contact modes)
  an extra, fastest-varying ``Band`` row whose values are the bands' centre frequencies (Hz).
  ``completed_guess_positions`` and ``completed_fit_positions`` (uint8, one per position) say
  which positions hold results.
* ``Raw_Data-Beam_Fit_NNN`` (the beam fit, any other model): one compound dataset ``Fit``
  shaped (positions, 1) over a ``Single_Step`` (the beam model uses every spectrum of a
  position, all biases included), one field ``'NAME [UNIT]'`` per map of ``maps.zarr`` (``k1
  [N/m]``, ``quality_factor [1]``, ...), the model settings in the group's attributes, and
  ``completed_positions``.

Both link the main dataset's ``Position_Indices``/``Position_Values`` and carry pyUSID's
book-keeping attributes (``tool``, ``num_source_dsets``, ``source_000``, ``timestamp``), plus
``pfmdyn_maps``: the ``maps.zarr`` they were written from.  Writing again from the same
``maps.zarr`` (a resumed run) replaces that group; any other run gets the next free index, as
BGlib does.
"""
from __future__ import annotations

import datetime
import os
import shutil

import numpy as np

from ..errors import UserError
from ..io.record import attribute_texts
from .readers import MapInput, require
from .sho import FIELDS, band_centres, is_sho
from .store import map_names, open_group

__all__ = ["write_usid"]


def write_usid(source: MapInput, maps: str, target: str) -> str:
    """Write the fit of ``maps`` (a ``maps.zarr`` of ``source``) into the HDF5 file ``target``
    (a copy of ``source.path`` made first unless it is ``source.path`` itself or exists); returns
    the results group's path inside it.
    """
    h5py = require("h5py")
    if source.layout != "usid":
        raise UserError(f"{source.path}: results are written in BGlib's layout only for USID input")
    if os.path.abspath(target) != os.path.abspath(source.path) and not os.path.exists(target):
        shutil.copyfile(source.path, target)
    group = open_group(maps, "r")
    sho = is_sho(source.model)
    done = _completed(np.asarray(group["done"][...]), source.shape)
    try:
        with h5py.File(target, "r+") as h5:
            main = h5[source.dataset]
            results = _results_group(main, "SHO_Fit" if sho else "Beam_Fit", os.path.abspath(maps))
            if sho:
                _write_sho(results, main, source, group, done)
            else:
                _write_beam(results, group, done)
            return results.name
    except OSError as exc:
        raise UserError(f"{target}: cannot write the results ({' '.join(str(exc).split())[:120]})") from None


def _completed(done_blocks, shape):
    """Per position (rows X fastest), 1 where its block is done."""
    ny, nx = shape
    block_y, block_x = -(-ny // done_blocks.shape[0]), -(-nx // done_blocks.shape[1])
    per_pixel = np.repeat(np.repeat(done_blocks, block_y, axis=0), block_x, axis=1)[:ny, :nx]
    return per_pixel.reshape(-1).astype(np.uint8)


def _results_group(main, tool, maps):
    """The group this ``maps.zarr`` wrote before (emptied), else a new one at the next free index."""
    parent, stem = main.parent, f"{main.name.split('/')[-1]}-{tool}_"
    taken = sorted(name for name in parent if name.startswith(stem) and name[len(stem):].isdigit())
    for name in taken:
        if parent[name].attrs.get("pfmdyn_maps") == maps:
            del parent[name]
            break
    else:
        name = f"{stem}{int(taken[-1][len(stem):]) + 1 if taken else 0:03d}"
    results = parent.create_group(name)
    results.attrs.update(tool=tool, num_source_dsets=1, source_000=main.ref, pfmdyn_maps=maps,
                         timestamp=datetime.datetime.now().strftime("%Y_%m_%d-%H_%M_%S"), machine_id="pfmdyn")
    return results


def _link_positions(dataset, main):
    for name in ("Position_Indices", "Position_Values"):
        if name in main.attrs:
            dataset.attrs[name] = main.file[main.attrs[name]].ref


def _spectroscopic(results, rows_index, rows_values, labels, units):
    """Reduced ``Spectroscopic_Indices``/``Values`` with their labels and units."""
    out = []
    for name, data, dtype in (("Spectroscopic_Indices", rows_index, np.uint32),
                              ("Spectroscopic_Values", rows_values, np.float32)):
        dataset = results.create_dataset(name, data=np.asarray(data, dtype))
        dataset.attrs["labels"] = np.array(labels, dtype="S")
        dataset.attrs["units"] = np.array(units, dtype="S")
        out.append(dataset)
    return out




def _sho_steps(main, source):
    """Reduced spectroscopic rows (indices, values, labels, units) and, per step in the file's
    order, the index of the model's bias step (``source.columns``'s row)."""
    index = main.file[main.attrs["Spectroscopic_Indices"]] if "Spectroscopic_Indices" in main.attrs else None
    values = main.file[main.attrs["Spectroscopic_Values"]]
    labels, units = attribute_texts(values.attrs.get("labels", [])), attribute_texts(values.attrs.get("units", []))
    spec_values = np.asarray(values[...], float).reshape(len(labels), -1)
    spec_index = np.asarray(index[...]).reshape(spec_values.shape) if index is not None else None
    columns = np.asarray(source.columns)             # (bias step, frequency) -> file column
    order = np.argsort(columns.min(axis=1), kind="stable")
    starts = columns.min(axis=1)[order]
    keep = [i for i, label in enumerate(labels) if label != "Frequency"]
    if not keep:
        return np.zeros((1, 1)), np.zeros((1, 1)), ["Single_Step"], ["a. u."], order
    rows_index = (spec_index[keep][:, starts] if spec_index is not None
                  else np.argsort(np.argsort(spec_values[keep][:, starts], axis=1), axis=1))
    return rows_index, spec_values[keep][:, starts], [labels[i] for i in keep], \
        [units[i] if i < len(units) else "" for i in keep], order


def _write_sho(results, main, source, group, done):
    model = source.model
    rows_index, rows_values, labels, units, order = _sho_steps(main, source)
    n_bands = len(model.bands)
    if n_bands > 1:      # a Band row, fastest varying
        centres = band_centres(model)
        rows_index = np.vstack([np.repeat(rows_index, n_bands, axis=1), np.tile(np.arange(n_bands), rows_index.shape[1])])
        rows_values = np.vstack([np.repeat(rows_values, n_bands, axis=1), np.tile(centres, rows_values.shape[1])])
        labels, units = labels + ["Band"], units + ["Hz"]
    spec_index, spec_values = _spectroscopic(results, rows_index, rows_values, labels, units)
    n_pos = source.shape[0] * source.shape[1]
    dtype = np.dtype({"names": list(FIELDS), "formats": [np.float64] * len(FIELDS)})
    parameters = {"Guess": {"guess-method": "pfmdyn SHO", "guess-algorithm": "Sanathanan-Koerner linearised SHO"},
                  "Fit": {"fit-method": "pfmdyn SHO", "fit-algorithm": "variable-projection Levenberg-Marquardt"}}
    for name, prefix in (("Guess", "guess_"), ("Fit", "")):
        table = np.empty((n_pos, rows_index.shape[1]), dtype)
        for field, key in FIELDS.items():
            values = np.asarray(group[prefix + key][...], float)          # (ny, nx[, bias][, band])
            values = values.reshape(n_pos, -1, n_bands) if model.bias_v is not None else values.reshape(n_pos, 1, n_bands)
            table[field] = values[:, order, :].reshape(n_pos, -1)
        dataset = results.create_dataset(name, data=table)
        dataset.attrs.update(quantity="SHO", units="compound", **parameters[name])
        _link_positions(dataset, main)
        dataset.attrs["Spectroscopic_Indices"], dataset.attrs["Spectroscopic_Values"] = spec_index.ref, spec_values.ref
        results.attrs.update(parameters[name])
    results.create_dataset("completed_guess_positions", data=done)
    results.create_dataset("completed_fit_positions", data=done)
    results.attrs["last_pixel"] = n_pos if done.all() else 0


def _write_beam(results, group, done):
    names = map_names(group)
    n_pos = done.size
    dtype = np.dtype({"names": [f"{name} [{group[name].attrs.get('units', '')}]" for name in names],
                      "formats": [np.float64] * len(names)})
    table = np.empty((n_pos, 1), dtype)
    for field, name in zip(dtype.names, names):
        table[field][:, 0] = np.asarray(group[name][...], float).reshape(n_pos)
    spec_index, spec_values = _spectroscopic(results, [[0]], [[0]], ["Single_Step"], ["a. u."])
    dataset = results.create_dataset("Fit", data=table)
    main = results.file[results.attrs["source_000"]]
    dataset.attrs.update(quantity="Beam", units="compound")
    _link_positions(dataset, main)
    dataset.attrs["Spectroscopic_Indices"], dataset.attrs["Spectroscopic_Values"] = spec_index.ref, spec_values.ref
    settings = {key: value for key, value in group.attrs.items()
                if key in ("model", "tip_position", "tip_mass", "surface_potential_v") and value is not None}
    results.attrs.update(settings)
    results.create_dataset("completed_positions", data=done)
