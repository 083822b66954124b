"""pfmdyn: cantilever dynamics in Piezoresponse Force Microscopy, derived and verified.

The numeric API never needs SymPy; the symbolic source lives in :mod:`pfmdyn.derivations`.
"""
__version__ = "0.1.0"
