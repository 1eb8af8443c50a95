"""The one writer of a benchmark's figures: ``benchmarks/results/<stem>.json``.

Every figure the project publishes lives in ``benchmarks/RESULTS.md``, which
``benchmarks/write_results.py`` writes from these JSON files. A benchmark calls :func:`record`
once at the end of a run with the figures it measured in that run; the file says when, on what
machine (cores, CPU model, load average at the end of the run) and with which command, so a
reader can re-run it and set the new figure beside the old. Nothing here measures anything.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import sys
from pathlib import Path
from typing import Any

#: Where the JSON files live (read by ``write_results.py``).
RESULTS_DIR = Path(__file__).resolve().parent / "results"


def figure(name: str, value: float, unit: str, target: str = "", comparison: str = "") -> dict[str, Any]:
    """One figure: what it is, its value and unit, the bar it is held to (if any) and what it
    is set beside, with the peer's settings (if it is a comparison)."""
    return {"name": name, "value": value, "unit": unit, "target": target, "comparison": comparison}


def cpu_model() -> str:
    """The CPU's model name as the kernel reports it (``platform.processor()`` elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict[str, Any]:
    """The machine a figure was measured on: cores, CPU model and the load average now."""
    load = [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else []
    return {"cores": os.cpu_count() or 0, "cpu_model": cpu_model(), "load_avg": load}


def record(
    stem: str,
    figures: list[dict[str, Any]],
    command: str | None = None,
    *,
    date: str | None = None,
    machine_info: dict[str, Any] | None = None,
    note: str = "",
    results_dir: Path = RESULTS_DIR,
) -> Path:
    """Write ``<results_dir>/<stem>.json`` with ``figures`` and return its path.

    ``command`` defaults to the command line that is running; ``date`` to today (UTC) and
    ``machine_info`` to this machine, both given only when a figure is carried over from an
    earlier publication (``note`` then says from where). The file is replaced atomically, so a
    run killed while writing leaves the previous figures in place.
    """
    if command is None:
        command = "python " + " ".join(["benchmarks/" + Path(sys.argv[0]).name, *sys.argv[1:]])
    doc: dict[str, Any] = {
        "benchmark": stem,
        "date": date or _dt.datetime.now(_dt.UTC).date().isoformat(),
        "machine": machine_info or machine(),
        "command": command,
        "figures": figures,
    }
    if note:
        doc["note"] = note
    results_dir.mkdir(parents=True, exist_ok=True)
    path = results_dir / f"{stem}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(doc, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    tmp.replace(path)
    return path
