"""The quickstart: the main job a new user runs on a fresh machine, offline, with no API key.

Generates a small POVBench-format dataset (unless one is given), runs the offline baselines
(center, random, oracle) over every condition as a sweep, and writes the paper-style report.
Every step is the ordinary library call a user would make; nothing here is special-cased.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import yaml

from povagent.config.pipeline import default_scorers
from povagent.files.confined_write import write_inside
from povagent.geometry.directions import DIRECTION_NAMES
from povagent.results.official_reading import OFFICIAL_PARSER

#: The baselines the quickstart compares (all offline and instant).
BASELINES = ("center", "random", "oracle")


@dataclass
class QuickstartResult:
    """Where the quickstart wrote its dataset, sweep and report."""

    dataset: Path
    sweep: Path
    report: Path
    main_table_markdown: str


def write_quickstart_configs(out: Path, dataset: Path, runs: int = 1) -> Path:
    """Write ``pipeline.yaml`` and ``sweep.yaml`` under ``out``; returns the sweep file."""
    out.mkdir(parents=True, exist_ok=True)
    pipeline = {
        "dataset": {"path": str(dataset.resolve())},
        "instances": {"conditions": ["a", "b", "c"], "directions": list(DIRECTION_NAMES)},
        "backend": {"name": "center", "options": {"frame_policy": "first"}},
        "strategy": "basic",
        "parser": OFFICIAL_PARSER,  # the official reading, and the pipeline's default scorers
        "scorers": default_scorers(),
        "runs": runs,
        "concurrency": 16,
        "output": str((out / "runs" / "single").resolve()),
    }
    sweep = {
        "base": "pipeline.yaml",
        "output": str((out / "sweep").resolve()),
        "axes": {"backend": [{"name": "center", "options": {"frame_policy": "first"}}, {"name": "random", "options": {"seed": 0}}, "oracle"]},
    }
    # aside and renamed: a link left at either name in a reused folder is replaced, not followed
    write_inside(out, "pipeline.yaml", yaml.safe_dump(pipeline, sort_keys=False))
    return write_inside(out, "sweep.yaml", yaml.safe_dump(sweep, sort_keys=False))


def run_quickstart(
    out: str | Path = "povagent-quickstart",
    dataset: str | Path | None = None,
    houses: int = 3,
    seed: int = 0,
    frames: int = 30,
    jobs: int | None = None,
    quiet: bool = False,
    say: Callable[[str], None] = print,
) -> QuickstartResult:
    """Generate (if needed), sweep the baselines, report. Safe to run again: it resumes.

    ``jobs``: worker processes generating the houses (``None``: one per core, at most one per
    house; see :func:`povagent.generate.dataset.default_jobs`)."""
    from povagent.report.build import write_report
    from povagent.report.tables import to_markdown
    from povagent.run.sweep import run_sweep

    out = Path(out)
    if dataset is None:
        data = out / "data"
        if not (data / "meta.json").is_file():  # none yet, or an interrupted one: generating resumes it
            from povagent.generate import generate_dataset

            say(f"generating {houses} houses (seed {seed}, {frames} frames each) into {data} ...")
            rep = generate_dataset(data, houses=houses, seed=seed, frames=frames, jobs=jobs, progress=not quiet)
            say(f"  done in {rep.seconds:.1f} s")
        else:
            say(f"using the dataset already generated in {data}")
    else:
        data = Path(dataset)
    sweep_file = write_quickstart_configs(out, data)
    say(f"running the offline baselines {', '.join(BASELINES)} over conditions A, B and C ...")
    result = run_sweep(sweep_file, quiet=quiet)
    say("writing the report ...")
    report = write_report(result.output)
    main = next((t for t in report.tables if t.key.startswith("main")), report.tables[0])
    return QuickstartResult(data, result.output, report.page, to_markdown(main))
