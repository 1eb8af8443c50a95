"""A loaded set seen through a task: the instances a pipeline's ``task:`` asks.

What it is for: the runner, rescore and show-prompt read instances from an
:class:`~povagent.dataset.set_interface.EvaluationSet`; :func:`for_task` hands them the loaded set
itself for the point task (POVBench's own: nothing changes) and a :class:`TaskSet` otherwise,
whose instances are the task's (:mod:`povagent.tasks.relation`, :mod:`povagent.tasks.multi_hop`)
under the point instances' ids. The config hash holds the task, so a run folder never mixes
rows of two tasks.

What it must not do: load or change the underlying set; a set the task cannot be asked of (a
sentence the generator does not write, a house without its generated record) is refused in one
line naming the file and field, before any request.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from povagent.config.models import TaskSpec
from povagent.dataset.instances import Instance
from povagent.dataset.problems import Problem
from povagent.dataset.release_models import Condition, Direction
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import DatasetError
from povagent.generate.scene import House as Scene
from povagent.tasks.multi_hop import Hop, find_hop, house_scene, multi_hop_instance
from povagent.tasks.relation import relation_instance
from povagent.tasks.sentence_parts import SentenceShapeError


def _sentence_field(instance: Instance) -> str:
    """Where the instance's sentence is in its house's file (``stage5.left.type_a``)."""
    if instance.condition is Condition.GIVEN:
        return f"stage6.{instance.direction}.type_c"
    return f"stage5.{instance.direction}.type_{'a' if instance.condition is Condition.INFERRED else 'b'}"


@dataclass
class TaskSet:
    """``base``'s instances asked as ``task`` (see the module docstring)."""

    base: EvaluationSet
    task: TaskSpec
    #: The dataset folder and the problems met loading it: the underlying set's.
    root: Path = field(init=False)
    problems: list[Problem] = field(init=False)
    _built: dict[str, Instance | None] = field(default_factory=dict, init=False, repr=False)
    _scenes: dict[str, Scene] = field(default_factory=dict, init=False, repr=False)
    _hops: dict[str, Hop] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        self.root, self.problems = self.base.root, self.base.problems

    @property
    def houses(self) -> Mapping[str, Any]:
        """The loaded houses by id."""
        return self.base.houses

    def _scene(self, house_id: str) -> Scene:
        scene = self._scenes.get(house_id)
        if scene is None:
            scene = self._scenes[house_id] = house_scene(self.root, house_id)
        return scene

    def asked(self, instance: Instance) -> Instance | None:
        """The task's instance of a point instance (None: the task has none for it)."""
        if instance.id in self._built:
            return self._built[instance.id]
        made: Instance | None
        try:
            if self.task.name == "relation":
                made = relation_instance(instance)
            else:
                hop = find_hop(instance, self._scene(instance.house_id))
                made = None if hop is None else multi_hop_instance(instance, hop, self.task.answer or "point")
                if hop is not None:
                    self._hops[instance.id] = hop
        except SentenceShapeError as exc:
            where = self.root / "artifacts" / instance.house_id / f"{instance.house_id}.json"
            raise DatasetError(
                f"{where}: pair {instance.pair_id} field {_sentence_field(instance)}: {exc}; task {self.task.name} runs on sets made by `povagent generate`"
            ) from None
        self._built[instance.id] = made
        return made

    def hop(self, instance_id: str) -> Hop | None:
        """The intermediate a multi-hop instance goes through (None: none, or another task)."""
        return self._hops.get(instance_id)

    def instances(
        self,
        conditions: Iterable[Condition | str] | None = None,
        directions: Iterable[Direction | str] | None = None,
        houses: Iterable[str] | None = None,
    ) -> Sequence[Instance]:
        """The task's instances of the selected point instances, in their order."""
        out = []
        for point in self.base.instances(conditions, directions, houses):
            made = self.asked(point)
            if made is not None:
                out.append(made)
        return out

    def instance(self, id_: str) -> Instance | None:
        """The task's instance with id ``house/pair/direction/condition``, or ``None``."""
        point = self.base.instance(id_)
        return None if point is None else self.asked(point)

    def check_scorers(self, scorers: Mapping[str, Any]) -> None:
        """As the underlying set's."""
        self.base.check_scorers(scorers)


def for_task(dataset: EvaluationSet, task: TaskSpec | None) -> EvaluationSet:
    """``dataset`` as the pipeline's task asks it: itself for the point task, and for a set
    already asked that task (the runner asks a set a sweep hands it, which may be asked)."""
    if task is None or task.is_point_task or task.answer == "walk":  # a walk goes to the point task's target
        return dataset
    if isinstance(dataset, TaskSet):  # already asked: asked again it is the same set
        if dataset.task != task:
            raise ValueError(f"a set asked as task {dataset.task.name} cannot be asked as task {task.name}")
        return dataset
    return TaskSet(dataset, task)
