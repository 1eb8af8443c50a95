"""The ``realworld`` format: a folder of photos marked by hand with ``realworld.json``
(:mod:`povagent.dataset.realworld_set`), its 2D marks scored by hit or miss (``success``)."""

from __future__ import annotations

from pathlib import Path

from povagent import hookimpl
from povagent.dataset.formats import DatasetFormat, DocsRow, FormatRead
from povagent.dataset.set_interface import EvaluationSet


def read_realworld_set(request: FormatRead) -> EvaluationSet:
    """The real-world set at ``request.path`` (:func:`povagent.dataset.realworld_set.load_realworld`)."""
    from povagent.dataset.realworld_set import load_realworld

    return load_realworld(request.path)


def holds_index(root: Path) -> bool:
    """Whether ``root`` holds ``realworld.json``."""
    from povagent.dataset.realworld_set import is_realworld

    return is_realworld(root)


REALWORLD = DatasetFormat(
    key="realworld",
    description="A real-world set: your robot's photos with the answer marked by hand (realworld.json)",
    read=read_realworld_set,
    record_id=lambda scenario: f"scenario {scenario}",
    answer_type="point",
    official_parser="official",
    official_scorer="success",
    source="povagent (realworld.json, version 1)",
    licence="yours",
    docs_row=DocsRow(name="a real-world set", where="your own photos", path="the folder holding `realworld.json`", how_to="how-to/realworld.md"),
    detect=holds_index,
    detect_order=10,
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the real-world set's format."""
    register(REALWORLD.key, REALWORLD, description=REALWORLD.description)
