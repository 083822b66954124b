"""The composed lever: the derived pieces assembled per frequency into one small linear system.

Each piece of the lever is derived once in ``derivations/pieces.py`` and generated in
``generated/lever_pieces.py``; here they are only put together (the dynamic-stiffness way) and read:
the beam anywhere (:func:`slope`, :func:`deflection`, :func:`response` at ``x_s = sigma L``), the
partials w.r.t. every parameter from the same system (:func:`slope_and_jacobian`), and its
determinant, the characteristic (:func:`characteristic`, :func:`characteristic_and_jacobian`).

One idea per module:

* :mod:`.parameters`: the arguments by name (:class:`Parameters`, the partials' names, the drives);
* :mod:`.segments`: a uniform segment read anywhere, in the basis that neither overflows nor cancels;
* :mod:`.assembly`: the assembled system, its partials and determinant (the general form, the reference);
* :mod:`.written_out`: the read-out by eliminating each segment's outer rows (no assembly);
* :mod:`.determinant`: the determinant written out from the segments, and its partials;
* :mod:`.readout`: the read-outs, choosing among the compiled, written-out and assembled forms;
* :mod:`.kernels`: the compiled (numba) read-out and characteristic, imported on first use;
* :mod:`.balls`: the characteristic and the blind-spot numerator in ball arithmetic (certified roots).

The written-out forms and the assembled one share the choice of basis per segment, its scale factors
and the determinant's sign (a root bracket reads the sign); the tests hold each written-out form and
each compiled kernel to the assembled system.

Every function takes ``beta`` (complex for a damped lever) and the lever's :class:`Parameters`, built in
one place from a probe (:meth:`pfmdyn.cantilever.Cantilever.model_parameters`; the discrepancy model's
:meth:`pfmdyn.discrepancy.model.Model.lever_parameters`), then where it has them the spot
``sigma = x_s / L``, the drives, the partials asked (``wrt``) and a probe's position.
"""
from __future__ import annotations

KERNELS = True
"""Whether read-outs without a probe and the characteristic run the compiled kernels
(:mod:`pfmdyn.composed.kernels`); False: the NumPy forms, the reference the tests hold them to.
Read per call by :mod:`.readout` and :mod:`.determinant` (set it here)."""

from .parameters import (DRIVES, JACOBIAN_PARAMETERS, PARAMETERS, PROBE_DRIVES,  # noqa: E402  (after KERNELS)
                         SPOT_JACOBIAN_PARAMETERS, TIP_DRIVES, Parameters)
from .determinant import characteristic, characteristic_and_jacobian  # noqa: E402
from .readout import LastReadOut, Reading, at_end, deflection, response, slope, slope_and_jacobian  # noqa: E402

__all__ = ["Parameters", "PARAMETERS", "JACOBIAN_PARAMETERS", "SPOT_JACOBIAN_PARAMETERS", "DRIVES", "TIP_DRIVES",
           "PROBE_DRIVES", "KERNELS", "slope", "deflection", "response", "slope_and_jacobian", "characteristic",
           "characteristic_and_jacobian", "Reading", "at_end", "LastReadOut"]
