"""Quality factors of the damped model's modes: complex roots of the damped characteristic.

A resonance table may give each mode's Q (an instrument's thermal or tune fit).  The model
predicts it from the damping substitution (:func:`pfmdyn.cantilever.damping_substitution`:
complex ``beta``, ``k``, ``k1`` and ``mu`` at ``r = f / f1``) put into the generated
characteristic (:func:`pfmdyn.composed.characteristic`).  That function of
``r`` is analytic, and its zero near each undamped root ``r_n`` is the damped mode
``r_c``; ``Q = |r_c| / (2 Im r_c)`` (the damped-oscillator definition: half-power width
``f_n / Q``).  No formula for Q is typed here: the three mechanisms give their own laws,

* internal friction: ``1/Q`` the modulus' loss for every free mode, less in contact (the
  springs store energy without loss);
* viscous drag: the same half-power width in Hz for every mode, so Q grows with ``f``;
* contact dashpot: free modes undamped, contact modes damped by ``k1``'s share of the
  modal energy times ``omega eta / k1``.

The damped characteristic takes complex ``r`` (the damping factors are analytic in it), and
its zeros are followed from the undamped roots as the losses grow by the one damped-root engine,
:func:`pfmdyn.roots.damped.follow`, the same as the probe's modes
(:mod:`pfmdyn.analysis.resonances`), to about ``1e-14`` in ``r``; a mode that has no damped root
(lost or overdamped) has no loss here (0).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .. import composed
from ..cantilever import damping_substitution
from ..generated import formulas
from ..generated.tilt_rotation import rotated
from ..roots.damped import follow
from .effects import drag
from .model import Model, free_root

__all__ = ["damped_roots", "loss_factors", "loss_and_roots"]

_STEPS = 1
"""Loss steps of the continuation: one, as a fit's modes are mostly lightly damped (a mode lost or
landing on another's root is followed again in finer steps by the engine)."""


def _characteristic(model: Model, internal, contact: bool):
    """The damped characteristic ``f(r, s)`` at complex ``r = f / f1`` (array of any shape), the
    losses scaled by ``s``."""
    c = model.coords(internal)
    m = model.meta
    b1 = free_root(m.spring_constant, m.tip_height, m.length, c["mu"], c["gamma"])

    def f(r, s):
        d = damping_substitution(r, formulas.beta_from_frequency(r, 1.0, b1), m.spring_constant, c["k1"], c["mu"],
                                 s * c["inv_q"], s * drag(c, r), s * c["x"])
        springs = rotated(d.k1, c["k2"], c["alpha"]) if contact else (0.0, 0.0, 0.0)
        return composed.characteristic(d.beta, model.lever_parameters(c, d, springs))
    return f


def damped_roots(model: Model, internal, contact: bool, r0, guess=None) -> np.ndarray:
    """Complex zeros ``r_c`` of the damped characteristic continuing the undamped roots ``r0``
    (NaN where a mode has none: lost or overdamped).

    ``guess``: roots of a nearby model (e.g. before a finite-difference step): one Newton run
    from them replaces the continuation.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> model = Model(meta, ("damping_viscous",))
    >>> rc = damped_roots(model, [-9.0, -9.0, 0.02], False, [1.0, 6.2669])
    >>> (np.abs(rc) / (2 * rc.imag)).round(1).tolist()     # same width: Q = r / 0.02
    [50.0, 313.3]
    """
    if guess is not None and not np.all(np.isfinite(guess)):
        guess = None
    return follow(_characteristic(model, internal, contact), r0, _STEPS, guess).roots


def loss_factors(model: Model, internal, contact: bool, frequency_hz) -> np.ndarray:
    """``1 / Q`` of the model's modes at the undamped resonances ``frequency_hz`` (0: no damping).

    >>> from pfmdyn.io.tables import Metadata
    >>> meta = Metadata(spring_constant=1.0, length=1e-4, width=3e-5, tip_height=1e-5, free_resonance=1e4)
    >>> loss = loss_factors(Model(meta, ("damping_internal",)), [-9.0, -9.0, 0.01], False, [1e4, 6.2669e4])
    >>> (1 / loss).round(2).tolist()
    [100.0, 100.0]
    """
    f = np.asarray(frequency_hz, float)
    if not model.damping_mechanisms or not len(f):
        return np.zeros(len(f))
    if not contact:
        # Free modes ignore the springs and the tilt: fits that vary only those reuse them.
        c = model.coords(internal)
        key = tuple(float(c[n]) for n in ("inv_q", "g", "x", "mu", "gamma"))
        return _free_loss(model.meta, key, tuple(f.tolist()))
    return _loss(model, internal, contact, f)


def _loss(model, internal, contact, f, guess=None):
    return loss_and_roots(model, internal, contact, f, guess)[0]


def loss_and_roots(model: Model, internal, contact: bool, frequency_hz, guess=None):
    """``1 / Q`` and the complex roots ``r_c`` (for ``guess`` of a nearby model), no cache."""
    f = np.asarray(frequency_hz, float)
    rc = damped_roots(model, internal, contact, f / model.meta.free_resonance, guess)
    loss = formulas.loss_factor_from_root(rc.real, np.abs(rc.imag))
    return np.where(np.isfinite(loss), loss, 0.0), rc


@lru_cache(maxsize=2048)
def _free_loss(meta, key, frequency_hz):
    q, g, x, mu, gamma = key
    model = Model(meta, ("damping_internal", "damping_viscous", "damping_contact", "tip_mass", "tip_setback"))
    out = _loss(model, [0.0, 0.0, q, g, x, mu, gamma], False, np.array(frequency_hz))
    out.flags.writeable = False
    return out
