"""Igor binary waves as Asylum's software saves them, written by igorwriter: shared by the tests of the
instrument readers and of DART images."""
import pytest


def asylum_note(values: dict, end="\r") -> str:
    """A note as Asylum writes it: settings first, then the lever, one ``Key: value`` per line."""
    lines = ["ScanSize: 2e-06", "FastScanSize: 2e-06", "SlowScanSize: 1.5e-06", "ScanRate: 1.0016", "ScanPoints: 16", "ScanLines: 12",
             "ImagingMode:PFM Mode", "Date: 2019-03-07", "Time: 11:42:09 AM"]
    return end.join(lines + [f"{k}: {v}" for k, v in values.items()] + ["UserName: Müller µ°", ""])


def igor_wave(path, data, name="wave0", scales=(), data_unit=None, labels=None, note=None, unicode=True):
    """Write ``data`` as igorwriter does for Igor; ``scales`` = (start, step, unit) per dimension."""
    igorwriter = pytest.importorskip("igorwriter")
    wave = igorwriter.IgorWave(data, name=name, unicode=unicode)
    for dim, (start, step, unit) in zip("xyzt", scales):
        wave.set_dimscale(dim, start, step, unit)
    if data_unit is not None:
        wave.set_datascale(data_unit)
    for dim, names in (labels or {}).items():
        for i, label in enumerate(names):
            wave.set_dimlabel(dim, i, label)
    if note is not None:
        wave.set_note(note)
    wave.save(str(path))
    return path
