"""The paper's printed statements, transcribed for checking only.

Nothing in :mod:`derivations` outside ``paper`` and ``checks`` reads these: the printed
forms are never used to compute anything but their own verdicts.
"""
