"""pfmdyn: cantilever dynamics in Piezoresponse Force Microscopy, derived and verified.

The numeric API never needs SymPy; the symbolic source lives in :mod:`pfmdyn.derivations`.
"""
__version__ = "0.1.0"

from .cantilever import Cantilever, Contact
from .transfer import (free_end_transfer, frictionless_stiff_transfer, frictionless_transfer,
                       indentation_stiff_transfer, indentation_transfer, pinned_transfer,
                       sliding_friction_transfer, tip_slope_transfer, torsion_elastic_transfer,
                       torsion_force_transfer)

from .generated import families as _families

# One transfer function per registry family that has one (derivations/families.py).
__all__ = ["Cantilever", "Contact", *sorted(f.function for f in _families.FAMILIES if f.function)]
