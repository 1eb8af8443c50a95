"""What the report reads of a run's ``summary.json``: the metrics its scorers declared.

A run's summary records each declared metric (:mod:`povagent.scoring.metrics`: label, caption,
better direction, aggregation, the row field it reads), so the report computes each one again
from the rows without importing the scorer's plugin (a run folder's plugins are never imported).
A summary without a ``metrics`` section, or none, declares nothing; one of a format newer than
this release is refused (read through :func:`povagent.results.upgrade.upgrade_summary`).
"""

from __future__ import annotations

from pathlib import Path

from povagent.scoring.metrics import Metric

#: A ``summary.json`` larger than this is not read for declarations (a run's is kilobytes).
MAX_SUMMARY_BYTES = 64 * 1024 * 1024


def declared_in_summary(path: Path) -> dict[str, tuple[Metric, ...]]:
    """``{scorer: metrics}`` as the ``metrics`` section of the summary at ``path`` declares
    them; empty when there is none, or the file is not a summary."""
    from pydantic import ValidationError
    from pydantic_core import from_json

    from povagent.results.upgrade import upgrade_summary
    from povagent.run.summary_model import RunSummary

    try:
        if path.stat().st_size > MAX_SUMMARY_BYTES:
            return {}
        data = from_json(path.read_bytes())
    except (OSError, ValueError):
        return {}
    try:
        summary = RunSummary.model_validate(upgrade_summary(data, str(path)))
    except ValidationError:
        return {}
    return {scorer: tuple(d.metric(name) for name, d in section.declared.items()) for scorer, section in (summary.metrics or {}).items()}
