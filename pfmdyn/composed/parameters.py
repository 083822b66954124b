"""The composed lever's arguments by name: its parameters (:class:`Parameters`, typed, built in one place
from a probe), the partials the Jacobians give, and the drives the system is solved for.

Separate because every other module of :mod:`pfmdyn.composed`, and every caller, speaks these names;
the tip point's parameters are the generated pieces' (:data:`pfmdyn.generated.lever_pieces.PARAMETERS`
after ``beta``), ``gamma`` (where the point lies) the assembly's own.
"""
from __future__ import annotations

from typing import NamedTuple

from ..generated import lever_pieces as pieces


class Parameters(NamedTuple):
    """The lever's parameters, the one argument after ``beta`` of every function of :mod:`pfmdyn.composed`,
    typed and named.  Built from a probe in one place, :meth:`pfmdyn.cantilever.Cantilever.model_parameters`
    (damped with :meth:`~typing.NamedTuple._replace`); each may be an array (broadcast with ``beta``).

    The tip point's parameters are the generated pieces' (``beta`` aside); ``gamma`` places the point:

    >>> tuple(p for p in PARAMETERS if p != "gamma") == pieces.PARAMETERS[1:]
    True
    """

    k: float
    """The lever's spring constant (N/m)."""
    kvv: float
    """The contact's vertical spring in the lever's axes (N/m; complex with a contact dashpot)."""
    kll: float
    """Its longitudinal spring in the lever's axes (N/m)."""
    kvl: float
    """Their coupling (N/m; a tilt's)."""
    H: float
    """The tip height (m)."""
    L: float
    """The lever's length (m)."""
    mu: float
    """The tip's mass over the lever's."""
    gamma: float
    """The tip's position over the length, ``0 < gamma <= 1``."""
    rho_g: float
    """The tip's radius of gyration over the length."""


PARAMETERS = Parameters._fields
JACOBIAN_PARAMETERS = ("beta", "k", "kvv", "kll", "kvl", "mu", "gamma", "rho_g")
"""The parameters of :func:`characteristic_and_jacobian`'s partials (and of the slope at the end)."""
SPOT_JACOBIAN_PARAMETERS = ("beta", "sigma", "k", "kvv", "kll", "kvl", "mu", "gamma", "rho_g")
DRIVES = ("d1", "d2", "f0", "m0", "q0", "y0")
"""Every drive the system is solved for: the tip's (surface displacements ``d1, d2``, force ``f0``,
couple ``m0``), the distributed load ``q0`` and the base (the clamp's displacement ``y0``)."""
TIP_DRIVES = ("d1", "d2", "f0", "q0")
"""The drives the read-outs give by default (the paper's)."""
PROBE_DRIVES = ("f_probe", "m_probe")
"""A force and a couple at a bare point of the lever (the probe), where asked."""
_Q0, _Y0 = DRIVES.index("q0"), DRIVES.index("y0")
_POINT = pieces.JACOBIAN_PARAMETERS


def _drive_columns(drives, known) -> list[int]:
    unknown = [d for d in drives if d not in known]
    if unknown:
        raise ValueError(f"unknown drive {unknown[0]!r}: one of {', '.join(known)}")
    return [known.index(d) for d in drives]
