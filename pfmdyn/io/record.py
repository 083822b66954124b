"""What pfmdyn understood from an instrument file: the record every format reader returns.

Kept apart from :mod:`pfmdyn.io.instruments` (the front door that picks a reader) so that the
format readers import the record without importing the front door back.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ..errors import UserError
from ..names import NAMES, canonical, checked

__all__ = ["FIELDS", "KINDS", "MissingFieldError", "Channel", "InstrumentRecord", "make_record", "make_channel",
           "si_unit",
           "si_value", "si_spectrum", "decode_text", "attribute_texts"]

FIELDS = {name: (NAMES[name].label, "" if NAMES[name].unit == "1" else NAMES[name].unit)
          for name in ("spring_constant", "free_resonance", "free_quality_factor", "contact_resonance",
                       "contact_quality_factor", "length", "width", "tip_height", "drive_frequency", "tip_bias",
                       "amplitude_peak")}
"""Cantilever field (its name in :mod:`pfmdyn.names`) -> (what it is, SI unit; '' for a pure
number), both from :mod:`pfmdyn.names`.  Every record lists each as found or missing, but those of
:data:`SWEEP_FIELDS`."""
SWEEP_FIELDS = ("amplitude_peak",)
"""Fields only a drive sweep's header holds (where its amplitude peaked, which is no resonance): never missing."""

KINDS = ("image", "spectrum", "thermal spectrum", "resonance metadata", "curve")


class MissingFieldError(UserError):
    """A cantilever field that neither the file nor the caller gives; ``field`` names it (a key
    of :data:`FIELDS`; a tuple of keys when several are missing) and is the error's
    :attr:`~pfmdyn.errors.UserError.quantity`, so that a command can say which option supplies it.

    >>> MissingFieldError("tip height not in a.ibw", "tip_height").quantity
    'tip_height'
    """

    def __init__(self, message: str, field: str | tuple[str, ...]):
        super().__init__(message, quantity=field)

    @property
    def field(self) -> str | tuple[str, ...]:
        """The missing field's name (the quantity), or the names when several are missing."""
        return self.quantity


@dataclass(frozen=True)
class Channel:
    """One data channel: name, unit and shape.

    ``unit`` is SI when the file's unit is a prefixed SI unit (``nm`` -> ``m``); the stored
    numbers times ``scale`` are then in that unit.  A unit pfmdyn does not know (``a.u.``,
    ``counts``) is kept as written with ``scale`` 1; '' when the file does not say.
    """

    name: str
    unit: str
    shape: tuple
    scale: float = 1.0


@dataclass(frozen=True)
class InstrumentRecord:
    """What pfmdyn understood from an instrument file.

    ``fields`` maps names of :data:`FIELDS` to SI values found in the file; ``missing``
    lists the others.  ``spectrum`` is ``(frequency_hz, values, unit)`` for spectra.
    """

    path: str
    kind: str
    instrument: str
    channels: tuple
    fields: dict
    missing: tuple = ()
    notes: tuple = ()
    spectrum: tuple | None = field(default=None, repr=False, compare=False)

    def left_out(self, names=None) -> list[str]:
        """The notes of values the file holds but no probe has (:func:`make_record`), of ``names`` (default: all).

        >>> make_record("x.ibw", "image", "test", (), {"spring_constant": -2.0}).left_out()
        ['spring constant -2 N/m in the file left out: spring_constant must be in (0.0001, 10000] N/m, got -2.0']
        """
        labels = [FIELDS[name][0] + " " for name in (names or FIELDS)]
        return [note for note in self.notes if note.startswith(tuple(labels)) and " in the file left out: " in note]

    def to_json(self) -> dict:
        """The JSON document of ``pfmdyn inspect``: numbers stay numbers."""
        return {"path": self.path, "kind": self.kind, "instrument": self.instrument,
                "channels": [{"name": c.name, "unit": c.unit, "shape": list(c.shape), "scale": c.scale}
                             for c in self.channels],
                "fields": {name: {"value": value, "unit": FIELDS[name][1]}
                           for name, value in self.fields.items()},
                "missing": list(self.missing), "notes": list(self.notes)}


def make_record(path, kind, instrument, channels, found: dict, notes=(), spectrum=None) -> InstrumentRecord:
    """A record from raw field values: keeps positive finite numbers, lists the rest missing.

    Instruments write NaN or 0 for a value never measured; neither is a cantilever property.
    A spectrum whose values are an amplitude spectral density (a unit per ``sqrt(Hz)``) is a
    thermal spectrum, whatever the format.

    Keys of ``found`` may be any spelling :func:`pfmdyn.names.canonical` knows (``length_m``).

    A value no probe has (a negative spring constant, a length of 225 m: micrometres written as metres)
    is left out too, with a note saying so (it was dropped in silence, or taken).

    >>> r = make_record("x.ibw", "image", "test", (), {"spring_constant_n_per_m": 2.0, "length": float("nan")})
    >>> r.fields, "length" in r.missing
    ({'spring_constant': 2.0}, True)
    >>> make_record("x.ibw", "image", "test", (), {"length": 225.0}).notes
    ('lever length 225 m in the file left out: length must be in (1e-06, 0.01] m, got 225.0',)
    """
    assert kind in KINDS, kind
    if kind == "spectrum" and spectrum is not None and str(spectrum[2]).endswith("/sqrt(Hz)"):
        kind = "thermal spectrum"
    found = {canonical(key) or key: value for key, value in found.items()}
    fields = {}
    for name in FIELDS:
        value = found.get(name)
        if value is None:
            continue
        value = float(value)
        # Tip bias may be zero or negative; every other field is a positive quantity.
        if not math.isfinite(value) or (value == 0 and name != "tip_bias"):
            continue            # never measured
        try:
            fields[name] = checked(name, value)
        except UserError as exc:
            notes = (*notes, f"{FIELDS[name][0]} {value:g}{' ' + FIELDS[name][1] if FIELDS[name][1] else ''} in the "
                             f"file left out: {exc}")
    missing = tuple(name for name in FIELDS if name not in fields and name not in SWEEP_FIELDS)
    # A unit pfmdyn cannot convert is kept as written; say so rather than let it pass as SI.
    notes = list(notes) + [f"{c.name}: unit '{c.unit}' is not an SI unit pfmdyn knows; values left as stored"
                           for c in channels if c.unit and si_unit(c.unit) is None]
    return InstrumentRecord(str(path), kind, instrument, tuple(channels), fields, missing,
                            tuple(notes), spectrum)


_PREFIX = {"a": 1e-18, "f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "μ": 1e-6, "m": 1e-3,
           "c": 1e-2, "": 1.0, "k": 1e3, "M": 1e6, "G": 1e9}
# Units that take an SI prefix -> (SI unit, factor); then units that take none.
_BASE = {"m": ("m", 1.0), "Hz": ("Hz", 1.0), "V": ("V", 1.0), "A": ("A", 1.0), "N": ("N", 1.0),
         "s": ("s", 1.0), "W": ("W", 1.0), "F": ("F", 1.0), "C": ("C", 1.0), "Pa": ("Pa", 1.0),
         "K": ("K", 1.0), "Ohm": ("Ohm", 1.0), "Ω": ("Ohm", 1.0), "g": ("kg", 1e-3), "rad": ("rad", 1.0)}
_PLAIN = {"deg": ("deg", 1.0), "°": ("deg", 1.0), "Å": ("m", 1e-10), "Angstrom": ("m", 1e-10)}


def _si_factor(term: str):
    """One factor of a unit (``nm``, ``sqrt(kHz)``, ``s^2``) -> (SI text, factor) or None."""
    power = 1.0
    root = re.fullmatch(r"(?:sqrt\((.+)\)|√\(?(.+?)\)?|rt(.+))", term)
    if root:
        term, power = next(g for g in root.groups() if g), 0.5
    exponent = re.fullmatch(r"(.+?)(?:\^\(?(-?\d+(?:\.\d+)?)\)?|([²³]))", term)
    if exponent:
        term = exponent.group(1)
        power *= float(exponent.group(2)) if exponent.group(2) else {"²": 2.0, "³": 3.0}[exponent.group(3)]
    if term in _PLAIN or term in _BASE:
        unit, factor = (_PLAIN.get(term) or _BASE[term])
    elif term[:1] in _PREFIX and term[1:] in _BASE:
        unit, factor = _BASE[term[1:]][0], _PREFIX[term[:1]] * _BASE[term[1:]][1]
    else:
        return None
    text = f"sqrt({unit})" if power == 0.5 else unit if power == 1 else f"{unit}^{power:g}"
    return text, factor ** power


def si_unit(unit: str):
    """A unit as an instrument writes it -> (SI unit, factor to SI); None if not an SI unit.

    '' is dimensionless.  Products (``*``, ``·``) and quotients (``/``) of prefixed units,
    square roots (``sqrt(Hz)``, ``√Hz``) and powers (``m^2``) are understood.

    >>> si_unit("kHz"), si_unit("pN/nm"), si_unit("mV"), si_unit("µm"), si_unit("Hz")
    (('Hz', 1000.0), ('N/m', 0.001), ('V', 0.001), ('m', 1e-06), ('Hz', 1.0))
    >>> si_unit("fm/√Hz"), si_unit("V/Hz^0.5"), si_unit("°"), si_unit("a.u."), si_unit("furlong")
    (('m/sqrt(Hz)', 1e-15), ('V/sqrt(Hz)', 1.0), ('deg', 1.0), None, None)
    """
    unit = str(unit).strip()
    if not unit:
        return "", 1.0
    parts = unit.split("/")
    if any(not p.strip() for p in parts):
        return None
    texts, factor = [], 1.0
    for i, part in enumerate(parts):
        pieces = []
        for term in re.split(r"[*·]", part.strip()):
            converted = _si_factor(term.strip())
            if converted is None:
                return None
            pieces.append(converted[0])
            factor = factor * converted[1] if i == 0 else factor / converted[1]
        texts.append("*".join(pieces))
    return "/".join(texts), factor


def make_channel(name: str, unit: str, shape) -> Channel:
    """A channel with its unit in SI (and the factor to it); unknown units are kept as written.

    >>> make_channel("Height", "nm", (4, 4))
    Channel(name='Height', unit='m', shape=(4, 4), scale=1e-09)
    """
    converted = si_unit(unit)
    if converted is None:
        return Channel(name, str(unit).strip(), tuple(shape))
    return Channel(name, converted[0], tuple(shape), converted[1])


def si_value(text, unit: str) -> float | None:
    """A value written with its unit (``'179.8kHz'``, ``'27.13 N/m'``) in SI; None if not that unit.

    >>> si_value("179.8kHz", "Hz"), si_value("27.13 N/m", "N/m"), si_value("442 ", ""), si_value("40 °C", "Hz")
    (179800.0, 27.13, 442.0, None)
    """
    match = re.fullmatch(r"\s*([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)\s*(\S*(?:\s+\S+)*)\s*", str(text))
    if not match:
        return None
    converted = si_unit(match.group(2))
    if converted is None or converted[0] != unit:
        return None
    return float(match.group(1)) * converted[1]


def decode_text(raw) -> str:
    """Bytes of an instrument's text as UTF-8 when they are valid UTF-8, else Latin-1 (old Igor, Windows).

    >>> decode_text("µm".encode("utf-8")), decode_text("µm".encode("latin-1"))
    ('µm', 'µm')
    """
    if not isinstance(raw, bytes):
        return str(raw)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def attribute_texts(values) -> list[str]:
    r"""An HDF5 attribute or note value as texts: a str, bytes (:func:`decode_text`) or an array of
    either, one text per element.

    >>> import numpy as np
    >>> attribute_texts(np.array([b"Frequency", "Bias"], dtype=object)), attribute_texts(b"\xb5m")
    (['Frequency', 'Bias'], ['µm'])
    """
    import numpy as np

    return [decode_text(v) for v in np.ravel(np.asarray(values, dtype=object))]


def si_spectrum(path, frequency, frequency_unit: str, values, unit: str) -> tuple:
    """``(frequency_hz, values, unit)`` of a spectrum in SI; a frequency axis not in Hz is an error.

    Values in a unit pfmdyn does not know stay as written (their unit says so).

    >>> f, v, u = si_spectrum("t.ibw", [300.0, 301.0], "kHz", [1.0, 2.0], "nm")
    >>> f.tolist(), v.tolist(), u
    ([300000.0, 301000.0], [1e-09, 2e-09], 'm')
    >>> si_spectrum("t.ibw", [1.0], "furlong", [1.0], "V")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: t.ibw: the frequency axis is in 'furlong', which pfmdyn cannot convert to Hz
    """
    import numpy as np

    from ..errors import UserError

    axis = si_unit(frequency_unit)
    if axis is None or axis[0] != "Hz":
        raise UserError(f"{path}: the frequency axis is in '{frequency_unit}', which pfmdyn cannot convert to Hz")
    values = np.asarray(values)
    values = values.astype(complex if np.iscomplexobj(values) else float)
    channel = make_channel("", unit, values.shape)
    return np.asarray(frequency, dtype=float) * axis[1], values * channel.scale, channel.unit
