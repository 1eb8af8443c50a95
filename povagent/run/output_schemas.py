"""The JSON Schemas of what povagent writes: ``summary.json``, a results row, ``sweep.json`` and
a training export's ``export.json``, and ``povagent rescore-log --json``'s object, generated from their pydantic models and shipped.

``povagent schema NAME`` prints one; ``python -m povagent.run.output_schemas`` rewrites the shipped
files (``povagent/schemas/output_<name>.schema.json``), and a test checks they equal what the
models generate and that every such file a test run writes validates against them.

The shipped schemas are closed: every object a model describes says ``additionalProperties:
false``, also where the model itself lets a reader keep fields it does not know (a row written by
another version of povagent loads and rescores with its fields intact). So a field no model
declares, such as a misspelled new row field, fails the output check the tests run on every file
they make, while reading stays lenient. Maps a model declares as open (a row's ``scores``, keyed
by scorer) stay open: they are typed as maps, not as objects with properties.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from povagent.results.rows import ResultRow
from povagent.run.rescore_log import RescoredLog
from povagent.run.summary_model import RunSummary
from povagent.run.sweep_index import SweepIndex
from povagent.train.export_manifest import ExportManifest

#: Schema name -> (the model, the file it describes).
OUTPUT_MODELS: dict[str, tuple[type[BaseModel], str]] = {
    "summary": (RunSummary, "a run folder's summary.json"),
    "row": (ResultRow, "one line of a run folder's results.jsonl"),
    "sweep": (SweepIndex, "a sweep folder's sweep.json (the cell index)"),
    "export": (ExportManifest, "a training export's export.json (its options and plan)"),
    "rescore-log": (RescoredLog, "povagent rescore-log --json: another harness's logged replies scored by each rule of their set"),
}


def output_schema(name: str) -> dict[str, Any]:
    """The JSON Schema of output ``name`` (one of :data:`OUTPUT_MODELS`)."""
    model, what = OUTPUT_MODELS[name]
    schema = closed(model.model_json_schema())
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = f"povagent {name}: {what}"
    return schema


def closed(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with every object that lists ``properties`` (the root and each ``$defs`` entry)
    refusing properties it does not list (see the module docstring)."""
    for definition in [schema, *schema.get("$defs", {}).values()]:
        if "properties" in definition:
            definition["additionalProperties"] = False
    return schema


def output_schema_text(name: str) -> str:
    """The schema as shipped (sorted keys, 2-space indent, final newline)."""
    return json.dumps(output_schema(name), indent=2, sort_keys=True) + "\n"


def shipped_path(folder: Path, name: str) -> Path:
    """Where output ``name``'s schema lives under a ``schemas`` folder."""
    return folder / f"output_{name}.schema.json"


def write_output_schemas(folder: Path) -> list[Path]:
    """Write every output schema into ``folder``; returns the paths written."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name in OUTPUT_MODELS:
        path = shipped_path(folder, name)
        path.write_text(output_schema_text(name), encoding="utf-8")
        out.append(path)
    return out


if __name__ == "__main__":
    for written in write_output_schemas(Path(__file__).resolve().parent.parent / "schemas"):
        print(written)
