"""JSON Schemas of the release files, generated from the pydantic models and shipped.

``python -m povagent.dataset.schema`` rewrites ``povagent/schemas/*.schema.json``; a test checks
the shipped files equal what the models generate, so the two cannot drift. Validation of files
uses the same schemas, generated in the running process, with ``jsonschema`` (every error, with its
JSON path); the shipped files are for tools outside povagent.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

from jsonschema import Draft202012Validator
from pydantic import TypeAdapter

from povagent.dataset.release_models import DatasetMeta, ExplorationRecord, PairEntry

#: Schema file name -> the type it describes.
SCHEMA_TYPES: dict[str, Any] = {
    "pair_file": list[PairEntry],
    "exploration_log": list[ExplorationRecord],
    "per_image_visible_objects": dict[str, list[str]],
    "meta": DatasetMeta,
}

_TITLES = {
    "pair_file": "POVBench house file (<house_id>.json): the list of (observer, anchor) pairs",
    "exploration_log": "POVBench exploration_log.json: one record per exploration frame",
    "per_image_visible_objects": "POVBench per_image_visible_objects.json: objectTypes visible per frame",
    "meta": "POVBench meta.json: free-form dataset metadata",
}


def generate_schema(name: str) -> dict[str, Any]:
    """The JSON Schema for one release file, from the models."""
    schema = TypeAdapter(SCHEMA_TYPES[name]).json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = _TITLES[name]
    return schema


def schema_text(name: str) -> str:
    """The schema as it is written to disk (sorted keys, 2-space indent, final newline)."""
    return json.dumps(generate_schema(name), indent=2, sort_keys=True) + "\n"


@cache
def validator(name: str) -> Draft202012Validator:
    """A compiled validator for the schema ``name``, generated from the models (the shipped file
    holds the same text, a test makes sure): a member added to a closed set such as the
    directions registry is accepted by the running code at once, not after a regeneration."""
    return Draft202012Validator(generate_schema(name))


def write_schemas(folder: Path) -> list[Path]:
    """Write every schema into ``folder``; returns the paths written."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name in SCHEMA_TYPES:
        p = folder / f"{name}.schema.json"
        p.write_text(schema_text(name), encoding="utf-8")
        out.append(p)
    return out


if __name__ == "__main__":
    for path in write_schemas(Path(__file__).resolve().parent.parent / "schemas"):
        print(path)
