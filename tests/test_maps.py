"""``pfmdyn map``: synthetic band-excitation maps from the finite-element beam (tests/fe_beam.py).

The spectra come from the independent FE cantilever, one solve per distinct k1 value, never from
the fitting code path.  The map has two ferroelectric domains (d_eff phase 0 and pi, different k1)
and a stiff inclusion, a known Q and complex Gaussian noise.
"""
from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")
pytest.importorskip("dask")
# The independent FE generator lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn.cli import main  # noqa: E402
from pfmdyn.maps.driver import open_map, run_map  # noqa: E402

K, L, F1, H, Q = 2.0, 225e-6, 75e3, 10e-6, 60.0
N = 32


def _k1_pattern():
    yy, xx = np.mgrid[:N, :N]
    k1 = np.where(xx < N // 2, 150.0, 400.0)
    k1[(yy - 20) ** 2 + (xx - 9) ** 2 < 16] = 1500.0
    return k1, np.where(xx < N // 2, 1.0, -1.0)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    k1, sign = _k1_pattern()
    beams = {v: FEBeam(K, L, F1, H, k1=v, Q=Q, n_elements=60) for v in np.unique(k1)}
    first = [b.contact_resonances(1)[0] for b in beams.values()]
    f = np.linspace(0.85 * min(first), 1.15 * max(first), 64)
    shapes = {v: b.slope(f)[:, 0] for v, b in beams.items()}
    clean = np.stack([sign[i, j] * 2e-3 * shapes[k1[i, j]] for i in range(N) for j in range(N)]).reshape(N, N, -1)
    rng = np.random.default_rng(7)
    noise = 0.005 * np.abs(clean).max(axis=2, keepdims=True) * (rng.standard_normal(clean.shape)
                                                               + 1j * rng.standard_normal(clean.shape))
    path = tmp_path_factory.mktemp("map") / "be.h5"
    with h5py.File(path, "w") as h:
        h["response"] = clean + noise
        h["frequency_hz"] = f
        # the FE beam has k2 = 0: held there (one band cannot tell)
        h.attrs.update(spring_constant_n_per_m=K, length_m=L, width_m=40e-6, tip_height_m=H, free_resonance_hz=F1,
                       k2=0.0)
    return path, k1


def _maps(out):
    group = zarr.open_group(str(out / "maps.zarr"), mode="r")
    return {name: np.asarray(group[name][...]) for name in ("k1", "k1_stderr", "quality_factor", "phase", "gap")
            if name in group}


@pytest.fixture(scope="module")
def local_run(synthetic, tmp_path_factory):
    path, _ = synthetic
    out = tmp_path_factory.mktemp("local")
    assert main(["map", str(path), "--out", str(out), "--no-progress", "--plot", str(out)]) == 0
    assert (out / "k1.png").stat().st_size > 1000
    return out


def test_k1_recovered_within_uncertainty(synthetic, local_run):
    _, k1 = synthetic
    m = _maps(local_run)
    z = (m["k1"] - k1) / m["k1_stderr"]
    assert np.mean(np.abs(z) <= 3) >= 0.95, np.mean(np.abs(z) <= 3)
    # the reported standard error is calibrated: about 68 % of pixels within one of it
    assert 0.6 <= np.mean(np.abs(z) <= 1) <= 0.8, np.mean(np.abs(z) <= 1)
    assert np.median(np.abs(m["quality_factor"] / Q - 1)) < 0.05
    # domains: d_eff phases differ by pi between the halves
    # circular means: phases near +-pi wrap
    left, right = (np.exp(1j * m["phase"][:, half]).mean() for half in (slice(None, N // 2), slice(N // 2, None)))
    dphi = np.angle(left / right)
    assert abs(abs(dphi) - np.pi) < 0.1
    group = zarr.open_group(str(local_run / "maps.zarr"), mode="r")
    assert group["k1"].attrs["units"] == "N/m" and group["k1"].shape == (N, N)


def test_interrupted_run_resumes_to_identical_maps(synthetic, local_run, tmp_path):
    path, _ = synthetic
    out = tmp_path / "resumed"
    shutil.copytree(local_run, out)
    group = zarr.open_group(str(out / "maps.zarr"), mode="r+")
    done = np.asarray(group["done"][...])
    done[1:, :] = 0                                   # as if stopped after the first row of blocks
    group["done"][...] = done
    group["k1"][16:, :] = np.nan
    summary = run_map(open_map(str(path)), str(out), progress=False)
    assert summary["blocks_run"] == 2                 # only the unfinished blocks
    np.testing.assert_array_equal(_maps(out)["k1"], _maps(local_run)["k1"])


def test_distributed_cluster_gives_identical_maps(synthetic, local_run, tmp_path):
    distributed = pytest.importorskip("distributed")
    path, _ = synthetic
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        run_map(open_map(str(path)), str(tmp_path), scheduler=cluster.scheduler_address, progress=False)
    for name, value in _maps(tmp_path).items():
        np.testing.assert_array_equal(value, _maps(local_run)[name], err_msg=name)


def test_bad_input_is_one_line_error(tmp_path, capsys):
    path = tmp_path / "bad.h5"
    with h5py.File(path, "w") as h:
        h["response"] = np.ones((2, 2, 3), complex)
        h["frequency_hz"] = [3.0, -2.0, 1.0]
        h.attrs.update(spring_constant_n_per_m=K, length_m=L, tip_height_m=H, free_resonance_hz=F1)
    assert main(["map", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "frequency_hz must be positive and finite" in capsys.readouterr().err
    with h5py.File(path, "a") as h:
        h["frequency_hz"][...] = [3.0, 1.0, 3.0]
    assert main(["map", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "frequency_hz holds 3 Hz twice" in capsys.readouterr().err
    path.unlink()
    with h5py.File(path, "w") as h:
        h["frequency_hz"] = [1.0]
    assert main(["map", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "missing dataset 'response'" in capsys.readouterr().err
    with h5py.File(path, "w") as h:         # a single-frequency image as pycroscopy's NSID stores it
        h.create_group("Measurement_000/Channel_000")["Channel_000"] = np.zeros((4, 4))
    assert main(["map", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "without a spectrum per pixel (an image's channels" in capsys.readouterr().err
    for other in (tmp_path / "scan.ibw", tmp_path / "empty_dir"):     # not HDF5, not a Zarr group
        other.write_bytes(b"IGOR") if other.suffix else other.mkdir()
        assert main(["map", str(other), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert "not a readable" in err and len(err.strip().splitlines()) == 1, err


def test_missing_extra_names_it(synthetic, tmp_path, monkeypatch, capsys):
    path, _ = synthetic
    monkeypatch.setitem(sys.modules, "zarr", None)        # import zarr raises ImportError
    assert main(["map", str(path), "--out", str(tmp_path)]) == 2
    assert "pip install 'pfmdyn[maps]'" in capsys.readouterr().err


def _write_usid(path, response, f, attrs, pyusid_style=False):
    """BE data the way BGlib writes it: positions x spectral values, with ancillary references.
    ``pyusid_style``: as pyUSID's ``write_main_dataset`` lays it out instead (position columns
    slowest first, [Y, X]), with the frequencies in kHz and the metadata on the measurement
    group under Asylum's names where Asylum has one."""
    ny, nx, nf = response.shape
    with h5py.File(path, "w") as h:
        meas = h.create_group("Measurement_000")
        chan = meas.create_group("Channel_000")
        raw = chan.create_dataset("Raw_Data", data=response.reshape(ny * nx, nf))
        yy, xx = np.divmod(np.arange(ny * nx), nx)
        columns, labels = ((yy, xx), ["Y", "X"]) if pyusid_style else ((xx, yy), ["X", "Y"])
        pos = chan.create_dataset("Position_Indices", data=np.stack(columns, axis=1).astype(np.uint32))
        pos.attrs["labels"] = labels
        spec = chan.create_dataset("Spectroscopic_Values", data=(f / 1e3 if pyusid_style else f)[None, :])
        spec.attrs["labels"] = ["Frequency"]
        spec.attrs["units"] = ["kHz" if pyusid_style else "Hz"]
        raw.attrs["Position_Indices"], raw.attrs["Spectroscopic_Values"] = pos.ref, spec.ref
        (meas if pyusid_style else h).attrs.update(attrs)


@pytest.mark.parametrize("pyusid_style", [False, True], ids=["bglib", "pyusid"])
def test_usid_layout_gives_the_plain_layout_maps(synthetic, local_run, tmp_path, pyusid_style):
    path, _ = synthetic
    with h5py.File(path, "r") as h:
        response, f = h["response"][...], h["frequency_hz"][...]
    usid = tmp_path / "be_usid.h5"
    attrs = {"tip_height_m": H, "free_resonance_hz": F1, "k2": 0.0}
    lever = ["--spring-constant", str(K), "--length", str(L)]
    if pyusid_style:
        attrs.update(SpringConstant=K, CustomLeverLength=L)
        lever = []
    _write_usid(usid, response, f, attrs, pyusid_style)
    assert main(["map", str(usid), "--out", str(tmp_path / "o"), "--no-progress"] + lever) == 0
    for name, value in _maps(tmp_path / "o").items():
        np.testing.assert_array_equal(value, _maps(local_run)[name], err_msg=name)


def test_contact_frequency_map_to_k1(synthetic, tmp_path):
    pytest.importorskip("pfmdyn.analysis.stiffness")
    _, k1 = synthetic
    beams = {v: FEBeam(K, L, F1, H, k1=v, n_elements=80) for v in np.unique(k1)}
    free = beams[150.0].free_resonances(1)[0]
    fc = {v: b.contact_resonances(1)[0] for v, b in beams.items()}
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.vectorize(fc.get)(k1)
        h.attrs.update(spring_constant_n_per_m=K, free_resonance_hz=free)
    assert main(["map", str(path), "--out", str(tmp_path)]) == 0
    np.testing.assert_allclose(_maps(tmp_path)["k1"], k1, rtol=1e-3)
    # the same map through pfmdyn stiffness, its --json the summary map writes (stiffness dropped it in silence)
    assert main(["map", str(path), "--out", str(tmp_path / "m"), "--json", str(tmp_path / "m.json"),
                 "--plot", str(tmp_path / "figures")]) == 0
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == ["k1.png", "k1_stderr.png"]   # was ignored
    assert main(["stiffness", str(path), "--out", str(tmp_path / "s"), "--json", str(tmp_path / "s.json")]) == 0
    np.testing.assert_array_equal(_maps(tmp_path / "s")["k1"], _maps(tmp_path)["k1"])
    by_map, by_stiffness = (json.loads((tmp_path / name).read_text()) for name in ("m.json", "s.json"))
    assert by_stiffness["results"] == by_map["results"] and by_stiffness["kind"] == "map"


def test_contact_frequency_map_no_pixel_explains_is_undetermined_with_why(tmp_path, capsys):
    """Ratios above the stiff limit of the lever without k2 (4.385): no 'nan' printed, the summary and
    the JSON say k1 is undetermined and why; lever flags the inversion would not use are refused."""
    import json
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((2, 3), 5.0 * F1)
        h.attrs.update(spring_constant=K, free_resonance=F1)
    assert main(["map", str(path), "--out", str(tmp_path / "o"), "--json", str(tmp_path / "m.json")]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out and "undetermined at every pixel" in out and "4.385" in out
    record = json.loads((tmp_path / "m.json").read_text())["results"]["median_k1"]
    assert record["status"] == "undetermined" and "4.385" in record["why"]
    for command in ("map", "stiffness"):
        assert main([command, str(path), "--out", str(tmp_path / command), "--tip-height", "1e-5"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--tip-height" in err[0] and "--contact" not in err[0], err
        assert not (tmp_path / command).exists()


def test_contact_frequency_map_checks_model_and_names_missing_flags(tmp_path, capsys):
    """--model is checked whatever the input (a typo was ignored on a contact map); a contact map
    without the lever's metadata names the flags that give it, as every command does."""
    path = tmp_path / "cr.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((2, 3), 3.0 * F1)
    lever = ["--spring-constant", str(K), "--free-resonance", str(F1)]
    for argv, words in ((["--model", "elastc"], "unknown model 'elastc'"), (["--model", "sho"], "--model"),
                        ([], "give --spring-constant and --free-resonance")):
        assert main(["map", str(path), "--out", str(tmp_path / "o"), *(lever if argv else []), *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0], err
    assert not (tmp_path / "o").exists()


def test_zarr_group_input_with_frequencies_in_any_order(synthetic, local_run, tmp_path):
    """A Zarr group whose frequencies are shuffled (a set: the spectra follow them)."""
    path, _ = synthetic
    group = zarr.open_group(str(tmp_path / "be.zarr"), mode="w")
    with h5py.File(path, "r") as h:
        order = np.random.default_rng(1).permutation(h["frequency_hz"].shape[0])
        group["response"] = h["response"][:16, :16][..., order]
        group["frequency_hz"] = h["frequency_hz"][...][order]
        group.attrs.update({key: float(v) for key, v in h.attrs.items()})
    assert main(["map", str(tmp_path / "be.zarr"), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    np.testing.assert_array_equal(_maps(tmp_path / "o")["k1"], _maps(local_run)["k1"][:16, :16])


def _two_band_map(tmp_path, name, **damping):
    """A 3 x 4 map of one FE beam (k1 = 100, k2 = 60 N/m) over its first two contact modes;
    returns the file and the true extra damping parameter: the dashpot's loss tangent at the free
    resonance (x = omega1 eta / k1) or the drag's g = c / (rho S omega1) = viscous_hz / f1."""
    undamped = FEBeam(K, L, F1, H, k1=100.0, k2=60.0, n_elements=60)
    f_contact = undamped.contact_resonances(2)
    if "eta" in damping:    # dashpot giving contact mode 1 a loss tangent of ~1/60
        damping["eta"] = 100.0 / (2 * np.pi * f_contact[0] * damping["eta"])
    beam = FEBeam(K, L, F1, H, k1=100.0, k2=60.0, n_elements=60, **damping)
    f = np.concatenate([np.linspace(0.93, 1.07, 40) * f_contact[0], np.linspace(0.95, 1.05, 40) * f_contact[1]])
    rng = np.random.default_rng(3)
    y = np.broadcast_to(2e-3 * np.exp(0.3j) * beam.slope(f)[:, 0], (3, 4, f.size))
    y = y + 0.01 * np.median(np.abs(y)) * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
    free = float(FEBeam(K, L, F1, H, n_elements=60).free_resonances(1)[0])
    with h5py.File(tmp_path / name, "w") as h:
        h["response"], h["frequency_hz"] = y, f
        h.attrs.update(spring_constant_n_per_m=K, length_m=L, tip_height_m=H, free_resonance_hz=free)
    return tmp_path / name, 2 * np.pi * free * beam.eta / beam.k1 + beam.viscous_hz / free


@pytest.mark.parametrize("damping, chosen", [({"Q": 80.0}, "elastic"), ({"eta": 60.0}, "elastic+contact"),
                                             ({"viscous_hz": F1 / 40}, "elastic+viscous")])
def test_two_contact_bands_separate_k1_and_k2_and_auto_names_the_damping(tmp_path, capsys, damping, chosen):
    path, x = _two_band_map(tmp_path, "two.h5", **damping)
    assert main(["map", str(path), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "k2 fitted" in out and f"model {chosen}:" in out
    group = zarr.open_group(str(tmp_path / "o" / "maps.zarr"), mode="r")
    assert group.attrs["model"] == chosen
    assert [r["model"] for r in group.attrs["model_selection"] if r["chosen"]] == [chosen]
    for name, true in (("k1", 100.0), ("k2", 60.0)):
        z = (np.asarray(group[name][...]) - true) / np.asarray(group[f"{name}_stderr"][...])
        assert np.all(np.abs(z) < 4), (name, z)
    extra = {"elastic+contact": "contact_loss", "elastic+viscous": "viscous_loss"}.get(chosen)
    if extra:
        z = (np.asarray(group[extra][...]) - x) / np.asarray(group[f"{extra}_stderr"][...])
        assert np.all(np.abs(z) < 4), z


def test_max_blocks_then_rerun_gives_identical_maps_with_progress(synthetic, local_run, tmp_path, capsys, monkeypatch):
    path, _ = synthetic
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)     # a bar is drawn on a terminal only
    args = ["map", str(path), "--out", str(tmp_path), "--max-blocks", "3", "--workers", "2"]
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "3/4 done" in captured.out
    assert "3/4" in captured.err and "pixels_per_s" in captured.err      # tqdm bar: blocks, pixels/s
    assert main(args) == 0
    assert "1 blocks fitted" in capsys.readouterr().out
    for name, value in _maps(tmp_path).items():
        np.testing.assert_array_equal(value, _maps(local_run)[name], err_msg=name)


@pytest.mark.parametrize("case", ["low_q", "stiff_two_band"])
def test_levers_the_start_grid_used_to_miss(case):
    """Failure classes of benchmarks/map_levers.py, one lever each drawn (seeded) from the class:
    a broad resonance (Q 5-8: the start grid's Q stopped at 25, and k1 ran to its bound), and a
    stiff contact seen in two bands (k1/k 2000-1e4, k2 = 0.8 k1: the grid had k2 = 0, which moves
    the modes of such a contact by decades of k1).  k1 (and k2) within 3 standard errors."""
    from pfmdyn import Cantilever, Contact
    from pfmdyn.maps.beam import BeamMapModel
    from pfmdyn.maps.fit import fit_block
    rng = np.random.default_rng({"low_q": 1, "stiff_two_band": 27}[case])
    k, length, height = 10 ** rng.uniform(-1, 1.5), rng.uniform(150e-6, 450e-6), rng.uniform(5e-6, 20e-6)
    f1 = 300e3 * (k / 40) ** (1 / 3) * (125e-6 / length)
    two = case == "stiff_two_band"
    ratio, q = 10 ** rng.uniform(*((3.3, 4) if two else (1, 3))), rng.uniform(*((100, 300) if two else (5, 8)))
    k1 = ratio * k * rng.uniform(0.7, 1.3, 4)
    beams = [FEBeam(k, length, f1, height, k1=v, k2=0.8 * v if two else 0.0, Q=q, n_elements=40) for v in k1]
    modes = np.array([b.contact_resonances(2) for b in beams])
    f = np.concatenate([np.linspace(0.85 * modes[:, m].min(), 1.15 * modes[:, m].max(), 64) for m in range(1 + two)])
    y = np.stack([2e-3 * b.slope(f)[:, 0] for b in beams])
    y = y + 0.01 * np.abs(y).max() * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
    free = float(FEBeam(k, length, f1, height, n_elements=40).free_resonances(1)[0])
    lever = Cantilever(k, free, length, tip_height=height)
    out = fit_block(BeamMapModel(lever, f, contact=Contact() if two else Contact(k2=0.0)), y)
    for name, true in (("k1", k1), ("k2", 0.8 * k1)) if two else (("k1", k1),):
        z = (out[name] - true) / out[f"{name}_stderr"]
        assert np.all(np.abs(z) < 3), (name, z)


def test_single_band_usid_map_ties_k2_and_names_nothing_false(tmp_path, monkeypatch, capsys):
    """The data most band-excitation users have: one band around the first contact resonance, a
    pycroscopy USID line map, k2 = 0.8 k1 in the FE data (contact resonances 4.3-4.8 f1, above the
    k2 = 0 pinned limit of 4.385 f1 at the stiff end).  With k2 tied to k1 by the default policy
    (Mindlin, Poisson 0.3: 0.82 k1) k1 is found within 5 % at >= 95 % of the pixels, no pixel sits
    at a bound, and ``--model auto`` adds nothing (the data hold no drag, dashpot or distributed
    load).  Fixing k2 = 0 instead, as maps did, drove k1 to its bound."""
    if not hasattr(np, "product"):                 # pyUSID 0.0.12 calls numpy.product (gone in NumPy 2)
        monkeypatch.setattr(np, "product", np.prod, raising=False)
    usid = pytest.importorskip("pyUSID")
    rng = np.random.default_rng(11)
    k, length, height, f1 = 3.0, 240e-6, 12e-6, 68e3
    nx = 20
    k1 = 10 ** rng.uniform(np.log10(200 * k / 2), np.log10(1000 * k / 2), nx)
    q = rng.uniform(80, 300, nx)
    beams = [FEBeam(k, length, f1, height, k1=v, k2=0.8 * v, Q=qq, n_elements=60) for v, qq in zip(k1, q)]
    fc = np.array([FEBeam(k, length, f1, height, k1=v, k2=0.8 * v, n_elements=60).contact_resonances(1)[0]
                   for v in k1])
    free = float(FEBeam(k, length, f1, height, n_elements=60).free_resonances(1)[0])
    assert 4.2 < fc.min() / free and fc.max() / free < 5.0
    f = np.linspace(0.95 * fc.min(), 1.05 * fc.max(), 128)
    y = np.stack([1e-3 * b.slope(f)[:, 0] for b in beams])
    y = y + 0.01 * np.abs(y).max(axis=1, keepdims=True) * (rng.standard_normal(y.shape)
                                                           + 1j * rng.standard_normal(y.shape))
    path = tmp_path / "line.h5"
    with h5py.File(path, "w") as h:
        group = usid.hdf_utils.create_indexed_group(h, "Measurement")
        channel = usid.hdf_utils.create_indexed_group(group, "Channel")
        positions = [usid.Dimension("X", "m", np.arange(nx) * 1e-7), usid.Dimension("Y", "m", [0.0])]
        usid.hdf_utils.write_main_dataset(channel, y, "Raw_Data", "Piezoresponse", "a.u.", positions,
                                          [usid.Dimension("Frequency", "Hz", f)])
        group.attrs.update(spring_constant=k, length=length, tip_height=height, free_resonance=free)
    assert main(["map", str(path), "--out", str(tmp_path / "o"), "--no-progress", "--scheduler", "sync"]) == 0
    out = capsys.readouterr().out
    assert "model (auto" in out and "elastic; " in out and "k2 tied to k1 at 0.824" in out, out
    group = zarr.open_group(str(tmp_path / "o" / "maps.zarr"), mode="r")
    found = np.asarray(group["k1"][...]).ravel()
    assert np.mean(np.abs(found / k1 - 1) < 0.05) >= 0.95, found / k1
    # the assumed tie's share is in k1's standard error (as pfmdyn stiffness states it): it covers
    # the FE data's k2 = 0.8 k1, which the fit's own error (1 % noise) alone does not
    stderr = np.asarray(group["k1_stderr"][...]).ravel()
    assert np.mean(np.abs(found - k1) <= 2 * stderr) >= 0.9, (found - k1) / stderr
    assert not np.any(np.asarray(group["at_bound"][...])) and group.attrs["model"] == "elastic"
    assert "Mindlin" in group.attrs["k2_policy"]


def test_a_map_without_a_tip_height_assumes_the_typical_one_and_states_its_share(tmp_path, capsys):
    """A band-excitation file that records no tip height (most do not): the map takes the default of every
    command (13 +- 2.5 um), prints it as assumed, stores and writes it so, and k1's standard error carries
    its share as ``pfmdyn stiffness`` states it for the same contact resonance (one band, k2 tied by
    the assumed Mindlin ratio: FE data with k2 = 0.8 k1)."""
    import json

    from pfmdyn import Cantilever, Contact
    from pfmdyn.analysis.stiffness_report import analyse
    height = 13e-6
    k1 = np.array([120.0, 200.0, 320.0])
    beams = [FEBeam(K, L, F1, height, k1=v, k2=0.8 * v, Q=Q, n_elements=40) for v in k1]
    fc = np.array([b.contact_resonances(1)[0] for b in beams])
    f = np.linspace(0.9 * fc.min(), 1.1 * fc.max(), 96)
    y = np.stack([2e-3 * b.slope(f)[:, 0] for b in beams])[None]
    y = y + 0.002 * np.abs(y).max() * np.random.default_rng(3).standard_normal(y.shape)
    free = float(FEBeam(K, L, F1, height, n_elements=40).free_resonances(1)[0])
    path = tmp_path / "be.h5"
    with h5py.File(path, "w") as h:
        h["response"], h["frequency_hz"] = y, f
        h.attrs.update(spring_constant_n_per_m=K, length_m=L, free_resonance_hz=free)
    common = ["--no-progress", "--scheduler", "sync", "--model", "elastic"]
    assert main(["map", str(path), "--out", str(tmp_path / "a"), "--json", str(tmp_path / "a.json"), *common]) == 0
    assert "assumed: tip height 1.3e-05 m (a typical PFM probe's" in capsys.readouterr().out
    assert json.loads((tmp_path / "a.json").read_text())["lever"]["tip_height"]["status"] == "assumed"
    group = zarr.open_group(str(tmp_path / "a" / "maps.zarr"), mode="r")
    assert "tip_height" in group.attrs["assumed"] and group.attrs["tip_height_uncertainty"] == 2.5e-6
    assumed = np.asarray(group["k1_stderr"][...]).ravel()
    # the same map with the tip height given exactly: the fit's and the tie's shares alone
    assert main(["map", str(path), "--out", str(tmp_path / "b"), "--tip-height", "13e-6",
                 "--tip-height-uncertainty", "0", *common]) == 0
    exact = np.asarray(zarr.open_group(str(tmp_path / "b" / "maps.zarr"), mode="r")["k1_stderr"][...]).ravel()
    found = np.asarray(group["k1"][...]).ravel()
    assert np.all(np.abs(found / k1 - 1) < 0.1), found / k1
    share = np.sqrt(assumed**2 - exact**2) / found
    lever = Cantilever(K, free, L, tip_height=height)
    stated = [analyse(lever, Contact(), [c], tip_height_uncertainty=2.5e-6).solution.sources["tip_height_uncertainty"]
              ["k1"] / analyse(lever, Contact(), [c]).solution.k1 for c in fc]
    assert np.all(share > 0.01) and np.allclose(share, stated, rtol=0.05), (share, stated)
