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

from ..errors import MissingExtraError, UserError
from . import asylum
from .record import Channel, InstrumentRecord, make_record

__all__ = ["read_hdf5"]

# Band-excitation settings as pyUSID translators name them.
_BE_DRIVE = ("BE_center_frequency_[Hz]", "BE_center_frequency")


def _text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    return str(value)


def _scan(h5, h5py):
    """Main datasets (path, dataset) and the metadata attributes of the file, merged."""
    mains, metadata = [], {}

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
    return mains, metadata


def _is_main(base: str, dataset) -> bool:
    """A main dataset: not a dimension scale (NSID) nor a Position/Spectroscopic table (USID)."""
    if _text(dataset.attrs.get("CLASS", "")) == "DIMENSION_SCALE":
        return False
    if base.startswith(("Position_", "Spectroscopic_")):
        return False
    return base == "Raw_Data" or ("quantity" in dataset.attrs and "units" in dataset.attrs)


def _spectroscopic_hz(h5, dataset) -> bool:
    """True when a USID main dataset has a spectroscopic dimension in Hz."""
    ref = dataset.attrs.get("Spectroscopic_Values")
    if ref is None:
        return False
    try:
        units = h5[ref].attrs.get("units", [])
    except (KeyError, ValueError, TypeError):
        return False
    return any(_text(u) == "Hz" for u in (units if hasattr(units, "__iter__") and not isinstance(units, (str, bytes)) else [units]))


def read_hdf5(path) -> InstrumentRecord:
    """Read an NSID or USID ``.h5`` file: main datasets as channels, cantilever fields found."""
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
                            "Measurement_*/Channel_* with datasets carrying 'quantity' and 'units')")
        channels, kinds = [], set()
        for name, dataset in mains:
            quantity = _text(dataset.attrs.get("quantity", name.rsplit("/", 1)[-1]))
            channels.append(Channel(quantity, _text(dataset.attrs.get("units", "")), tuple(dataset.shape)))
            data_type = _text(dataset.attrs.get("data_type", "")).upper()
            if data_type == "IMAGE" or (data_type == "" and dataset.ndim == 2 and "Spectroscopic_Values" not in dataset.attrs):
                kinds.add("image")
            elif data_type in ("SPECTRUM", "SPECTRAL_IMAGE") or _spectroscopic_hz(h5, dataset):
                kinds.add("spectrum")
            else:
                kinds.add("image")
        convention = "NSID" if any("data_type" in d.attrs for _, d in mains) else "USID"
    found = asylum.cantilever_fields(metadata)
    for key in _BE_DRIVE:
        if key in metadata and "drive_frequency_hz" not in found:
            found["drive_frequency_hz"] = metadata[key]
    kind = "spectrum" if "spectrum" in kinds else "image"
    return make_record(path, kind, f"pycroscopy HDF5 ({convention})", channels, found)
