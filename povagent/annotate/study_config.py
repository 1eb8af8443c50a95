"""An annotation YAML: a pipeline YAML whose backend is ``human``, plus who answers.

Answer mode takes the pipeline YAML a model run takes (dataset, instances, strategy for the
prompt text, scorers, output) with ``backend: human`` and two keys of its own::

    annotator: alice            # the system is named human:alice in every report
    annotation:                 # optional
      seed: 0                   # the annotator's order (with the name)
      pairs_apart: true         # never two instances of one pair back to back

A person answers one question at a time and may look for as long as they need, so the run is
made with ``concurrency: 1``, the longest ``timeout`` a pipeline allows, and no response cache,
whatever the YAML says.

Judge mode takes a YAML of its own, naming the judge and the runs whose predictions are judged::

    judge: carol                 # judgements go to <judgements>/carol.jsonl
    runs: [runs/model-a, sweeps/realworld]
    judgements: runs/judgements  # optional; default: judgements/ beside the first of runs
    seed: 0                      # optional: the judge's order (with the name)
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from povagent.annotate.desk import PERSON_NAME
from povagent.config.models import MAX_WAIT_S, PipelineConfig
from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource, read_yaml
from povagent.errors import ConfigError
from povagent.results.judgements import JUDGEMENTS_FOLDER


@dataclass(frozen=True)
class AnswerStudy:
    """What answer mode runs: the pipeline, and the annotator's order."""

    pipeline: PipelineConfig
    annotator: str
    seed: int = 0
    pairs_apart: bool = True


@dataclass(frozen=True)
class JudgeStudy:
    """What judge mode shows: the runs' predictions, who judges, where the judgements go."""

    judge: str
    runs: list[Path]
    #: the folder the judge named (followed), or the first run's parent for the default
    judgements: Path
    seed: int = 0
    #: the default ``judgements`` folder below :attr:`judgements`, never followed as a link ("": named)
    judgements_below: str = ""


def load_study(path: str | Path) -> AnswerStudy | JudgeStudy:
    """An annotation YAML of either mode: judge mode when it names a ``judge``."""
    source = read_yaml(path)
    if isinstance(source.data, Mapping) and "judge" in source.data:
        return _judge_study(source)
    return load_answer_study(path)


def _judge_study(source: ConfigSource) -> JudgeStudy:
    data = dict(source.data)
    unknown = sorted(set(data) - {"judge", "runs", "judgements", "seed"})
    if unknown:
        raise ConfigError(f"{source.where((unknown[0],))}: {unknown[0]}: judge mode takes judge, runs, judgements and seed only")
    judge = data["judge"]
    if not isinstance(judge, str) or not re.fullmatch(PERSON_NAME, judge):
        raise ConfigError(f"{source.where(('judge',))}: judge: {judge!r} is not a name (letters, digits, '_', '.', '-'; at most 64)")
    runs = data.get("runs")
    if isinstance(runs, str):
        runs = [runs]
    if not isinstance(runs, list) or not runs or not all(isinstance(r, str) and r for r in runs):
        raise ConfigError(f"{source.where(('runs',))}: runs: list the run or sweep folders whose predictions are judged")
    base = Path(source.file).parent
    folders = [(base / r).resolve() if not Path(r).is_absolute() else Path(r) for r in runs]
    for folder, raw in zip(folders, runs):
        if not folder.is_dir():
            raise ConfigError(f"{source.where(('runs',))}: runs: {raw} is not a folder")
    where = data.get("judgements")
    if where is not None and not isinstance(where, str):
        raise ConfigError(f"{source.where(('judgements',))}: judgements: a folder path")
    seed = data.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise ConfigError(f"{source.where(('seed',))}: seed: an integer")
    if where:
        return JudgeStudy(judge, folders, (base / where).resolve(), seed)
    return JudgeStudy(judge, folders, folders[0].parent, seed, judgements_below=JUDGEMENTS_FOLDER)


def _backend_name(backend: Any) -> Any:
    return backend.get("name") if isinstance(backend, Mapping) else backend


def load_answer_study(path: str | Path) -> AnswerStudy:
    """Read an annotation YAML (answer mode); any problem is one :class:`ConfigError` line naming
    the file and the field."""
    source = read_yaml(path)
    if not isinstance(source.data, Mapping):
        raise ConfigError(f"{source.file}: an annotation config must be a YAML mapping (key: value)")
    data = dict(source.data)
    annotator = data.pop("annotator", None)
    if not isinstance(annotator, str):
        raise ConfigError(f"{source.where(('annotator',))}: annotator: name the person answering (annotator: alice)")
    if not re.fullmatch(PERSON_NAME, annotator):  # refused here, before any page is served or its address printed
        raise ConfigError(f"{source.where(('annotator',))}: annotator: {annotator!r:.80} is not a name (letters, digits, '_', '.', '-'; at most 64)")
    extra = data.pop("annotation", None) or {}
    if not isinstance(extra, Mapping) or set(extra) - {"seed", "pairs_apart"}:
        raise ConfigError(f"{source.where(('annotation',))}: annotation: takes only seed (an integer) and pairs_apart (true or false)")
    seed, apart = extra.get("seed", 0), extra.get("pairs_apart", True)
    if not isinstance(seed, int) or isinstance(seed, bool) or not isinstance(apart, bool):
        raise ConfigError(f"{source.where(('annotation',))}: annotation: seed must be an integer and pairs_apart true or false")
    backend = data.get("backend")
    if _backend_name(backend) != "human":
        raise ConfigError(f"{source.where(('backend',))}: backend: answer mode takes `backend: human` (a person answers), got {backend!r}")
    options = dict(backend.get("options") or {}) if isinstance(backend, Mapping) else {}
    data["backend"] = {"name": "human", "options": {**options, "annotator": annotator}}
    data.update(concurrency=1, timeout=MAX_WAIT_S, cache={"enabled": False})
    pipeline = pipeline_from_source(ConfigSource(source.file, data, source.lines, source.folder))
    return AnswerStudy(pipeline, annotator, seed, apart)
