"""Physical constants and the conditions assumed when none are given, each typed once."""
from __future__ import annotations

__all__ = ["BOLTZMANN", "ROOM_TEMPERATURE"]

BOLTZMANN = 1.380649e-23
"""J/K (exact in the SI since 2019)."""
ROOM_TEMPERATURE = 293.15
"""K (20 C): the temperature of air or water when neither a flag nor the file gives one."""
