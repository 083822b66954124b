"""``pfmdyn map``, ``stiffness FILE`` and ``inspect`` never end in a traceback on a map file.

Property (hypothesis, derandomised for CI): any map file, well formed or not, ends in maps
(exit 0) or in one line ``pfmdyn COMMAND: error: ...`` (exit 2) with nothing written.  The files
are drawn around a valid one (spectra of the independent finite-element beam,
``tests/fe_beam.py``): metadata missing, zero, negative, NaN, text or arrays; frequency axes
empty, short, 2-D, with NaN, repeats or shuffled; response shapes that disagree with the axes,
empty grids, text data; NaN, inf and all-zero pixels; HDF5 or Zarr.  Pixels holding NaN are
masked (k1 NaN, ``explained`` 0) and the others fitted.  Wider sweeps with pass counts:
``benchmarks/malformed_inputs.py``.
"""
from __future__ import annotations

import contextlib

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn.cli import main  # noqa: E402

K, L, F1, H = 2.0, 225e-6, 75e3, 10e-6
BEAM = FEBeam(K, L, F1, H, k1=200.0, k2=160.0, Q=60.0, n_elements=30)
"""One contact band cannot separate k2 from k1: the map ties them, here by ``--k2-over-k1 0.8``."""
F_CONTACT = float(BEAM.contact_resonances(1)[0])
META = {"spring_constant_n_per_m": K, "length_m": L, "tip_height_m": H, "free_resonance_hz": F1}
BAD_VALUES = [None, 0.0, -1.0, math.nan, math.inf, "abc", np.array([1.0, 2.0])]
"""None: the key is missing."""

faults = st.one_of(
    st.tuples(st.just("meta"), st.sampled_from(sorted(META)), st.sampled_from(BAD_VALUES)),
    st.tuples(st.just("tip"), st.sampled_from(["tip_position", "tip_mass_ratio"]),
              st.sampled_from([0.9, 0.2, 1.5, -1.0, 0.0, "x"])),
    st.tuples(st.just("n_freq"), st.sampled_from([0, 1, 2, 3])),
    st.tuples(st.just("axis"), st.sampled_from(["shuffled", "repeat", "nan", "negative", "2d", "text"])),
    st.tuples(st.just("grid"), st.sampled_from([(1, 4), (0, 3), (3, 0)])),
    st.tuples(st.just("shape"), st.sampled_from(["fewer_freq", "flat", "extra_axis"])),
    st.tuples(st.just("dtype"), st.sampled_from(["real", "text"])),
)
maps = st.fixed_dictionaries({
    "faults": st.lists(faults, max_size=2),
    "bad_pixels": st.lists(st.tuples(st.integers(0, 8), st.sampled_from(["nan", "inf", "zero", "all_nan"])),
                           max_size=3),
    "zarr": st.booleans(),
})
"""A valid 3 x 3 map with up to two faults and a few bad pixels."""


def _write(p, path: Path) -> Path:
    fault = {kind: args for kind, *args in p["faults"]}
    n = fault.get("n_freq", [24])[0]
    axis = fault.get("axis", ["sorted"])[0]
    f = F_CONTACT * np.linspace(0.85, 1.15, n)
    f = {"shuffled": f[::-1], "repeat": np.r_[f[:1], f[:-1]], "nan": np.where(np.arange(n) == 1, np.nan, f),
         "negative": -f, "2d": f[None, :], "text": np.full(n, "x")}.get(axis, f)
    ny, nx = fault.get("grid", [(3, 3)])[0]
    y = np.broadcast_to(2e-3 * BEAM.slope(F_CONTACT * np.linspace(0.85, 1.15, n))[:, 0], (ny, nx, n)).copy()
    y += 1e-3 * np.abs(y).max(initial=1.0) * np.random.default_rng(n).standard_normal(y.shape)
    for pixel, kind in p["bad_pixels"]:
        if pixel < ny * nx:
            row, col = divmod(pixel, nx)
            if kind == "all_nan":
                y[row, col] = np.nan
            else:
                y[row, col, n // 2:] = {"nan": np.nan, "inf": np.inf, "zero": 0.0}[kind]
    shape = fault.get("shape", [None])[0]
    y = {"fewer_freq": y[..., :-1], "flat": y.reshape(ny * nx, n), "extra_axis": y[..., None, :]}.get(shape, y)
    y = {"real": y.real, "text": np.full(y.shape, "x")}.get(fault.get("dtype", [None])[0], y)
    attrs = dict(META)
    for kind, key, value in (f for f in p["faults"] if f[0] in ("meta", "tip")):
        attrs[key] = value
    attrs = {key: value for key, value in attrs.items() if value is not None}
    if p["zarr"]:
        path = path.with_suffix(".zarr")
        group = zarr.open_group(str(path), mode="w")
        group["response"], group["frequency_hz"] = y, f
        group.attrs.update({k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in attrs.items()})
    else:
        with h5py.File(path, "w") as h:
            h["response"] = y.astype("S1") if y.dtype.kind == "U" else y
            h["frequency_hz"] = f.astype("S1") if f.dtype.kind == "U" else f
            h.attrs.update(attrs)
    return path


def _one_line_or_success(argv, capsys, written: Path) -> int:
    status = main(argv)
    err = capsys.readouterr().err
    assert status in (0, 2), err
    if status == 2:
        assert err.count("\n") == 1 and err.startswith(f"pfmdyn {argv[0]}: error: "), err
        assert not written.exists(), f"{written} written although {err}"
    return status


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(p=maps)
def test_map_files_end_in_maps_or_one_line(tmp_path_factory, capsys, p):
    tmp = tmp_path_factory.mktemp("map")
    path = _write(p, tmp / "be.h5")
    out = tmp / "out"
    status = _one_line_or_success(["map", str(path), "--out", str(out), "--scheduler", "sync", "--model", "elastic",
                                   "--no-progress"], capsys, out)
    if status == 0:
        group = zarr.open_group(str(out / "maps.zarr"), mode="r")
        k1, explained = np.asarray(group["k1"][...]), np.asarray(group["explained"][...])
        # a Zarr 3 group is no context manager
        with (h5py.File(path, "r") if path.suffix == ".h5"
              else contextlib.nullcontext(zarr.open_group(str(path), mode="r"))) as root:
            y = np.asarray(root["response"][...])
        masked = ~np.all(np.isfinite(y), axis=-1) | np.all(y == 0, axis=-1)
        assert np.all(np.isnan(k1[masked])) and np.all(explained[masked] == 0)
        assert np.all(np.isfinite(k1[~masked]) & (k1[~masked] > 0))
    _one_line_or_success(["stiffness", str(path), "--json", str(tmp / "k.json")], capsys, tmp / "k.json")
    _one_line_or_success(["inspect", str(path), "--json", str(tmp / "i.json")], capsys, tmp / "i.json")


@pytest.mark.parametrize("change, message", [
    ({"frequency_hz": np.zeros(0), "response": np.zeros((2, 2, 0), complex)}, "the frequency axis is empty"),
    ({"spring_constant_n_per_m": -2.0}, "spring_constant must be in (0.0001, 10000] N/m, got -2.0"),
    ({"length_m": 0.0}, "length must be in (1e-06, 0.01] m, got 0.0"),
    ({"free_resonance_hz": "75 kHz"}, "free_resonance must be a number, got '75 kHz'"),
    ({"frequency_hz": F_CONTACT * np.array([1.0, 1.01])}, "a band needs at least 3"),
])
def test_the_reported_tracebacks_are_one_line_and_write_nothing(tmp_path, capsys, change, message):
    """The malformed maps of issue 23 that ended in tracebacks (and a one-frequency band,
    which gave k1 to 14 digits from two numbers)."""
    f = change.get("frequency_hz", F_CONTACT * np.linspace(0.85, 1.15, 24))
    data = {"response": np.broadcast_to(BEAM.slope(f)[:, 0], (2, 2, f.size)), "frequency_hz": f, **change}
    with h5py.File(tmp_path / "be.h5", "w") as h:
        h["response"], h["frequency_hz"] = data["response"], data["frequency_hz"]
        h.attrs.update({**META, **{k: v for k, v in change.items() if k in META}})
    assert main(["map", str(tmp_path / "be.h5"), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "be.h5" in err, err
    assert not (tmp_path / "out").exists()


def test_nan_pixels_are_masked_and_the_rest_fitted_as_without_them(tmp_path):
    """A few NaN (and one all-zero) pixels: NaN maps and ``explained`` 0 there; every other pixel
    as in the same map without them."""
    f = F_CONTACT * np.linspace(0.85, 1.15, 32)
    clean = np.broadcast_to(2e-3 * BEAM.slope(f)[:, 0], (4, 5, f.size)).copy()
    clean += 2e-3 * np.abs(clean).max() * np.random.default_rng(5).standard_normal(clean.shape)
    broken = clean.copy()
    broken[0, 0, 3], broken[2, 4, :], broken[3, 1] = np.nan, np.nan, 0.0
    masked = np.zeros((4, 5), bool)
    masked[0, 0] = masked[2, 4] = masked[3, 1] = True
    results = {}
    for name, y in (("clean", clean), ("broken", broken)):
        with h5py.File(tmp_path / f"{name}.h5", "w") as h:
            h["response"], h["frequency_hz"] = y, f
            h.attrs.update(META)
        out = tmp_path / f"out_{name}"
        assert main(["map", str(tmp_path / f"{name}.h5"), "--out", str(out), "--no-progress",
                     "--k2-over-k1", "0.8"]) == 0
        results[name] = zarr.open_group(str(out / "maps.zarr"), mode="r")
    k1, explained = np.asarray(results["broken"]["k1"][...]), np.asarray(results["broken"]["explained"][...])
    assert np.all(np.isnan(k1[masked])) and np.all(explained[masked] == 0)
    assert np.all(explained[~masked] == 1)
    np.testing.assert_allclose(k1[~masked], np.asarray(results["clean"]["k1"][...])[~masked], rtol=1e-9)
    assert abs(np.median(k1[~masked]) / 200.0 - 1) < 0.01        # the FE lever's k1
