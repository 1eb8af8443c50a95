"""The gold label and category of a multiple-choice question no row scored, read from the set.

The runner scores only answers, so a question every system answered with no option (or whose
every request failed) has no scored row telling its gold label. The set the run names
(``dataset: {path, format, images}`` in its config, asked as its ``task:``) knows it: each of
its instances carries its :class:`~povagent.answers.choice_question.ChoiceQuestion`, whose ``gold`` and
``category`` are what the choice scorer writes (:mod:`povagent_plugins.scorers.choice_scorer`). The set
is opened as the runner opens it (:func:`~povagent.dataset.evaluation_set.open_evaluation_set`,
then :func:`~povagent.tasks.task_set.for_task`), once per report and only when a question needs
it; a set that cannot be opened leaves the question's gold unknown,
and :meth:`SetQuestions.why_unknown` says why in one line.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from povagent.errors import PovagentError
from povagent.report.collect import RunInfo

#: How a set is told apart: its file or folder, its format, its images folder and the task it is
#: asked as (the config's ``task:`` as JSON; ``None``: POVBench's point task).
_SetKey = tuple[Path, str | None, Path | None, str | None, str | None]


class SetQuestions:
    """The questions of the sets a report's runs name, each set opened at most once."""

    def __init__(self) -> None:
        self._sets: dict[_SetKey, Any] = {}
        self._keys: dict[Path, _SetKey | None] = {}  # each run's set, read from its config once
        self._reasons: dict[str, None] = {}  # why a question stayed unknown, in the order met

    def question(self, run: RunInfo, instance_id: str) -> tuple[str, str] | None:
        """``(gold, category)`` of ``instance_id`` in the set ``run`` names, or ``None`` (the
        reason is kept for :meth:`why_unknown`)."""
        if run.folder not in self._keys:
            self._keys[run.folder] = run_set_key(run)
        key = self._keys[run.folder]
        if key is None:
            self._reasons.setdefault(f"{run.folder / 'config.yaml'} names no dataset", None)
            return None
        loaded = self.opened(key)
        if isinstance(loaded, str):
            self._reasons.setdefault(loaded, None)
            return None
        instance = loaded.instance(instance_id)
        question = getattr(instance, "question", None)
        if question is None:
            self._reasons.setdefault(f"{key[0]} holds no multiple-choice question of their ids", None)
            return None
        return str(question.gold), str(question.category or "")

    def opened(self, key: _SetKey) -> Any:
        """The set ``key`` names (:func:`open_run_set`, opened once), or the line saying why not."""
        if key not in self._sets:
            self._sets[key] = open_run_set(key)
        return self._sets[key]

    def why_unknown(self, n: int) -> str:
        """One sentence: the gold of ``n`` questions is unknown, and why (``""`` when ``n`` is 0)."""
        if n == 0:
            return ""
        because = "; ".join(self._reasons) or "no row of them was scored"
        return f"The gold label of {n} question{'s' if n != 1 else ''} is unknown because {because}."


def run_set_key(run: RunInfo, override: Path | None = None) -> _SetKey | None:
    """What tells the set ``run`` was asked apart: its file or folder (``override`` in its
    place when given), format, images folder, task and format options (``None``: its config
    names no set)."""
    path = override if override is not None else run.dataset_path
    if path is None:
        return None
    ds = run.config.get("dataset")
    ds = ds if isinstance(ds, dict) else {}
    format = str(ds["format"]) if ds.get("format") else None
    images = _resolved(run, ds["images"]) if ds.get("images") else None
    task = run.config.get("task")
    options = json.dumps(ds["options"], sort_keys=True) if isinstance(ds.get("options"), dict) and ds["options"] else None
    return path, format, images, None if task in (None, "point") else json.dumps(task, sort_keys=True), options


def _resolved(run: RunInfo, raw: object) -> Path:
    """A path of the run's config, as :attr:`RunInfo.dataset_path` resolves the set's."""
    p = Path(str(raw)).expanduser()
    return p if p.is_absolute() or p.exists() else (run.folder / p).resolve()


def open_run_set(key: _SetKey) -> Any:
    """The set ``key`` names, opened as the runner opens it (its format, images and task), or one line (``<file>: <reason>``) saying why it cannot be opened."""
    from povagent.dataset.evaluation_set import open_evaluation_set

    root, format, images, task, options = key
    try:
        # the run's own plugins are not loaded: a report never runs code a run folder names (a
        # format must be installed, built in or by entry point, for its runs to be reported)
        loaded = open_evaluation_set(root, check_images=False, format=format, images=images, options=json.loads(options) if options else None)
        if task is None:
            return loaded
        from povagent.config.models import TaskSpec
        from povagent.tasks.task_set import for_task  # the generator's scene: only when a task asks

        return for_task(loaded, TaskSpec.model_validate(json.loads(task)))
    except (PovagentError, OSError, ValueError) as exc:  # ValueError: a task the config cannot hold
        reason = " ".join(str(exc).split())
        return reason if reason.startswith(str(root)) else f"{root}: {reason}"
