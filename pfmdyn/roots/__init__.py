"""Certified resonance roots and the branches they form against contact stiffness."""
