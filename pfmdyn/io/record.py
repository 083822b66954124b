"""What pfmdyn understood from an instrument file: the record every format reader returns.

Kept apart from :mod:`pfmdyn.io.instruments` (the front door that picks a reader) so that the
format readers import the record without importing the front door back.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["FIELDS", "KINDS", "Channel", "InstrumentRecord", "make_record"]

FIELDS = {
    "spring_constant_n_per_m": ("spring constant", "N/m"),
    "free_resonance_hz": ("free resonance", "Hz"),
    "free_quality_factor": ("free Q", ""),
    "contact_resonance_hz": ("contact resonance", "Hz"),
    "contact_quality_factor": ("contact Q", ""),
    "length_m": ("lever length", "m"),
    "width_m": ("lever width", "m"),
    "tip_height_m": ("tip height", "m"),
    "drive_frequency_hz": ("drive frequency", "Hz"),
    "tip_bias_v": ("tip bias", "V"),
}
"""Cantilever field -> (what it is, SI unit).  Every record lists each as found or missing."""

KINDS = ("image", "spectrum", "thermal spectrum", "resonance metadata", "curve")


@dataclass(frozen=True)
class Channel:
    """One data channel: name, unit (SI, '' when the file does not say) and shape."""

    name: str
    unit: str
    shape: tuple


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

    def to_json(self) -> dict:
        """The JSON document of ``pfmdyn inspect --json``: numbers stay numbers."""
        return {"path": self.path, "kind": self.kind, "instrument": self.instrument,
                "channels": [{"name": c.name, "unit": c.unit, "shape": list(c.shape)}
                             for c in self.channels],
                "fields": {name: {"value": value, "unit": FIELDS[name][1]}
                           for name, value in self.fields.items()},
                "missing": list(self.missing), "notes": list(self.notes)}


def make_record(path, kind, instrument, channels, found: dict, notes=(), spectrum=None) -> InstrumentRecord:
    """A record from raw field values: keeps positive finite numbers, lists the rest missing.

    Instruments write NaN or 0 for a value never measured; neither is a cantilever property.

    >>> r = make_record("x.ibw", "image", "test", (), {"spring_constant_n_per_m": 2.0, "length_m": float("nan")})
    >>> r.fields, "length_m" in r.missing
    ({'spring_constant_n_per_m': 2.0}, True)
    """
    assert kind in KINDS, kind
    fields = {}
    for name in FIELDS:
        value = found.get(name)
        if value is None:
            continue
        value = float(value)
        # Tip bias may be zero or negative; every other field is a positive quantity.
        if math.isfinite(value) and (value > 0 or (name == "tip_bias_v")):
            fields[name] = value
    missing = tuple(name for name in FIELDS if name not in fields)
    return InstrumentRecord(str(path), kind, instrument, tuple(channels), fields, missing,
                            tuple(notes), spectrum)
