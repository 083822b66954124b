"""Maps: the elastic-contact beam model (or BGlib's SHO) fitted at every pixel of a band-excitation map, on Dask.

:mod:`pfmdyn.maps.beam` is the beam response at a pixel (the mechanisms its spec names,
:mod:`pfmdyn.maps.spec`; the maps it writes, :mod:`pfmdyn.maps.outputs`);
:mod:`pfmdyn.maps.fit` fits all pixels of a block at once (the batched Levenberg-Marquardt of
:mod:`pfmdyn.fitting.batched`);
:mod:`pfmdyn.maps.sho` fits BGlib's simple harmonic oscillator the same way;
:mod:`pfmdyn.maps.bias` derives the electrostatic maps when the spectra have a bias axis;
:mod:`pfmdyn.maps.select` chooses the mechanisms (the model ``auto``);
:mod:`pfmdyn.maps.driver` reads the map, runs the blocks on a Dask scheduler and streams the
result to Zarr (:mod:`pfmdyn.maps.store`), skipping blocks an interrupted run already wrote;
:mod:`pfmdyn.maps.usid` writes the fit into a USID file in BGlib's layout;
:func:`open_result` reads the result as an :class:`xarray.Dataset`.
"""
from .beam import BeamMapModel
from .fit import fit_block
from .result import open_result

__all__ = ["BeamMapModel", "fit_block", "open_result"]
