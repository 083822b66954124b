"""The project's sign convention for the electrostatic drives (stated once, quoted by the checks).

``u`` (tip deflection), ``d1`` (vertical surface displacement), ``f0`` (tip force) and ``q0``
(distributed load) are positive away from the surface.  The capacitive force between tip or
cantilever and surface is attractive for either sign of the bias, so a physical electrostatic
drive has ``f0 < 0`` and ``q0 < 0``; its first harmonic, proportional to ``V_ac (V_dc - V_surf)``,
changes sign with the bias.  Verdicts that depend on this choice say so in their evidence.
"""

from ..evidence import Tex, say, text

_F0, _Q0 = Tex("f_0", "f0"), Tex("q_0", "q0")
SIGN_CONVENTION_SENTENCE = say(_F0, " and ", _Q0, " count positive away from the surface (along ", Tex("+u", "+u"),
                               ", the tip deflection); the capacitive tip-surface force is attractive, so physical ",
                               _F0, " and ", _Q0, " are negative")
"""The convention as a sentence of evidence (typeset in the errata)."""
SIGN_CONVENTION = text(SIGN_CONVENTION_SENTENCE)
"""The same in plain text."""
