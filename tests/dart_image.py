"""Independent DART images: an Asylum ``.ibw`` as the instrument writes it, from the finite-element
lever of :mod:`fe_beam` in contact (nothing of ``derivations/``, ``generated/`` or ``pfmdyn``'s model).

The sample: grains of different contact stiffness ``k1`` and contact loss (the dashpot ``eta`` of
the FE beam, ``contact_loss = omega_f1 eta / k1``), crossed by stripe domains of opposite ``d_eff``;
the lever: its internal friction ``Q`` (the free lever's Q, written as ``ThermalQ``), ``k2`` a fixed
fraction of ``k1``, the laser spot where asked.  The tracking is imperfect (the centre ``fc`` off the
contact resonance by a random fraction of its width), the two lock-ins noisy (circular complex noise,
relative).  The truth of the resonance and Q is the two-frequency oscillator through the exact
(noise-free) signals of the same pixel, typed here from the SHO ``D f0**2 / (f0**2 - f**2 + i f f0/Q)``
through its two points, or where none goes through them (a negative Q), the FE beam's damped pole.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fe_beam import FEBeam  # noqa: E402
from igor_files import asylum_note, igor_wave  # noqa: E402

INVOLS, AMP_INVOLS = 60e-9, 66e-9       # m/V: the amplitude channels are read through AmpInvOLS


@dataclass
class DartCase:
    """A drawn case: the lever, the settings, the channels ``(y, x)``, the truth maps and the exact
    (noise-free) drives and signals with the FE beam's damped pole (``f1``, ``f2``, ``s1``, ``s2``,
    ``pole_resonance``, ``pole_quality_factor``, each ``(y, x)``)."""

    lever: dict
    settings: dict
    channels: dict
    truth: dict
    exact: dict


def _sho_through(f1, f2, s1, s2):
    """The SHO through two complex points, by least squares on its four real unknowns (a route of its own)."""
    out = np.empty((len(f1), 2))
    for i in range(len(f1)):
        # c / s = f0^2 - f^2 + i f w  with c complex, a = f0^2, w = f0/Q:  rows in (Re c, Im c, a, w)
        rows, rhs = [], []
        for f, s in ((f1[i], s1[i]), (f2[i], s2[i])):
            z = 1 / s
            rows += [[z.real, -z.imag, -1.0, 0.0], [z.imag, z.real, 0.0, -f]]
            rhs += [-f**2, 0.0]
        c_re, c_im, a, w = np.linalg.solve(np.array(rows), np.array(rhs))
        out[i] = math.sqrt(a), math.sqrt(a) / w
    return out


def _peak(beam: FEBeam) -> tuple[float, float]:
    """The oscillator through the exact response 0.1 % either side of the undamped contact resonance."""
    f0 = beam.contact_resonances(1)[0]
    f_pair = np.array([0.999 * f0, 1.001 * f0])
    s = beam.slope(f_pair)[:, 0]
    return tuple(_sho_through(f_pair[:1], f_pair[1:], s[:1], s[1:])[0])


def _pole(beam: FEBeam) -> tuple[float, float]:
    """The damped first contact resonance of the FE beam as ``(|r|, |r| / (2 Im r))``: the eigenvalue
    ``lambda = i omega`` of ``K + lambda D + lambda**2 M`` (linearised) nearest the undamped one."""
    Kb, T, M, _, D, _, _ = beam._matrices(parts=True)
    K = Kb * (1 + 1j / beam.Q) + T
    n = len(K)
    Minv = np.linalg.inv(M)
    companion = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ D]])
    omega = -1j * np.linalg.eigvals(companion)
    undamped = 2 * math.pi * beam.contact_resonances(1)[0]
    r = omega[np.argmin(np.abs(omega - undamped))] / (2 * math.pi)
    return abs(r), abs(r) / (2 * r.imag)


def dart_case(seed: int, ny: int = 16, nx: int = 16, *, spot: float = 1.0, k2_over_k1: float = 0.5,
              noise=(0.005, 0.02), lossy: bool = False, grains: int = 4, n_elements: int = 40) -> DartCase:
    """A DART image over real ranges (module docstring): a lever of k 1-40 N/m, L 120-300 um, H 5-15 um,
    f1 from its thickness (silicon), internal Q 150-600; grains of k1 50-1500 N/m and contact loss
    0.004-0.045 (``lossy``: the contact loss giving a contact Q of 25 +- 15 %, the oscillator's at the peak, where a loss up to 0.1 gives it); d_eff 2-20 pm/V, signed by
    stripes; df 0.7-1.5 contact widths; tracking off by 0-30 % of a width; noise drawn in ``noise``."""
    rng = np.random.default_rng(seed)
    E, rho = 169e9, 2330.0
    k, L, w, H = 10 ** rng.uniform(0, math.log10(40)), rng.uniform(120e-6, 300e-6), 35e-6, rng.uniform(5e-6, 15e-6)
    t = (4 * k * L**3 / (E * w)) ** (1 / 3)
    f_bare = 1.8751040687119611**2 / (2 * math.pi) * t / L**2 * math.sqrt(E / 12 / rho)
    q_lever = rng.uniform(150, 600)
    sigma = rng.uniform(*noise)
    drive_v = rng.uniform(0.5, 3.0)
    free = float(FEBeam(k, L, f_bare, H, n_elements=n_elements).free_resonances(1)[0])
    # grains: a Voronoi tessellation of the image
    centres = rng.uniform(0, 1, (grains, 2)) * (ny, nx)
    yy, xx = np.mgrid[0:ny, 0:nx]
    grain = np.argmin((yy[..., None] - centres[:, 0]) ** 2 + (xx[..., None] - centres[:, 1]) ** 2, axis=-1)
    k1s = 10 ** rng.uniform(math.log10(50), math.log10(1500), grains)
    losses = rng.uniform(0.004, 0.045, grains)
    beam = lambda k1, loss: FEBeam(k, L, f_bare, H, k1=k1, k2=k2_over_k1 * k1, Q=q_lever,  # noqa: E731
                                   eta=loss * k1 / (2 * math.pi * free), spot=spot, n_elements=n_elements)
    beams = []
    for k1, loss in zip(k1s, losses):
        if lossy:       # a contact Q of 25 +- 15 %: the oscillator's 1/Q at the peak is linear in the dashpot
            target, trial = 1 / (25 * rng.uniform(0.85, 1.15)), 0.03
            lever_only, with_trial = (1 / _peak(beam(k1, x))[1] for x in (0.0, trial))
            loss = min(trial * (target - lever_only) / (with_trial - lever_only), 0.1)     # stiff grains: Q above
        beams.append(beam(k1, loss))
    losses = np.array([b.eta * 2 * math.pi * free / b.k1 for b in beams])
    # the contact resonance and its width, from the exact response's oscillator near the peak
    resonance, width = np.empty(grains), np.empty(grains)
    for g, b in enumerate(beams):
        resonance[g], q = _peak(b)
        width[g] = resonance[g] / q
    df = float(np.median(width) * rng.uniform(0.7, 1.5))
    d_abs = rng.uniform(2e-12, 20e-12)
    stripes = np.where((xx + yy // 2) // max(nx // 4, 1) % 2 == 0, 1.0, -1.0)
    d_eff = d_abs * stripes * rng.uniform(0.9, 1.1, grains)[grain]
    centre = resonance[grain] + width[grain] * rng.uniform(-0.3, 0.3, (ny, nx))
    f1, f2 = centre - df / 2, centre + df / 2
    s1, s2 = np.empty((ny, nx), complex), np.empty((ny, nx), complex)
    for g, beam in enumerate(beams):
        mask = grain == g
        both = beam.slope(np.concatenate([f1[mask], f2[mask]]))[:, 0] * (2 * L / 3)
        n = mask.sum()
        s1[mask], s2[mask] = both[:n], both[n:]
    s1, s2 = s1 * d_eff * drive_v, s2 * d_eff * drive_v
    exact = _sho_through(f1.ravel(), f2.ravel(), s1.ravel(), s2.ravel())
    # where no oscillator goes through the exact signals (an anti-resonance of the slope near the peak), the pole
    poles = np.array([_pole(beam) for beam in beams])
    off = ~(np.isfinite(exact[:, 1]) & (exact[:, 1] > 0))
    exact[off] = poles[grain.ravel()[off]]
    noisy = [s * (1 + sigma * (rng.standard_normal(s.shape) + 1j * rng.standard_normal(s.shape)) / math.sqrt(2))
             for s in (s1, s2)]
    channels = {"Amplitude1Retrace": np.abs(noisy[0]) * AMP_INVOLS / INVOLS,
                "Amplitude2Retrace": np.abs(noisy[1]) * AMP_INVOLS / INVOLS,
                "Phase1Retrace": -np.degrees(np.angle(noisy[0])), "Phase2Retrace": -np.degrees(np.angle(noisy[1])),
                "FrequencyRetrace": centre, "HeightRetrace": 1e-9 * rng.standard_normal((ny, nx))}
    lever = dict(spring_constant=k, free_resonance=free, length=L, tip_height=H, quality_factor=q_lever,
                 spot_position=spot, k2_over_k1=k2_over_k1)
    settings = dict(frequency_width=df, drive_amplitude=drive_v, noise=sigma)
    truth = dict(k1=np.array(k1s)[grain], contact_loss=losses[grain], d_eff=d_eff,
                 contact_resonance=exact[:, 0].reshape(ny, nx), contact_quality_factor=exact[:, 1].reshape(ny, nx))
    exact = dict(f1=f1, f2=f2, s1=s1, s2=s2, pole_resonance=poles[grain, 0], pole_quality_factor=poles[grain, 1])
    return DartCase(lever, settings, channels, truth, exact)


def write_ibw(case: DartCase, path, order=None) -> Path:
    """The case as Asylum's ``.ibw``: one wave (points, lines, layers) in ``order`` (default: the channels'),
    the note with the lever and DART's settings; ``y`` the lines (the wave's second dimension)."""
    order = list(case.channels) if order is None else order
    data = np.stack([case.channels[name].T for name in order], axis=-1).astype("f8")
    lever, settings = case.lever, case.settings
    note = asylum_note({"SpringConstant": repr(lever["spring_constant"]), "ThermalFrequency": repr(lever["free_resonance"]),
                        "ThermalQ": repr(lever["quality_factor"]), "CustomLeverLength": repr(lever["length"]),
                        "DFRTFrequencyWidth": repr(settings["frequency_width"]),
                        "DFRTFrequencyCenter": repr(float(np.median(case.channels["FrequencyRetrace"]))),
                        "DriveAmplitude": repr(settings["drive_amplitude"]), "InvOLS": repr(INVOLS),
                        "AmpInvOLS": repr(AMP_INVOLS), "ImagingMode": "DART PFM"})
    return igor_wave(Path(path), data, Path(path).stem, [(0.0, 1e-8, "m"), (0.0, 1e-8, "m")], "m", {2: order}, note)
