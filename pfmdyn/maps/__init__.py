"""Maps: the elastic-contact beam model fitted at every pixel of a band-excitation map, on Dask.

:mod:`pfmdyn.maps.fit` fits all pixels of a block at once (batched Levenberg-Marquardt);
:mod:`pfmdyn.maps.bias` derives the electrostatic maps when the spectra have a bias axis;
:mod:`pfmdyn.maps.select` chooses the mechanisms (``--model auto``);
:mod:`pfmdyn.maps.driver` reads the map, runs the blocks on a Dask scheduler and streams the
result to Zarr, skipping blocks an interrupted run already wrote.
"""
from .fit import BeamMapModel, fit_block

__all__ = ["BeamMapModel", "fit_block"]
