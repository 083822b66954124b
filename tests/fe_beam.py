"""Independent synthetic data: a finite-element Euler-Bernoulli cantilever (Hermite cubics).

Nothing here uses ``derivations/`` or ``generated/``: the beam is discretised into
``n_elements`` two-node elements with the textbook Hermite-cubic stiffness and consistent
mass matrices, clamped at node 0, and solved in the frequency domain,
``(K_beam (1 + i/Q) + K_tip + i omega (C + D) - omega**2 M) U = F``.  Three damping
mechanisms: internal friction (complex modulus of the beam, ``Q``), a viscous force per
unit length ``c u_t`` (``C = c M_beam / (rho S)``; ``viscous_hz = c / (2 pi rho S)`` is the
half-power width every mode shares), and a dashpot ``eta`` in parallel with ``k1`` at the
tip (``D``, rotated with ``k1`` by the tilt).  The tip node may sit inside the beam
(set-back), carry a rigid body (a lumped mass, and its moment of inertia
``J = m_tip r_g**2`` on the node's rotation), and hold a 2x2 spring tensor on ``(u, H u')``
(tilt); a uniform load uses the consistent load vector.  The tilt is given either as
pfmdyn's internal ``alpha`` (the rotation of :mod:`derivations.tilt`) or, independently,
as ``tilt_deg`` in the public convention (free end nearer the sample > 0), from which the
springs are built from the explicit geometry (:meth:`FEBeam.spring_tensor`).  The output is the slope at the last node,
or at a detection spot ``x_s = spot L`` inside the beam (the elements' Hermite shape functions).
Test data follow :func:`spectrum` and :func:`resonances`; :func:`random_case` draws a
cantilever, contact and hidden effects over realistic ranges.
"""
from __future__ import annotations

import dataclasses
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
    viscous_hz: float = 0.0
    eta: float = 0.0
    n_elements: int = 200
    air_exponent: float = 0.0
    """The viscous force's coefficient grows as ``(f / f1)**air_exponent``: 0 for a constant
    half-power width (viscous), 0.5 for air (the boundary layer thins as 1/sqrt(f)), so that
    ``viscous_hz`` is the width at f1."""
    gyration_radius: float = 0.0
    tilt_deg: float = 0.0
    spot: float = 1.0
    """Detection (laser) spot ``x_s / L`` where :meth:`slope` reads the beam (1: the free end)."""

    def spring_tensor(self, normal: float, tangential: float) -> tuple[float, float, float]:
        """``(kvv, kll, kvl)`` on the beam axes (v: beam normal, l: beam axis) of springs
        ``normal`` along the surface normal and ``tangential`` along the surface.

        With ``tilt_deg``, from the geometry: lab frame x along the surface (from the clamp's
        side to the tip's), y up from the sample; the beam axis, clamp to free end, points
        down towards the sample, ``e_l = (cos t, -sin t)``, and its normal ``e_v = (sin t,
        cos t)`` is the side facing away from the sample (``u > 0``); each spring is
        ``k n n^T`` with ``n`` its direction in beam components.  Else from ``alpha``.
        """
        if self.tilt_deg:
            t = math.radians(self.tilt_deg)
            e_l, e_v = np.array([math.cos(t), -math.sin(t)]), np.array([math.sin(t), math.cos(t)])
            K = np.zeros((2, 2))
            for stiffness, lab in ((normal, np.array([0.0, 1.0])), (tangential, np.array([1.0, 0.0]))):
                n = np.array([lab @ e_v, lab @ e_l])
                K += stiffness * np.outer(n, n)
            return K[0, 0], K[1, 1], K[0, 1]
        c, s_ = math.cos(self.alpha), math.sin(self.alpha)
        return (normal * c * c + tangential * s_ * s_, normal * s_ * s_ + tangential * c * c,
                (normal - tangential) * s_ * c)

    def _matrices(self, parts: bool = False):
        n, le = self.n_elements, self.L / self.n_elements
        EI = self.k * self.L**3 / 3
        rhoS = BETA1**4 * EI / ((2 * math.pi * self.f1) ** 2 * self.L**4)
        ke = EI / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                    [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
        me = rhoS * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                         [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
        size = 2 * (n + 1)
        K, M, q = np.zeros((size, size)), np.zeros((size, size)), np.zeros(size)
        T, D = np.zeros((size, size)), np.zeros((size, size))     # tip springs, tip dashpot
        for e in range(n):
            s = slice(2 * e, 2 * e + 4)
            K[s, s] += ke
            M[s, s] += me
            q[s] += le * np.array([0.5, le / 12, 0.5, -le / 12])
        tip = round(self.gamma * n)
        kvv, kll, kvl = self.spring_tensor(self.k1, self.k2)
        dvv, dll, dvl = self.spring_tensor(self.eta, 0.0)
        iu, it = 2 * tip, 2 * tip + 1
        C = M * (2 * math.pi * self.viscous_hz)        # c / (rho S) times the beam's mass matrix
        # Springs act on (u, H u'): K_spring = T^T Kt T with T = diag(1, H).
        for target, (vv, ll, vl) in ((T, (kvv, kll, kvl)), (D, (dvv, dll, dvl))):
            target[iu, iu] += vv
            target[iu, it] += vl * self.H
            target[it, iu] += vl * self.H
            target[it, it] += ll * self.H**2
        M[iu, iu] += self.mu * rhoS * self.L
        M[it, it] += self.mu * rhoS * self.L * self.gyration_radius**2     # J = m_tip r_g**2 on the rotation
        # Surface displacements d1 (along k1) and d2 (along k2) load through springs and dashpot:
        # per unit d the load is (spring + i omega dashpot) column; returned as two parts.
        loads = np.zeros((size, 4))
        loads[iu, 0], loads[it, 0] = kvv, kvl * self.H          # per unit d1
        loads[iu, 1], loads[it, 1] = kvl, kll * self.H          # per unit d2
        loads[iu, 2] = 1.0                                       # per unit f0
        loads[:, 3] = q                                          # per unit q0
        dash = np.zeros((size, 4))
        dash[iu, 0], dash[it, 0] = dvv, dvl * self.H
        dash[iu, 1], dash[it, 1] = dvl, dll * self.H
        # Rotations times L have the units of displacements: keeps the SI matrices well scaled.
        scale = np.tile([1.0, 1.0 / self.L], n + 1)
        sc = np.outer(scale, scale)
        keep = slice(2, size)                                    # clamp node 0
        out = [X * sc for X in (K, T, M, C, D)] + [loads * scale[:, None], dash * scale[:, None]]
        out = [X[keep, keep] if X.shape[1] == size else X[keep] for X in out]
        if parts:
            return out
        K, T, M, _, _, F, _ = out
        return K + T, M, F

    def slope(self, frequency_hz) -> np.ndarray:
        """Tip slope at L per unit (d1, d2, f0, q0): complex array of shape (n_freq, 4)."""
        Kb, T, M, C, D, F, Fd = self._matrices(parts=True)
        loss = 1 + 1j / self.Q if math.isfinite(self.Q) else 1.0
        K = Kb * loss + T
        out = np.empty((len(frequency_hz), 4), complex)
        # Hermite elements couple neighbouring nodes only: half-bandwidth 3 in banded storage.
        size = len(K)
        rows, cols = np.nonzero(np.abs(np.subtract.outer(np.arange(size), np.arange(size))) <= 3)

        def band(X):
            b = np.zeros((7, size), complex)
            b[3 + rows - cols, cols] = X[rows, cols]
            return b

        kb, mb, cb, db = band(K), band(M), band(C), band(D)
        for i, f in enumerate(np.asarray(frequency_hz, float)):
            w = 2 * math.pi * f
            ab = kb + 1j * w * (cb * (f / self.f1) ** self.air_exponent + db) - w**2 * mb
            out[i] = self._at_spot(scipy.linalg.solve_banded((3, 3), ab, F + 1j * w * Fd))
        return out

    def _at_spot(self, U) -> np.ndarray:
        """Slope at ``spot L`` of the solution ``U`` (clamp removed, rotations times L), from the
        derivatives of the Hermite shape functions of the element holding the spot (exact at a node)."""
        n, le = self.n_elements, self.L / self.n_elements
        nodes = np.concatenate([np.zeros((2,) + U.shape[1:], U.dtype), U])    # node 0: clamped
        e = min(int(math.floor(self.spot * n)), n - 1)
        xi = self.spot * n - e
        u0, r0, u1, r1 = nodes[2 * e], nodes[2 * e + 1] / self.L, nodes[2 * e + 2], nodes[2 * e + 3] / self.L
        return ((6 * xi * xi - 6 * xi) * (u0 - u1) / le + (1 - 4 * xi + 3 * xi * xi) * r0
                + (3 * xi * xi - 2 * xi) * r1)

    def free_resonances(self, count: int = 3) -> np.ndarray:
        """First ``count`` free flexural resonances (Hz) with the tip mass, no contact."""
        free = FEBeam(self.k, self.L, self.f1, self.H, mu=self.mu, gamma=self.gamma,
                      n_elements=self.n_elements, gyration_radius=self.gyration_radius)    # undamped: the resonances of the table
        K, M, _ = free._matrices()
        w2 = scipy.linalg.eigh(K, M, eigvals_only=True)[:count]
        return np.sqrt(w2) / (2 * math.pi)

    def contact_resonances(self, count: int = 2) -> np.ndarray:
        """First ``count`` resonances in contact (undamped), Hz."""
        K, M, _ = self._matrices()
        w2 = scipy.linalg.eigh(K, M, eigvals_only=True)[:count]
        return np.sqrt(w2) / (2 * math.pi)


def _metadata(beam: FEBeam, description: str) -> str:
    return (f"# spring_constant: {beam.k!r}\n# length: {beam.L!r}\n# width: 3e-05\n"
            f"# tip_height: {beam.H!r}\n# free_resonance: {float(beam.free_resonances(1)[0])!r}\n"
            f"# description: {description}\n")


def spectrum(beam: FEBeam, frequency_hz, biases=(-2.0, -1.0, 0.0, 1.0, 2.0), *, noise=0.01,
             background=0.0, polar=False, seed=0, order="frequency", gain_drift=0.0) -> str:
    """CSV text of a frequency-bias spectrum; ``noise`` relative to the median |response|.

    ``gain_drift``: the detector gain of each bias sweep is multiplied by ``1 + gain_drift z``
    (z standard normal, one per sweep): outside any model that fits one gain to all sweeps.

    ``order``: ``"frequency"`` (rows grouped by frequency), ``"instrument"`` (one sweep per
    bias, one after another) or ``"shuffled"``.

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
    if gain_drift:
        R = R * (1 + gain_drift * rng.standard_normal(len(biases)))[:, None]
    scale = np.median(np.abs(R))
    R = R + background * scale * (f / f.max()) * (1 + 0.5 * np.array(biases))[:, None] * np.exp(1.1j)
    R = R + noise * scale * (rng.standard_normal(R.shape) + 1j * rng.standard_normal(R.shape)) / math.sqrt(2)
    cols = "amplitude,phase_deg" if polar else "x,y"
    lines = []
    for j, fj in enumerate(f):
        for i, V in enumerate(biases):
            z = R[i, j]
            a, b = (abs(z), math.degrees(np.angle(z))) if polar else (z.real, z.imag)
            lines.append(f"{float(fj)!r},{float(V)!r},{float(a)!r},{float(b)!r}")
    if order == "instrument":
        lines = [lines[j * len(biases) + i] for i in range(len(biases)) for j in range(len(f))]
    elif order == "shuffled":
        lines = [lines[i] for i in rng.permutation(len(lines))]
    header = _metadata(beam, "FE synthetic spectrum") + f"frequency_hz,bias_v,{cols}"
    return "\n".join([header] + lines) + "\n"


def resonances(beam: FEBeam, n_free=3, n_contact=2) -> str:
    """CSV text of a resonances table (free and contact modes) from the FE eigenproblem."""
    lines = [_metadata(beam, "FE synthetic resonances") + "mode,condition,frequency_hz"]
    lines += [f"{i + 1},free,{float(v)!r}" for i, v in enumerate(beam.free_resonances(n_free))]
    lines += [f"{i + 1},contact,{float(v)!r}" for i, v in enumerate(beam.contact_resonances(n_contact))]
    return "\n".join(lines) + "\n"


EFFECTS = ("damping", "tip_mass", "tip_setback", "tilt", "background", "lateral_stiffness")
"""Hidden-effect classes of :func:`random_case` (the vocabulary of ``pfmdyn discrepancy``)."""


def silicon_lever(rng) -> tuple[float, float, float, float, float]:
    """``(k, L, w, H, f1)`` of a silicon lever drawn over everyday ranges: k 0.2-40 N/m (log-uniform),
    L 120-450 um, w 25-50 um, H 5-15 um; ``f1`` from the thickness that gives ``k``."""
    E, rho = 169e9, 2330.0
    k, L = 10 ** rng.uniform(math.log10(0.2), math.log10(40)), rng.uniform(120e-6, 450e-6)
    w, H = rng.uniform(25e-6, 50e-6), rng.uniform(5e-6, 15e-6)
    f1 = BETA1**2 / (2 * math.pi) * (4 * k * L**3 / (E * w)) ** (1 / 3) / L**2 * math.sqrt(E / 12 / rho)
    return k, L, w, H, f1


def random_beam(rng, hidden=(), n_elements: int = 120) -> tuple[FEBeam, dict, np.ndarray]:
    """A random silicon lever in contact with the ``hidden`` geometric effects and damping.

    k log-uniform 0.05-50 N/m, L 100-500 um, w 20-60 um (thickness from k, f1 from the
    geometry), H 3-20 um; k1/k log-uniform 1-1e4 (redrawn until 2-4 contact modes lie
    below 25 f1), k2/k1 0-1.5 (0.3-1.5 when ``lateral_stiffness`` is hidden, which is meant
    to be analysed ``--vertical-only``).  Damping picks one mechanism at random: internal
    (Q 20-300), viscous (free mode-1 Q 5-100) or a contact dashpot (first contact mode
    Q about 20-300).  Returns the beam, the truth and its first six contact resonances.
    """
    E, rho = 169e9, 2330.0
    while True:
        k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
        L, w, H = rng.uniform(100e-6, 500e-6), rng.uniform(20e-6, 60e-6), rng.uniform(3e-6, 20e-6)
        t = (4 * k * L**3 / (E * w)) ** (1 / 3)
        f1 = BETA1**2 / (2 * math.pi) * t / L**2 * math.sqrt(E / 12 / rho)
        k1 = k * 10 ** rng.uniform(0, 4)
        k2 = k1 * rng.uniform(0.3 if "lateral_stiffness" in hidden else 0.0, 1.5)
        truth = {"k": k, "L": L, "width": w, "H": H, "f1": f1, "k1": k1, "k2": k2}
        if "tip_mass" in hidden:
            truth["mu"] = rng.uniform(0.1, 0.5)
        if "tip_setback" in hidden:
            truth["gamma"] = rng.uniform(0.8, 0.95)
        if "tilt" in hidden:
            truth["alpha"] = rng.choice([-1, 1]) * rng.uniform(0.15, 0.4)
        beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, n_elements=n_elements,
                      **{p: truth[p] for p in ("mu", "gamma", "alpha") if p in truth})
        contact = beam.contact_resonances(6)
        truth["contact_modes"] = int(rng.integers(2, 5))
        if contact[truth["contact_modes"] - 1] < 25 * f1:
            break
    if "damping" in hidden:
        mechanism = str(rng.choice(["internal", "viscous", "contact"]))
        truth["damping_mechanism"] = mechanism
        if mechanism == "internal":
            truth["Q"] = 10 ** rng.uniform(math.log10(20), math.log10(300))
        elif mechanism == "viscous":
            truth["viscous_hz"] = f1 / 10 ** rng.uniform(math.log10(5), math.log10(100))
        else:
            # A dashpot eta alone damps contact mode 1 to about Q = k1 / (omega eta) times the
            # share of the modal energy in k1; aim at Q 20-300 for the mode.
            truth["eta"] = k1 / (2 * math.pi * contact[0] * 10 ** rng.uniform(math.log10(20), math.log10(300)))
        beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, n_elements=n_elements,
                      **{p: truth[p] for p in ("mu", "gamma", "alpha", "Q", "viscous_hz", "eta") if p in truth})
    return beam, truth, contact


def random_probe(rng, n_elements: int = 100, tilt_deg=(5.0, 15.0), mass_ratio=(0.05, 0.5)) -> tuple[FEBeam, dict]:
    """A random probe in contact over the real ranges, as the FE lever and the public description.

    k 0.05-50 N/m, L 100-500 um, H 3-20 um, k1/k 1-1e4, k2 = 0.85 k1, tip at a node in
    0.85-1 L with a tip mass ratio in ``mass_ratio`` and radius of gyration H/4 times 0.5-2,
    tilt (public sign, explicit geometry) in ``tilt_deg``.  The description uses the public
    names (``spring_constant``, ``free_resonance`` as measured: the FE's first free mode with
    its tip, ..., ``k1``, ``k2``).
    """
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    L, H = rng.uniform(100e-6, 500e-6), rng.uniform(3e-6, 20e-6)
    k1 = k * 10 ** rng.uniform(0, 4)
    gamma = int(rng.integers(int(0.85 * n_elements), n_elements + 1)) / n_elements
    mu, r_g, tilt = rng.uniform(*mass_ratio), rng.uniform(0.5, 2.0) * H / 4, rng.uniform(*tilt_deg)
    fe = FEBeam(k, L, 1e5, H, k1=k1, k2=0.85 * k1, mu=mu, gamma=gamma, gyration_radius=r_g, tilt_deg=tilt,
                n_elements=n_elements)
    return fe, dict(spring_constant=k, free_resonance=float(fe.free_resonances(1)[0]), length=L, tip_height=H,
                    tip_position=gamma, tip_mass_ratio=mu, tip_gyration_radius=r_g, tilt=tilt, k1=k1, k2=0.85 * k1)


def random_case(seed: int, hidden=(), n_freq: int = 1000, order: str = "instrument",
                n_elements: int = 120) -> tuple[str, dict]:
    """A random spectrum (:func:`random_beam`) with the ``hidden`` effects: CSV text and the truth.

    The band covers the 2-4 drawn contact modes, 3-7 biases, noise 0.3-2 % of the median
    |response|, x/y or polar columns at random, rows in ``order``.
    """
    rng = np.random.default_rng(seed)
    beam, truth, contact = random_beam(rng, hidden, n_elements)
    n_modes = truth["contact_modes"]
    lo, hi = 0.5 * contact[0], min(0.5 * (contact[n_modes - 1] + contact[n_modes]), 1.15 * contact[n_modes - 1])
    n_bias = int(rng.integers(3, 8))
    biases = tuple(np.round(np.linspace(-3, 3, n_bias), 3))
    noise = 10 ** rng.uniform(math.log10(0.003), math.log10(0.02))
    truth.update(band_hz=(lo, hi), biases=n_bias, noise=noise)
    background = rng.uniform(0.05, 0.3) if "background" in hidden else 0.0
    text = spectrum(beam, np.linspace(lo, hi, n_freq), biases, noise=noise, background=background,
                    polar=bool(rng.integers(2)), seed=seed, order=order)
    return text.replace("# width: 3e-05", f"# width: {truth['width']!r}"), truth


def random_table(seed: int, hidden=(), relative_uncertainty: float = 1e-4, n_elements: int = 120) -> tuple[str, dict]:
    """A random resonance table: 3 free and 2-4 contact modes with Gaussian noise of
    ``relative_uncertainty`` (declared as ``frequency_uncertainty_hz`` from mode 1), shuffled rows."""
    rng = np.random.default_rng(seed)
    beam, truth, _ = random_beam(rng, tuple(h for h in hidden if h != "damping"), n_elements)
    free = beam.free_resonances(3)
    contact = beam.contact_resonances(truth["contact_modes"])
    sigma = float(relative_uncertainty * free[0])
    rows = [f"{i + 1},free,{float(v + sigma * rng.standard_normal())!r}" for i, v in enumerate(free)]
    rows += [f"{i + 1},contact,{float(v + sigma * rng.standard_normal())!r}" for i, v in enumerate(contact)]
    rows = [rows[i] for i in rng.permutation(len(rows))]
    head = _metadata(beam, "FE synthetic resonances").replace("# width: 3e-05", f"# width: {truth['width']!r}")
    return head + f"# frequency_uncertainty_hz: {sigma!r}\nmode,condition,frequency_hz\n" + "\n".join(rows) + "\n", truth


ACQUISITION = ("band_viscous", "band_air", "band_air_setback", "gain_drift", "large_setback")
"""Classes of :func:`acquisition_case`: how real instruments record (band excitation, DFRT)."""

SPOT = ("band_spot", "spot")
"""Classes of :func:`acquisition_case` read at a laser spot 0.6-0.95 L from the clamp."""
ACQUISITION += SPOT


def noise_truth(text: str, noise: float) -> float:
    """The RMS complex noise :func:`spectrum` added (``noise`` times the median |response|
    before noise), from the CSV text and the same relative ``noise``: the truth a noise
    estimate is checked against."""
    rows = np.array([[float(c) for c in line.split(",")] for line in text.splitlines()
                     if line and not line.startswith("#") and not line[0].isalpha()])
    z = rows[:, 2] + 1j * rows[:, 3]
    # The noise barely moves the median of |R| (it is 0.3-2 % of it).
    return float(noise * np.median(np.abs(z)))


def acquisition_case(seed: int, kind: str, n_elements: int = 80, *, spot: float | None = None) -> tuple[str, dict]:
    """A spectrum recorded as instruments do, of class ``kind`` (:data:`ACQUISITION`):

    * ``band_viscous``: 2-4 bands of 64-256 bins around the contact resonances, viscous
      damping of constant width (hidden: damping);
    * ``band_air``: the same bands, air damping, width ~ sqrt(f) (hidden: damping);
    * ``band_air_setback``: and the tip 0.80-0.95 L from the clamp (hidden: damping, tip_setback);
    * ``gain_drift``: a full sweep with air damping and a gain that drifts by 0.2-0.5 %
      between bias sweeps (hidden: damping; the drift is outside the library);
    * ``large_setback``: a soft (k 0.3-0.8 N/m, L 130-190 um) or stiff (k 5-40 N/m, L
      200-450 um) lever, tip at 0.70-0.97 L, viscous damping, three biases, noise 1-2 %,
      full sweep in instrument order (hidden: damping, tip_setback);
    * ``band_spot``, ``spot``: the bands, or a full sweep, read at a laser spot drawn in
      0.6-0.95 L (or ``spot``: 1 reads the free end of the same lever), viscous damping (air
      damping on odd seeds) (hidden: damping, spot_position).

    Returns the CSV text and the truth (``hidden``: the effect names; ``noise_sigma``: the
    RMS complex noise added; ``spot``: x_s / L).
    """
    rng = np.random.default_rng(seed)
    E, rho = 169e9, 2330.0
    gamma = 1.0
    if kind == "large_setback":
        soft = bool(seed % 2 == 0)
        k = rng.uniform(0.3, 0.8) if soft else 10 ** rng.uniform(math.log10(5), math.log10(40))
        L = rng.uniform(130e-6, 190e-6) if soft else rng.uniform(200e-6, 450e-6)
        gamma = rng.uniform(0.70, 0.97)
    else:
        k, L = 10 ** rng.uniform(math.log10(0.2), math.log10(40)), rng.uniform(120e-6, 450e-6)
        if kind == "band_air_setback":
            gamma = rng.uniform(0.80, 0.95)
    w, H = rng.uniform(25e-6, 50e-6), rng.uniform(5e-6, 15e-6)
    t = (4 * k * L**3 / (E * w)) ** (1 / 3)
    f1 = BETA1**2 / (2 * math.pi) * t / L**2 * math.sqrt(E / 12 / rho)
    n_modes = 3 if kind == "large_setback" else int(rng.integers(2, 5))
    for attempt in range(60):
        k1 = k * 10 ** rng.uniform(1, 3)
        k2 = k1 * rng.uniform(0.5, 1.0)
        beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, gamma=gamma, n_elements=n_elements)
        contact = beam.contact_resonances(n_modes + 1)
        if contact[n_modes - 1] < 25 * f1:
            break
        if attempt % 20 == 19:
            n_modes = max(n_modes - 1, 2)       # a set-back tip lifts the higher contact modes
    air = kind in ("band_air", "band_air_setback", "gain_drift")
    q1 = 10 ** rng.uniform(math.log10(10), math.log10(60))         # free mode-1 Q
    beam = FEBeam(k, L, f1, H, k1=k1, k2=k2, gamma=gamma, n_elements=n_elements, viscous_hz=f1 / q1,
                  air_exponent=0.5 if air else 0.0)
    hidden = ["damping"] + (["tip_setback"] if gamma < 1 else [])
    if kind in SPOT:
        # The laser spot where users put it; it moves no resonance (the bands stay).
        drawn = float(rng.uniform(0.6, 0.95))
        beam = dataclasses.replace(beam, spot=drawn if spot is None else spot,
                                   air_exponent=0.5 if seed % 2 else 0.0)
        hidden += ["spot_position"] if beam.spot < 1 else []
    if kind == "large_setback":
        biases, noise = (-2.0, 0.0, 2.0), rng.uniform(0.01, 0.02)
    else:
        biases, noise = tuple(np.round(np.linspace(-3, 3, int(rng.integers(3, 6))), 3)), rng.uniform(0.003, 0.015)
    if kind.startswith("band"):
        bands = []
        for fc in contact[:n_modes]:
            # A band excitation window: a few half-power widths each side, 64-256 bins.
            width = beam.viscous_hz * (fc / f1) ** beam.air_exponent
            half = max(4 * width, 0.02 * fc)
            bands.append(np.linspace(fc - half, fc + half, int(rng.integers(64, 257))))
        freq = np.unique(np.concatenate(bands))
    else:
        lo, hi = 0.5 * contact[0], min(0.5 * (contact[n_modes - 1] + contact[n_modes]), 1.15 * contact[n_modes - 1])
        freq = np.linspace(lo, hi, 1000)
    drift = float(rng.uniform(0.002, 0.005)) if kind == "gain_drift" else 0.0
    text = spectrum(beam, freq, biases, noise=noise, seed=seed, order="instrument", gain_drift=drift)
    truth = {"kind": kind, "hidden": sorted(hidden), "k": k, "L": L, "H": H, "f1": f1, "k1": k1, "k2": k2,
             "gamma": gamma, "q1": q1, "noise": noise, "gain_drift": drift, "biases": len(biases),
             "rows": len(freq) * len(biases), "contact_hz": [float(c) for c in contact[:n_modes]]}
    truth["noise_sigma"] = noise_truth(text, noise)
    truth["spot"] = beam.spot
    return text, truth
