"""Checks that give each claim of the paper a computed verdict.

Importing this package registers every check in :data:`core.REGISTRY`.
"""
from . import core  # noqa: F401
# Import order is the order of the verdict table and of the errata list (roughly the paper's).
from . import flexural, limits, torsion, numbers, electrostatics  # noqa: F401,I001  (registration)
from . import detection  # noqa: F401,E402  (the detection point: claims beyond the paper)
from . import statements, xref  # noqa: F401,E402  (the text audit; empty without the transcription)
