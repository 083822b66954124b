"""pycroscopy HDF5 files (NSID and USID conventions), read with :mod:`h5py`.

* NSID (pyNSID/sidpy): each main dataset carries ``quantity``, ``units`` and ``data_type``
  (``IMAGE``, ``SPECTRUM``, ...); an instrument's original settings are the attributes of a
  sibling ``original_metadata`` group.
* USID (pyUSID): main datasets (``Raw_Data`` and others) carry ``quantity`` and ``units``
  plus references to ``Position_*`` and ``Spectroscopic_*`` datasets; acquisition settings
  are attributes of the ``Measurement_*`` groups.  A spectroscopic dimension in Hz (band
  excitation) makes the file a spectrum.

Asylum settings found in either place are mapped by :mod:`pfmdyn.io.asylum`.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MissingExtraError, UserError
from ..names import canonical
from . import asylum
from .record import (
    FIELDS,
    InstrumentRecord,
    attribute_texts,
    make_channel,
    make_record,
    si_spectrum,
    si_unit,
)

__all__ = ["read_hdf5", "is_usid_main"]

# Band-excitation settings as pyUSID translators name them.
_BE_DRIVE = ("BE_center_frequency_[Hz]", "BE_center_frequency")


def _attribute(value) -> str:
    return attribute_texts(value)[0] if np.size(value) == 1 else " ".join(attribute_texts(value))


def is_usid_main(dataset) -> bool:
    """A USID main dataset: it references its Position_ and Spectroscopic_ tables."""
    return "Spectroscopic_Values" in dataset.attrs and "Position_Indices" in dataset.attrs


def _scan(h5, h5py):
    """Main datasets (path, dataset) and the metadata attributes of the file, merged."""
    # pfmdyn's own map files keep the cantilever on the root (named as pfmdyn's fields).
    mains, metadata = [], dict(h5.attrs)

    def visit(name, obj):
        base = name.rsplit("/", 1)[-1]
        if isinstance(obj, h5py.Group):
            # pyNSID nests dictionaries as sub-groups of (original_)metadata; pyUSID keeps
            # acquisition settings on the Measurement_* groups.
            parts = name.split("/")
            if base.startswith("Measurement_") or "original_metadata" in parts or "metadata" in parts:
                metadata.update({k: v for k, v in obj.attrs.items()})
        elif _is_main(base, obj):
            mains.append((name, obj))

    h5.visititems(visit)
    # Some converters keep the instrument's whole note as one text attribute ('Key: value' lines).
    for value in list(metadata.values()):
        text = _attribute(value)
        if "\n" in text or "\r" in text:
            for key, item in asylum.parse_note(text).items():
                metadata.setdefault(key, item)
    return mains, metadata


def _is_main(base: str, dataset) -> bool:
    """A main dataset: not a dimension scale (NSID) nor a Position/Spectroscopic table (USID)."""
    if _attribute(dataset.attrs.get("CLASS", "")) == "DIMENSION_SCALE":
        return False
    if base.startswith(("Position_", "Spectroscopic_")):
        return False
    if base == "response" and "frequency_hz" in dataset.parent or base == "contact_frequency_hz":
        return True         # pfmdyn's plain map layout, its map of contact resonances
    return base == "Raw_Data" or is_usid_main(dataset) or ("quantity" in dataset.attrs and "units" in dataset.attrs)


def _frequency_axis(h5, dataset):
    """Frequencies (Hz) of a main dataset's frequency dimension, or None when it has none.

    USID: a row of ``Spectroscopic_Values`` whose unit is a frequency (one cycle of it);
    NSID: a dimension scale whose ``units`` is a frequency.  Any SI prefix (kHz, MHz).
    """
    if dataset.name.rsplit("/", 1)[-1] == "response" and "frequency_hz" in dataset.parent:
        return np.asarray(dataset.parent["frequency_hz"][()], dtype=float).ravel()
    ref = dataset.attrs.get("Spectroscopic_Values")
    if ref is not None:
        try:
            table = h5[ref]
        except (KeyError, ValueError, TypeError):
            return None
        units = [_attribute(u) for u in np.ravel(table.attrs.get("units", []))]
        for row, unit in enumerate(units):
            converted = si_unit(unit)
            if converted and converted[0] == "Hz":
                values = np.asarray(table[row if table.ndim > 1 else slice(None)]).ravel()
                # Several spectroscopic dimensions repeat the frequencies: keep one cycle.
                return np.unique(values) * converted[1]
        return None
    for dim in range(dataset.ndim):
        for scale in dataset.dims[dim].values():
            converted = si_unit(_attribute(scale.attrs.get("units", "")))
            if converted and converted[0] == "Hz" and scale.shape == (dataset.shape[dim],):
                return np.asarray(scale[()], dtype=float) * converted[1]
    return None


def _spectroscopic_size(h5, dataset) -> int:
    ref = dataset.attrs.get("Spectroscopic_Values")
    try:
        return int(h5[ref].shape[-1]) if ref is not None else 0
    except (KeyError, ValueError, TypeError):
        return 0


def _names(mains) -> list[str]:
    """Channel names: the ``quantity`` of each dataset, with the dataset's name when two share one."""
    quantities = [_attribute(d.attrs.get("quantity", "")) or name.rsplit("/", 1)[-1] for name, d in mains]
    return [q if quantities.count(q) == 1 else f"{q} ({name.rsplit('/', 1)[-1]})"
            for q, (name, _) in zip(quantities, mains)]


def read_hdf5(path) -> InstrumentRecord:
    """Read an NSID or USID ``.h5`` file: main datasets as channels, cantilever fields found.

    A dataset with a frequency dimension is a spectrum; a single one (one position) is
    returned in SI as the record's ``spectrum``.
    """
    path = Path(path)
    try:
        import h5py
    except ImportError:
        raise MissingExtraError("h5py", "files") from None
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise UserError(f"{path}: not a readable HDF5 file ({' '.join(str(exc).split())})") from None
    with h5:
        mains, metadata = _scan(h5, h5py)
        if not mains:
            raise UserError(f"{path}: no pycroscopy dataset found (expected NSID/USID groups "
                            "Measurement_*/Channel_* with datasets carrying 'quantity' and 'units', "
                            "or pfmdyn's map layouts: response, frequency_hz; contact_frequency_hz)")
        channels, kinds, notes, spectra = [], set(), [], []
        for label, (name, dataset) in zip(_names(mains), mains):
            unit = "Hz" if name.endswith("contact_frequency_hz") else \
                asylum.layer_unit(_attribute(dataset.attrs.get("quantity", "")), _attribute(dataset.attrs.get("units", "")))
            channels.append(make_channel(label, unit, dataset.shape))
            data_type = _attribute(dataset.attrs.get("data_type", "")).upper()
            frequency = _frequency_axis(h5, dataset)
            if frequency is not None and data_type not in ("IMAGE", "IMAGE_STACK"):
                kinds.add("spectrum")
                points = dataset.size // max(len(frequency), 1)
                if points == 1:
                    spectra.append(si_spectrum(path, frequency, "Hz", np.ravel(dataset[()]), unit))
                else:
                    notes.append(f"{label}: {points} spectra of {len(frequency)} frequencies ({frequency.min():.6g} "
                                 f"to {frequency.max():.6g} Hz)")
            elif name.endswith("contact_frequency_hz"):
                kinds.add("image")
                notes.append(f"{label}: a map of contact resonances (pfmdyn map, or stiffness with an output folder, "
                             "gives k1 at each pixel)")
            elif data_type in ("SPECTRUM", "SPECTRAL_IMAGE"):
                kinds.add("spectrum")
                notes.append(f"{label}: its spectral dimension has no frequency unit")
            elif data_type == "" and _spectroscopic_size(h5, dataset) > 1:
                kinds.add("curve")          # USID curves against bias, time, ... (not a frequency)
            else:
                kinds.add("image")
        convention = ("NSID" if any("data_type" in d.attrs for _, d in mains) else
                      "USID" if any(name.endswith("Raw_Data") or "quantity" in d.attrs for name, d in mains)
                      else "")
    # Asylum's names first, then pfmdyn's own (any spelling pfmdyn.names knows), then the
    # band-excitation settings.
    own = {canonical(key): key for key in metadata if canonical(key) in FIELDS}
    found, problems = {}, []
    for keys in (asylum.NOTE_KEYS, own, *({"drive_frequency": key} for key in _BE_DRIVE)):
        more, said = asylum.cantilever_fields(metadata, keys)
        found, problems = {**more, **found}, problems + said
    kind = next(k for k in ("spectrum", "image", "curve") if k in kinds)
    instrument = f"pycroscopy HDF5 ({convention})" if convention else "HDF5 (pfmdyn map layout)"
    return make_record(path, kind, instrument, channels, found,
                       notes + problems, spectra[0] if len(spectra) == 1 else None)
