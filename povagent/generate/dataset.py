"""A whole generated dataset: the houses not yet on disk, in one or more processes, then ``meta.json``.

What it is for: ``generate_dataset``, the library entry point behind ``povagent generate``.
Houses are independent (each seeded by (seed, index)) and each becomes complete by one rename
(``record``), so a generation can be stopped and resumed, extended to more houses, and spread
over any number of processes (``--jobs``, workers started with ``spawn``) or a Dask cluster
(``--cluster``, through ``povagent.cluster``, imported only then) with the same bytes; the
plain functions of one house that every engine runs are :mod:`povagent.generate.house_task`.
What it must not do: print anything other than the optional progress bar and the notices
handed to ``notice``, write timings into files, or import Dask.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Literal, Mapping, Sequence

from povagent.errors import DatasetError, GenerationError, is_file_system_error
from povagent.files.redaction import Redactor
from povagent.generate.deterministic_json import write_json
from povagent.generate.house_task import HouseFailure, HouseOutcome, make_house
from povagent.generate.judge import DEFAULT_JUDGE, RegisteredJudge, SurfaceJudge, judge_name
from povagent.generate.record import (
    ARTIFACTS,
    PARTIAL,
    RECORD,
    GenerationOptions,
    HouseRecord,
    HouseSummary,
    clear_partial,
    complete_houses,
    remove_half_written,
)
from povagent.geometry.directions import DIRECTION_NAMES

GENERATOR_VERSION = "3"
#: The directions registry's :func:`~povagent.geometry.directions.generation_fingerprint` each
#: generator version was made with: a change to the registry's order, rules or sentence phrases
#: changes the houses generated, so it comes with a version bump and a new entry here (a test
#: holds the two together).
DIRECTIONS_FINGERPRINTS = {"3": "275bb768694f849f"}
DIRECTIONS = DIRECTION_NAMES


@dataclass
class GenerationReport:
    """What was generated, and how long it took (the timing is reported, never written)."""

    out: Path
    seed: int
    houses: list[HouseSummary] = field(default_factory=list)
    seconds: float = 0.0
    #: Houses made by this call (the others were already complete on disk).
    generated: int = 0
    #: Houses found complete and kept as they were.
    kept: int = 0
    #: CPU seconds the houses made by this call took where they ran (measured, never written).
    cpu_seconds: float = 0.0

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
#: Where a cluster's workers put houses: "auto" probes once whether they see the output folder.
Storage = Literal["auto", "shared", "return"]
#: Command-line flags of the options a dataset records, for the message refusing a mismatch.
OPTION_FLAGS = {
    "version": "generator version",
    "seed": "--seed",
    "frames": "--frames",
    "with_render": "--with-render",
    "judge": "--judge",
    "judge_options": "--judge-option",
}


def default_jobs(houses: int) -> int:
    """Worker processes for ``houses`` houses: one per core this process may run on (its CPU
    affinity, else the machine's count), never more than the houses."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(houses, cores))


def generate_dataset(
    out: Path,
    houses: int,
    seed: int,
    frames: int = 30,
    jobs: int | None = None,
    progress: bool | ProgressCallback = True,
    with_render: bool = False,
    judge: str | SurfaceJudge = DEFAULT_JUDGE,
    judge_options: Mapping[str, Any] | None = None,
    plugins: Sequence[str] = (),
    cluster: Any = None,
    storage: Storage = "auto",
    notice: Callable[[str], None] | None = None,
) -> GenerationReport:
    """Generate ``houses`` houses in the POVBench release layout under ``out``, or the missing ones.

    ``progress``: True shows a rich progress bar when stdout is a terminal, a callable is
    called as ``progress(summary, done, total)`` after each house, False is silent.
    ``with_render`` also writes depth maps and instance masks under each house's ``_render/``.
    ``judge`` decides stage 3: the name of a registered judge (``register_judges``; default
    ``physical-rules``), made with ``judge_options``, with the plugin modules ``plugins``
    (dotted names or ``.py`` paths, as a pipeline's ``plugins:``) loaded first; or a
    :class:`~povagent.generate.judge.SurfaceJudge` object, which must pickle when ``jobs > 1``
    or on a cluster. A pair keeps only if the judge allows ``pairs.MIN_DIRECTIONS`` (2) of its
    directions. ``meta.json`` records the judge's name (and its options, secrets redacted).
    The judge is made before anything is written, so an unknown name or bad options raise
    :class:`~povagent.errors.PluginError` with ``out`` untouched.

    Resuming and extending: ``out`` must be empty, new, or a dataset this generator wrote. Houses
    already complete there are kept as they are (bytes and times); half-written ones are redone;
    asking for more houses makes only the new ones. Options that differ from the ones the houses
    on disk were made with (seed, frames, with_render, judge and its options) raise
    :class:`~povagent.errors.DatasetError` naming the option; so does asking for fewer houses than
    are complete. ``meta.json`` is written last, from the houses on disk.

    Where it runs: ``jobs`` local processes, or with ``cluster`` (``"local:N"``, a scheduler
    address ``"tcp://HOST:PORT"`` or a ``distributed.Client``) a Dask cluster, which needs the
    ``cluster`` extra. ``storage`` says how cluster workers hand houses over: ``"shared"`` (they
    write into ``out``), ``"return"`` (they send the files back and this process writes them) or
    ``"auto"`` (probe once). ``notice`` receives one-line messages meant for the user (the
    dashboard's address, what the storage probe found).

    The files depend only on (houses, seed, frames, with_render, judge), never on ``jobs``, the
    cluster or the order houses finish. A house that raises does not stop the others; at the
    end :class:`~povagent.errors.GenerationError` names every failed house (index, seed, error),
    ``meta.json`` is not written, and the same call redoes only those houses. An output folder
    that refuses a write (full, read-only, here or under the workers) raises
    :class:`~povagent.errors.GenerationError` naming the file and the error; complete houses stay.

    ``jobs``: worker processes, one house each at a time; ``None`` (the default) is
    :func:`default_jobs`: a worker per core this process may use, at most one per house (one
    when ``judge`` is an object, which need not pickle).
    """
    out = Path(out)
    if jobs is None:
        jobs = default_jobs(houses) if isinstance(judge, str) else 1
    if isinstance(judge, str):
        registered = RegisteredJudge(judge, judge_options, plugins)
        registered.resolve()  # an unknown name or bad options fail here, before any work
        judge = registered
    elif judge_options:
        raise ValueError("judge_options apply to a judge given by its registered name, not to a judge object")
    elif not isinstance(judge, SurfaceJudge):
        raise TypeError(f"judge must be a registered judge name or a SurfaceJudge, not {type(judge).__name__}")
    if storage not in ("auto", "shared", "return"):
        raise ValueError(f"storage must be 'auto', 'shared' or 'return', not {storage!r}")
    recorded_options = Redactor().value(dict(judge_options)) if judge_options else {}
    options = GenerationOptions(GENERATOR_VERSION, seed, frames, with_render, judge_name(judge), recorded_options)
    if cluster is not None:
        # the value and the extra are checked before anything is written (neither imports Dask)
        from povagent.cluster.client import require_distributed
        from povagent.config.cluster_spec import parse_cluster_spec

        if isinstance(cluster, str):
            parse_cluster_spec(cluster)
        require_distributed()
    try:
        start = time.perf_counter()
        kept = _prepare(out, options, houses)
        pending = [i for i in range(houses) if i not in kept]
        report = GenerationReport(out=out, seed=seed, kept=len(kept))
        failures: list[HouseFailure] = []
        if pending:
            # The dataset is changing: until meta.json is written again, it is not a finished one.
            (out / "meta.json").unlink(missing_ok=True)
            remove_half_written(out, keep=set(kept))
            callback, finish = _progress(progress, houses, len(kept))
            done = len(kept)

            def finished(outcome: HouseOutcome) -> None:
                nonlocal done
                if outcome.failure is not None:
                    failures.append(outcome.failure)
                    return
                assert outcome.record is not None
                done += 1
                report.generated += 0 if outcome.kept else 1
                report.cpu_seconds += outcome.cpu_seconds
                callback(outcome.record.summary, done, houses)

            try:
                if cluster is not None:
                    from povagent.cluster.generation import generate_on_cluster

                    generate_on_cluster(cluster, out, options, pending, judge, finished, storage=storage, notice=notice)
                else:
                    _generate_here(out, options, pending, judge, jobs, finished)
            finally:
                finish()
            clear_partial(out)
        if failures:
            failures.sort(key=lambda f: f.index)
            raise GenerationError(_failure_message(out, failures, houses), failures)
        on_disk = complete_houses(out)
        report.houses = [on_disk[i].summary for i in range(houses)]
        _write_meta(out, options, judge_options, report)
    except OSError as exc:
        # a full disk or a read-only --out (here or on the workers' shared folder) is the
        # user's to fix: one line naming the file, not a traceback nor a lost scheduler
        if not is_file_system_error(exc):
            raise
        raise GenerationError.cannot_write(out, exc) from exc
    report.seconds = time.perf_counter() - start
    return report


def _generate_here(
    out: Path, options: GenerationOptions, pending: list[int], judge: SurfaceJudge, jobs: int,
    finished: Callable[[HouseOutcome], None],
) -> None:
    """Make the ``pending`` houses in this process or in ``jobs`` local worker processes."""
    if jobs <= 1 or len(pending) <= 1:
        for index in pending:
            finished(make_house(out, options, index, judge))
        return
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        futures = [pool.submit(make_house, out, options, i, judge) for i in pending]
        for future in as_completed(futures):
            finished(future.result())


def _failure_message(out: Path, failures: list[HouseFailure], houses: int) -> str:
    shown = "; ".join(f"house {f.index} (seed {f.seed}): {f.error}" for f in failures[:5])
    more = f"; and {len(failures) - 5} more" if len(failures) > 5 else ""
    return (
        f"{len(failures)} of {houses} houses failed: {shown}{more}. The other houses are complete in {out}; "
        "run the same command again to redo only the failed ones"
    )


def _write_meta(
    out: Path, options: GenerationOptions, judge_options: Mapping[str, Any] | None, report: GenerationReport
) -> None:
    """``meta.json``, last, from the houses on disk; renamed into place so it is never half-written."""
    judge_record: dict[str, Any] = {"judge": options.judge}
    if judge_options:
        judge_record["judge_options"] = dict(options.judge_options)
    tmp = out / f".meta.json.{os.getpid()}"
    write_json(
        tmp,
        {
            "version": GENERATOR_VERSION,
            "seed": options.seed,
            "generator": {
                "name": "povagent.generate",
                "frames": options.frames,
                "houses": len(report.houses),
                "camera": {"exploration_height": 0.9, "exploration_horizon": 30, "observer_height": 1.55, "fov": 100},
                **judge_record,
            },
            "counts": report.counts(),
        },
    )
    os.replace(tmp, out / "meta.json")


def _prepare(out: Path, options: GenerationOptions, houses: int) -> dict[int, HouseRecord]:
    """Make ``out`` ready and return the houses already complete in it.

    ``out`` must be new, empty, or a dataset this generator wrote (finished: its ``meta.json``
    says so; or unfinished: only ``artifacts/`` and ``.partial/``, with house records). A folder
    holding anything else is refused rather than mixed with generated houses; so are houses made
    with other options, and a request for fewer houses than are complete.
    """
    if out.exists() and any(out.iterdir()):
        if not _ours(out):
            raise DatasetError(f"{out} is not empty and not a generated dataset: choose an empty or new folder")
        kept = complete_houses(out)
        for index, record in sorted(kept.items()):
            differs = options.difference(record.options)
            if differs is not None:
                flag = OPTION_FLAGS.get(differs, differs)
                raise DatasetError(
                    f"{out} was generated with {differs} {record.options.get(differs)!r} (house {index}), this run asks "
                    f"for {options.record()[differs]!r}: give the same {flag} to resume or extend it, or choose a new folder"
                )
        beyond = sorted(i for i in kept if i >= houses)
        if beyond:
            raise DatasetError(
                f"{out} already holds {len(kept)} complete houses (up to index {beyond[-1]}); --houses {houses} "
                f"would leave some out of meta.json: ask for at least {beyond[-1] + 1} houses, or choose a new folder"
            )
        return kept
    out.mkdir(parents=True, exist_ok=True)
    return {}


def _ours(out: Path) -> bool:
    """Whether ``out`` holds a dataset this generator wrote, finished or not."""
    meta = out / "meta.json"
    if meta.is_file():
        try:
            return json.loads(meta.read_text()).get("generator", {}).get("name") == "povagent.generate"
        except (ValueError, AttributeError, OSError):
            return False
    names = {p.name for p in out.iterdir() if not p.name.startswith(f"{PARTIAL}-removed-")}
    if not names <= {ARTIFACTS, PARTIAL}:
        return False
    return (out / PARTIAL).is_dir() or bool(complete_houses(out)) or any((out / ARTIFACTS).glob(f"*/{RECORD}"))


def _progress(
    progress: bool | ProgressCallback, total: int, already: int = 0
) -> tuple[ProgressCallback, Callable[[], None]]:
    """The per-house callback and the closing action for the requested kind of progress."""
    if callable(progress):
        return progress, lambda: None
    if not progress or not sys.stdout.isatty():
        return (lambda s, d, t: None), lambda: None
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(TextColumn("generating houses"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    task = bar.add_task("houses", total=total, completed=already)
    bar.start()

    def advance(summary: HouseSummary, done: int, total_: int) -> None:
        """Move the bar to ``done`` houses."""
        bar.update(task, completed=done)

    return advance, bar.stop
