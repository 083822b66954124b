"""``OUT/maps.zarr`` in xarray's Zarr convention: ``xarray.open_zarr`` opens the maps of a beam
map and of an SHO map (biases and bands) with their dimensions, coordinates, units and long names.

Read without pfmdyn: the consolidated metadata (``.zmetadata``, what xarray reads of a format-2
store) under either Zarr, and ``xarray.open_zarr`` itself where it runs (recent xarray opens
Zarr stores only with Zarr 3; CI runs this file once more with Zarr 2).  The beam map's spectra
come from the independent finite-element beam (tests/fe_beam.py), the SHO map's from BGlib's SHO
typed by hand.
"""
from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")
pytest.importorskip("dask")
xarray = pytest.importorskip("xarray")
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn.cli import main  # noqa: E402
from pfmdyn.maps import open_result  # noqa: E402

NY, NX = 6, 8
XARRAY_OPENS_ZARR = int(zarr.__version__.split(".")[0]) >= 3


def _beam_map(tmp_path):
    """Two domains of k1 150 and 400 N/m on a 2 N/m, 75 kHz lever, one band around the first contact resonance."""
    k1 = np.where(np.arange(NX)[None, :] < NX // 2, 150.0, 400.0) * np.ones((NY, 1))
    beams = {v: FEBeam(2.0, 225e-6, 75e3, 10e-6, k1=v, Q=60.0, n_elements=40) for v in (150.0, 400.0)}
    first = [b.contact_resonances(1)[0] for b in beams.values()]
    f = np.linspace(0.85 * min(first), 1.15 * max(first), 48)
    clean = np.stack([2e-3 * beams[v].slope(f)[:, 0] for v in k1.ravel()]).reshape(NY, NX, -1)
    rng = np.random.default_rng(3)
    response = clean * (1 + 0.003 * rng.standard_normal(clean.shape))
    path = tmp_path / "beam.h5"
    with h5py.File(path, "w") as h:
        h["response"], h["frequency_hz"] = response, f
        h.attrs.update(spring_constant_n_per_m=2.0, length_m=225e-6, width_m=40e-6, tip_height_m=10e-6,
                       free_resonance_hz=75e3, k2=0.0)
    return path, ["--model", "elastic"], {}


def _sho_map(tmp_path):
    """Two DC biases, two bands (300 and 920 kHz), BGlib's SHO at Q 60 and 150."""
    bands = [np.linspace(280e3, 320e3, 40), np.linspace(880e3, 960e3, 40)]
    bias = np.array([-2.0, 2.0])
    rng = np.random.default_rng(4)
    f0 = [rng.uniform(295e3, 305e3, (NY, NX, 2, 1)), rng.uniform(910e3, 930e3, (NY, NX, 2, 1))]
    response = np.concatenate([1e-3 * np.exp(0.3j) * f0b**2 / (band**2 - 1j * band * f0b / q - f0b**2)
                               for band, f0b, q in zip(bands, f0, (60.0, 150.0))], axis=-1)
    path = tmp_path / "sho.h5"
    with h5py.File(path, "w") as h:
        h["response"], h["frequency_hz"], h["bias_v"] = response, np.concatenate(bands), bias
    return path, ["--model", "sho"], {"bias": bias, "band": np.array([300e3, 920e3])}


def _map(path, model, out, *options):
    assert main(["map", str(path), *model, "--out", str(out), "--no-progress", "--scheduler", "sync",
                 "--block", "4", *options]) == 0


@pytest.mark.parametrize("make", [_beam_map, _sho_map], ids=["beam", "sho"])
def test_xarray_opens_the_maps_with_dims_units_and_long_names(tmp_path, make):
    path, model, coordinates = make(tmp_path)
    _map(path, model, tmp_path / "o")
    _assert_xarray_opens(tmp_path / "o", model, coordinates)


def test_a_map_begun_before_the_convention_resumes_into_it(tmp_path):
    path, model, coordinates = _sho_map(tmp_path)
    _map(path, model, tmp_path / "o", "--max-blocks", "1")
    store = tmp_path / "o" / "maps.zarr"
    # the store as it was written before: no dimension names, coordinates or consolidated metadata
    (store / ".zmetadata").unlink()
    group = zarr.open_group(str(store), mode="r+")
    for name in list(group.array_keys()):
        if name in ("y", "x", *coordinates):
            del group[name]
        else:
            del group[name].attrs["_ARRAY_DIMENSIONS"]
    _map(path, model, tmp_path / "o")
    _assert_xarray_opens(tmp_path / "o", model, coordinates)


def _assert_xarray_opens(out, model, coordinates):
    store = out / "maps.zarr"
    expected = open_result(out)
    dims = ("y", "x", *coordinates)
    maps = [name for name in expected.data_vars]
    assert {"k1", "gap"} <= set(maps) if "elastic" in model else {"measured_resonance", "measured_quality_factor"} <= set(maps)
    # the convention as stored: every array names its dimensions, one per axis, and says what it holds
    metadata = json.loads((store / ".zmetadata").read_text())["metadata"]
    for name in [*maps, *dims]:
        attrs, shape = metadata[f"{name}/.zattrs"], metadata[f"{name}/.zarray"]["shape"]
        assert len(attrs["_ARRAY_DIMENSIONS"]) == len(shape) and attrs["units"] and attrs["long_name"], name
    if not XARRAY_OPENS_ZARR:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("error")        # no "falling back to non-consolidated metadata"
        dataset = xarray.open_zarr(store)
    sizes = {"y": NY, "x": NX, **{dim: len(values) for dim, values in coordinates.items()}}
    assert dict(dataset.sizes) == {**sizes, "block_y": 2, "block_x": 2}
    assert dataset["x"].values.tolist() == list(range(NX)) and dataset["y"].values.tolist() == list(range(NY))
    for dim, values in coordinates.items():
        np.testing.assert_allclose(dataset[dim].values, values, rtol=1e-3)
    assert dataset["bias"].attrs["units"] == "V" if "bias" in coordinates else "bias" not in dataset
    assert dataset["done"].values.tolist() == [[1, 1], [1, 1]]
    for name in maps:
        variable = dataset[name]
        assert variable.dims == dims and variable.shape == tuple(sizes[d] for d in dims), name
        assert variable.attrs == expected[name].attrs and variable.attrs["long_name"] != name, name
        np.testing.assert_array_equal(variable.values, expected[name].values)
    unit = dataset["k1"].attrs["units"] if "elastic" in model else dataset["measured_resonance"].attrs["units"]
    assert unit == ("N/m" if "elastic" in model else "Hz")
    assert np.isfinite(dataset[maps[0]].values).mean() > 0.9
