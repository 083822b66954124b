"""Batched simple-harmonic-oscillator (SHO) fit of band-excitation spectra, in BGlib's model and conventions.

Band-excitation users describe each spectrum by an SHO,
``A e^{i phi} w0**2 / (f**2 - i f w0/Q - w0**2)`` (f in Hz; BGlib's ``BESHOfitter``): ``A`` is the
response's magnitude far below resonance (the peak's is ``A Q``) and ``phi`` carries BGlib's ``+pi``
(far below resonance the response is ``-A e^{i phi}``).  The
response and its partials are :func:`pfmdyn.generated.formulas.sho_response` and its
``_d_log_*`` companions.  Each spectrum (every pixel, bias step and frequency band: BGlib fits each
spectroscopic step on its own) is fitted in two stages, every spectrum of a block at once:

1. *Guess*: the SHO's denominator is linear in ``w0**2`` and ``w0/Q``, so ``y D(f) = A e^{i phi}
   w0**2`` is a linear least-squares problem per spectrum; three Sanathanan-Koerner passes
   reweight it by ``1/|D|`` of the previous pass (the equation error becomes the residual).
   No start values, no grid: resonances anywhere in or near the band, any Q.
2. *Fit*: the complex amplitude enters linearly and is projected out (variable projection);
   ``log w0`` and ``log Q`` follow the Levenberg-Marquardt iteration of the beam fit
   (:func:`pfmdyn.fitting.batched.levenberg_marquardt`).

Both stages run compiled, one spectrum at a time (:mod:`pfmdyn.maps.sho_kernel`, the noise
estimate of :mod:`pfmdyn.fitting.noise` with them); the NumPy path, all spectra of a block at once
through the beam fit's Levenberg-Marquardt, is the reference it is tested against.

Both stages report BGlib's ``R2 Criterion``, ``1 - sum|y - model|**2 / sum|y - mean(y)|**2``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import UserError
from ..fitting.noise import GAP_LIMIT, gap, noise_sigmas
from ..generated.formulas import sho_response, sho_response_d_log_quality, sho_response_d_log_resonance
from ..fitting.batched import band_covariance, levenberg_marquardt, project_bands
from .spec import bands

__all__ = ["FIELDS", "RENAMED", "SHOMapModel", "fit_spectra", "fit_sho_block", "is_sho"]

FIELDS = {"Amplitude [V]": "amplitude", "Frequency [Hz]": "measured_resonance",
          "Quality Factor": "measured_quality_factor", "Phase [rad]": "phase", "R2 Criterion": "r2"}
"""BGlib's compound fields -> pfmdyn's map names (``guess_`` + name for the guess).  The SHO's Q is the
measured one of each mode (:mod:`pfmdyn.names`' ``measured_quality_factor``: all damping together), not
the lever's internal friction ``quality_factor`` of the beam maps."""

RENAMED = {"quality_factor": "measured_quality_factor", "quality_factor_stderr": "measured_quality_factor_stderr",
           "guess_quality_factor": "guess_measured_quality_factor",
           "resonance_frequency": "measured_resonance", "resonance_frequency_stderr": "measured_resonance_stderr",
           "guess_resonance_frequency": "guess_measured_resonance"}
"""The SHO maps' names before (Q renamed in schema 1, the resonance after it) -> now (a store begun before is renamed when a run resumes it)."""

_FIT = {
    "amplitude": ("response units", "SHO amplitude A (|response| far below resonance; at the peak A Q)"),
    "measured_resonance": ("Hz", "SHO resonance frequency w0, as measured"),
    "measured_resonance_stderr": ("Hz", "standard error of measured_resonance"),
    "measured_quality_factor": ("1", "SHO quality factor Q: the mode's measured Q, all damping together"),
    "measured_quality_factor_stderr": ("1", "standard error of measured_quality_factor"),
    "phase": ("rad", "SHO phase phi (BGlib's convention: the usual phase + pi)"),
    "r2": ("1", "R2 criterion 1 - sum|y - model|^2 / sum|y - mean(y)|^2"),
}
_QUANTITIES = {
    **_FIT,
    **{f"guess_{name}": (unit, f"guess: {text}") for name, (unit, text) in _FIT.items() if not name.endswith("stderr")},
    "gap": ("1", "noise-normalised RMS residual sqrt(mean |y - model|^2) / sigma: 1 = fitted to the noise "
                 "(sigma from the spectrum, pfmdyn.fitting.noise)"),
    "explained": ("1", "1 where the SHO explains the spectrum (gap below the threshold, default 2), else 0"),
}

_Q_RANGE = (0.1, 1e5)


@dataclass(frozen=True)
class SHOMapModel:
    """The frequencies (and DC biases) of a map fitted with one SHO per spectrum and band.

    >>> m = SHOMapModel(np.linspace(3e5, 3.2e5, 8))
    >>> m.name, m.dims, list(m.outputs)[:2]
    ('sho', ('y', 'x'), ['amplitude', 'measured_resonance'])
    """

    frequency_hz: np.ndarray
    bias_v: np.ndarray | None = None
    name = "sho"

    @property
    def bands(self) -> list[slice]:
        """Frequency bands (:func:`pfmdyn.maps.spec.bands`): each gets an SHO of its own."""
        return bands(self.frequency_hz)

    @property
    def step_shape(self) -> tuple[int, ...]:
        """Trailing shape of every map after ``(y, x)``: bias steps, then bands when more than one."""
        return (() if self.bias_v is None else (len(self.bias_v),)) + ((len(self.bands),) if len(self.bands) > 1 else ())

    @property
    def dims(self) -> tuple[str, ...]:
        """Dimension names of every map."""
        return ("y", "x") + (() if self.bias_v is None else ("bias",)) + (("band",) if len(self.bands) > 1 else ())

    @property
    def outputs(self) -> dict[str, tuple[str, str]]:
        """The maps written: name -> (unit, description)."""
        return dict(_QUANTITIES)


def is_sho(model) -> bool:
    """Whether a map model is the SHO's (by its name: a class test fails when a module is loaded
    twice, as pytest's doctests do).

    >>> is_sho(SHOMapModel(np.array([1.0, 2.0]))), is_sho(object())
    (True, False)
    """
    return getattr(model, "name", None) == SHOMapModel.name


@dataclass(frozen=True)
class _Oscillator:
    """The SHO over one band as the Levenberg-Marquardt of :mod:`pfmdyn.fitting.batched` wants a model:
    internal parameters ``(log w0, log Q)``, one transfer function, one band."""

    frequency_hz: np.ndarray
    parameters = ("log_f0", "log_q")

    @property
    def bands(self):
        return [slice(None)]

    def design(self, p, jacobian=True):
        f0, q = np.exp(p[:, 0, None]), np.exp(p[:, 1, None])
        f = self.frequency_hz
        g = sho_response(f, f0, q)[:, None, :]
        if not jacobian:
            return g, None
        return g, np.stack([sho_response_d_log_resonance(f, f0, q), sho_response_d_log_quality(f, f0, q)])[:, :, None]


def _guess(f, y, passes=3):
    """``(log w0, log Q)`` per spectrum from the linearised SHO (see the module docstring).

    ``y (f**2 - u - i f v) = c`` with ``u = w0**2``, ``v = w0/Q`` (real) and ``c`` complex, in
    frequencies scaled by the band's centre; each pass weights the equations by ``1/|D|`` of the
    previous one.
    """
    centre = float(np.mean(f))
    x = f / centre
    weight = np.ones(y.shape)
    for _ in range(passes):
        yw = y * weight
        # unknowns (u, v, Re c, Im c); complex columns whose real normal matrix is Re(C^H C)
        columns = np.stack([yw, 1j * x * yw, weight + 0j, 1j * weight], axis=1)     # (n, 4, nf)
        normal = (columns.conj() @ columns.transpose(0, 2, 1)).real
        rhs = (columns.conj() @ (yw * x**2)[:, :, None]).real
        scale = np.sqrt(np.maximum(np.einsum("nii->ni", normal), 1e-300))
        solution = np.linalg.solve(normal / scale[:, :, None] / scale[:, None, :] + 1e-12 * np.eye(4),
                                   rhs / scale[:, :, None])[..., 0] / scale
        u = np.clip(solution[:, 0], (x[0] / 2) ** 2, (2 * x[-1]) ** 2)
        v = np.abs(solution[:, 1])
        x0 = np.sqrt(u)
        q = np.clip(x0 / np.maximum(v, x0 / _Q_RANGE[1]), *_Q_RANGE)
        weight = 1.0 / np.abs(x**2 - 1j * x * (x0 / q)[:, None] - u[:, None])
        weight /= np.max(weight, axis=1, keepdims=True)
    return np.stack([np.log(x0 * centre), np.log(q)], axis=1)


def _r2(total, residual_squares):
    """BGlib's R2 criterion per spectrum from ``total``, ``sum |y - mean(y)|**2`` (0 for a constant
    spectrum, NaN for a masked one)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(total == 0, 0.0, 1 - residual_squares / total)


def fit_spectra(frequency_hz, spectra, *, iterations=40, tolerance=1e-3, compiled=True,
                threads=1) -> dict[str, np.ndarray]:
    """SHO guess and least-squares fit of every spectrum ``(n, n_freq)`` over one band.

    Returns ``(n,)`` arrays named as :attr:`SHOMapModel.outputs` (guess and fit), ``cost``
    (squared relative residual) and ``gap`` (the noise-normalised RMS residual,
    :mod:`pfmdyn.fitting.noise`).  ``compiled``: the kernel of :mod:`pfmdyn.maps.sho_kernel`
    (one spectrum at a time, on ``threads`` threads), which masks a spectrum holding NaN or inf
    or nothing but zeros (NaN for all its values); else NumPy on all spectra at once, the
    reference, for finite spectra.

    >>> f = np.linspace(290e3, 310e3, 64)
    >>> y = 2e-3 * np.exp(0.5j) * sho_response(f, 301.2e3, 150.0)
    >>> for compiled in (True, False):
    ...     out = fit_spectra(f, y[None], compiled=compiled)
    ...     print(round(float(out["measured_resonance"][0]), 3), round(float(out["measured_quality_factor"][0]), 6),
    ...           round(float(out["amplitude"][0]), 9), round(float(out["phase"][0]), 9), round(float(out["r2"][0]), 9))
    301200.0 150.0 0.002 0.5 1.0
    301200.0 150.0 0.002 0.5 1.0
    """
    f = np.asarray(frequency_hz, float)
    y = np.asarray(spectra, complex)
    bounds = (np.log([f[0] / 2, _Q_RANGE[0]]), np.log([2 * f[-1], _Q_RANGE[1]]))
    if compiled:
        from .sho_kernel import fit_sho
        fit = fit_sho(f, y, _Q_RANGE, bounds, iterations, tolerance, threads)
    else:
        fit = _fit_numpy(f, y, bounds, iterations, tolerance)
    norm, out = fit["norm"], {}
    for prefix, params, amp, squares in (("guess_", fit["guess_p"], fit["guess_c"], fit["guess_cost"]),
                                         ("", fit["p"], fit["c"], fit["cost"])):
        amplitude = amp * norm
        out.update({f"{prefix}amplitude": np.abs(amplitude), f"{prefix}measured_resonance": np.exp(params[:, 0]),
                    f"{prefix}measured_quality_factor": np.exp(params[:, 1]), f"{prefix}phase": np.angle(amplitude),
                    f"{prefix}r2": _r2(fit["total"], squares)})
    out["measured_resonance_stderr"] = out["measured_resonance"] * fit["spread"][:, 0]
    out["measured_quality_factor_stderr"] = out["measured_quality_factor"] * fit["spread"][:, 1]
    out["cost"], out["gap"] = fit["cost"], gap(fit["cost"] * (norm / fit["sigma"]) ** 2, f.size)
    return out


def _fit_numpy(f, y, bounds, iterations, tolerance) -> dict[str, np.ndarray]:
    """:func:`fit_spectra`'s guess and fit by NumPy on all spectra at once, named as
    :func:`pfmdyn.maps.sho_kernel.fit_sho` names them."""
    norm = np.sqrt(np.sum(np.abs(y) ** 2, axis=1))
    norm[norm == 0] = 1.0
    yn = y / norm[:, None]
    model = _Oscillator(f)
    p0 = _guess(f, yn)
    g0 = model.design(p0, jacobian=False)[0]
    c0, r0, _ = project_bands(g0, None, yn[:, None, :], model.bands)
    p, c, _, _, cost, g, dg = levenberg_marquardt(model, yn[:, None, :], p0.copy(), bounds, iterations, tolerance)
    cov = band_covariance(model, g, dg, c, cost / max(2 * f.size - 4, 1))
    with np.errstate(over="ignore"):
        spread = np.sinh(np.sqrt(np.abs(cov[:, [0, 1], [0, 1]])))
    return {"norm": norm, "total": np.sum(np.abs(yn - yn.mean(axis=1, keepdims=True)) ** 2, axis=1),
            "guess_p": p0, "guess_c": c0[:, 0, 0, 0], "guess_cost": np.sum(r0**2, axis=1),
            "p": p, "c": c[:, 0, 0, 0], "cost": cost, "spread": spread, "sigma": noise_sigmas(f, None, y[:, None, :])}


def fit_sho_block(model: SHOMapModel, response, *, gap_threshold=GAP_LIMIT, iterations=40, tolerance=1e-3,
                  threads=1) -> dict[str, np.ndarray]:
    """Fit every spectrum of ``response`` (``(..., n_freq)``, or ``(..., n_bias, n_freq)`` with
    biases) on ``threads`` threads; maps of the pixel shape plus :attr:`SHOMapModel.step_shape`.

    >>> f = np.concatenate([np.linspace(290e3, 310e3, 32), np.linspace(600e3, 640e3, 32)])
    >>> y = sho_response(f, 300e3, 80.0) * (f < 4e5) + 1j * sho_response(f, 620e3, 120.0) * (f > 4e5)
    >>> out = fit_sho_block(SHOMapModel(f), np.broadcast_to(y, (2, 3, f.size)))
    >>> out["measured_resonance"].shape, np.round(out["measured_quality_factor"][0, 0], 6).tolist()
    ((2, 3, 2), [80.0, 120.0])
    >>> masked = fit_sho_block(SHOMapModel(f), np.stack([y, np.full(f.size, np.nan)]))
    >>> np.isnan(masked["measured_resonance"][1]).tolist(), masked["explained"][:, 0].tolist()
    ([True, True], [1.0, 0.0])
    """
    y = np.asarray(response, complex)
    tail = (len(model.bias_v), len(model.frequency_hz)) if model.bias_v is not None else (len(model.frequency_hz),)
    if y.shape[-len(tail):] != tail:
        raise UserError(f"response has shape {y.shape}; its last axes must be {tail} (biases, frequencies)")
    shape = y.shape[:y.ndim - 1]
    spectra = y.reshape(-1, tail[-1])
    f = np.asarray(model.frequency_hz, float)
    per_band = [fit_spectra(f[band], spectra[:, band], iterations=iterations, tolerance=tolerance, threads=threads)
                for band in model.bands]
    stacked = {name: np.stack([b[name] for b in per_band], axis=-1) for name in model.outputs if name in per_band[0]}
    # a masked spectrum (NaN or inf, or nothing but zeros) has NaN maps and is not explained
    stacked["explained"] = np.where(np.isfinite(stacked["gap"]), stacked["gap"] < gap_threshold, 0.0)
    bands_shape = (len(model.bands),) if len(model.bands) > 1 else ()
    return {name: value.reshape(shape + bands_shape) for name, value in stacked.items()}


def band_centres(model: SHOMapModel) -> list[float]:
    """Centre frequency of each band (Hz), the ``band`` coordinate of the maps.

    >>> band_centres(SHOMapModel(np.array([1.0, 2.0, 3.0, 50.0, 51.0])))
    [2.0, 50.5]
    """
    f = np.asarray(model.frequency_hz, float)
    return [float(math.fsum(f[b]) / len(f[b])) for b in model.bands]
