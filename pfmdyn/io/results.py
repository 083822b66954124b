"""Results written as JSON: one record per number, one envelope per document, one writer.

Every number a command reports is a *record* (lmfit's Parameter in xarray's attribute style)::

    {"value": 2.1e-12, "stderr": 3e-14, "unit": "kg", "status": "fitted"}

under a key of :mod:`pfmdyn.names` (its unit looked up there, ``"1"`` for pure numbers), built by
:func:`quantity`.  ``status`` says where the value comes from (:data:`STATUSES`); ``why`` is there
exactly when the value was not fitted, derived or given.  A value the data leave undetermined is
``null`` with status ``undetermined``; an infinite one (an undamped mode's Q) is ``"inf"`` with status
``unbounded``.  An array carries ``dims`` (its axes' names); a complex value is ``{"real", "imag"}``.

Every document is one envelope (:func:`document`): ``schema``, ``command``, ``kind``, ``source``
(where the data came from), ``lever`` and ``results`` (records), ``fit`` (how the fit went, records
too), ``notes`` (sentences), and in a discrepancy report ``missing_effects``.  The package holds a
JSON Schema per kind (``pfmdyn/schemas/``, :func:`schema_of`); :func:`to_dataset` reads a document as
an :class:`xarray.Dataset`.

JSON has no NaN or infinity: the writer (:func:`write_json`, :func:`dumps`) turns any other
non-finite number into ``null`` and NumPy scalars and arrays into plain numbers and lists.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from ..errors import UserError

__all__ = ["SCHEMA", "STATUSES", "EXPLAINED", "quantity", "records", "document", "schema_of", "to_dataset",
           "json_ready", "dumps", "write_json", "check_writable", "check_directory"]

SCHEMA = 1
"""The version of the envelope and the record; it grows when a key changes meaning or goes."""

STATUSES = {
    "fitted": "estimated by a fit to the data (stderr from the fit's covariance)",
    "derived": "computed from fitted or given values (stderr propagated)",
    "given": "given on the command line",
    "file": "read from the input file (why: which file)",
    "assumed": "a default: neither a flag nor the file gave it (why: which default)",
    "held": "held fixed in the fit (why: why it is not fitted)",
    "tied": "set by another value through a stated relation (why: the relation)",
    "undetermined": "the data do not determine it: value null (why: what is missing)",
    "unbounded": "infinite, value \"inf\" or \"-inf\" (why: e.g. no damping)",
}
"""Where a value comes from: the vocabulary of a record's ``status``."""

EXPLAINED = frozenset(STATUSES) - {"fitted", "derived", "given"}
"""The statuses whose records carry a ``why``."""

ENVELOPE = ("schema", "command", "kind", "source", "lever", "results", "fit", "notes")
"""The keys of every document (a discrepancy report adds ``missing_effects``)."""


def _plain(value):
    """A value of a record as JSON holds it: arrays to lists, a complex number to ``{real, imag}``, -0.0 as 0.0
    (a sign no reader needs: ``-0.0`` and ``0.0`` are one value).

    >>> _plain(np.array([-0.0, 1.5])), _plain(complex(-0.0, -0.0)), _plain(-0.0)
    ([0.0, 1.5], {'real': 0.0, 'imag': 0.0}, 0.0)
    """
    array = np.asarray(value)
    if np.iscomplexobj(array):
        return {"real": _plain(array.real), "imag": _plain(array.imag)}
    if array.dtype.kind == "f" and array.ndim and np.isinf(array).any():
        return [_plain(v) for v in array]      # infinity is "inf" in a list too (JSON has none)
    if array.dtype.kind == "f" and not array.ndim and np.isinf(array):
        return "inf" if array > 0 else "-inf"
    if array.dtype.kind == "f":
        return (array + 0.0).tolist()          # -0.0 + 0.0 is 0.0
    if array.dtype.kind in "iub":
        return array.tolist()
    return value


def quantity(name: str, value, stderr=None, status: str = "fitted", why: str | None = None, dims=None) -> dict:
    """The record of one number (or array, with ``dims``) under ``name``, a key of :mod:`pfmdyn.names`.

    A NaN value (or None) makes the record ``undetermined`` and an infinite one ``unbounded``; both need
    ``why``, as do the statuses of :data:`EXPLAINED`.  A non-finite stderr is written ``null``.

    >>> quantity("k1", 152.0, 3.1)
    {'value': 152.0, 'stderr': 3.1, 'unit': 'N/m', 'status': 'fitted'}
    >>> quantity("quality_factor", float("inf"), why="no internal friction in the model")["value"]
    'inf'
    >>> quantity("added_mass", float("nan"), 1.0, why="the two sweeps do not differ")
    {'value': None, 'stderr': None, 'unit': 'kg', 'status': 'undetermined', 'why': 'the two sweeps do not differ'}
    >>> quantity("tip_position", 0.9, status="assumed")
    Traceback (most recent call last):
    ...
    ValueError: tip_position: a value assumed needs a why
    """
    from ..names import NAMES

    unit = NAMES[name].unit
    if isinstance(value, (float, np.floating)) or value is None:
        if value is None or math.isnan(value):
            value, stderr, status = None, None, "undetermined"
        elif math.isinf(value):
            value, stderr, status = ("inf" if value > 0 else "-inf"), None, "unbounded"
    if dims is None and np.ndim(np.asarray(value, dtype=object)) > 0:
        raise ValueError(f"{name}: an array needs its dims")
    if status not in STATUSES:
        raise ValueError(f"{name}: status {status!r} is none of {', '.join(STATUSES)}")
    if (why is not None) != (status in EXPLAINED):
        raise ValueError(f"{name}: a value {status} {'needs a why' if why is None else 'takes no why'}")
    record = {"value": _plain(value), "stderr": _plain(stderr), "unit": unit, "status": status}
    if isinstance(record["stderr"], float) and not math.isfinite(record["stderr"]):
        record["stderr"] = None
    if why is not None:
        record["why"] = why
    if dims is not None:
        record["dims"] = list(dims)
    return record


def records(values: dict, status: str = "given", why: str | None = None) -> dict:
    """Records of every known value of ``values`` (name -> number; None skipped), all of one ``status``.

    >>> records({"spring_constant": 2.0, "tip_mass_ratio": None})
    {'spring_constant': {'value': 2.0, 'stderr': None, 'unit': 'N/m', 'status': 'given'}}
    """
    return {name: quantity(name, value, status=status, why=why) for name, value in values.items()
            if value is not None}


def document(command: str, kind: str, source: dict | None, lever: dict | None, results: dict,
             fit: dict | None = None, notes=(), missing_effects=None) -> dict:
    """The envelope of every JSON document: ``schema``, what wrote it (``command``, ``kind``), where the
    data came from (``source``: ``path``, ``instrument``, ...), the ``lever`` it assumed and the
    ``results`` (records), how the ``fit`` went and ``notes`` (sentences); a discrepancy report adds its
    ``missing_effects`` (a list, empty when the model explains the data).

    >>> doc = document("stiffness", "contact_resonance", {"path": "tune.csv"}, None,
    ...                {"k1": quantity("k1", 152.0, 3.1)})
    >>> doc["schema"], doc["kind"], doc["results"]["k1"]["unit"]
    (1, 'contact_resonance', 'N/m')
    """
    out = {"schema": SCHEMA, "command": command, "kind": kind, "source": dict(source or {}),
           "lever": lever, "results": results, "fit": fit, "notes": list(notes)}
    if missing_effects is not None:
        out["missing_effects"] = list(missing_effects)
    return out


def schema_of(command: str, kind: str) -> dict:
    """The JSON Schema of a document kind, as shipped in ``pfmdyn/schemas/COMMAND.KIND.json``.

    >>> schema_of("stiffness", "contact_resonance")["properties"]["command"]["const"]
    'stiffness'
    """
    path = Path(__file__).resolve().parent.parent / "schemas" / f"{command}.{kind}.json"
    return json.loads(path.read_text(encoding="utf-8"))


def to_dataset(doc: dict):
    """A document's records as an :class:`xarray.Dataset`: one variable per record of ``lever``,
    ``results`` and ``fit`` (``units``, ``status``, ``why`` as attributes), its standard error beside it
    as ``NAME_stderr`` named by the variable's ``ancillary_variables``; the envelope in ``attrs``.
    An undetermined value is NaN, an unbounded one infinite, a complex one complex.

    >>> ds = to_dataset(document("stiffness", "contact_resonance", {"path": "t.csv"}, None,
    ...                          {"k1": quantity("k1", [150.0, 152.0], [3.0, 3.1], dims=["mode"])}))
    >>> ds["k1"].dims, ds["k1"].attrs["units"], float(ds["k1_stderr"][1]), ds["k1"].attrs["ancillary_variables"]
    (('mode',), 'N/m', 3.1, 'k1_stderr')
    """
    try:
        import xarray
    except ImportError:
        raise UserError("to_dataset needs xarray (pip install 'pfmdyn[maps]')") from None

    variables, coords, labels = {}, {}, {}
    for group in ("lever", "results", "fit"):
        for name, record in _flat(doc.get(group) or {}):
            name = f"{group}.{name}" if name in variables or name in coords else name
            dims = tuple(record.get("dims", ()))
            value = _number(record["value"])
            if value.dtype.kind not in "fcbiu":     # a name (a medium, an effect): a label, not a number
                if dims:
                    coords[name] = xarray.Variable(dims, value)
                else:
                    labels[name] = str(record["value"])
                continue
            attrs = {"units": record["unit"], "status": record["status"], "group": group}
            if "why" in record:
                attrs["why"] = record["why"]
            if record.get("stderr") is not None:
                attrs["ancillary_variables"] = f"{name}_stderr"
                variables[f"{name}_stderr"] = xarray.Variable(
                    dims, _number(record["stderr"]), {"units": record["unit"], "long_name": f"standard error of {name}"})
            variables[name] = xarray.Variable(dims, value, attrs)
    attrs = {"schema": doc["schema"], "command": doc["command"], "kind": doc["kind"],
             "source": json.dumps(doc.get("source") or {}), "notes": "\n".join(doc.get("notes") or ())}
    if "missing_effects" in doc:
        attrs["missing_effects"] = ", ".join(doc["missing_effects"])
    return xarray.Dataset(variables, coords=coords, attrs={**attrs, **labels})


def _flat(records: dict, prefix: str = ""):
    """``(name, record)`` of a group of records and of the groups inside it (``GROUP.NAME``; lists of
    groups, such as a fit's steps, are left to the JSON)."""
    for key, entry in records.items():
        if isinstance(entry, dict) and "status" in entry:
            yield prefix + key, entry
        elif isinstance(entry, dict):
            yield from _flat(entry, f"{prefix}{key}.")


def _number(value):
    """A record's value as a NumPy array: null to NaN, ``"inf"`` to infinity, ``{real, imag}`` to complex."""
    if isinstance(value, dict):
        return _number(value["real"]) + 1j * _number(value["imag"])
    if value is None:
        return np.array(np.nan)
    if isinstance(value, str):
        return np.array(float(value) if value in ("inf", "-inf") else value)
    if isinstance(value, list) and any(v is None or v in ("inf", "-inf") for v in np.ravel(np.asarray(value, object))):
        return np.array([_number(v) for v in value], dtype=float)
    return np.asarray(value)


def json_ready(obj):
    """A copy of ``obj`` that JSON can hold: non-finite numbers to None, NumPy to Python.

    >>> json_ready({"q": [np.float64(80.0), float("inf")], "n": np.int64(2), "k1": float("nan")})
    {'q': [80.0, None], 'n': 2, 'k1': None}
    """
    if isinstance(obj, dict):
        return {key: json_ready(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [json_ready(value) for value in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def dumps(document) -> str:
    """``document`` as JSON text (indented, non-finite numbers as null).

    >>> print(dumps({"value": float("nan")}))
    {
      "value": null
    }
    """
    return json.dumps(json_ready(document), indent=2, allow_nan=False)


def write_json(path, document) -> None:
    """Write ``document`` to ``path`` as JSON (:func:`dumps`, ending in a newline); a path that
    cannot be written is one :class:`~pfmdyn.errors.UserError` line.

    >>> write_json("/nonexistent/folder/out.json", {})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /nonexistent/folder/out.json: No such file or directory
    """
    text = dumps(document) + "\n"
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from None


def check_writable(*paths, figure: bool = False) -> None:
    """A :class:`~pfmdyn.errors.UserError` naming the first of ``paths`` (None: skipped) that
    cannot be written as a file; checked before anything is computed, so that a command
    writing several outputs writes none when one of them would fail.  ``figure``: the paths
    are figures, their suffix must be a format matplotlib writes.  ``-`` (standard output) is
    a path of a document, not of a figure.

    >>> check_writable(None, "/nonexistent/folder/out.json")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /nonexistent/folder/out.json: no such directory /nonexistent/folder
    """
    for path in paths:
        if path is None or (str(path) == "-" and not figure):
            continue
        path = Path(path)
        folder = path.parent if str(path.parent) else Path(".")
        if path.is_dir():
            problem = "it is a directory"
        elif not folder.is_dir():
            problem = f"{'not a directory' if folder.exists() else 'no such directory'} {folder}"
        elif not os.access(folder, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
            problem = "permission denied"
        elif figure and path.suffix.lower().lstrip(".") not in _figure_formats():
            problem = f"matplotlib writes no {path.suffix or 'suffix-less'} figures (use .png, .pdf or .svg)"
        else:
            continue
        raise UserError(f"cannot write {path}: {problem}")


def _figure_formats() -> set:
    from matplotlib.backend_bases import FigureCanvasBase
    return set(FigureCanvasBase.get_supported_filetypes())


def check_directory(path) -> None:
    """A :class:`~pfmdyn.errors.UserError` when ``path`` cannot be (or become) a directory that
    the command writes into: a file in the way, a file among its parents, no permission.

    >>> check_directory("/dev/null/results")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write into /dev/null/results: /dev/null is not a directory
    """
    path = Path(path)
    existing = next((p for p in (path, *path.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise UserError(f"cannot write into {path}: {existing} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise UserError(f"cannot write into {path}: permission denied on {existing}")
