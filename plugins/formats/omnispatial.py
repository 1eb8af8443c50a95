"""The ``omnispatial`` format: OmniSpatial's ``data.json`` and its task folders' images
(:mod:`povagent.dataset.choice_sets.omnispatial_records`), asked in the set's own wording and read by its
own default ``re`` rule (its other readings and lmms-eval's two tasks' are alternatives a pipeline names)."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.omnispatial_records import DATA_FILE, PROFILE, read_omnispatial
from povagent.dataset.formats import DocsRow, PromptProfile
from povagent_plugins.parsers.mcq.upstream import OMNISPATIAL
from povagent_plugins.strategies import spatial_set_profiles

FILES = ChoiceFiles(key="omnispatial", records=lambda file, cache: read_omnispatial(file), repository_file=DATA_FILE)

OMNISPATIAL_FORMAT = choice_set_format(
    FILES,
    description="OmniSpatial: multiple-choice spatial reasoning in four task types; Perspective_Taking by sub-task",
    # api_eval.py's default --eval_type re, its none-reads-A fallback included; omnispatial-re-corrected beside it
    official_parser="omnispatial-re",
    official_scorer="choice",
    prompt_profile=PromptProfile(PROFILE, spatial_set_profiles.omnispatial_text, spatial_set_profiles.OMNISPATIAL_SOURCE),
    source=OMNISPATIAL,
    licence="CC-BY-NC-4.0",
    docs_row=DocsRow(
        name="OmniSpatial",
        where="[`qizekun/OmniSpatial`](https://huggingface.co/datasets/qizekun/OmniSpatial)",
        path="`data.json` of the unpacked `OmniSpatial-test.zip` (or its folder)",
        how_to="how-to/omnispatial.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the OmniSpatial format."""
    register(OMNISPATIAL_FORMAT.key, OMNISPATIAL_FORMAT, description=OMNISPATIAL_FORMAT.description)


__all__ = ["FILES", "OMNISPATIAL_FORMAT"]
