"""Symbolic source of pfmdyn: the beam equation solved for every boundary-condition family.

Nothing here imports :mod:`pfmdyn.generated`; the numeric runtime never imports SymPy.
Installed as ``pfmdyn.derivations``.
"""
