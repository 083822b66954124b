"""Independent resonance tables with Q values: complex eigenvalues of the finite-element beam.

Nothing here uses ``derivations/`` or ``generated/``.  The damped modes of
:class:`fe_beam.FEBeam` solve the quadratic eigenproblem ``(K + lambda (C + D) + lambda**2 M) u
= 0`` (``K`` complex with internal friction), linearised to a generalised eigenproblem of
twice the size; ``lambda = i omega`` and ``Q = |lambda| / (2 |Re lambda|)``, the damped
oscillator's definition (half-power width ``f / Q``).  Frequencies in the table are the
undamped ones, as in :func:`fe_beam.random_table`.
"""
from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.linalg

# Test support next to fe_beam.py: importable however pytest collects this file.
sys.path.insert(0, str(Path(__file__).resolve().parent))
from fe_beam import _metadata, random_beam  # noqa: E402


def quality_factors(beam, count: int, contact: bool) -> np.ndarray:
    """Q of the first ``count`` damped modes of ``beam`` (free: springs and dashpot removed)."""
    if not contact:
        beam = replace(beam, k1=0.0, k2=0.0, eta=0.0)
    K, T, M, C, D, _, _ = beam._matrices(parts=True)
    loss = 1 + 1j / beam.Q if math.isfinite(beam.Q) else 1.0
    K = K * loss + T
    n = len(K)
    eye, zero = np.eye(n), np.zeros((n, n))
    a = np.block([[zero, eye], [-K, -(C + D)]])
    b = np.block([[eye, zero], [zero, M]])
    lam = scipy.linalg.eigvals(a, b)
    lam = lam[np.isfinite(lam) & (lam.imag > 0)]
    lam = lam[np.argsort(lam.imag)][:count]
    with np.errstate(divide="ignore"):
        return np.abs(lam) / (2 * np.abs(lam.real))


MECHANISMS = ("internal", "viscous", "contact")


def damped_table(seed: int, mechanism: str, hidden=(), relative_uncertainty: float = 1e-4,
                 q_noise: float = 0.0, n_elements: int = 60, columns: str = "plain") -> tuple[str, dict]:
    """A random table (:func:`fe_beam.random_beam`): 3 free and 2-4 contact modes, each with
    its Q from one damping ``mechanism`` (blank where the mode is undamped, e.g. free modes
    under a contact dashpot), shuffled rows; ``q_noise`` relative Gaussian noise on Q.

    ``columns``: ``"plain"`` (mode, condition, frequency_hz, quality_factor) or ``"other"``
    (reordered, frequency in kHz, Q named ``Q``, plus nothing else).
    """
    rng = np.random.default_rng(seed)
    beam, truth, _ = random_beam(rng, tuple(h for h in hidden if h != "damping"), n_elements)
    if mechanism == "internal":
        truth["Q"] = 10 ** rng.uniform(math.log10(20), math.log10(300))
        beam = replace(beam, Q=truth["Q"])
    elif mechanism == "viscous":
        truth["viscous_hz"] = beam.f1 / 10 ** rng.uniform(math.log10(5), math.log10(100))
        beam = replace(beam, viscous_hz=truth["viscous_hz"])
    else:
        first = beam.contact_resonances(1)[0]
        truth["eta"] = beam.k1 / (2 * math.pi * first * 10 ** rng.uniform(math.log10(20), math.log10(300)))
        beam = replace(beam, eta=truth["eta"])
    truth["damping_mechanism"] = mechanism
    n_contact = truth["contact_modes"]
    sigma = float(relative_uncertainty * beam.free_resonances(1)[0])
    rows = []
    for contact, freqs in ((False, beam.free_resonances(3)), (True, beam.contact_resonances(n_contact))):
        qs = quality_factors(beam, len(freqs), contact)
        for i, (f, q) in enumerate(zip(freqs, qs)):
            q_text = "" if not q < 1e6 else repr(float(q * (1 + q_noise * rng.standard_normal())))
            f_noisy = float(f + sigma * rng.standard_normal())
            rows.append((i + 1, "contact" if contact else "free", f_noisy, q_text))
    rows = [rows[i] for i in rng.permutation(len(rows))]
    head = _metadata(beam, "FE damped resonances").replace("# width: 3e-05", f"# width: {truth['width']!r}")
    head += f"# frequency_uncertainty_hz: {sigma!r}\n"
    if q_noise:
        head += f"# quality_factor_uncertainty: {max(q_noise, 0.01)!r}\n"
    if columns == "plain":
        body = "mode,condition,frequency_hz,quality_factor\n" + "\n".join(
            f"{m},{c},{f!r},{q}" for m, c, f, q in rows)
    else:
        body = "Q,frequency_khz,condition,mode\n" + "\n".join(f"{q},{f / 1e3!r},{c},{m}" for m, c, f, q in rows)
    return head + body + "\n", truth
