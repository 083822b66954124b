"""Checks that give each claim of the paper's registry a computed verdict.

Importing this package registers every check in :data:`core.REGISTRY`.  The audit of the
paper's text (cross-references, symbols, statements) adds its own checks
(``pfmdyn.audit.register``), building on these.
"""
from . import core  # noqa: F401
# Import order is the order of the verdict table and of the errata list (roughly the paper's).
from . import flexural, limits, torsion, numbers, electrostatics  # noqa: F401,I001  (registration)
from . import detection  # noqa: F401,E402  (the detection point: claims beyond the paper)
from . import drives  # noqa: F401,E402  (the base drive: beyond the paper)
from . import calibration  # noqa: F401,E402  (the free lever's calibration: claims beyond the paper)
