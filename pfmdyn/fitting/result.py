"""The result of a fitting command: JSON-ready fields, read as a mapping, and a text report.

``pfmdyn discrepancy`` (:class:`pfmdyn.discrepancy.report.DiscrepancyReport`) and ``pfmdyn map``
(:class:`pfmdyn.maps.result.MapResult`) return one: ``to_dict()`` gives the fields (the JSON
keys), ``report()`` the summary the command prints, and what is not a field (the fits behind a
report, the map's pixel shape) is an attribute, not a hidden key.
"""
from __future__ import annotations

from collections.abc import Mapping

__all__ = ["Result"]


class Result(Mapping):
    """Read-only fields plus attributes; subclasses give :meth:`report`.

    >>> r = Result({"gap": 1.02}, note="kept")
    >>> r["gap"], r.to_dict(), r.note
    (1.02, {'gap': 1.02}, 'kept')
    >>> r.updated(stride=2).to_dict()
    {'gap': 1.02, 'stride': 2}
    """

    def __init__(self, fields: dict, **attributes):
        self._fields = dict(fields)
        self._attributes = attributes
        for name, value in attributes.items():
            setattr(self, name, value)

    def __getitem__(self, key):
        return self._fields[key]

    def __iter__(self):
        return iter(self._fields)

    def __len__(self) -> int:
        return len(self._fields)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._fields!r})"

    def to_dict(self) -> dict:
        """The fields as a new dict (JSON-ready)."""
        return dict(self._fields)

    def updated(self, **fields) -> "Result":
        """A copy with ``fields`` added or replaced (attributes kept)."""
        return type(self)({**self._fields, **fields}, **self._attributes)

    def report(self) -> str:
        """The text summary."""
        raise NotImplementedError
