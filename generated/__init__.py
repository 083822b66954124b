# generated — do not edit. Written by pfmdyn; see derivations/ for the source.
