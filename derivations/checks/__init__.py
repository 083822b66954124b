"""Checks that give each claim of the paper a computed verdict.

Importing this package registers every check in :data:`core.REGISTRY`.
"""
from . import core  # noqa: F401
from . import electrostatics, flexural, limits, numbers, torsion  # noqa: F401  (registration)
