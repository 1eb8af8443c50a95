"""What a pipeline run returns: its exit code, the summary it wrote and this session's counters.

The runner (:mod:`povagent.run.runner`) fills these in; ``povagent run``, ``povagent sweep`` and
the annotation session read them. They hold values only: nothing here runs, reads or writes.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from povagent.run.summary_model import RunSummary

#: Exit codes of ``povagent run`` and ``sweep`` (documented in the README's reliability section).
EXIT_OK = 0  # every key has an answered or parse-error row
EXIT_FAILED_KEYS = 3  # the run ended, but some keys are infra_error rows (run again to retry them)
EXIT_STOPPED = 4  # the run stopped early (fail fast or circuit breaker): keys were left untried


@dataclass
class RunStats:
    """What this session did (a resumed run counts only its own calls)."""

    requests: int = 0
    cache_hits: int = 0
    retries: int = 0
    rows_written: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    cost_usd: float = 0.0
    wall_s: float = 0.0
    fsyncs: int = 0
    fsync_s: float = 0.0
    statuses: Counter = field(default_factory=Counter)

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        d = dataclasses.asdict(self)
        d["statuses"] = dict(self.statuses)
        return d


@dataclass
class RunResult:
    """What :func:`~povagent.run.runner.run_pipeline` returns."""

    run_dir: Path
    #: What ``summary.json`` holds, as the type it is.
    summary: RunSummary
    stats: RunStats
    n_total: int
    n_pending: int
    interrupted: bool = False
    #: why the run stopped before every pending key was tried (fail fast, circuit breaker)
    stopped: str | None = None
    #: the first row's error type when it stopped the run at once (fail fast), else ``None``
    stop_kind: str | None = None

    @property
    def n_failed(self) -> int:
        """Keys whose row is ``infra_error``."""
        rows = self.summary.rows
        return rows.infra_error if rows is not None else 0

    @property
    def n_missing(self) -> int:
        """Keys with no row at all (a stopped or interrupted run)."""
        rows = self.summary.rows
        return rows.missing if rows is not None else 0

    @property
    def exit_code(self) -> int:
        """:data:`EXIT_OK`, :data:`EXIT_FAILED_KEYS` or :data:`EXIT_STOPPED` (see there)."""
        if self.stopped is not None or self.n_missing:
            return EXIT_STOPPED
        return EXIT_FAILED_KEYS if self.n_failed else EXIT_OK
