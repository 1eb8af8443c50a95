"""``export.json`` as a type: what a training export records (:class:`ExportManifest`).

:mod:`povagent.train.training_export` writes it before the shards and reads it to resume; ``povagent
schema export`` publishes its JSON Schema. Only types.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict


class RecordedOptions(BaseModel):
    """The export's options (:class:`povagent.train.export_options.ExportOptions`) as recorded."""

    model_config = ConfigDict(extra="forbid")

    format: str
    rationale: str
    split: str
    split_seed: int
    text_seed: int
    conditions: list[str]
    max_shard_bytes: int
    exact_answers: bool
    #: The task the examples ask (recorded only when it is not the point task).
    task: str = "point"


class RecordedShard(BaseModel):
    """One planned shard: its file name, its split and the instance ids it holds, in order."""

    model_config = ConfigDict(extra="forbid")

    name: str
    split: str
    examples: list[str]


class ExportManifest(BaseModel):
    """Everything ``export.json`` holds: the format version, the tool, the dataset, the options
    and the plan."""

    model_config = ConfigDict(extra="forbid")

    version: int
    tool: str
    dataset: str
    options: RecordedOptions
    shards: list[RecordedShard]
