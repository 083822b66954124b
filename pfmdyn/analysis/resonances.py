"""Where a probe's resonances are: certified undamped free and contact modes, and with damping
each mode's Q, damped frequency and amplitude-peak frequency.

The model is the composed lever (:mod:`pfmdyn.composed`; certified in :mod:`pfmdyn.composed.balls`):
the tip at ``x_tip = tip_position L`` with its mass and rotary inertia, the contact springs
``k1`` (along the sample normal) and ``k2`` (along the surface) rotated into the lever's axes by
the tilt, the three damping mechanisms of ``derivations/damping.py``.

Frequency scale.  The measured first free resonance ``f1`` is that of the lever *with* its tip,
so the bare lever's scale follows from the first free root ``beta_1`` of the same model:
``f_n = f1 (beta_n / beta_1)**2`` for every root ``beta_n`` (free or in contact).

Proof.  The roots in ``beta`` are isolated and refined in ball arithmetic
(:func:`pfmdyn.derivations.certify.certify`) on ``characteristic_balls``, the generated
characteristic in a math namespace: the trivial zero at ``beta = 0`` is cleared with exact
rational series, every bracket holds exactly one simple zero, and the list is complete up to
the highest root reported (``*_complete_below_hz``).  The parameters enter exactly as the
floats given (``k1``, ``k2`` after the rotation by the tilt).  A proof that fails gives a
result with ``certified = False``, the reason, and no numbers.

Damping (``quality_factor``, ``viscous_loss``, ``contact_loss``).  Each mode's complex
frequency ``r_c = f_c / f1`` is the zero of the damped characteristic (the generated damping
factors are analytic in ``r``), followed from the undamped root as the losses grow from zero
to the given ones in :data:`_STEPS` steps (:func:`pfmdyn.roots.damped.follow`, the one damped-root
engine, also the discrepancy's: a heavily damped mode's root lies far from the undamped one,
where a single run may land on another mode's root or on ``beta = 0``);
``Q = |r_c| / (2 Im r_c)``, the damped frequency is ``f1 Re r_c``.  A mode whose root cannot be
followed, or that is overdamped (the root reaches the imaginary axis: no oscillation), has no
Q, damped or peak frequency: NaN, with the reason in ``Modes.undetermined``.  The amplitude-peak frequency
is the maximum of the tip slope's magnitude near the mode for the drive an instrument uses:
the surface displacement ``d1`` in contact, a uniform load ``q0`` for free modes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from fractions import Fraction

import flint
import numpy as np

from ..cantilever import Cantilever, Contact
from .. import composed
from ..composed import balls as composed_balls
from ..generated import formulas
from ..generated.characteristic import FLINT
from ..derivations.certify import CertificationError, certify
from ..roots.damped import follow

__all__ = ["Modes", "ResonanceResult", "resonances", "contact_spread"]

_DIGITS = 15
"""Significant digits of each certified root in ``beta`` (the Hz values are floats)."""


@dataclass(frozen=True)
class Modes:
    """Resonances of one condition (free or in contact), in mode order.

    ``hz``: undamped resonances; ``intervals_hz``: certified enclosures; ``complete_below_hz``:
    no resonance was missed or counted twice below it.  With damping, ``q``, ``damped_hz`` and
    ``peak_hz`` per mode (else empty).
    """

    hz: tuple = ()
    intervals_hz: tuple = ()
    complete_below_hz: float = math.nan
    q: tuple = ()
    damped_hz: tuple = ()
    peak_hz: tuple = ()
    undetermined: tuple = ()
    """Per mode with damping: why its Q, damped and peak frequencies are NaN ('' when they are not)."""


@dataclass(frozen=True)
class ResonanceResult:
    """Resonances of a probe (:func:`resonances`); ``to_dict()`` is the JSON report."""

    lever: Cantilever
    contact: Contact | None
    free: Modes = field(default_factory=Modes)
    in_contact: Modes = field(default_factory=Modes)
    certified: bool = False
    reason: str = ""

    @property
    def damped(self) -> bool:
        """True when a damping mechanism was given (then Q, damped and peak frequencies exist)."""
        return _damped(self.lever, self.contact)

    def to_dict(self) -> dict:
        """Names -> values (Hz, SI): ``free_hz``, ``contact_hz`` and their proofs, the probe,
        with damping ``free_q``, ``free_damped_hz``, ``free_peak_hz`` (and ``contact_...``).

        >>> r = resonances(Cantilever(2.0, 7e4, 2e-4), Contact(k1=100.0), modes=2)
        >>> d = r.to_dict()
        >>> [round(f) for f in d["free_hz"]], [round(f) for f in d["contact_hz"]]
        ([70000, 438683], [277474, 696317])
        """
        out = {name: value for name, value in self.lever.to_dict().items()}
        if self.contact is not None:
            out.update(k1=self.contact.k1, k2=self.contact.k2_of(self.contact.k1),
                       contact_loss=self.contact.contact_loss)
        out["certified"] = self.certified
        if self.medium_note:
            out["medium_note"] = self.medium_note
        if not self.certified:
            out["reason"] = self.reason
            return out
        for prefix, modes in (("free", self.free), ("contact", self.in_contact)):
            out[f"{prefix}_hz"] = list(modes.hz)
            out[f"{prefix}_intervals_hz"] = [list(i) for i in modes.intervals_hz]
            out[f"{prefix}_complete_below_hz"] = modes.complete_below_hz if modes.hz else None
            if self.damped:
                # An undamped mode's Q is infinite: the JSON writer (pfmdyn.io.results) makes it null.
                out[f"{prefix}_q"] = list(modes.q)
                out[f"{prefix}_damped_hz"] = list(modes.damped_hz)
                out[f"{prefix}_peak_hz"] = list(modes.peak_hz)
                # null above is "undetermined": say why, per mode (None where determined).
                out[f"{prefix}_undetermined"] = [why or None for why in modes.undetermined]
        return out

    def report(self, contact_stderr=None) -> str:
        """A readable table of the modes; with ``contact_stderr`` (Hz, per contact mode: :func:`contact_spread`)
        each contact resonance beside its standard uncertainty over the inputs that were assumed.

        >>> print(resonances(Cantilever(2.0, 7e4, 2e-4), None, modes=2).report())
        mode  condition  resonance (Hz)
           1  free       70000.0
           2  free       438682.5
        certified: no resonance missed or counted twice below 445306.2 Hz (free)
        """
        if not self.certified:
            return f"not certified: {self.reason}"
        damped = self.damped
        spread = contact_stderr is not None and any(u != 0 for u in contact_stderr)
        width = 24 if spread else 14
        head = f"mode  condition  {'resonance (Hz)':<{width}}" + ("   damped (Hz)      peak (Hz)        Q" if damped else "")
        lines = [head.rstrip()]
        for label, modes in (("free", self.free), ("contact", self.in_contact)):
            for i, f in enumerate(modes.hz):
                u = contact_stderr[i] if spread and label == "contact" else 0.0
                cell = f"{f:.1f}" + ("" if u == 0 else f" +- {u:.2g}" if math.isfinite(u) else " +- undetermined")
                row = f"{i + 1:4d}  {label:9s}  {cell:<{width}}"
                if damped:
                    values = (modes.damped_hz[i], modes.peak_hz[i])
                    row += "".join(f"   {v:<14.1f}" if math.isfinite(v) else f"   {'-':<14}" for v in values)
                    row += f"  {modes.q[i]:.4g}" if math.isfinite(modes.q[i]) else "  -"
                    row += f"  ({modes.undetermined[i]})" if modes.undetermined[i] else ""
                lines.append(row.rstrip())
        proof = [f"{m.complete_below_hz:.1f} Hz ({label})" for label, m in (("free", self.free),
                                                                           ("contact", self.in_contact)) if m.hz]
        lines.append("certified: no resonance missed or counted twice below " + " and ".join(proof))
        if self.medium_note:
            lines.append(self.medium_note)
        return "\n".join(lines)

    @property
    def medium_note(self) -> str | None:
        """What each frequency is in a medium (None in vacuum): the certified resonance is the undamped lever's in
        vacuum, the damped and peak frequencies the medium's."""
        if self.lever.medium is None:
            return None
        return (f"in {self.lever.medium.name}: 'resonance' is the undamped lever's in vacuum, the others are in the "
                "medium")


def _damped(lever: Cantilever, contact: Contact | None) -> bool:
    return (math.isfinite(lever.quality_factor) or lever.viscous_loss > 0 or lever.medium is not None
            or (contact is not None and contact.contact_loss > 0))


def _fmpq(value: float) -> flint.fmpq:
    q = Fraction(float(value))          # exact: the float given is the parameter proven for
    return flint.fmpq(q.numerator, q.denominator)


def _certified_roots(params: tuple, count: int) -> tuple[list, flint.arb]:
    """The first ``count`` roots in ``beta`` as certified balls, and the end of the complete range."""
    exact = [_fmpq(p) for p in params]
    balls = [flint.arb(p) for p in exact]

    def on_series(s):
        return composed_balls.characteristic_balls(s, FLINT, *balls)

    def on_exact(s):
        return composed_balls.characteristic_balls(s, FLINT, *exact)

    return certify(on_series, count, _DIGITS, f_exact=on_exact)


def resonances(lever: Cantilever, contact: Contact | None = None, modes: int = 3) -> ResonanceResult:
    """Certified free and contact resonances of ``lever`` (and ``contact``), first ``modes`` of each.

    Parameters
    ----------
    lever : the probe (:class:`pfmdyn.Cantilever`): ``free_resonance`` is the measured first free
        resonance with the tip; tip position, mass, gyration radius, tilt and losses as given.
    contact : :class:`pfmdyn.Contact` with ``k1`` (and ``k2`` or a policy; none: ``k2 = 0``), or
        None for free modes only.
    modes : number of modes of each condition.

    Returns
    -------
    ResonanceResult

    Examples
    --------
    >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, tip_mass_ratio=0.1,
    ...                    tip_gyration_radius=2.5e-6, tilt=12.0, quality_factor=200.0)
    >>> r = resonances(lever, Contact(k1=200.0, k2_over_k1=0.85), modes=2)
    >>> round(r.free.hz[0]), round(r.in_contact.hz[0]), round(r.in_contact.q[0])
    (70000, 355728, 247)
    """
    if modes < 1:
        raise ValueError("modes must be at least 1")
    if contact is not None and contact.k1 is None:
        contact = None
    old = flint.ctx.prec
    try:
        free_balls, free_top = _certified_roots(lever.model_parameters(None), modes)
        contact_balls, contact_top = (_certified_roots(lever.model_parameters(contact), modes)
                                      if contact is not None else ([], None))
    except CertificationError as exc:
        return ResonanceResult(lever, contact, reason=str(exc))
    finally:
        flint.ctx.prec = old
    f1 = flint.arb(_fmpq(lever.vacuum_resonance))      # the undamped modes are the lever's in vacuum
    beta1 = free_balls[0]

    def hz(ball):
        return formulas.frequency_from_beta(ball, f1, beta1)

    def condition(balls, top, where):
        values = [hz(b) for b in balls]
        mids = tuple(float(v.mid()) for v in values)
        out = Modes(mids, tuple((float(v.lower()), float(v.upper())) for v in values), float(hz(top).mid()))
        if not _damped(lever, contact):
            return out
        ratios = [float(formulas.frequency_from_beta(b, 1, beta1).mid()) for b in balls]      # f / f1
        return Modes(out.hz, out.intervals_hz, out.complete_below_hz, *_damped_modes(lever, where, ratios))

    return ResonanceResult(lever, contact, condition(free_balls, free_top, None),
                           condition(contact_balls, contact_top, contact) if contact is not None else Modes(),
                           certified=True)


def contact_spread(lever: Cantilever, contact: Contact, modes: int, variations: dict) -> tuple[list, dict]:
    """Standard uncertainty (Hz) of each of the first ``modes`` contact resonances over the inputs that were assumed:
    the certified (undamped) resonances with each input moved down and up by its standard uncertainty
    (``variations``: input -> ``((lever, contact), (lever, contact))``), half their difference, added in quadrature
    over the inputs; NaN where a proof fails.  Returns ``(stderr, shares)``, shares: input -> its part per mode.

    >>> lever = Cantilever(2.0, 7e4, 2e-4, tip_height=13e-6)
    >>> moved = {"tip_height_uncertainty": tuple((replace(lever, tip_height=h), Contact(k1=100.0, k2=80.0))
    ...                                          for h in (10.5e-6, 15.5e-6))}
    >>> stderr, shares = contact_spread(lever, Contact(k1=100.0, k2=80.0), 2, moved)
    >>> [round(u) for u in stderr], shares["tip_height_uncertainty"] == stderr
    ([1756, 523], True)
    """
    def undamped(lever, contact):       # the certified resonances alone, in contact (free mode 1 scales them)
        old = flint.ctx.prec
        try:
            beta1 = _certified_roots(lever.model_parameters(None), 1)[0][0]
            balls = _certified_roots(lever.model_parameters(contact), modes)[0]
        except CertificationError:
            return (math.nan,) * modes
        finally:
            flint.ctx.prec = old
        f1 = flint.arb(_fmpq(lever.vacuum_resonance))
        return [float(formulas.frequency_from_beta(ball, f1, beta1).mid()) for ball in balls]
    shares = {}
    for source, (down, up) in variations.items():
        shares[source] = [abs(b - a) / 2 for a, b in zip(undamped(*down), undamped(*up))]
    return [math.hypot(*column) for column in zip(*shares.values())] if shares else [0.0] * modes, shares


def _damped_characteristic(lever: Cantilever, contact: Contact | None, r, fluid: float = 1.0):
    """The damped characteristic at (complex) ``r = f / f1`` (``f1`` in vacuum; the probe's own damping
    substitution, :meth:`pfmdyn.Cantilever.model_arguments`, with ``fluid`` times a medium's load)."""
    return composed.characteristic(*lever.model_arguments(r * lever.vacuum_resonance, contact, fluid=fluid))


def _slope(lever: Cantilever, contact: Contact | None, r):
    """Slope per unit drive at real ``r``: ``d1`` in contact, ``q0`` when free (the probe's own
    damped response, :meth:`pfmdyn.Cantilever.response`)."""
    response = lever.response(np.asarray(r, dtype=float) * lever.vacuum_resonance, contact or Contact(k1=0.0))
    return response.vertical if contact is not None else response.distributed_load


_STEPS = 24
"""Steps of the losses from zero to the given ones along which each damped root is followed (a probe's
Q may be near critical: finer than the discrepancy fits')."""


def _followed_roots(lever: Cantilever, contact: Contact | None, r0: list) -> tuple[np.ndarray, list]:
    """The damped roots ``r_c`` continuing the undamped roots ``r0``, and per mode '' or why there is none."""
    inv_q, g = 1.0 / lever.quality_factor, lever.viscous_loss
    x = contact.contact_loss if contact is not None else 0.0

    def f(r, s):
        q = min(1.0 / (s * inv_q), 1e9) if inv_q else math.inf
        step_contact = replace(contact, contact_loss=s * x) if contact is not None else None
        # a medium's load grows with the other losses, from the vacuum's undamped roots
        return _damped_characteristic(replace(lever, quality_factor=q, viscous_loss=s * g), step_contact, r, s)

    out = follow(f, r0, _STEPS)
    why = ["overdamped: the mode does not oscillate (no resonance)" if over
           else "two modes lead to the same damped root" if shared else _lost(complex(last)) if np.isnan(rc) else ""
           for rc, last, over, shared in zip(out.roots, out.last, out.overdamped, out.shared)]
    return out.roots, why


def _lost(last: complex) -> str:
    """Why a followed root was lost, from the last one found (critical damping: Q = 1/2)."""
    if last.imag and abs(last) / (2 * abs(last.imag)) < 1.0:
        return f"overdamped or nearly: the root was lost at Q = {abs(last) / (2 * abs(last.imag)):.2g} (critical: 0.5)"
    return "the damped root could not be followed from the undamped mode"


def _damped_modes(lever: Cantilever, contact: Contact | None, r0: list) -> tuple[tuple, tuple, tuple, tuple]:
    """(Q, damped Hz, peak Hz, why undetermined) of the modes near the undamped roots ``r0``
    (NaN and the reason where a mode has none)."""
    f1 = lever.vacuum_resonance
    with np.errstate(all="ignore"):
        roots, why = _followed_roots(lever, contact, r0)
        roots = [complex(rc) for rc in roots]
        q = tuple(math.nan if w else abs(rc) / (2 * abs(rc.imag)) if rc.imag else math.inf
                  for rc, w in zip(roots, why))
        damped_hz = tuple(math.nan if w else f1 * rc.real for rc, w in zip(roots, why))
        peak = [math.nan if w else _peak(lever, contact, rc, rn) * f1 for rc, rn, w in zip(roots, r0, why)]
    # A heavily damped mode may have no amplitude maximum of its own: none in its window,
    # or the one maximum two overlapping modes share.
    shared = [any(j != i and abs(p - other) <= 1e-6 * p for j, other in enumerate(peak)) for i, p in enumerate(peak)]
    for i, p in enumerate(peak):
        if not why[i] and (not math.isfinite(p) or shared[i]):
            peak[i] = math.nan
            why[i] = "no amplitude peak of its own (too heavily damped); Q and damped frequency stand"
    return q, damped_hz, tuple(peak), tuple(why)


def _peak(lever: Cantilever, contact: Contact | None, rc: complex, rn: float) -> float:
    """``r`` of the slope magnitude's maximum near the mode (bounded search over half-widths);
    NaN when the window holds no maximum."""
    from scipy.optimize import minimize_scalar     # here: an undamped probe never needs it (0.4 s to import)

    centre, width = rc.real, max(abs(rc.imag), 1e-9 * rn)
    lo, hi = max(centre - 4 * width, 0.5 * centre), centre + 4 * width
    grid = np.linspace(lo, hi, 81)
    # exactly at an undamped mode's real root the response is singular (NaN): its peak
    magnitude = np.nan_to_num(np.abs(_slope(lever, contact, grid)), nan=np.inf)
    # The local maximum nearest the mode (a wide window of a damped mode may hold a neighbour's
    # higher peak); none inside the window: no peak of its own.
    inner = np.flatnonzero((magnitude[1:-1] >= magnitude[:-2]) & (magnitude[1:-1] >= magnitude[2:])) + 1
    if inner.size == 0:
        return math.nan
    i = int(inner[np.argmin(np.abs(grid[inner] - centre))])
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    best = minimize_scalar(lambda r: -abs(complex(_slope(lever, contact, np.array([r]))[0])), bounds=(a, b),
                           method="bounded", options={"xatol": 1e-13 * centre})
    return float(best.x)
