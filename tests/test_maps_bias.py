"""``pfmdyn map`` with a bias axis: the electrostatic term and the nulling bias at every pixel.

Spectra from the independent finite-element beam (tests/fe_beam.py): at each pixel the surface
moves by ``d1`` (two domains, opposite signs) and a local electrostatic force
``f0 = F_loc (V - V_surf)`` acts on the tip, with a surface-potential pattern, read through a
complex instrument gain, with complex Gaussian noise.  Two levers drawn from the ranges real ones
have.  The truth the maps must recover, with ``T_d1 = k1 T_f0`` (the force enters the tip's
boundary condition beside ``k1 d1``): slope ``G = gain F_loc / k1`` per volt, nulling bias
``V_surf - d1 k1 / F_loc`` and ``d_eff`` amplitude ``|gain d1|`` at ``V_surf``.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
zarr = pytest.importorskip("zarr")
pytest.importorskip("dask")
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn import Cantilever  # noqa: E402
from pfmdyn.cli import main  # noqa: E402

N = 8
BIASES = np.array([-3.0, -1.5, 0.0, 1.5, 3.0, 1.5, 0.0, -1.5])   # a triangle: values repeat
GAIN = 2e5 * np.exp(0.7j)
F_LOC = 2e-9           # N per volt


def _levers():
    """Two levers (seeded): soft and long, stiff and short; contact k1/k in their ranges."""
    rng = np.random.default_rng(11)
    soft = dict(k=rng.uniform(0.1, 1.0), L=rng.uniform(350e-6, 480e-6), ratio=rng.uniform(50, 500))
    stiff = dict(k=rng.uniform(10, 45), L=rng.uniform(110e-6, 160e-6), ratio=rng.uniform(2, 20))
    return {"soft": soft, "stiff": stiff}


def _write_map(path, lever, usid=False, q0=0.0):
    """The map file and the truth per pixel (k1, slope G, nulling bias, |d_eff|); ``q0``: an
    electrostatic load along the lever, ``q0 (V - V_surf)`` N/m."""
    k, L = lever["k"], lever["L"]
    f1 = 300e3 * (k / 40) ** (1 / 3) * (125e-6 / L)       # silicon levers: f1 ~ k^(1/3) / L at fixed width
    yy, xx = np.mgrid[:N, :N]
    k1 = np.where(xx < N // 2, 1.0, 1.6) * lever["ratio"] * k
    d1 = np.where(yy < N // 2, 5e-12, -5e-12)                  # two domains
    v_surf = np.where(xx + yy < N, 0.4, -0.6)                  # a surface-potential step
    beams = {v: FEBeam(k, L, f1, 10e-6, k1=v, Q=80.0, n_elements=50) for v in np.unique(k1)}
    fc = [b.contact_resonances(1)[0] for b in beams.values()]
    f = np.linspace(0.85 * min(fc), 1.15 * max(fc), 48)
    slope = {v: b.slope(f) for v, b in beams.items()}          # per (d1, d2, f0, q0)
    free = float(FEBeam(k, L, f1, 10e-6, n_elements=50).free_resonances(1)[0])
    y = np.empty((N, N, BIASES.size, f.size), complex)
    for i in range(N):
        for j in range(N):
            T = slope[k1[i, j]]
            force = T[:, 2] * F_LOC + T[:, 3] * q0
            y[i, j] = GAIN * (T[:, 0] * d1[i, j] + force * (BIASES[:, None] - v_surf[i, j]))
    rng = np.random.default_rng(5)
    y += 0.01 * np.abs(y).max(axis=(2, 3), keepdims=True) * (rng.standard_normal(y.shape)
                                                             + 1j * rng.standard_normal(y.shape))
    attrs = dict(spring_constant_n_per_m=k, length_m=L, tip_height_m=10e-6, free_resonance_hz=free, k2=0.0)
    with h5py.File(path, "w") as h:
        if usid:
            _write_beps(h, y, f, attrs)
        else:
            h["response"], h["frequency_hz"], h["bias_v"] = y, f, BIASES
            h.attrs.update(attrs)
    truth = {"k1": k1, "electrostatic": np.abs(GAIN) * F_LOC / k1, "nulling_bias": v_surf - d1 * k1 / F_LOC,
             "amplitude": np.abs(GAIN * d1), "v_surf": v_surf}
    return path, truth


def _write_beps(h, y, f, attrs):
    """As BGlib lays out BEPS: positions x (DC step, frequency bin), Frequency fastest, bias in
    a ``DC_Offset`` row in mV, spectral columns listed with the frequencies in decreasing order
    and an ``Field`` row holding one value."""
    ny, nx, nb, nf = y.shape
    raw = y[:, :, :, ::-1].reshape(ny * nx, nb * nf)
    chan = h.create_group("Measurement_000/Channel_000")
    main = chan.create_dataset("Raw_Data", data=raw)
    yy, xx = np.divmod(np.arange(ny * nx), nx)
    pos = chan.create_dataset("Position_Indices", data=np.stack([xx, yy], axis=1).astype(np.uint32))
    pos.attrs["labels"] = ["X", "Y"]
    fi, bi = np.tile(np.arange(nf), nb), np.repeat(np.arange(nb), nf)
    values = np.stack([f[::-1][fi], 1e3 * BIASES[bi], np.zeros(nb * nf)])
    spec = chan.create_dataset("Spectroscopic_Values", data=values)
    index = chan.create_dataset("Spectroscopic_Indices", data=np.stack([fi, bi, np.zeros(nb * nf, int)]))
    for d in (spec, index):
        d.attrs["labels"], d.attrs["units"] = ["Frequency", "DC_Offset", "Field"], ["Hz", "mV", ""]
    main.attrs["Position_Indices"], main.attrs["Spectroscopic_Values"] = pos.ref, spec.ref
    main.attrs["Spectroscopic_Indices"] = index.ref
    h.attrs.update(attrs)


def _maps(out):
    group = zarr.open_group(str(out / "maps.zarr"), mode="r")
    return {name: np.asarray(group[name][...]) for name in group.array_keys() if name != "done"}


@pytest.fixture(scope="module", params=["soft", "stiff"])
def bias_run(request, tmp_path_factory):
    d = tmp_path_factory.mktemp(request.param)
    path, truth = _write_map(d / "beps.h5", _levers()[request.param])
    assert main(["map", str(path), "--out", str(d / "o"), "--no-progress", "--model", "elastic",
                 "--surface-potential", "0.4"]) == 0
    return request.param, path, truth, _maps(d / "o")


@pytest.mark.parametrize("name", ["k1", "electrostatic", "nulling_bias"])
def test_electrostatic_maps_within_uncertainty(bias_run, name):
    _, _, truth, m = bias_run
    z = (m[name] - truth[name]) / m[f"{name}_stderr"]
    assert np.mean(np.abs(z) <= 3) >= 0.95, (name, z)
    assert np.mean(np.abs(z) <= 1) >= 0.5, (name, z)          # the errors are not inflated either


def test_signs_of_the_electrostatic_and_electromechanical_terms(bias_run):
    """A force F_loc > 0 per volt and d1 > 0 (top domain) both read through the gain: their
    phases are arg(gain); a sign slip anywhere would put them at arg(gain) + pi."""
    _, _, truth, m = bias_run
    top = (np.arange(N)[:, None] < N // 2) & (truth["v_surf"] == 0.4)    # d1 > 0, V_surf as given
    for phase in (m["electrostatic_phase"], m["phase"][top]):
        offset = np.angle(np.mean(np.exp(1j * (phase - np.angle(GAIN)))))
        assert abs(offset) < 0.05, offset


def test_d_eff_at_the_given_surface_potential(bias_run):
    _, _, truth, m = bias_run
    at = truth["v_surf"] == 0.4                               # pixels whose V_surf was given
    z = (m["amplitude"] - truth["amplitude"]) / m["amplitude_stderr"]
    assert np.mean(np.abs(z[at]) <= 3) >= 0.95, z[at]
    # opposite domains: d_eff phases differ by pi
    top, bottom = (np.exp(1j * m["phase"][half][at[half]]).mean() for half in (slice(None, N // 2), slice(N // 2, None)))
    assert abs(abs(np.angle(top / bottom)) - np.pi) < 0.1


def test_beps_usid_layout_gives_the_same_maps(bias_run, tmp_path):
    name, _, _, m = bias_run
    path, _ = _write_map(tmp_path / "beps_usid.h5", _levers()[name], usid=True)
    assert main(["map", str(path), "--out", str(tmp_path / "o"), "--no-progress", "--model", "elastic",
                 "--surface-potential", "0.4"]) == 0
    for name, value in _maps(tmp_path / "o").items():
        np.testing.assert_allclose(value, m[name], rtol=1e-9, atol=1e-300, err_msg=name)


def test_beps_written_by_pyusid(tmp_path, monkeypatch):
    """pyUSID's own writer (positions [Y, X], spectroscopic rows slowest first: DC_Offset, then
    Frequency) gives the maps of the plain layout holding the same numbers."""
    if not hasattr(np, "product"):                 # pyUSID 0.0.12 calls numpy.product (gone in NumPy 2)
        monkeypatch.setattr(np, "product", np.prod, raising=False)
    usid = pytest.importorskip("pyUSID")
    path, _ = _write_map(tmp_path / "plain.h5", _levers()["stiff"])
    with h5py.File(path, "r") as h:
        y, f, attrs = h["response"][...], h["frequency_hz"][...], dict(h.attrs)
    with h5py.File(tmp_path / "pyusid.h5", "w") as h:
        group = usid.hdf_utils.create_indexed_group(h, "Measurement")
        channel = usid.hdf_utils.create_indexed_group(group, "Channel")
        positions = [usid.Dimension("X", "m", np.arange(N) * 1e-7), usid.Dimension("Y", "m", np.arange(N) * 1e-7)]
        spectral = [usid.Dimension("Frequency", "Hz", f), usid.Dimension("DC_Offset", "V", np.arange(BIASES.size))]
        main_data = usid.hdf_utils.write_main_dataset(channel, y.reshape(N * N, -1), "Raw_Data", "Piezoresponse",
                                                      "a.u.", positions, spectral)
        # the bias steps' values (a triangle repeats them; pyUSID wants distinct ones to build the indices)
        values = h[main_data.attrs["Spectroscopic_Values"]]
        row = [label.decode() if isinstance(label, bytes) else label for label in values.attrs["labels"]].index("DC_Offset")
        values[row] = BIASES[values[row].astype(int)]
        f_written = np.unique(values[1 - row])
        group.attrs.update(attrs)
    with h5py.File(path, "a") as h:            # pyUSID keeps float32 values: the plain file gets the same
        del h["frequency_hz"]
        h["frequency_hz"] = f_written
    outs = []
    for name in (path, tmp_path / "pyusid.h5"):
        out = tmp_path / ("o_" + Path(name).stem)
        assert main(["map", str(name), "--out", str(out), "--no-progress", "--model", "elastic"]) == 0
        outs.append(_maps(out))
    for name, value in outs[1].items():
        np.testing.assert_allclose(value, outs[0][name], rtol=1e-9, atol=1e-300, err_msg=name)


def test_distributed_load_is_named_and_gives_the_surface_potential(tmp_path, capsys):
    """A soft lever with the derived parallel-plate load along it (eps0 w / H^2 per volt of dV,
    w = 30 um, H = 10 um; the size only, from the generated formula): at the first contact
    resonance it drives the tip ~5x more than the local force.  ``--model auto`` must name it; then k1, the local term, V_surf (now
    identifiable: the distributed load has a spectrum of its own) and d_eff at the fitted V_surf
    lie within their standard errors."""
    from pfmdyn.analysis.diagram import EPSILON_0
    from pfmdyn.generated.formulas import capacitive_load_per_volt2
    path, truth = _write_map(tmp_path / "soft.h5", _levers()["soft"], q0=capacitive_load_per_volt2(EPSILON_0, 30e-6, 10e-6))
    assert main(["map", str(path), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    assert "model elastic+distributed:" in capsys.readouterr().out
    m = _maps(tmp_path / "o")
    truth["surface_potential"] = truth["v_surf"]
    for name in ("k1", "electrostatic", "surface_potential", "amplitude"):
        z = (m[name] - truth[name]) / m[f"{name}_stderr"]
        assert np.mean(np.abs(z) <= 3) >= 0.95, (name, z)


def test_bias_axis_errors_are_one_line(tmp_path, capsys):
    attrs = dict(spring_constant_n_per_m=2.0, length_m=225e-6, tip_height_m=10e-6, free_resonance_hz=75e3)
    cases = [({"response": np.ones((2, 2, 3, 4), complex), "frequency_hz": [1.0, 2.0, 3.0, 4.0]},
              "a bias axis needs a bias_v dataset"),
             ({"response": np.ones((2, 2, 2, 4), complex), "frequency_hz": [1.0, 2.0, 3.0, 4.0], "bias_v": [1.0, 1.0]},
              "at least two distinct biases"),
             # repeated sweeps at 0 V, the bias written as computed (-0.3 + 3 * 0.1): one setpoint, no slope
             ({"response": np.ones((2, 2, 4, 4), complex), "frequency_hz": [1.0, 2.0, 3.0, 4.0],
               "bias_v": [0.0, -0.3 + 3 * 0.1, 0.1 * 3 - 0.3, 0.0]}, "at least two distinct biases"),
             ({"response": np.ones((2, 2, 3, 4), complex), "frequency_hz": [1.0, 2.0, 3.0, 4.0], "bias_v": [0, 1, 2, 3]},
              "(n_bias = len(bias_v))")]
    for data, message in cases:
        path = tmp_path / "bad.h5"
        with h5py.File(path, "w") as h:
            for key, value in data.items():
                h[key] = value
            h.attrs.update(attrs)
        assert main(["map", str(path), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err


def test_closed_form_normal_matrix_matches_the_explicit_jacobian():
    """The covariance's closed-form blocks against the real Jacobian of the full problem, built
    column by column (two bands, two bias components, two drives, drag: every block type)."""
    from pfmdyn.fitting.batched import band_covariance
    from pfmdyn.maps.beam import BeamMapModel
    rng = np.random.default_rng(1)
    f = np.concatenate([np.linspace(2.5e5, 3.5e5, 30), np.linspace(9e5, 1.1e6, 30)])
    model = BeamMapModel(Cantilever(2.0, 75e3, 225e-6, tip_height=10e-6), f,
                         mechanisms=("internal", "viscous", "distributed"))
    n = 5
    p = np.column_stack([np.log10(rng.uniform(200, 400, n)), np.log10(rng.uniform(30, 90, n)),
                         np.log10(rng.uniform(100, 300, n)), rng.uniform(0, 0.1, n)])
    c = rng.standard_normal((n, 2, 2, 2)) + 1j * rng.standard_normal((n, 2, 2, 2))   # (pixel, q, band, drive)
    g, dg = model.design(p)
    columns = []
    for i in range(dg.shape[0]):                       # d residual / d p_i = -sum_k c_qjk dg_ik in band j
        d = np.zeros((n, 2, f.size), complex)
        for j, b in enumerate(model.bands):
            d[:, :, b] = -np.einsum("nqk,nkf->nqf", c[:, :, j], dg[i][:, :, b])
        columns.append(d)
    for q in range(2):
        for j, b in enumerate(model.bands):
            for k in range(2):
                for unit in (1.0, 1j):                 # d residual / d (Re, Im) c_qjk = -(1, i) g_k
                    d = np.zeros((n, 2, f.size), complex)
                    d[:, q, b] = -unit * g[:, k, b]
                    columns.append(d)
    J = np.stack([np.concatenate([d.real, d.imag], axis=1).reshape(n, -1) for d in columns], axis=2)
    expected = np.linalg.inv(np.einsum("nki,nkj->nij", J, J))
    scale = np.sqrt(np.einsum("nii->ni", expected))
    np.testing.assert_allclose(band_covariance(model, g, dg, c, np.ones(n)) / (scale[:, :, None] * scale[:, None, :]),
                               expected / (scale[:, :, None] * scale[:, None, :]), atol=1e-8)


@pytest.mark.parametrize("geometry", [{"gamma": 0.92}, {"gamma": 0.95, "mu": 0.3}], ids=["setback", "setback+mass"])
def test_known_tip_geometry_is_used(tmp_path, geometry):
    """A tip set back from the free end (and a tip mass), as a lever's datasheet gives them:
    with --tip-position/--tip-mass the map recovers k1 (four values over a decade) within its
    errors; the plain model, tip at the end, misses it by many."""
    lever = _levers()["stiff"]
    k, L = lever["k"], lever["L"]
    f1 = 300e3 * (k / 40) ** (1 / 3) * (125e-6 / L)
    k1 = k * np.geomspace(5, 50, 4)
    # 100 elements: a node at the tip (the FE beam puts it at the nearest node)
    beams = [FEBeam(k, L, f1, 10e-6, k1=v, Q=60.0, n_elements=100, **geometry) for v in k1]
    fc = [b.contact_resonances(1)[0] for b in beams]
    f = np.linspace(0.85 * min(fc), 1.15 * max(fc), 64)
    y = np.stack([3e5 * b.slope(f)[:, 0] * 1e-11 for b in beams]).reshape(2, 2, -1)
    rng = np.random.default_rng(2)
    y = y + 0.005 * np.abs(y).max() * (rng.standard_normal(y.shape) + 1j * rng.standard_normal(y.shape))
    free = float(FEBeam(k, L, f1, 10e-6, n_elements=100, **geometry).free_resonances(1)[0])
    with h5py.File(tmp_path / "m.h5", "w") as h:
        h["response"], h["frequency_hz"] = y, f
        h.attrs.update(spring_constant_n_per_m=k, length_m=L, tip_height_m=10e-6, free_resonance_hz=free, k2=0.0)
    tip = ["--tip-position", str(geometry["gamma"]), "--tip-mass-ratio", str(geometry.get("mu", 0.0))]
    z = {}
    for name, extra in (("known", tip), ("plain", [])):
        assert main(["map", str(tmp_path / "m.h5"), "--out", str(tmp_path / name), "--no-progress",
                     "--model", "elastic", *extra]) == 0
        m = _maps(tmp_path / name)
        z[name] = np.abs(m["k1"].ravel() - k1) / m["k1_stderr"].ravel()
    assert np.all(z["known"] < 3), z
    # the plain model either misses k1 by many errors or cannot reach the spectra at all (a
    # parameter at its bound: the pixel is unexplained, k1 not reported)
    assert np.median(np.where(np.isnan(z["plain"]), np.inf, z["plain"])) > 10, z
