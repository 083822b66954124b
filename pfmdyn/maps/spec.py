"""What a beam map model is asked to fit: the mechanisms its spec names
(``elastic[+viscous][+contact][+distributed]``, the model ``pfmdyn map`` is given) and the frequency bands of
its spectra, one per contact mode driven.
"""
from __future__ import annotations

import numpy as np

from ..errors import UserError

__all__ = ["MECHANISMS", "bands", "model_name", "parse_model"]

MECHANISMS = ("internal", "viscous", "contact", "distributed")
"""Mechanisms a map model may hold: damping (``internal`` always: the baseline; viscous drag, a
contact dashpot) and the electrostatic load distributed along the lever (a second transfer
function, :attr:`pfmdyn.maps.beam.BeamMapModel.drives`)."""


def parse_model(spec: str) -> tuple[str, ...]:
    """Mechanisms of a model spec ``elastic[+viscous][+contact][+distributed]``.

    >>> parse_model("elastic+contact")
    ('internal', 'contact')
    """
    names = spec.split("+")
    unknown = [n for n in names[1:] if n not in MECHANISMS[1:]]
    if names[0] != "elastic" or unknown:
        raise UserError(f"unknown model {spec!r}: use 'auto', 'sho' or elastic[+viscous][+contact][+distributed]")
    return ("internal",) + tuple(m for m in MECHANISMS[1:] if m in names)


def model_name(mechanisms) -> str:
    """Inverse of :func:`parse_model`.

    >>> model_name(("internal", "viscous"))
    'elastic+viscous'
    """
    return "+".join(["elastic", *[m for m in mechanisms if m != "internal"]])


def bands(frequency_hz) -> list[slice]:
    """Split a sorted frequency vector into bands at gaps wider than 10 median steps.

    >>> bands([1.0, 2.0, 3.0, 50.0, 51.0])
    [slice(0, 3, None), slice(3, 5, None)]
    """
    f = np.asarray(frequency_hz, float)
    step = np.diff(f)
    cuts = np.flatnonzero(step > 10 * np.median(step)) + 1 if step.size else []
    edges = [0, *list(cuts), len(f)]
    return [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]

