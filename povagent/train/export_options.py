"""What a training export is asked for, and what it reports back: plain data, shared by the
exporter (:mod:`povagent.train.training_export`) and the dataset card (:mod:`povagent.train.card`).

:class:`ExportOptions` is everything that decides an export's bytes (``export.json`` records
it, and resuming compares it); :data:`FORMAT_FOLDERS` says where each format's shards go;
:class:`ExportReport` is what an export wrote; :class:`ExportError` is why it cannot go on.
This module must not read a dataset or write a file: it only describes and checks values.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from povagent.config.models import TASK_NAMES, TaskSpec
from povagent.dataset.release_models import CONDITIONS
from povagent.errors import PovagentError
from povagent.train.rationale import RATIONALES
from povagent.train.shards import DEFAULT_SHARD_BYTES
from povagent.train.splits import DEFAULT_SPLIT, SplitError, parse_split

FORMATS = ("hf", "messages", "openai")
#: Where each format's shards go, and their suffix.
FORMAT_FOLDERS = {"hf": ("data", "parquet"), "messages": ("messages", "jsonl"), "openai": ("openai", "jsonl")}


class ExportError(PovagentError):
    """An export cannot go on: an evaluation house, options that differ from the export's, ..."""


@dataclass(frozen=True)
class ExportOptions:
    """Everything that decides an export's bytes (recorded in ``export.json``)."""

    format: str = "hf"
    rationale: str = "s-cot"
    split: str = DEFAULT_SPLIT
    split_seed: int = 0
    text_seed: int = 0
    conditions: tuple[str, ...] = tuple(c.value for c in CONDITIONS)
    max_shard_bytes: int = DEFAULT_SHARD_BYTES
    exact_answers: bool = False
    #: The task each example asks (:data:`~povagent.config.models.TASK_NAMES`): ``point``, or a
    #: generated choice task (``relation``, ``multi-hop``) answered with its option's label.
    task: str = "point"

    def __post_init__(self) -> None:
        # one spelling per set of conditions: ``a,b,b`` and ``b,a`` are ``a,b`` (the card, the
        # shards and a resume's comparison all read this one tuple)
        known = [c.value for c in CONDITIONS]
        given = tuple(str(c).strip() for c in self.conditions)
        ordered = sorted(set(given), key=lambda c: (known.index(c) if c in known else len(known), c))
        object.__setattr__(self, "conditions", tuple(ordered))

    def check(self) -> None:
        """Refuse values outside what the exporter knows, naming the option."""
        if self.format not in FORMATS:
            raise ExportError(f"--format {self.format!r}: one of {', '.join(FORMATS)}")
        if self.task not in TASK_NAMES:
            raise ExportError(f"--task {self.task!r}: one of {', '.join(TASK_NAMES)}")
        if self.rationale not in RATIONALES:
            raise ExportError(f"--rationale {self.rationale!r}: one of {', '.join(RATIONALES)}")
        if self.max_shard_bytes < 1024 * 1024:
            raise ExportError(f"--max-shard-mb: a shard holds at least 1 MB (got {self.max_shard_bytes} bytes)")
        for c in self.conditions:
            if c not in {x.value for x in CONDITIONS}:
                raise ExportError(f"--conditions {c!r}: one of a, b, c")
        if not self.conditions:
            raise ExportError("--conditions: name at least one of a, b, c")
        try:
            parse_split(self.split)
        except SplitError as exc:
            raise ExportError(str(exc)) from None


def task_spec(options: ExportOptions) -> TaskSpec:
    """The task the export's examples ask: a generated task is asked as a choice."""
    return TaskSpec(name=options.task) if options.task == "point" else TaskSpec(name=options.task, answer="choice")


@dataclass
class ExportReport:
    """What an export wrote: examples per split/condition/direction, shards, skips, exclusion."""

    out: Path
    examples: int = 0
    shards: list[str] = field(default_factory=list)
    shards_written: int = 0
    counts: dict[str, dict[str, int]] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    #: Houses and pairs loading left out (``house`` or ``house pair P`` -> the loader's reasons).
    left_out: dict[str, str] = field(default_factory=dict)
    excluded: dict[str, str] = field(default_factory=dict)
    evaluation_sources: list[str] = field(default_factory=list)
    houses_by_split: dict[str, list[str]] = field(default_factory=dict)
    seconds: float = 0.0
