"""Which harnesses' logs ``povagent rescore-log`` reads, and the one entry point that reads one.

Each harness's reader is its own module (:mod:`.lmms_eval_log`, :mod:`.vlmevalkit_log`), both
built on :mod:`.harness_logs`; this module only names them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Mapping

from povagent.results.harness_logs import HarnessLog

#: Reads a log: ``(file) -> HarnessLog``.
LogReader = Callable[[Path], HarnessLog]


def log_readers() -> Mapping[str, LogReader]:
    """The harnesses whose logs can be read, by the name ``--harness`` takes."""
    from povagent.results.lmms_eval_log import read_lmms_eval_log
    from povagent.results.vlmevalkit_log import read_vlmevalkit_predictions

    return {"lmms-eval": read_lmms_eval_log, "vlmevalkit": read_vlmevalkit_predictions}


def read_harness_log(file: str | Path, harness: str) -> HarnessLog:
    """The log ``file`` as ``harness`` writes it (a name of :func:`log_readers`);
    :class:`~povagent.errors.PredictionsError` when the file cannot be read at all."""
    from povagent.errors import PredictionsError

    readers = log_readers()
    if harness not in readers:
        raise PredictionsError(f"unknown harness {harness!r} (known: {', '.join(readers)})")
    return readers[harness](Path(file))


__all__ = ["LogReader", "log_readers", "read_harness_log"]
