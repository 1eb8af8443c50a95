"""``sweep.json`` as a type: the sweep's cell index (:class:`SweepIndex`).

:func:`povagent.run.sweep.run_sweep` writes it after every cell; ``povagent report`` and the
run-folder check read it; ``povagent schema sweep`` publishes its JSON Schema. Only types.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict

from povagent.run.summary_model import Cell, RowCounts

#: Where a cell stands: not started, running, every key has a row, stopped early, or it failed.
CellStatus = Literal["pending", "running", "done", "incomplete", "interrupted", "failed"]


class SweepCell(BaseModel):
    """One cell: its axis values, its run folder, the model that answered and its status
    (with its row counts and overall cell once it has run, its error when it failed)."""

    model_config = ConfigDict(extra="forbid")

    name: str
    axes: dict[str, Any]
    run_dir: str
    config_hash: str
    model: str
    profile: str | None
    status: CellStatus
    rows: RowCounts | None = None
    overall: Cell | None = None
    error: str | None = None


class SweepIndex(BaseModel):
    """Everything ``sweep.json`` holds: the sweep file, the output folder and every cell."""

    model_config = ConfigDict(extra="forbid")

    sweep: str
    output: str
    cells: list[SweepCell]
