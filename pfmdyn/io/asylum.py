"""Asylum Research conventions: the ``key: value`` note and the channel names of its images.

The same note appears in ``.ibw`` files and, as HDF5 attributes, in their pycroscopy NSID
conversions; both readers map it here.  Keys (Asylum software, MFP-3D and Cypher):

* ``SpringConstant`` (N/m), ``ThermalFrequency`` (Hz) and ``ThermalQ``: the fit of the
  thermal tune of the free cantilever (tip away from the surface);
* ``TuneFreqResult`` (Hz) and ``TuneQResult``: the last tune fit, which in PFM and
  contact-resonance work is made in contact, i.e. a contact resonance;
* ``CustomLeverLength``, ``CustomLeverWidth`` (m), ``DriveFrequency`` (Hz), ``TipVoltage`` (V).

No tip height is recorded.
"""
from __future__ import annotations

import math
import re

from .record import FIELDS, decode_text, si_unit, si_value

__all__ = ["NOTE_KEYS", "DART_CHANNELS", "DART_KEYS", "note_number", "dart_note", "parse_note", "cantilever_fields", "channel_name", "channel_unit", "layer_unit"]

NOTE_KEYS = {
    "spring_constant": "SpringConstant",
    "free_resonance": "ThermalFrequency",
    "free_quality_factor": "ThermalQ",
    "contact_resonance": "TuneFreqResult",
    "contact_quality_factor": "TuneQResult",
    "length": "CustomLeverLength",
    "width": "CustomLeverWidth",
    "drive_frequency": "DriveFrequency",
    "tip_bias": "TipVoltage",
}
"""pfmdyn field -> Asylum note key (values already in SI units)."""

# Units of Asylum image channels by their data type (the name without Trace/Retrace).
_UNITS = {"Height": "m", "ZSensor": "m", "Amplitude": "m", "Amplitude1": "m", "Amplitude2": "m",
          "Deflection": "m", "Phase": "deg", "Phase1": "deg", "Phase2": "deg", "Frequency": "Hz",
          "Potential": "V", "Bias": "V", "UserIn0": "V", "UserIn1": "V", "UserIn2": "V", "Current": "A",
          "Dissipation": "W",
          # force curves: raw and sensed piezo, deflection, amplitude, frequency
          "Raw": "m", "ZSnsr": "m", "LVDT": "m", "Defl": "m", "Amp": "m", "Freq": "Hz"}


DART_CHANNELS = ("Amplitude1", "Amplitude2", "Phase1", "Phase2", "Frequency")
"""The layers a DART image needs (their names without ``Trace``/``Retrace``)."""
DART_KEYS = {"frequency_width": "DFRTFrequencyWidth", "frequency_centre": "DFRTFrequencyCenter",
             "drive_amplitude": "DriveAmplitude", "invols": "InvOLS", "amp_invols": "AmpInvOLS"}
"""What pfmdyn.io.dart reads of the note besides the lever -> Asylum's key."""


def parse_note(text: str) -> dict:
    """The note's ``key: value`` (or ``key=value``) lines as a dict of strings (any line end; later keys win).

    >>> parse_note("SpringConstant: 8.3589\\rImagingMode:PFM Mode\\nTime: 12:30\\r\\nWidth = 2\\rno pair here")
    {'SpringConstant': '8.3589', 'ImagingMode': 'PFM Mode', 'Time': '12:30', 'Width': '2'}
    """
    out = {}
    # Igor pads some notes with NULs, which are not whitespace to str.strip.
    for line in re.split(r"\r\n|\r|\n", text.replace("\0", "")):
        key, sep, value = line.partition(":")
        if not sep:
            key, sep, value = line.partition("=")
        if sep and key.strip():
            out[key.strip()] = value.strip()
    return out


def _number(value) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def note_number(note: dict, key: str) -> float | None:
    """The finite number leading the note's value of ``key`` (``'2500 Hz'``: 2500.0), else None.

    >>> note_number({"DriveAmplitude": "1.5 V", "ThermalQ": "NaN"}, "DriveAmplitude"), note_number({}, "ThermalQ")
    (1.5, None)
    """
    parts = str(note.get(key, "")).split()
    return _number(parts[0]) if parts else None


def dart_note(labels, note: dict) -> list[str]:
    """What ``pfmdyn inspect`` says of an image whose layers are a DART image's: that ``pfmdyn map`` inverts it,
    with the DART settings its note holds (none for any other image).

    >>> dart_note(["HeightRetrace", "Amplitude1Retrace", "Amplitude2Retrace", "Phase1Retrace", "Phase2Retrace",
    ...            "FrequencyRetrace"], {"DFRTFrequencyWidth": "2500", "DriveAmplitude": "1.5"})
    ['a DART image (pfmdyn map inverts it); DART settings in the note: DFRTFrequencyWidth 2500 Hz, DriveAmplitude 1.5 V']
    >>> dart_note(["HeightRetrace", "PhaseRetrace"], {})
    []
    """
    if any(not {name + "Retrace", name + "Trace"} & set(labels) for name in DART_CHANNELS):
        return []
    units = {"frequency_width": "Hz", "frequency_centre": "Hz", "drive_amplitude": "V", "invols": "m/V",
             "amp_invols": "m/V"}
    settings = [f"{key} {value:g} {units[name]}" for name, key in DART_KEYS.items()
                if (value := note_number(note, key)) is not None]
    return ["a DART image (pfmdyn map inverts it); DART settings in the note: " + (", ".join(settings) or "none")]


def cantilever_fields(note: dict, keys: dict = NOTE_KEYS) -> tuple[dict, list[str]]:
    """pfmdyn fields (SI) found in an Asylum note, and a line for each value not understood.

    ``keys`` maps pfmdyn fields to the note's keys (Asylum's by default).

    Values are numbers in SI (as Asylum writes them) or text with a unit, prefixed or not
    (``'300 kHz'``).  NaN means never measured; a unit of the wrong kind is reported.

    >>> cantilever_fields({"SpringConstant": "0.46538", "ThermalQ": "NaN", "TipVoltage": 3})
    ({'spring_constant': 0.46538, 'tip_bias': 3.0}, [])
    >>> cantilever_fields({"DriveFrequency": "300 kHz", "CustomLeverLength": "225 furlong"})
    ({'drive_frequency': 300000.0}, ["CustomLeverLength '225 furlong' not understood as m: lever length left out"])
    """
    found, problems = {}, []
    for name, key in keys.items():
        value = note.get(key)
        if value is None:
            continue
        if hasattr(value, "item") and getattr(value, "size", 1) == 1:
            value = value.item()         # HDF5 attributes come as NumPy scalars
        value = decode_text(value) if isinstance(value, bytes) else value
        number = _number(value)
        if number is None and isinstance(value, str) and value.strip().lower() not in ("nan", ""):
            number = si_value(value, FIELDS[name][1])
            if number is None:
                problems.append(f"{key} {value.strip()!r} not understood as {FIELDS[name][1] or 'a number'}: "
                                f"{FIELDS[name][0]} left out")
        if number is not None and math.isfinite(number):
            found[name] = number
    return found, problems


def channel_name(label: str) -> str:
    """An image layer's label, cleaned of the padding igor2 leaves from the previous label.

    Labels are fixed 32-byte fields; igor2 drops the NUL but keeps the stale bytes after it
    (``PhaseRetrace`` + ``race``).  Asylum names end in ``Trace`` or ``Retrace``.

    >>> channel_name("PhaseRetracerace"), channel_name("UserIn0Tracetrace"), channel_name("Custom")
    ('PhaseRetrace', 'UserIn0Trace', 'Custom')
    """
    match = re.match(r"(.*?(?:Retrace|Trace))", label)
    return match.group(1) if match else label


def channel_unit(name: str) -> str:
    """SI unit of an Asylum channel from its name ('' when unknown).

    >>> channel_unit("AmplitudeRetrace"), channel_unit("PhaseTrace"), channel_unit("UserIn0Retrace"), channel_unit("Foo")
    ('m', 'deg', 'V', '')
    """
    base = re.sub(r"(Retrace|Trace)$", "", name)
    return _UNITS.get(base, "")


def layer_unit(name: str, data_unit: str) -> str:
    """The unit of an image layer or column: the stated data unit, unless the name says otherwise.

    An Igor wave has one data unit for all its layers, and Asylum writes 'm' for a layered
    image, which its phase, frequency and voltage layers do not have (SciFiReaders copies
    that 'm' into NSID files).  A phase is an angle whatever the wave's unit says, unless
    that unit is an angle too.  Then the name's unit is the channel's.

    >>> layer_unit("PhaseRetrace", "m"), layer_unit("HeightRetrace", "nm"), layer_unit("Amplitude", "V")
    ('deg', 'nm', 'V')
    >>> layer_unit("UserIn0Retrace", "m"), layer_unit("PhaseTrace", "rad"), layer_unit("Custom", "")
    ('V', 'rad', '')
    """
    by_name = channel_unit(name)
    kind = (si_unit(data_unit) or (data_unit,))[0]
    if not data_unit:
        return by_name
    if by_name and by_name != kind and kind not in ("deg", "rad") and (by_name == "deg" or kind == "m"):
        return by_name
    return data_unit
