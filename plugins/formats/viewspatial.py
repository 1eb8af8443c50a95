"""The ``viewspatial`` format: ViewSpatial-Bench's JSON list of questions (:mod:`povagent.dataset.choice_sets.viewspatial_records`),
asked in its paper's wording and read by its own ``evaluate.py``."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.viewspatial_records import PROFILE, read_viewspatial
from povagent.dataset.formats import DocsRow, PromptProfile
from povagent_plugins.parsers.mcq.upstream import VIEWSPATIAL_BENCH
from povagent_plugins.strategies import set_profiles

FILES = ChoiceFiles(
    key="viewspatial",
    records=lambda file, cache: read_viewspatial(file),
    record_id=lambda item_id: f"$[{item_id}]",  # the record's position in the JSON list: the set gives no id
    repository_file="eval/ViewSpatial-Bench.json",
    images_hint="ViewSpatial-Bench's image paths are relative to its repository root: give the repository "
    "folder as dataset.path (the set's file is then its eval/ViewSpatial-Bench.json), or that root as dataset.images",
)

VIEWSPATIAL = choice_set_format(
    FILES,
    description="ViewSpatial-Bench: multiple-choice perspective taking over ScanNet and COCO images",
    # the set's own evaluate.py; lmms-eval's port (viewspatial, after its reasoning strip) is an alternative
    official_parser="viewspatial-official",
    official_scorer="choice",
    prompt_profile=PromptProfile(PROFILE, set_profiles.viewspatial_text, set_profiles.VIEWSPATIAL_SOURCE),
    source=VIEWSPATIAL_BENCH,
    licence="Apache-2.0",
    docs_row=DocsRow(
        name="ViewSpatial-Bench",
        where="[`lidingm/ViewSpatial-Bench`](https://huggingface.co/datasets/lidingm/ViewSpatial-Bench)",
        path="the JSON list of questions",
        how_to="how-to/perspective-sets.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the ViewSpatial-Bench format."""
    register(VIEWSPATIAL.key, VIEWSPATIAL, description=VIEWSPATIAL.description)


__all__ = ["FILES", "VIEWSPATIAL"]
