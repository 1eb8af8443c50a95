"""``export_training_set``: a POVBench-format dataset -> a training set on disk.

The flow: check the options and the extras they need (before anything is written), check no
house is an evaluation house, read the houses one at a time (a house or pair that cannot be used
is left out and named, with why) to plan their examples, assign houses to splits, cut the plan
into shards, then hold the export folder (:mod:`povagent.train.export_folder`: checked, locked)
and write each shard that is not already there (one after another, or as cluster tasks), count
the shards on disk, and last write the dataset card. ``export.json`` records the options and the plan: the same command resumes, and
other options over an existing export are refused naming the option that differs.

Memory stays flat in the number of houses: no step holds more than one house's records (the
plan keeps only each example's id and size), and a shard is written from one house at a time.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from povagent.dataset.loader import Dataset, House, dataset_house_folders, house_folders, load_house, read_meta
from povagent.dataset.problems import Problem
from povagent.dataset.release_models import Condition
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import DatasetError
from povagent.tasks.scene_facts import NoTeachingFrame, instance_facts
from povagent.train.card import write_card
from povagent.train.examples import TrainingExample
from povagent.train.exclusion import EvaluationSets, cached_release_root, dataset_identities
from povagent.train.export_folder import MANIFEST, MANIFEST_VERSION, export_folder, manifest
from povagent.train.export_options import FORMAT_FOLDERS, ExportError, ExportOptions, ExportReport, task_spec
from povagent.train.left_out import left_out
from povagent.train.shards import PlannedExample, Shard, plan_shards, remove_stale_temporaries
from povagent.train.splits import assign_splits, parse_split

__all__ = ["MANIFEST", "MANIFEST_VERSION", "export_training_set", "shard_path", "write_shard"]

#: Estimated bytes of an example's text (question, rationale, facts) for shard planning.
TEXT_BYTES = 8 * 1024


def _conditions(options: ExportOptions) -> list[Condition]:
    return [Condition(c) for c in options.conditions]


def one_house(root: Path, house: House) -> Dataset:
    """A dataset of ``house`` alone: its instances are built from it and dropped with it."""
    return Dataset(root, None, {house.house_id: house}, [])


def asked_house(root: Path, house: House, options: ExportOptions) -> EvaluationSet:
    """``house`` alone, its instances as the export's task asks them (the point task: the loader's)."""
    if options.task == "point":
        return one_house(root, house)
    from povagent.tasks.task_set import for_task

    return for_task(one_house(root, house), task_spec(options))


def _house_plan(root: Path, house: House, options: ExportOptions, report: ExportReport) -> list[tuple[str, int]]:
    """``(instance id, estimated bytes)`` of every example of ``house``, in the loader's
    instance order; an instance that cannot teach goes into ``report.skipped``."""
    frame_bytes = {f.image_path: f.file.stat().st_size for f in house.frames}
    out = []
    for inst in asked_house(root, house, options).instances(conditions=_conditions(options)):
        try:
            instance_facts(inst, house.pairs[inst.pair_id])
        except NoTeachingFrame as exc:
            report.skipped[inst.id] = str(exc).partition(": ")[2]
            continue
        if options.format in ("hf", "openai"):  # images inside the shard (openai: base64, 4/3)
            if inst.povbench_condition.uses_exploration_frames:
                size = sum(frame_bytes.get(f.image_path, 0) for f in inst.frames)
            else:
                size = inst.frames[0].file.stat().st_size
            size = size * 4 // 3 if options.format == "openai" else size
        else:
            size = 0
        out.append((inst.id, size + TEXT_BYTES))
    return out


def _plan_houses(
    root: Path, folders: Sequence[Path], options: ExportOptions, report: ExportReport, problems: list[Problem]
) -> dict[str, list[tuple[str, int]]]:
    """:func:`_house_plan` of every house that loads (image checks on), one house read at a time;
    what loading left out (houses, pairs) goes into ``report.left_out``."""
    by_house = {}
    for folder in folders:
        before = len(problems)
        house = load_house(folder, root, problems, check_images=True)
        report.left_out.update(left_out(folder, house, problems[before:]))
        if house is not None:
            by_house[house.house_id] = _house_plan(root, house, options, report)
    return by_house


def _plan(by_house: dict[str, list[tuple[str, int]]], splits: dict[str, str | None]) -> list[PlannedExample]:
    """Every example to write, in export order (split, house, the loader's instance order)."""
    order = {"train": 0, "validation": 1, "test": 2}
    houses = sorted((h for h in by_house if splits.get(h) is not None), key=lambda h: (order[splits[h] or "train"], h))
    return [PlannedExample(iid, hid, splits[hid] or "train", size) for hid in houses for iid, size in by_house[hid]]


def shard_path(out: Path, fmt: str, shard_name: str) -> Path:
    """Where a shard of format ``fmt`` is written."""
    return out / FORMAT_FOLDERS[fmt][0] / shard_name


def write_shard(dataset_root: str, out: str, shard: Shard, options: ExportOptions) -> int:
    """Write one shard (a plain function of its inputs: the same bytes wherever it runs).

    Loads only the shard's houses, builds their examples in plan order and writes them
    atomically; returns the number of examples written.
    """
    from povagent.tasks.task_set import TaskSet
    from povagent.train.chat_jsonl import write_jsonl_shard
    from povagent.train.examples import house_examples, make_strategy
    from povagent.train.openai_jsonl import write_openai_shard
    from povagent.train.parquet import write_parquet_shard

    root, target = Path(dataset_root), Path(out)
    wanted = {e.id for e in shard.examples}
    strategy = make_strategy(options.rationale, options.task)

    def examples() -> Iterator[TrainingExample]:
        for hid in shard.houses:  # one house in memory at a time
            house = load_house(root / "artifacts" / hid, root, [], check_images=False)
            if house is None:
                raise DatasetError(f"{root / 'artifacts' / hid}: the house could not be loaded for shard {shard.name}")
            asked = asked_house(root, house, options)
            insts = [i for i in asked.instances(conditions=_conditions(options)) if i.id in wanted]
            hop_of = asked.hop if isinstance(asked, TaskSet) else None  # a multi-hop instance's intermediate
            for ex in house_examples(house, insts, options.rationale, strategy, options.text_seed, options.exact_answers, hop_of):
                if isinstance(ex, tuple):
                    raise DatasetError(f"{ex[0]}: planned for {shard.name} but cannot teach now ({ex[1]})")
                yield ex

    path = shard_path(target, options.format, shard.name)
    if options.format == "hf":
        n = write_parquet_shard(path, examples(), shard.split, options.rationale, inside=target, planned_bytes=shard.size)
    elif options.format == "openai":
        n = write_openai_shard(path, target, examples())
    else:
        n = write_jsonl_shard(path, target, examples(), shard.split, options.rationale)
    if n != len(shard.examples):
        path.unlink(missing_ok=True)
        raise DatasetError(f"{shard.name}: planned {len(shard.examples)} examples, wrote {n}")
    return n


def _shard_complete(out: Path, options: ExportOptions, shard: Shard) -> bool:
    path = shard_path(out, options.format, shard.name)
    if path.is_symlink() or not path.is_file():  # a planted link is no shard of ours
        return False
    if options.format == "hf":
        from povagent.train.parquet import parquet_rows

        try:
            return parquet_rows(path) == len(shard.examples)
        except Exception:  # a file that is not Parquet: written again
            return False
    from povagent.train.chat_jsonl import jsonl_rows

    return jsonl_rows(path) == len(shard.examples)


ShardProgress = Callable[[Shard, int, int], None]


def _check_requirements(options: ExportOptions, cluster: Any) -> None:
    """Say what is missing (an extra) before anything is written: a refused export leaves no
    ``export.json`` that would refuse the next try with other options."""
    if options.format == "hf":
        from povagent.train.parquet import require_pyarrow

        require_pyarrow()
    if cluster is not None and isinstance(cluster, str):
        from povagent.cluster.client import require_distributed
        from povagent.config.cluster_spec import parse_cluster_spec

        parse_cluster_spec(cluster)
        require_distributed()


def export_training_set(
    dataset: str | Path,
    out: str | Path,
    options: ExportOptions | None = None,
    exclude: Sequence[str | Path] = (),
    drop_excluded: bool = False,
    check_release: bool = True,
    cluster: Any = None,
    progress: ShardProgress | None = None,
) -> ExportReport:
    """Export ``dataset`` as a training set under ``out`` (see the module docstring).

    ``exclude``: evaluation datasets whose houses must not be exported (by content hash, shared
    frames and generator identity); the release is checked too when it is in the local Hugging
    Face cache (``check_release``). A match is an :class:`ExportError` naming the houses, unless
    ``drop_excluded`` (then they are left out and listed in the card). ``cluster``: a
    ``--cluster`` value or a ``distributed.Client`` to write shards as cluster tasks.
    """
    options = options or ExportOptions()
    options.check()
    _check_requirements(options, cluster)
    start = time.perf_counter()
    root, target = Path(dataset).absolute(), Path(out).absolute()
    folders = dataset_house_folders(root)
    problems: list[Problem] = []
    meta = read_meta(root, problems)
    report = ExportReport(out=Path(out))
    evaluation = EvaluationSets()
    release = cached_release_root() if check_release else None
    if release is not None:
        if release.resolve() == root.resolve():
            raise ExportError(f"{root} is the POVBench release, an evaluation set: it cannot be a training set")
        evaluation.add(f"release ({release})", dataset_identities(release))
    for ex in exclude:
        ex_root = Path(ex)
        if not house_folders(ex_root):
            raise ExportError(f"--exclude {ex_root}: no house folders under {ex_root / 'artifacts'}")
        evaluation.add(str(ex_root), dataset_identities(ex_root))
    report.evaluation_sources = list(evaluation.sources)
    for ident in dataset_identities(root):
        hit = evaluation.match(ident)
        # a house that does not load is no house of the export, evaluation house or not
        if hit is not None and load_house(root / "artifacts" / ident.house_id, root, [], check_images=True) is not None:
            report.excluded[ident.house_id] = hit
    if report.excluded and not drop_excluded:
        shown = ", ".join(f"{h} (= {m})" for h, m in list(report.excluded.items())[:5])
        more = f" and {len(report.excluded) - 5} more" if len(report.excluded) > 5 else ""
        raise ExportError(
            f"{len(report.excluded)} house(s) of {root} are evaluation houses: {shown}{more}; "
            "a training set never holds them (--drop-excluded leaves them out)"
        )
    by_house = _plan_houses(root, [f for f in folders if f.name not in report.excluded], options, report, problems)
    if not by_house and not report.excluded:
        listing = "\n".join(f"  - {p}" for p in problems[:20])
        raise DatasetError(f"{root}: no usable house; problems:\n{listing}")
    splits = assign_splits(sorted(by_house), parse_split(options.split), options.split_seed)
    for hid, split in splits.items():
        if split is not None:
            report.houses_by_split.setdefault(split, []).append(hid)
    planned = _plan(by_house, splits)
    shards = plan_shards(planned, options.max_shard_bytes, FORMAT_FOLDERS[options.format][1])
    with export_folder(target, manifest(options, shards, root)):
        remove_stale_temporaries(target)
        todo = [s for s in shards if not _shard_complete(target, options, s)]
        _write(root, target, todo, len(shards) - len(todo), len(shards), options, cluster, progress)
        # what is on disk, not what the writers said: a worker writing where this machine does
        # not look would otherwise count as done
        missing = [s.name for s in shards if not _shard_complete(target, options, s)]
        if missing:
            raise ExportError(
                f"{target}: {len(missing)} shard(s) not on disk after writing ({', '.join(missing[:3])}"
                f"{' ...' if len(missing) > 3 else ''}); run the same command again to write them"
            )
        report.shards = [s.name for s in shards]
        report.shards_written = len(todo)
        report.examples = len(planned)
        report.counts = _counts(planned)
        write_card(target, root, meta, len(by_house) + len(report.excluded), options, report, shards)
    report.seconds = time.perf_counter() - start
    return report


def _write(
    root: Path, target: Path, todo: Sequence[Shard], done: int, total: int, options: ExportOptions, cluster: Any, progress: ShardProgress | None
) -> None:
    """Write the shards ``todo``, one after another or as cluster tasks."""

    def finished(shard: Shard) -> None:
        nonlocal done
        done += 1
        if progress:
            progress(shard, done, total)

    if cluster is None:
        for shard in todo:
            write_shard(str(root), str(target), shard, options)
            finished(shard)
    elif todo:
        from povagent.cluster.export_shards import write_shards_on_cluster

        write_shards_on_cluster(cluster, write_shard, root, target, todo, options, finished)


def _counts(planned: Sequence[PlannedExample]) -> dict[str, dict[str, int]]:
    """Examples per split, condition and direction."""
    counts: dict[str, Counter[str]] = {"split": Counter(), "condition": Counter(), "direction": Counter()}
    for e in planned:
        _instance, direction, condition = e.id.rsplit("/", 2)  # a pair id may hold "/"
        counts["split"][e.split] += 1
        counts["condition"][condition] += 1
        counts["direction"][direction] += 1
    return {k: dict(sorted(v.items())) for k, v in counts.items()}
