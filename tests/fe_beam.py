"""Independent synthetic data: a finite-element Euler-Bernoulli cantilever (Hermite cubics).

Nothing here uses ``derivations/`` or ``generated/``: the beam is discretised into
``n_elements`` two-node elements with the textbook Hermite-cubic stiffness and consistent
mass matrices, clamped at node 0, and solved in the frequency domain,
``(K / (1 - i/Q) - omega**2 M) U = F``; the complex modulus is the loss model of
:mod:`pfmdyn.cantilever` (``beta**4 -> beta**4 (1 - i/Q)``).  The tip node may sit inside
the beam (set-back), carry a lumped mass, and hold a 2x2 spring tensor on
``(u, H u')`` (tilt); a uniform load uses the consistent load vector.  The output is the
slope at the last node.  Test data follow :func:`spectrum` and :func:`resonances`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

BETA1 = 1.8751040687119611  # first root of 1 + cos cosh, for the free-resonance metadata only


@dataclass(frozen=True)
class FEBeam:
    """Cantilever of spring constant ``k`` (N/m), length ``L`` (m), free resonance ``f1`` (Hz,
    of the bare beam) and the tip-surface contact, with the hidden effects as fields."""

    k: float
    L: float
    f1: float
    H: float
    k1: float = 0.0
    k2: float = 0.0
    Q: float = math.inf
    mu: float = 0.0
    gamma: float = 1.0
    alpha: float = 0.0
    n_elements: int = 200

    def _matrices(self):
        n, le = self.n_elements, self.L / self.n_elements
        EI = self.k * self.L**3 / 3
        rhoS = BETA1**4 * EI / ((2 * math.pi * self.f1) ** 2 * self.L**4)
        ke = EI / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                    [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
        me = rhoS * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                         [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
        size = 2 * (n + 1)
        K, M, q = np.zeros((size, size)), np.zeros((size, size)), np.zeros(size)
        for e in range(n):
            s = slice(2 * e, 2 * e + 4)
            K[s, s] += ke
            M[s, s] += me
            q[s] += le * np.array([0.5, le / 12, 0.5, -le / 12])
        tip = round(self.gamma * n)
        c, s_ = math.cos(self.alpha), math.sin(self.alpha)
        kvv = self.k1 * c * c + self.k2 * s_ * s_
        kll = self.k1 * s_ * s_ + self.k2 * c * c
        kvl = (self.k1 - self.k2) * s_ * c
        iu, it = 2 * tip, 2 * tip + 1
        # Springs act on (u, H u'): K_spring = T^T Kt T with T = diag(1, H).
        K[iu, iu] += kvv
        K[iu, it] += kvl * self.H
        K[it, iu] += kvl * self.H
        K[it, it] += kll * self.H**2
        M[iu, iu] += self.mu * rhoS * self.L
        loads = np.zeros((size, 4))
        loads[iu, 0], loads[it, 0] = kvv, kvl * self.H          # per unit d1
        loads[iu, 1], loads[it, 1] = kvl, kll * self.H          # per unit d2
        loads[iu, 2] = 1.0                                       # per unit f0
        loads[:, 3] = q                                          # per unit q0
        # Rotations times L have the units of displacements: keeps the SI matrices well scaled.
        scale = np.tile([1.0, 1.0 / self.L], n + 1)
        K, M, loads = K * np.outer(scale, scale), M * np.outer(scale, scale), loads * scale[:, None]
        keep = slice(2, size)                                    # clamp node 0
        return K[keep, keep], M[keep, keep], loads[keep]

    def slope(self, frequency_hz) -> np.ndarray:
        """Tip slope at L per unit (d1, d2, f0, q0): complex array of shape (n_freq, 4)."""
        K, M, F = self._matrices()
        Kc = K / (1 - 1j / self.Q) if math.isfinite(self.Q) else K.astype(complex)
        out = np.empty((len(frequency_hz), 4), complex)
        # Hermite elements couple neighbouring nodes only: half-bandwidth 3 in banded storage.
        size = len(K)
        rows, cols = np.nonzero(np.abs(np.subtract.outer(np.arange(size), np.arange(size))) <= 3)
        kb = np.zeros((7, size), complex)
        mb = np.zeros((7, size))
        kb[3 + rows - cols, cols] = Kc[rows, cols]
        mb[3 + rows - cols, cols] = M[rows, cols]
        for i, f in enumerate(np.asarray(frequency_hz, float)):
            ab = kb - (2 * math.pi * f) ** 2 * mb
            out[i] = scipy.linalg.solve_banded((3, 3), ab, F)[-1] / self.L
        return out

    def free_resonances(self, count: int = 3) -> np.ndarray:
        """First ``count`` free flexural resonances (Hz) with the tip mass, no contact."""
        free = FEBeam(self.k, self.L, self.f1, self.H, mu=self.mu, gamma=self.gamma,
                      n_elements=self.n_elements)
        K, M, _ = free._matrices()
        w2 = scipy.linalg.eigh(K, M, eigvals_only=True)[:count]
        return np.sqrt(w2) / (2 * math.pi)

    def contact_resonances(self, count: int = 2) -> np.ndarray:
        """First ``count`` resonances in contact (undamped), Hz."""
        K, M, _ = self._matrices()
        w2 = scipy.linalg.eigh(K, M, eigvals_only=True)[:count]
        return np.sqrt(w2) / (2 * math.pi)


def _metadata(beam: FEBeam, description: str) -> str:
    return (f"# spring_constant_n_per_m: {beam.k!r}\n# length_m: {beam.L!r}\n# width_m: 3e-05\n"
            f"# tip_height_m: {beam.H!r}\n# free_resonance_hz: {float(beam.free_resonances(1)[0])!r}\n"
            f"# description: {description}\n")


def spectrum(beam: FEBeam, frequency_hz, biases=(-2.0, -1.0, 0.0, 1.0, 2.0), *, noise=0.01,
             background=0.0, polar=False, seed=0) -> str:
    """CSV text of a frequency-bias spectrum; ``noise`` relative to the median |response|.

    Drives: d1 = 1 pm, d2 = 0.3 pm, f0 = 2 nN (V - 0.3), q0 = 0.5 nN/m... (V - 0.3) per
    volt, read through the complex gain 1e6 exp(0.4 i); ``background`` adds cross-talk
    ``background * median|R| * (f / f_max) (1 + 0.5 V) e^{1.1 i}``.
    """
    f = np.asarray(frequency_hz, float)
    T = beam.slope(f)
    rng = np.random.default_rng(seed)
    gain = 1e6 * np.exp(0.4j)
    rows = []
    for V in biases:
        drive = np.array([1e-12, 0.3e-12, 2e-9 * (V - 0.3), 0.5e-6 * (V - 0.3)])
        rows.append(gain * T @ drive)
    R = np.array(rows)                                      # (bias, freq)
    scale = np.median(np.abs(R))
    R = R + background * scale * (f / f.max()) * (1 + 0.5 * np.array(biases))[:, None] * np.exp(1.1j)
    R = R + noise * scale * (rng.standard_normal(R.shape) + 1j * rng.standard_normal(R.shape)) / math.sqrt(2)
    cols = "amplitude,phase_deg" if polar else "x,y"
    lines = [_metadata(beam, "FE synthetic spectrum") + f"frequency_hz,bias_v,{cols}"]
    for j, fj in enumerate(f):
        for i, V in enumerate(biases):
            z = R[i, j]
            a, b = (abs(z), math.degrees(np.angle(z))) if polar else (z.real, z.imag)
            lines.append(f"{float(fj)!r},{float(V)!r},{float(a)!r},{float(b)!r}")
    return "\n".join(lines) + "\n"


def resonances(beam: FEBeam, n_free=3, n_contact=2) -> str:
    """CSV text of a resonances table (free and contact modes) from the FE eigenproblem."""
    lines = [_metadata(beam, "FE synthetic resonances") + "mode,condition,frequency_hz"]
    lines += [f"{i + 1},free,{float(v)!r}" for i, v in enumerate(beam.free_resonances(n_free))]
    lines += [f"{i + 1},contact,{float(v)!r}" for i, v in enumerate(beam.contact_resonances(n_contact))]
    return "\n".join(lines) + "\n"
