"""A finished run folder, opened once: the one reader the report, ``rescore``, ``export`` and
``compare`` share.

A run folder holds ``config.yaml`` (the resolved pipeline), ``results.jsonl`` (one row per key,
the last row of a key winning), ``summary.json`` (the run's summary, with the metrics its
scorers declared) and, inside each row, its transcript. :meth:`FinishedRun.open` checks the
folder is a run's and reads its config; its rows are indexed, and the summary's declarations
read, the first time they are asked for, and never again; a row's turns when they are looked at
(:class:`~povagent.results.transcript.RunTurns` over :attr:`FinishedRun.rows`).

What it must not do: import a plugin the folder names (a run folder is anyone's), score a row,
or write anything. Every file is read through :mod:`povagent.files.confined_read` (a pipe or a
device planted in the folder is one line naming it, never a wait) and with a bound.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import yaml

from povagent.errors import PredictionsError
from povagent.files.confined_read import check_regular, read_regular
from povagent.results.rows import ResultRow, StoredRows, read_rows
from povagent.results.upgrade import upgrade_summary
from povagent.scoring.metrics import Metric

RESULTS_FILE = "results.jsonl"
CONFIG_FILE = "config.yaml"
SUMMARY_FILE = "summary.json"
#: A run's ``config.yaml`` larger than this is refused: the bound every pipeline reader uses
#: (:data:`povagent.config.yaml_reader.MAX_CONFIG_BYTES`, held equal by a test).
MAX_CONFIG_BYTES = 1024 * 1024
#: A ``summary.json`` larger than this is not read for declarations (a run's is kilobytes).
MAX_SUMMARY_BYTES = 64 * 1024 * 1024


def is_run_folder(folder: Path) -> bool:
    """Whether ``folder`` holds a run's results (what makes a folder a run folder)."""
    return (folder / RESULTS_FILE).exists()


@dataclass
class FinishedRun:
    """One run folder as it was left: its rows, its config, its summary's declarations."""

    folder: Path
    #: ``config.yaml`` as written (``None``: the folder has none); :attr:`config` parses it.
    config_bytes: bytes | None = field(default=None, repr=False)

    @classmethod
    def open(cls, folder: str | Path) -> FinishedRun:
        """The run in ``folder``; a folder without a results file is a :class:`PredictionsError`."""
        folder = Path(folder)
        if not is_run_folder(folder):
            raise PredictionsError(f"{folder}: no {RESULTS_FILE} (is this a run folder?)")
        check_regular(folder / RESULTS_FILE, what="results file")  # a pipe or a device planted there: one line, now
        config = folder / CONFIG_FILE
        return cls(folder, read_regular(config, MAX_CONFIG_BYTES, what="run config") if config.exists() else None)

    @cached_property
    def rows(self) -> StoredRows:
        """The rows (one per key, the last row of a key winning), read from the results file as
        they are iterated: a reader of any number of rows holds none of them."""
        return StoredRows(self.folder / RESULTS_FILE)

    def all_rows(self) -> list[ResultRow]:
        """The same rows, read in one pass and held: for a command that rewrites every row (a
        rescore), which would otherwise read each twice."""
        return read_rows(self.folder / RESULTS_FILE)

    @cached_property
    def config(self) -> dict[str, Any]:
        """The resolved config as plain data (``{}``: none, or not a mapping); text that is not
        YAML is a :class:`PredictionsError` naming the file."""
        if self.config_bytes is None:
            return {}
        try:
            data = yaml.safe_load(self.config_bytes.decode("utf-8"))
        except yaml.YAMLError as exc:
            raise PredictionsError(f"{self.folder / CONFIG_FILE}: not valid YAML ({exc})") from exc
        return data if isinstance(data, dict) else {}

    @cached_property
    def declared(self) -> dict[str, tuple[Metric, ...]]:
        """``{scorer: metrics}`` as the summary's ``metrics`` section declares them (each
        :meth:`~povagent.scoring.metrics.Metric.describe`\\ d), so a reader computes each one
        again from the rows without the scorer's plugin; empty when there is no summary, it
        declares nothing, or it is not a summary; a summary of a format newer than this release
        is refused (:func:`~povagent.results.upgrade.upgrade_summary`)."""
        path = self.folder / SUMMARY_FILE
        try:
            if not path.exists() or path.stat().st_size > MAX_SUMMARY_BYTES:
                return {}
            data = json.loads(read_regular(path, MAX_SUMMARY_BYTES, what="run summary"))
        except (OSError, ValueError):
            return {}
        sections = upgrade_summary(data, str(path)).get("metrics") or {} if isinstance(data, dict) else {}
        try:
            return {scorer: tuple(Metric.declared(name, d) for name, d in section["declared"].items()) for scorer, section in sections.items()}
        except (OSError, ValueError, TypeError, KeyError, AttributeError):
            return {}
