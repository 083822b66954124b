"""The project's sign convention for the electrostatic drives (stated once, quoted by the checks).

``u`` (tip deflection), ``d1`` (vertical surface displacement), ``f0`` (tip force) and ``q0``
(distributed load) are positive away from the surface.  The capacitive force between tip or
cantilever and surface is attractive for either sign of the bias, so a physical electrostatic
drive has ``f0 < 0`` and ``q0 < 0``; its first harmonic, proportional to ``V_ac (V_dc - V_surf)``,
changes sign with the bias.  Verdicts that depend on this choice say so in their evidence.
"""

SIGN_CONVENTION = ("f0 and q0 count positive away from the surface (along +u, the tip deflection); the capacitive "
                   "tip-surface force is attractive, so physical f0 and q0 are negative")
