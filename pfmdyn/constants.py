"""Physical constants and the conditions assumed when none are given, each typed once."""
from __future__ import annotations

__all__ = ["BOLTZMANN", "ROOM_TEMPERATURE", "TIP_HEIGHT", "TIP_HEIGHT_SPREAD", "LEVER_LENGTH", "LEVER_LENGTH_SPREAD",
           "RESONANCE_RELATIVE_UNCERTAINTY", "Q_RELATIVE_UNCERTAINTY"]

BOLTZMANN = 1.380649e-23
"""J/K (exact in the SI since 2019)."""
ROOM_TEMPERATURE = 293.15
"""K (20 C): the temperature of air or water when neither a flag nor the file gives one."""
TIP_HEIGHT = 13e-6
"""m: the tip height of a typical PFM probe, assumed when neither a flag nor the file gives one (no
instrument file records it).  Datasheets of common conductive PFM probes give 10-17 um (Bruker
SCM-PIT-V2 10-15, Nanosensors PPP-EFM 10-15, Olympus OMCL-AC240TM 14, MikroMasch HQ:NSC18/Pt 15,
BudgetSensors Multi75E-G 17)."""
TIP_HEIGHT_SPREAD = 2.5e-6
"""m: standard uncertainty of the assumed :data:`TIP_HEIGHT`, a uniform spread over 8.7-17.3 um (the
datasheets' 10-17 um and a little beyond); k1 can depend on it steeply, so it enters k1's uncertainty
with its share."""
LEVER_LENGTH = 225e-6
"""m: the length of a typical PFM lever (225-240 um on the same datasheets), assumed where only the
ratio of the assumed tip height to the length acts and no length is known."""
LEVER_LENGTH_SPREAD = 0.1
"""Relative standard uncertainty of the assumed :data:`LEVER_LENGTH` (levers of 180-270 um)."""
RESONANCE_RELATIVE_UNCERTAINTY = 1e-3
"""Relative standard uncertainty of a resonance frequency (free or contact) when neither a flag nor the file
gives one: a resonance found by a tune, a thermal fit or contact-resonance tracking moves by about 0.1 %
between repeats (drift of the lever's temperature, the load, a peak's fitted centre at Q 50-500).  Every
command that takes resonances as numbers (``discrepancy`` on a table, ``stiffness``) assumes it, and says so."""
Q_RELATIVE_UNCERTAINTY = 0.05
"""Relative standard uncertainty of a Q value when the file gives none (instrument fits of a peak's width)."""
