"""Model composition for ``pfmdyn discrepancy``: the paper's baseline plus named effects.

The baseline is Eq. 5 as printed: undamped, tip at the free end, massless tip, springs
``k1``, ``k2`` at tip height ``H``.  The measured response at frequency ``f`` and bias
``V`` is ``G theta``, with ``d1``, ``d2`` bias-independent and ``f0``, ``q0`` both
proportional to ``V - V_surf``.  ``G`` and the drives enter only as products, so the
model is linear in the complex coefficients of the columns::

    T_d1, T_d2, T_q, V T_f, V T_q        (T_x = tip slope per unit x)

(``T_d1 = k1 T_f`` without a contact dashpot, so ``T_d1`` also carries the constant part
of ``f0``; with the dashpot ``T_f`` is a sixth column), solved by linear least squares
inside the nonlinear fit of the other parameters (variable projection).  The effects
(:mod:`pfmdyn.discrepancy.effects`) share the composed lever
(:mod:`pfmdyn.composed`, Eq. 5 at ``gamma = 1``, ``mu = 0``, no tilt), so they
compose; damping enters as the generated substitution (:func:`pfmdyn.cantilever.damping_substitution`:
complex ``beta``, ``k`` and ``k1``), tilt as the rotation of the spring tensor
(:mod:`pfmdyn.derivations.tilt`), background as two linear columns
``(b0 + b1 V) f / f_max``, and the laser spot (``spot_position``) by reading the same
lever at ``x_s = spot_position L`` instead of the free end (a :class:`pfmdyn.composed.Reading`).

The solver's Jacobian comes from the derivations too: the partials of the slopes
(:func:`pfmdyn.composed.slope_and_jacobian`, from the same assembled system), of the damping substitution and
of the rotation, composed by the chain rule (:meth:`Model.slopes_and_jacobian`), enter the
variable-projection Jacobian (:data:`JACOBIAN`).  The model's undamped resonances are
:mod:`pfmdyn.discrepancy.undamped_modes`'s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
from scipy.optimize import least_squares

from ..cantilever import damping_substitution, free_root
from ..fitting import trust_region
from ..fitting.noise import gap
from ..fitting.parameters import LN10, Parameter
from ..fitting.projection import CUTOFF, bias_nodes, jacobian_covariance, project
from .. import composed
from ..generated import formulas
from ..generated.tilt_rotation import rotated, rotated_jacobian
from .effects import BASE_COLUMNS, EFFECTS, RAMP, Chain, Effect, drag, public_name, spring_parameters

__all__ = ["Model", "FitResult", "fit", "free_root", "free_root_and_jacobian", "characteristic_partials"]

@dataclass(frozen=True)
class Model:
    """Baseline (with or without ``k2``) plus an ordered tuple of effect components."""

    meta: object
    effects: tuple[str, ...] = ()
    vertical_only: bool = False

    @cached_property
    def components(self) -> tuple[Effect, ...]:
        """The effect components, in the model's order."""
        return tuple(EFFECTS[e] for e in self.effects)

    @cached_property
    def springs(self) -> tuple[Parameter, ...]:
        """``k1`` and, unless held at 0 (``vertical_only`` without an effect that frees it), ``k2``."""
        held = self.vertical_only and not any(e.frees_lateral_spring for e in self.components)
        return spring_parameters(self.meta, held)

    @cached_property
    def parameters(self) -> tuple[Parameter, ...]:
        """Nonlinear parameters in order: the springs, then each effect's."""
        return self.springs + tuple(p for e in self.components for p in e.parameters)

    @cached_property
    def _absent(self) -> dict[str, float]:
        """Coordinates (:meth:`coords`) of every parameter of the library at its null value."""
        every = spring_parameters(self.meta, False) + tuple(p for e in EFFECTS.values() for p in e.parameters)
        return {p.name: _coordinate(p, p.null) for p in every if p.null is not None}

    @cached_property
    def columns(self) -> tuple[tuple[int, bool], ...]:
        """The design columns as ``(source, per volt)`` (:data:`pfmdyn.discrepancy.effects.BASE_COLUMNS`), the
        components' in the library's order after the baseline's."""
        return BASE_COLUMNS + tuple(c for e in EFFECTS.values() if e.name in self.effects for c in e.columns)

    def with_effect(self, component: str) -> "Model":
        """This model plus one effect component."""
        return Model(self.meta, self.effects + (component,), self.vertical_only)

    @property
    def public_effects(self) -> list[str]:
        """Report names of the effects, in order, without repeats (damping once)."""
        return list(dict.fromkeys(public_name(e) for e in self.effects))

    @property
    def damping_mechanisms(self) -> list[str]:
        """Damping mechanisms present (``internal``, ``viscous``, ``contact``)."""
        return [e.split("_", 1)[1] for e in self.effects if e.startswith("damping_")]

    def coords(self, internal) -> dict[str, float]:
        """Internal coordinates by name (springs converted to N/m), null values for absent effects."""
        out = dict(self._absent)
        for p, v in zip(self.parameters, internal):
            out[p.name] = _coordinate(p, v)
        return out

    def values(self, internal) -> dict[str, float]:
        """Physical parameter values by name."""
        return {p.name: p.value(v) for p, v in zip(self.parameters, internal)}

    def slopes(self, frequency_hz, internal):
        """Slope per unit (d1, d2, f0, q0) at each frequency: 4 complex arrays (at the free
        end, or where a component reads it: the laser spot with the effect ``spot_position``)."""
        c = self.coords(internal)
        m = self.meta
        r = np.asarray(frequency_hz, dtype=float) / m.free_resonance
        b1 = free_root(m.spring_constant, m.tip_height, m.length, c["mu"], c["gamma"])
        with np.errstate(all="ignore"):
            d = damping_substitution(r, formulas.beta_from_frequency(r, 1.0, b1), m.spring_constant, c["k1"], c["mu"],
                                     c["inv_q"], drag(c, r), c["x"])
            lever = self.lever_parameters(c, d, rotated(d.k1, c["k2"], c["alpha"]))
            return self._reading(c).slope(d.beta, lever)

    def slopes_and_jacobian(self, frequency_hz, internal):
        """:meth:`slopes` and their derivatives w.r.t. the internal parameters.

        Returns ``(T, dT)``: ``T`` of shape (4, n), ``dT`` of shape (4, p, n).  The composed
        lever's partials (:func:`pfmdyn.composed.slope_and_jacobian`, read at the free end or,
        with the effect ``spot_position``, at the spot) are composed by
        the chain rule with the generated damping factors' derivatives
        (:func:`pfmdyn.generated.damping.d_factors_wrt`), the rotation's
        (:func:`pfmdyn.generated.tilt_rotation.rotated_jacobian`) and the free root's motion
        with ``mu`` and ``gamma`` (implicit differentiation of the generated characteristic).
        """
        c = self.coords(internal)
        m = self.meta
        r = np.asarray(frequency_hz, dtype=float) / m.free_resonance
        b1, d_b1 = free_root_and_jacobian(m.spring_constant, m.tip_height, m.length, c["mu"], c["gamma"])
        with np.errstate(all="ignore"):
            loss = (c["inv_q"], drag(c, r), c["x"])
            root_r = formulas.beta_from_frequency(r, 1.0, b1)
            d = damping_substitution(r, root_r, m.spring_constant, c["k1"], c["mu"], *loss)
            spring = d.k1
            rot = rotated_jacobian(spring, c["k2"], c["alpha"])
            reading = self._reading(c)
            lever = self.lever_parameters(c, d, rotated(spring, c["k2"], c["alpha"]))
            T, computed = reading.slopes_and_partials(d.beta, lever, wrt=self._partials_needed(c, reading))
            T = np.ascontiguousarray(T)
            # Partials not computed have a zero multiplier below.
            part = dict.fromkeys(reading.JACOBIAN_PARAMETERS, 0.0) | computed
            chain = Chain(part, rot, c, m, root_r, b1, d_b1, d.factors, r, loss, spring)
            # the springs' terms (log10 coordinates), then each component's
            terms = [chain.rotation(j) * (v * LN10) for j, v in enumerate((spring, c["k2"])[:len(self.springs)])]
            terms += [t for e in self.components for t in e.jacobian(chain)]
            out = np.zeros((4, len(self.parameters), len(r)), dtype=complex)
            for j, term in enumerate(terms):
                out[:, j] = term
        return T, out

    def lever_parameters(self, c, d, springs) -> composed.Parameters:
        """The composed lever's parameters at coordinates ``c`` (:meth:`coords`): the damped stiffness and
        mass of ``d`` (:func:`pfmdyn.cantilever.damping_substitution`), the contact ``springs``
        ``(kvv, kll, kvl)`` in the lever's axes, the probe's tip height and length, no rotary inertia.

        >>> from types import SimpleNamespace
        >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
        >>> model = Model(meta)
        >>> d = damping_substitution(1.0, 1.9, 1.0, 100.0, 0.0, 0.0, 0.0, 0.0)
        >>> p = model.lever_parameters(model.coords([2.0, 2.0]), d, (100.0, 100.0, 0.0))
        >>> complex(p.k), p.kvv, p.H, p.gamma       # undamped: k as it was (complex, the substitution's)
        ((1+0j), 100.0, 1e-05, 1.0)
        """
        m = self.meta
        return composed.Parameters(k=d.k, kvv=springs[0], kll=springs[1], kvl=springs[2], H=m.tip_height, L=m.length,
                                   mu=d.mu, gamma=c["gamma"], rho_g=0.0)

    def _reading(self, c) -> composed.Reading:
        """Where the model reads the slope: the free end (:data:`pfmdyn.composed.at_end`) unless a
        component reads elsewhere (the laser spot)."""
        for e in self.components:
            reading = e.reading(c)
            if reading is not None:
                return reading
        return composed.at_end

    def _partials_needed(self, c, reading=composed.at_end) -> tuple[str, ...]:
        """The partials of ``reading`` the chain rule uses at coordinates ``c`` (others multiply zero)."""
        need = {"kvv", "kll"} | ({"kvl"} if c["alpha"] != 0.0 else set())
        for e in self.components:
            need |= e.partials(c)
        return tuple(p for p in reading.JACOBIAN_PARAMETERS if p in need)

    @property
    def n_linear(self) -> int:
        """Number of complex linear coefficients."""
        return len(self.columns)

    def design(self, freq_unique, inverse, bias, internal) -> np.ndarray:
        """Complex design matrix (rows, columns) of the linear coefficients."""
        return self._columns(self.slopes(freq_unique, internal), freq_unique, inverse, bias)

    def design_and_partials(self, freq_unique, inverse, bias, internal) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`design` and the slopes' partials ``dT`` (:meth:`slopes_and_jacobian`) from one read-out:
        a least-squares fit asks for the Jacobian at most points where it evaluates the residual.

        >>> from types import SimpleNamespace
        >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
        >>> model, f, x = Model(meta, ("damping_internal",)), np.array([0.5e4, 2e4]), np.array([1.0, 0.5, 0.01])
        >>> A, dT = model.design_and_partials(f, np.arange(2), np.zeros(2), x)
        >>> bool(np.array_equal(A, model.design(f, np.arange(2), np.zeros(2), x))), dT.shape
        (True, (4, 3, 2))
        """
        T, dT = self.slopes_and_jacobian(freq_unique, internal)
        return self._columns(T, freq_unique, inverse, bias), dT

    def design_derivative_times(self, inverse, bias, dT, coef) -> np.ndarray:
        """``(d design / d internal_j) @ coef`` for every parameter ``j``: (rows, parameters).

        From the generated partials ``dT`` (:meth:`slopes_and_jacobian` at the unique
        frequencies), combined per unique frequency before expanding to rows (the background
        ramp does not depend on them).
        """
        parts = {False: 0.0, True: 0.0}         # the bias-independent and the per-volt part
        for (source, per_volt), c in zip(self.columns, coef):
            if source != RAMP:                  # the background's ramp does not move
                parts[per_volt] = parts[per_volt] + dT[source] * c
        fixed, per_volt = parts[False], parts[True]
        # gathered row-wise: the (rows, parameters) result contiguous, as the projection reads it
        return fixed.T[inverse] + bias[:, None] * per_volt.T[inverse]

    def _columns(self, slopes, freq_unique, inverse, bias):
        """Design columns from the slopes at the unique frequencies (order: see module)."""
        rows = tuple(t[inverse] for t in slopes) + (freq_unique[inverse] / freq_unique.max(),)
        return np.stack([bias * rows[source] if per_volt else rows[source] for source, per_volt in self.columns], axis=1)


def _coordinate(p: Parameter, internal) -> float:
    """The coordinate :meth:`Model.coords` gives a parameter: springs in N/m, others internal."""
    return 10.0**internal if p.log else float(internal)


@lru_cache(maxsize=4096)
def free_root_and_jacobian(k, H, L, mu, gamma) -> tuple[float, tuple[float, float]]:
    """:func:`pfmdyn.cantilever.free_root` and its derivatives w.r.t. ``(mu, gamma)`` (implicit
    differentiation).

    >>> b1, (d_mu, d_gamma) = free_root_and_jacobian(1.0, 1e-5, 1e-4, 0.0, 1.0)
    >>> round(b1, 6), d_mu < 0
    (1.875104, True)
    """
    b1 = free_root(k, H, L, mu, gamma)
    free = composed.Parameters(k=k, kvv=0.0, kll=0.0, kvl=0.0, H=H, L=L, mu=mu, gamma=gamma, rho_g=0.0)
    d_beta, d_mu, d_gamma = characteristic_partials(b1, free, ("beta", "mu", "gamma"))
    return b1, (-float(d_mu / d_beta), -float(d_gamma / d_beta))


def characteristic_partials(beta, parameters: composed.Parameters, wrt) -> np.ndarray:
    """Partials of :func:`pfmdyn.composed.characteristic` of an undamped lever (real ``parameters``)
    at real ``beta`` w.r.t. the names ``wrt`` (of :data:`pfmdyn.composed.JACOBIAN_PARAMETERS`),
    one row each.  The tip at the end and ``gamma`` fixed: :func:`pfmdyn.composed.characteristic_and_jacobian`
    (compiled, the product rule); otherwise compiled complex steps
    (:func:`pfmdyn.composed.kernels.characteristic_partials`, 100x the assembled system's adjugate, which
    is the reference with :data:`pfmdyn.composed.KERNELS` off: both agree to 1e-9).

    >>> lever = composed.Parameters(k=1.0, kvv=0.0, kll=0.0, kvl=0.0, H=1e-5, L=1e-4, mu=0.0, gamma=0.9, rho_g=0.0)
    >>> d_beta, d_mu = characteristic_partials(np.array([1.9]), lever, ("beta", "mu"))
    >>> composed.KERNELS = False
    >>> want = composed.characteristic_and_jacobian(np.array([1.9]), lever, wrt=("beta", "mu"))[1]
    >>> composed.KERNELS = True
    >>> bool(np.allclose([d_beta, d_mu], [want[0], want[5]], rtol=1e-10, atol=0))
    True
    """
    names = composed.JACOBIAN_PARAMETERS
    if composed.KERNELS and ("gamma" in wrt or parameters.gamma != 1.0):
        from ..composed.kernels import characteristic_partials as compiled

        beta = np.asarray(beta, float)
        at = np.array([-1 if p == "beta" else composed.PARAMETERS.index(p) for p in wrt], np.int64)
        out = np.empty((len(wrt), beta.size))
        compiled(beta.reshape(-1), np.array(parameters, float), at, out)
        return out.reshape((len(wrt),) + beta.shape)
    d = composed.characteristic_and_jacobian(beta, parameters, wrt=wrt)[1]
    return np.array([d[names.index(p)] for p in wrt])


@dataclass
class FitResult:
    """One fit: internal parameters, covariance, residuals (data units), noise, criteria.

    ``gap`` is the noise-normalised RMS residual (1 = fitted to the noise); ``bic`` the
    Bayesian information criterion, with the noise variance profiled out (spectra) or
    known (resonance tables).  ``fitted`` marks the parameters the data determine.
    """

    model: Model
    internal: np.ndarray
    covariance: np.ndarray
    residual: np.ndarray
    sigma: object
    k: int
    sigma_known: bool = False
    prediction: np.ndarray | None = None
    fitted: np.ndarray | None = None
    extra: dict = field(default_factory=dict)

    @property
    def chi2(self) -> float:
        """Sum of squared noise-normalised residuals (complex ones count twice, real + imag)."""
        return float(np.sum(np.abs(self.residual / self.sigma) ** 2))

    @property
    def n(self) -> int:
        """Number of real data values."""
        return (2 if np.iscomplexobj(self.residual) else 1) * len(self.residual)

    @property
    def gap(self) -> float:
        """``sqrt(mean |r / sigma|**2)``: 1 when the residual is noise (:func:`pfmdyn.fitting.noise.gap`)."""
        return float(gap(self.chi2, len(self.residual)))

    @property
    def bic(self) -> float:
        """``chi2 + k ln n`` (noise known) or ``n ln(RSS/n) + k ln n`` (noise profiled)."""
        if self.sigma_known:
            return self.chi2 + self.k * math.log(self.n)
        return self.n * math.log(max(self.chi2, 1e-300) / self.n) + self.k * math.log(self.n)

    def parameters(self) -> dict[str, dict]:
        """Physical values with 1-sigma uncertainties; undetermined ones have value None."""
        out, j = {}, 0
        fitted = self.fitted if self.fitted is not None else np.ones(len(self.internal), bool)
        for i, p in enumerate(self.model.parameters):
            if not fitted[i]:
                out[p.key] = {"value": None, "stderr": None, "unit": p.unit, "determined": False}
                continue
            sd = math.sqrt(max(self.covariance[j, j], 0.0)) if self.covariance.size else math.nan
            value, err = p.value(self.internal[i]), p.stderr(self.internal[i], sd)
            # A parameter whose uncertainty exceeds its value is not determined by these data.
            determined = bool(math.isfinite(err) and (err < abs(value) or (p.inverse and err < 1e12)))
            out[p.key] = {"value": value, "stderr": err, "unit": p.unit, "determined": determined}
            j += 1
        for e in self.model.components:
            out.update(e.derived(out, self.model.meta))
        return out

    def report(self) -> str:
        """lmfit-style text: effects, fit statistics, parameters.

        >>> from types import SimpleNamespace
        >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
        >>> r = FitResult(Model(meta, ("tip_mass",), True), np.array([2.0, 0.1]), np.eye(2) * 1e-4,
        ...               np.ones(4), 1.0, 2, sigma_known=True)
        >>> print(r.report().splitlines()[1])
        [[Fit statistics]] chi2 = 4, gap = 1, BIC = 6.77259
        """
        lines = [f"[[Model]] baseline + {', '.join(self.model.effects) or 'nothing'}",
                 f"[[Fit statistics]] chi2 = {self.chi2:.6g}, gap = {self.gap:.6g}, BIC = {self.bic:.6g}",
                 "[[Variables]]"]
        for name, p in self.parameters().items():
            if p["value"] is None:
                lines.append(f"    {name}: not determined by these data")
            else:
                err = "" if p["stderr"] is None else f" +/- {p['stderr']:.3g}"
                lines.append(f"    {name}: {p['value']:.6g}{err} {p['unit']}".rstrip())
        return "\n".join(lines)


JACOBIAN = "analytic"
"""How :func:`fit` differentiates: ``"analytic"`` (variable-projection Jacobian, Kaufman's
approximation, from the generated partials of the design matrix), ``"projection"`` (the
same with finite differences of the design matrix) or ``"finite-difference"`` (SciPy's
two-point differences of the whole residual, the reference in benchmarks)."""


def bounds(model: Model):
    """Lower and upper internal bounds of the model's parameters."""
    params = model.parameters
    return np.array([p.lower for p in params]), np.array([p.upper for p in params])


COMPILED = True
"""Whether a fit with the analytic Jacobian evaluates its residual and Jacobian compiled
(:mod:`pfmdyn.discrepancy.fit_kernel`); False: the NumPy steps of :class:`_Problem`, the reference the
tests hold it to."""


class _Problem:
    """Residual and Jacobian of one model on one spectrum, with the last projection cached.

    The rows are the spectrum's folded per frequency (:func:`pfmdyn.fitting.projection.bias_nodes`: every
    design column is a slope, or the ramp, at the row's frequency, times its bias or not), at most two per
    frequency, plus one residual element, ``sqrt(constant) / sigma`` with a zero Jacobian row: the cost,
    ``J^T J`` and ``J^T r`` are the measured rows' (to rounding), so the solver takes the same steps on
    fewer rows.  Both paths, compiled and NumPy, work on the folded rows."""

    def __init__(self, model, data, sigma):
        self.model, self.sigma = model, sigma
        self.nodes = nodes = bias_nodes(data.frequency_hz, data.bias_v, data.response)
        self.freq_u, self.inverse, self.bias, self.y = nodes.frequency_hz, nodes.inverse, nodes.bias_v, nodes.response
        self.weight = nodes.weight
        # the misfit the folded rows do not carry, one more residual element (none when nothing was folded)
        self._tail = np.sqrt([nodes.constant]) / sigma if nodes.folded else np.empty(0)
        self._key, self._state = None, None
        self.compiled = COMPILED and JACOBIAN == "analytic"
        if self.compiled:
            # what every evaluation of this fit shares: the columns, the ramp, the projection's buffers
            rows, m = len(self.y), model.n_linear
            self._columns = (np.array([c[0] for c in model.columns], np.int64),
                             np.array([c[1] for c in model.columns], np.bool_))
            self._ramp = self.freq_u[self.inverse] / self.freq_u.max()
            self._buffers = (np.empty((rows, m), complex), np.empty((rows, m), complex), np.empty(m),
                             np.empty((m, m), complex), np.empty(m, complex))

    def _evaluated(self, x):
        """Design matrix, amplitudes, residual and Jacobian compiled (:data:`COMPILED`), and the slopes; fresh
        residual and Jacobian arrays (the solver keeps them)."""
        from .fit_kernel import design_and_gram, residual_and_jacobian

        T, dT = self.model.slopes_and_jacobian(self.freq_u, x)
        A, As, scale, G, Ay = self._buffers
        design_and_gram(T, self.inverse, self.bias, self.weight, self._ramp, *self._columns, self.y, A, As, scale, G,
                        Ay)
        w, V = np.linalg.eigh(G)
        rows, c, tail = len(self.y), np.empty(self.model.n_linear, complex), len(self._tail)
        r, J = np.empty(2 * rows + tail), np.empty((2 * rows + tail, len(x)))
        residual_and_jacobian(dT, self.inverse, self.bias, self.weight, *self._columns, self.y, float(self.sigma), A,
                              As, scale, Ay, w, V, CUTOFF, True, c, r[:2 * rows], J[:2 * rows])
        r[2 * rows:], J[2 * rows:] = self._tail, 0.0
        return A, c, r, J, T

    def _at(self, x):
        """Design matrix, amplitudes, projection (:func:`pfmdyn.fitting.projection.project`) and, for
        the analytic Jacobian, the slopes' partials (one read-out with the values: the solver asks for
        the Jacobian at most points it evaluates); compiled (:data:`COMPILED`): the design, the amplitudes,
        the residual and the Jacobian."""
        key = tuple(np.asarray(x, float))
        if key != self._key:
            x = np.asarray(x, float)
            if self.compiled:
                self._key, self._state = key, self._evaluated(x)
                return self._state
            if JACOBIAN == "analytic":
                A, dT = self.model.design_and_partials(self.freq_u, self.inverse, self.bias, x)
            else:
                A, dT = self.model.design(self.freq_u, self.inverse, self.bias, x), None
            A = A * self.weight[:, None]
            projection = project(A[None], self.y[None, :, None])
            self._key, self._state = key, (A, projection.amplitudes[0, :, 0], projection, dT)
        return self._state

    def residual(self, x):
        if self.compiled:
            return self._at(x)[2]
        A, c = self._at(x)[:2]
        r = (self.y - A @ c) / self.sigma
        r = np.concatenate([r.real, r.imag])
        bad = ~np.isfinite(r)
        r[bad] = 1e6 * np.tile(self.weight, 2)[bad]          # a folded row stands for weight**2 rows
        return np.concatenate([r, self._tail])

    def jacobian(self, x):
        if self.compiled:
            return self._at(x)[3]
        A, c, projection, dT = self._at(x)
        x = np.asarray(x, float)
        if JACOBIAN == "analytic":
            v = self.model.design_derivative_times(self.inverse, self.bias, dT, c) * self.weight[:, None]
        else:
            upper = bounds(self.model)[1]
            v = np.empty((len(self.y), len(x)), complex)
            for j in range(len(x)):
                h = 1e-7 * max(1.0, abs(x[j]))
                step = h if x[j] + h <= upper[j] else -h
                xs = x.copy()
                xs[j] += step
                moved = self.model.design(self.freq_u, self.inverse, self.bias, xs) * self.weight[:, None]
                v[:, j] = (moved - A) @ c / step
        # v = (d design / d x_j) c, shape (rows, parameters); Kaufman's -(I - P) dA c treats every
        # column alike, so the parameters go in as right-hand sides (one product for all)
        col = projection.jacobian(v[None, None])[0, 0] / self.sigma
        out = np.concatenate([col.real, col.imag, np.zeros((len(self._tail), len(x)))])
        out[~np.isfinite(out)] = 0.0
        return out

    def prediction(self, x, frequency_hz, bias_v) -> np.ndarray:
        """``A c`` at the measured rows ``(frequency_hz, bias_v)``, with the folded rows' amplitudes at ``x``
        (compiled: from the slopes of that evaluation)."""
        state = self._at(x)
        inverse = np.unique(frequency_hz, return_inverse=True)[1]
        if self.compiled:
            A = self.model._columns(state[4], self.freq_u, inverse, bias_v)
        else:
            A = self.model.design(self.freq_u, inverse, bias_v, np.asarray(x, float))
        return A @ state[1]


def fit(model: Model, data, starts: list[np.ndarray], sigma: float, max_nfev: int = 100,
        solve_each=None) -> FitResult:
    """Fit ``model`` to spectrum ``data`` from each start; keep the best (least RSS).

    Nonlinear parameters by the trust-region reflective method with bounds
    (:func:`pfmdyn.fitting.trust_region.least_squares`: SciPy's steps, compiled; SciPy's own with the
    finite-difference Jacobian), the complex linear coefficients by projection at every evaluation
    (:data:`JACOBIAN`), on the rows folded per frequency (:class:`_Problem`: the same cost and ``J^T J``, so the
    same covariance); the residual and prediction are the measured rows'.  ``solve_each(model, starts,
    max_nfev)``: each start's :func:`solve` (e.g. in worker processes), else they are solved here in turn.
    """
    problem = _Problem(model, data, sigma)
    lower = bounds(model)[0]
    best = None
    for res in solve_each(model, starts, max_nfev) if solve_each else (_solve(problem, s, max_nfev) for s in starts):
        if np.isfinite(res.cost) and (best is None or res.cost < best.cost):
            best = res
    if best is None:
        raise FloatingPointError("no start gave a finite misfit")
    k = len(lower) + 2 * model.n_linear
    n = 2 * len(data.response)
    cov = jacobian_covariance(best.jac, 2 * best.cost / max(n - k, 1))
    pred = problem.prediction(best.x, data.frequency_hz, data.bias_v)       # every measured row's
    return FitResult(model, best.x, cov, data.response - pred, sigma, k, prediction=pred)


def solve(model: Model, data, start: np.ndarray, sigma: float, max_nfev: int):
    """One start's least-squares solution in :func:`fit` (a :class:`pfmdyn.fitting.trust_region.Solution`): a fit's
    starts solved apart (in worker processes) give the fit it gives.

    >>> from types import SimpleNamespace
    >>> meta = SimpleNamespace(spring_constant=1.0, tip_height=1e-5, length=1e-4, free_resonance=1e4)
    >>> f, v = np.repeat(np.linspace(3e4, 9e4, 40), 2), np.tile([-1.0, 1.0], 40)
    >>> data = SimpleNamespace(frequency_hz=f, bias_v=v, response=(1 + v) / (1 - (f / 6e4) ** 2 + 0.05j))
    >>> model, start = Model(meta, ("damping_internal",)), np.array([2.0, 2.0, -3.0])
    >>> alone = solve(model, data, start, 1e-3, 10)
    >>> bool((alone.x == fit(model, data, [start], 1e-3, 10).internal).all())
    True
    """
    return _solve(_Problem(model, data, sigma), start, max_nfev)


def _solve(problem: _Problem, start: np.ndarray, max_nfev: int):
    lower, upper = bounds(problem.model)
    if JACOBIAN == "finite-difference":
        return least_squares(problem.residual, np.clip(start, lower, upper), jac="2-point", bounds=(lower, upper),
                             method="trf", diff_step=1e-7, max_nfev=max_nfev, x_scale=1.0)
    return trust_region.least_squares(problem.residual, problem.jacobian, np.clip(start, lower, upper), (lower, upper),
                                      max_nfev)
