"""Asylum DART images (dual AC resonance tracking) from ``.ibw`` files.

One wave ``(points, lines, layers)``: the layers named ``Amplitude1Retrace``, ``Amplitude2Retrace``
(m, through ``AmpInvOLS``), ``Phase1Retrace``, ``Phase2Retrace`` (degrees: the deflection's lag
behind the bias) and ``FrequencyRetrace`` (the tracked centre ``fc``, Hz), in any order beside the
height and others (``...Trace`` when no retrace is recorded).  The note gives ``DFRTFrequencyWidth``
(``df``: the two drives are ``fc -/+ df/2``), ``DFRTFrequencyCenter``, ``DriveAmplitude`` (V,
zero-to-peak), ``InvOLS`` and ``AmpInvOLS`` (m/V) and the lever (:mod:`pfmdyn.io.asylum`; the
free lever's ``ThermalQ`` is its internal loss).  Maps come out as ``(y, x)``: ``y`` the slow-scan
line (the wave's second dimension), ``x`` the fast-scan point (its first), in the stored order.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import UserError
from . import asylum, ibw
from .asylum import DART_CHANNELS, DART_KEYS
from .record import decode_text

__all__ = ["DART_CHANNELS", "DART_KEYS", "DartImage", "read_dart"]



@dataclass(frozen=True)
class DartImage:
    """A DART image: the channels as ``(y, x)`` arrays in SI (phases in degrees), the note's settings
    (``settings``: names of :data:`DART_KEYS` -> SI values found), the lever's fields found
    (:func:`pfmdyn.io.asylum.cantilever_fields`) and notes on what was read."""

    path: str
    amplitude1: np.ndarray
    amplitude2: np.ndarray
    phase1: np.ndarray
    phase2: np.ndarray
    centre: np.ndarray
    settings: dict
    fields: dict
    direction: str = "Retrace"
    notes: tuple = field(default=())

    @property
    def signals(self) -> tuple[np.ndarray, np.ndarray]:
        """The deflection signals at ``f1`` and ``f2`` as complex numbers ``A exp(-i phi)`` (m, through the
        static InvOLS: the amplitudes times ``InvOLS / AmpInvOLS`` when the note has both).

        >>> one = np.ones((1, 1))
        >>> image = DartImage("a.ibw", 1.1e-9 * one, 1.1e-9 * one, 0 * one, 90 * one, 3e5 * one,
        ...                   {"invols": 60e-9, "amp_invols": 66e-9}, {})
        >>> [complex(np.round(s[0, 0] * 1e9, 12)) for s in image.signals]      # nm: a lag of 90 deg is -i
        [(1+0j), -1j]
        """
        scale = self.settings.get("invols", 1.0) / self.settings.get("amp_invols", self.settings.get("invols", 1.0))
        return tuple(scale * a * np.exp(-1j * np.radians(p))
                     for a, p in ((self.amplitude1, self.phase1), (self.amplitude2, self.phase2)))

    def frequencies(self, width: float) -> tuple[np.ndarray, np.ndarray]:
        """``f1 = fc - width/2`` and ``f2 = fc + width/2`` at each pixel (Hz).

        >>> one = np.ones((1, 1))
        >>> image = DartImage("a.ibw", one, one, one, one, 3e5 * one, {}, {})
        >>> [float(f[0, 0]) for f in image.frequencies(4e3)]
        [298000.0, 302000.0]
        """
        return self.centre - width / 2, self.centre + width / 2


def _layers(path: Path) -> tuple[dict, dict]:
    """The wave's layers by label and its note."""
    wave = ibw._load(path)
    data = np.asarray(wave["wData"])
    if data.ndim != 3:
        raise UserError(f"{path}: not a DART image (a wave of {data.ndim} dimensions, not points x lines x layers)")
    labels = ibw._labels(path, wave, 2, data.shape[2]) or []
    note = asylum.parse_note(decode_text(wave.get("note", b"")))
    return {label: data[:, :, i] for i, label in enumerate(labels)}, note


def _pick(layers: dict, name: str):
    for direction in ("Retrace", "Trace"):
        if name + direction in layers:
            return direction, layers[name + direction]
    return None


def read_dart(path) -> DartImage:
    """Read a DART image from an Asylum ``.ibw`` file (module docstring).

    >>> read_dart("missing.ibw")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: missing.ibw: no such file
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    layers, note = _layers(path)
    notes = []
    picked = {name: _pick(layers, name) for name in DART_CHANNELS}
    missing = [name for name, found in picked.items() if found is None]
    if len(missing) == len(DART_CHANNELS) and layers:      # an ordinary image, as most .ibw files are
        raise UserError(f"{path}: a single-frequency image (layers: {', '.join(layers)}), not a DART image: nothing "
                        "to fit per pixel; map inverts DART images (Amplitude1, Amplitude2, Phase1, Phase2, Frequency "
                        "layers), and 'pfmdyn stiffness FILE' the contact resonance an image's note records")
    if missing:
        raise UserError(f"{path}: not a DART image: no {', '.join(n + 'Retrace' for n in missing)} layer "
                        f"(layers: {', '.join(layers) or 'none labelled'})")
    directions = {found[0] for found in picked.values()}
    direction = "Retrace" if "Retrace" in directions else "Trace"
    channels = {name: np.asarray(found[1], float).T for name, found in picked.items()}     # (points, lines) -> (y, x)
    blank = ~np.all([np.isfinite(channel) for channel in channels.values()], axis=0)
    if blank.all():
        raise UserError(f"{path}: no pixel of the DART image has a number in every channel "
                        f"({', '.join(n + direction for n in DART_CHANNELS)})")
    if blank.any():
        # no signal there (undetermined downstream), read at the image's median centre
        for name in DART_CHANNELS:
            fill = np.median(channels[name][~blank]) if name == "Frequency" else np.nan if "Amplitude" in name else 0.0
            channels[name] = np.where(blank, fill, channels[name])
        notes.append(f"{blank.sum()} pixel{'s' if blank.sum() > 1 else ''} without a number in every channel: undetermined")
    settings = {name: value for name, key in DART_KEYS.items() if (value := asylum.note_number(note, key)) is not None}
    centre = channels["Frequency"]
    if "frequency_centre" in settings and np.median(np.abs(centre)) < 0.5 * settings["frequency_centre"]:
        centre = centre + settings["frequency_centre"]      # a frequency channel recorded as the shift
        notes.append("FrequencyRetrace read as the shift from DFRTFrequencyCenter")
    fields, problems = asylum.cantilever_fields(note)
    return DartImage(str(path), channels["Amplitude1"], channels["Amplitude2"], channels["Phase1"],
                     channels["Phase2"], centre, settings, fields, direction, tuple(notes + problems))
