"""Quality factors of the damped model's modes: complex roots of the damped characteristic.

A resonance table may give each mode's Q (an instrument's thermal or tune fit).  The model
predicts it from the generated damping substitution (:func:`pfmdyn.generated.damping.factors`:
complex ``beta``, ``k``, ``k1`` and ``mu`` at ``r = f / f1``) put into the generated
characteristic (:func:`pfmdyn.generated.tip_setback.characteristic`).  That function of
``r`` is analytic, and its zero near each undamped root ``r_n`` is the damped mode
``r_c``; ``Q = |r_c| / (2 Im r_c)`` (the damped-oscillator definition: half-power width
``f_n / Q``).  No formula for Q is typed here: the three mechanisms give their own laws,

* internal friction: ``1/Q`` the modulus' loss for every free mode, less in contact (the
  springs store energy without loss);
* viscous drag: the same half-power width in Hz for every mode, so Q grows with ``f``;
* contact dashpot: free modes undamped, contact modes damped by ``k1``'s share of the
  modal energy times ``omega eta / k1``.

The damped characteristic takes real ``r`` only (the generated factors are real-frequency
transfer substitutions), so the complex zero is found from real samples: a polynomial
through samples around ``Re r_c`` (span ``1.5 Im r_c``, degree 5), re-centred three times.
Its accuracy is better than 0.1 % in Q down to Q = 5.
"""
from __future__ import annotations

import numpy as np

from ..generated import damping, tip_setback
from ..generated.tilt_rotation import rotated
from .model import Model, free_root

__all__ = ["damped_roots", "loss_factors"]

_PASSES = ((1, 3), (5, 11), (5, 11))
"""(polynomial degree, samples) per pass of the complex-root search."""


def _characteristic(model: Model, internal, contact: bool, r):
    """The damped characteristic at real ``r = f / f1`` (array of any shape)."""
    c = model.coords(internal)
    m = model.meta
    b1 = free_root(m.k, m.H, m.L, c["mu"], c["gamma"])
    beta_f, k_f, k1_f, mu_f = damping.factors(r, c["Q"], c["Q_viscous"], c["contact_loss"])
    if contact:
        kvv, kll, kvl = rotated(c["k1"] * k1_f, c["k2"], c["alpha"])
    else:
        kvv = kll = kvl = 0.0
    return tip_setback.characteristic(b1 * np.sqrt(r) * beta_f, m.k * k_f, kvv, kll, kvl, m.H, m.L,
                                      c["mu"] * mu_f, c["gamma"])


def damped_roots(model: Model, internal, contact: bool, r0) -> np.ndarray:
    """Complex zeros ``r_c`` of the damped characteristic near the undamped roots ``r0``.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(k=1.0, H=1e-5, L=1e-4, f1=1e4)
    >>> model = Model(meta, ("damping_viscous",))
    >>> rc = damped_roots(model, [-9.0, -9.0, 0.02], False, [1.0, 6.2669])
    >>> (np.abs(rc) / (2 * rc.imag)).round(1).tolist()     # same width: Q = r / 0.02
    [50.0, 313.3]
    """
    r0 = np.atleast_1d(np.asarray(r0, float))
    centre = r0.astype(complex)
    span = 1e-3 * r0
    with np.errstate(all="ignore"):
        for degree, count in _PASSES:
            t = np.linspace(-1.0, 1.0, count)
            x = centre.real[:, None] + span[:, None] * t
            y = _characteristic(model, internal, contact, np.maximum(x, 1e-9))
            for i in range(len(r0)):
                if not np.all(np.isfinite(y[i])):
                    centre[i] = np.nan
                    continue
                # Scaling y keeps the fit well conditioned whatever the characteristic's size.
                z = np.roots(np.polyfit(t, y[i] / np.max(np.abs(y[i])), degree)) * span[i] + centre[i].real
                centre[i] = z[np.argmin(np.abs(z - centre[i]))] if len(z) else np.nan
            span = np.where(np.isfinite(centre), np.maximum(1.5 * np.abs(centre.imag), 1e-4 * r0), span)
    return centre


def loss_factors(model: Model, internal, contact: bool, frequency_hz) -> np.ndarray:
    """``1 / Q`` of the model's modes at the undamped resonances ``frequency_hz`` (0: no damping).

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(k=1.0, H=1e-5, L=1e-4, f1=1e4)
    >>> loss = loss_factors(Model(meta, ("damping_internal",)), [-9.0, -9.0, 0.01], False, [1e4, 6.2669e4])
    >>> (1 / loss).round(2).tolist()
    [100.0, 100.0]
    """
    f = np.asarray(frequency_hz, float)
    if not model.damping_mechanisms or not len(f):
        return np.zeros(len(f))
    rc = damped_roots(model, internal, contact, f / model.meta.f1)
    loss = 2 * np.abs(rc.imag) / np.abs(rc)
    return np.where(np.isfinite(loss), loss, 0.0)
