"""A whole generated dataset: houses in one or more processes, then ``meta.json``.

What it is for: ``generate_dataset``, the library entry point behind ``povagent generate``.
Houses are independent (each seeded by (seed, index)), so any number of worker processes gives
the same bytes; workers are started with ``spawn`` so it is safe wherever it runs. What it must
not do: print anything other than the optional progress bar, or write timings into files.
"""

from __future__ import annotations

import json
import multiprocessing
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from povagent.errors import DatasetError
from povagent.generate.judge import DEFAULT_JUDGE, RegisteredJudge, SurfaceJudge, judge_name
from povagent.generate.pipeline import HouseSummary, generate_house
from povagent.generate.writer import write_json
from povagent.run.logs import Redactor

GENERATOR_VERSION = "2"
DIRECTIONS = ("right", "left", "front", "up")


@dataclass
class GenerationReport:
    """What was generated, and how long it took (the timing is reported, never written)."""

    out: Path
    seed: int
    houses: list[HouseSummary] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def pairs(self) -> int:
        """Validated (observer, anchor) pairs over all houses."""
        return sum(h.pairs for h in self.houses)

    @property
    def instances_per_condition(self) -> int:
        """Valid (pair, direction) instances: each is one query per condition."""
        return sum(sum(h.directions.values()) for h in self.houses)

    @property
    def renders(self) -> int:
        """Full 512x512 frames rendered (exploration frames and observer views)."""
        return sum(h.renders for h in self.houses)

    def direction_counts(self) -> dict[str, int]:
        """Instances per direction."""
        return {d: sum(h.directions.get(d, 0) for h in self.houses) for d in DIRECTIONS}

    def direction_shares(self) -> dict[str, float]:
        """Share of pairs that have each direction (the paper: front 97%, up 66%, ...)."""
        n = max(self.pairs, 1)
        return {d: c / n for d, c in self.direction_counts().items()}

    def counts(self) -> dict[str, object]:
        """The counts ``meta.json`` records."""
        return {
            "houses": len(self.houses),
            "pairs": self.pairs,
            "instances_per_condition": self.instances_per_condition,
            "instances": 3 * self.instances_per_condition,
            "directions": self.direction_counts(),
            "exploration_frames": sum(h.reachable_frames for h in self.houses),
            "observer_views": self.pairs,
        }


ProgressCallback = Callable[[HouseSummary, int, int], None]


def generate_dataset(
    out: Path,
    houses: int,
    seed: int,
    frames: int = 30,
    jobs: int = 1,
    progress: bool | ProgressCallback = True,
    with_render: bool = False,
    judge: str | SurfaceJudge = DEFAULT_JUDGE,
    judge_options: Mapping[str, Any] | None = None,
    plugins: Sequence[str] = (),
) -> GenerationReport:
    """Generate ``houses`` houses in the POVBench release layout under ``out``.

    ``progress``: True shows a rich progress bar when stdout is a terminal, a callable is
    called as ``progress(summary, done, total)`` after each house, False is silent.
    ``with_render`` also writes depth maps and instance masks under each house's ``_render/``.
    ``judge`` decides stage 3: the name of a registered judge (``register_judges``; default
    ``physical-rules``), made with ``judge_options``, with the plugin modules ``plugins``
    (dotted names or ``.py`` paths, as a pipeline's ``plugins:``) loaded first; or a
    :class:`~povagent.generate.judge.SurfaceJudge` object, which must pickle when ``jobs > 1``.
    A pair keeps only if the judge allows ``pairs.MIN_DIRECTIONS`` (2) of its directions.
    ``meta.json`` records the judge's name (and its options, secrets redacted, when given).
    The judge is made before anything is written, so an unknown name or bad options raise
    :class:`~povagent.errors.PluginError` with ``out`` untouched.
    The files depend only on (houses, seed, frames, with_render, judge), never on ``jobs``. ``out``
    must be empty, new, or a dataset this generator wrote (which is then replaced whole);
    anything else raises :class:`~povagent.errors.DatasetError`.
    """
    out = Path(out)
    if isinstance(judge, str):
        registered = RegisteredJudge(judge, judge_options, plugins)
        registered.resolve()  # an unknown name or bad options fail here, before any work
        judge = registered
    elif judge_options:
        raise ValueError("judge_options apply to a judge given by its registered name, not to a judge object")
    elif not isinstance(judge, SurfaceJudge):
        raise TypeError(f"judge must be a registered judge name or a SurfaceJudge, not {type(judge).__name__}")
    judge_record: dict[str, Any] = {"judge": judge_name(judge)}
    if judge_options:
        judge_record["judge_options"] = Redactor().value(dict(judge_options))
    _prepare(out)
    start = time.perf_counter()
    report = GenerationReport(out=out, seed=seed)
    callback, finish = _progress(progress, houses)
    try:
        if jobs <= 1 or houses <= 1:
            for index in range(houses):
                summary = generate_house(out, seed, index, frames, with_render, judge)
                report.houses.append(summary)
                callback(summary, len(report.houses), houses)
        else:
            context = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
                futures = [
                    pool.submit(generate_house, out, seed, i, frames, with_render, judge) for i in range(houses)
                ]
                for future in as_completed(futures):
                    summary = future.result()
                    report.houses.append(summary)
                    callback(summary, len(report.houses), houses)
    finally:
        finish()
    report.houses.sort(key=lambda h: h.index)
    write_json(
        out / "meta.json",
        {
            "version": GENERATOR_VERSION,
            "seed": seed,
            "generator": {
                "name": "povagent.generate",
                "frames": frames,
                "houses": houses,
                "camera": {"exploration_height": 0.9, "exploration_horizon": 30, "observer_height": 1.55, "fov": 100},
                **judge_record,
            },
            "counts": report.counts(),
        },
    )
    report.seconds = time.perf_counter() - start
    return report


def _prepare(out: Path) -> None:
    """Make ``out`` ready: empty, or a dataset this generator wrote (its houses are replaced).

    A folder holding anything else is refused rather than mixed with generated houses.
    """
    if out.exists() and any(out.iterdir()):
        meta = out / "meta.json"
        ours = False
        if meta.is_file():
            try:
                ours = json.loads(meta.read_text()).get("generator", {}).get("name") == "povagent.generate"
            except (ValueError, AttributeError):
                ours = False
        if not ours:
            raise DatasetError(f"{out} is not empty and not a generated dataset: choose an empty or new folder")
        shutil.rmtree(out / "artifacts", ignore_errors=True)
        meta.unlink()
    out.mkdir(parents=True, exist_ok=True)


def _progress(progress: bool | ProgressCallback, total: int) -> tuple[ProgressCallback, Callable[[], None]]:
    """The per-house callback and the closing action for the requested kind of progress."""
    if callable(progress):
        return progress, lambda: None
    if not progress or not sys.stdout.isatty():
        return (lambda s, d, t: None), lambda: None
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn("generating houses"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    task = bar.add_task("houses", total=total)
    bar.start()

    def advance(summary: HouseSummary, done: int, total_: int) -> None:
        """Move the bar to ``done`` houses."""
        bar.update(task, completed=done)

    return advance, bar.stop
