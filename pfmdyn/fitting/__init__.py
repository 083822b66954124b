"""The fitting core shared by ``pfmdyn discrepancy`` and ``pfmdyn map``.

* :mod:`~pfmdyn.fitting.parameters`: a nonlinear parameter (public name, unit, internal
  transform, bounds, null value, seeds), in the spirit of lmfit's ``Parameter``;
* :mod:`~pfmdyn.fitting.projection`: variable projection of complex linear amplitudes, the
  Jacobian of the projected residual and the covariance from a normal matrix, batched over
  leading axes (a map block of pixels and a single spectrum run the same code), and a spectrum's
  rows folded per frequency for a design linear in the bias;
* :mod:`~pfmdyn.fitting.batched`: a Levenberg-Marquardt iteration over variable projection that
  fits a block of spectra at once (``pfmdyn map``'s beam and SHO models), and their covariance;
* :mod:`~pfmdyn.fitting.trust_region`: bounded nonlinear least squares by SciPy's trust-region reflective
  steps, compiled (a discrepancy analysis's fits);
* :mod:`~pfmdyn.fitting.noise`: the noise of a spectrum and the gap, the noise-normalised RMS
  residual (1 = fitted to the noise).
* :mod:`~pfmdyn.fitting.result`: a fit's result, JSON-ready fields (``to_dict()``) and a text
  summary (``report()``);
* :mod:`~pfmdyn.fitting.workers`: worker processes for independent fits (the maps' blocks, a
  spectrum's candidate effects) and the CPU seconds a budget counts.

A compute layer below the engines: nothing here imports :mod:`pfmdyn.discrepancy` or
:mod:`pfmdyn.maps`.
"""
