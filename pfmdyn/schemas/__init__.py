"""The JSON Schema of each document kind the commands write (``COMMAND.KIND.json``; the envelope and
the record in ``envelope.json``): see :mod:`pfmdyn.io.results`."""
