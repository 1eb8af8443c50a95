"""The ``mindcube`` format: MindCube's JSONL records (:mod:`povagent.dataset.choice_sets.mindcube_records`), asked
in its raw-QA template and read by its own evaluator's cascade."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.mindcube_records import PROFILE, read_mindcube
from povagent.dataset.formats import DocsRow, PromptProfile
from povagent_plugins.parsers.mcq.upstream import MINDCUBE as MINDCUBE_SOURCE
from povagent_plugins.strategies import set_profiles

FILES = ChoiceFiles(key="mindcube", records=lambda file, cache: read_mindcube(file))

MINDCUBE = choice_set_format(
    FILES,
    description="MindCube: multiple-choice spatial reasoning from a few views of one scene",
    # the set's own evaluator (its cascade on the reply as written); lmms-eval's port is `mindcube`
    official_parser="mindcube-official",
    # the evaluator's overall leaves the translation setting out
    official_scorer="choice-mindcube",
    prompt_profile=PromptProfile(PROFILE, set_profiles.mindcube_text, set_profiles.MINDCUBE_SOURCE, interleaved=True),
    source=MINDCUBE_SOURCE,
    licence="see the dataset card (the code is MIT)",
    docs_row=DocsRow(
        name="MindCube",
        where="[`MLL-Lab/MindCube`](https://huggingface.co/datasets/MLL-Lab/MindCube)",
        path="a JSONL file (`MindCube_tinybench.jsonl`, ...)",
        how_to="how-to/perspective-sets.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the MindCube format."""
    register(MINDCUBE.key, MINDCUBE, description=MINDCUBE.description)
