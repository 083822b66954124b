"""Validate pfmdyn's JSON documents against the schemas shipped in ``pfmdyn/schemas``: the shape
(jsonschema) and the keys (every key outside the envelope and the record a name of ``pfmdyn.names``)."""
from __future__ import annotations

import functools
import json
from pathlib import Path

import jsonschema
import referencing

from pfmdyn.io.results import ENVELOPE
from pfmdyn.names import GROUPS, NAMES

SCHEMAS = Path(__file__).resolve().parent.parent / "pfmdyn" / "schemas"
RECORD = {"value", "stderr", "unit", "status", "why", "dims"}


@functools.cache
def _registry():
    resources = []
    for path in SCHEMAS.glob("*.json"):
        schema = json.loads(path.read_text())
        resources.append((schema["$id"], referencing.Resource.from_contents(schema)))
    return referencing.Registry().with_resources(resources)


def validate(doc: dict) -> None:
    """Raise when ``doc`` (as written, after a JSON round trip) breaks its kind's schema or names."""
    doc = json.loads(json.dumps(doc))
    path = SCHEMAS / f"{doc['command']}.{doc['kind']}.json"
    assert path.exists(), f"no schema for {doc['command']} {doc['kind']}"
    schema = json.loads(path.read_text())
    jsonschema.Draft202012Validator(schema, registry=_registry()).validate(doc)
    assert set(doc) <= set(ENVELOPE) | {"missing_effects"}
    for group in ("lever", "results", "fit"):
        _names(doc[group], group)


def _names(entry, where):
    if isinstance(entry, list):
        for i, item in enumerate(entry):
            _names(item, f"{where}[{i}]")
    elif isinstance(entry, dict):
        if "status" in entry and set(entry) <= RECORD:
            return
        for key, value in entry.items():
            assert key in NAMES or key in GROUPS, f"{where}: key {key!r} is not a name of pfmdyn.names"
            _names(value, f"{where}.{key}")
