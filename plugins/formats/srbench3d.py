"""The ``3dsrbench`` format: 3DSRBench's TSV in VLMEvalKit's layout (:mod:`povagent.dataset.choice_sets.srbench3d_records`),
scored as its authors score it, with VLMEvalKit's exact matching and the four accuracies over a
question's copies."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.srbench3d_records import PROFILE, read_srbench3d
from povagent.dataset.formats import DocsRow, PromptProfile
from povagent_plugins.parsers.mcq.upstream import VLMEVALKIT
from povagent_plugins.strategies import set_profiles

FILES = ChoiceFiles(key="3dsrbench", records=read_srbench3d)

SRBENCH3D = choice_set_format(
    FILES,
    description="3DSRBench: multiple-choice 3D spatial reasoning, each question asked in circular and flipped copies",
    # VLMEvalKit's exact matching, with which the set's authors score it; lmms-eval's is `3dsrbench-lmms`
    official_parser="vlmevalkit-exact",
    official_scorer="choice-3dsrbench",
    prompt_profile=PromptProfile(PROFILE, set_profiles.srbench3d_text, set_profiles.SRBENCH3D_SOURCE),
    source=VLMEVALKIT,
    licence="CC-BY-4.0",
    docs_row=DocsRow(
        name="3DSRBench",
        where="[`ccvl/3DSRBench`](https://huggingface.co/datasets/ccvl/3DSRBench)",
        path="the TSV (VLMEvalKit's layout)",
        how_to="how-to/perspective-sets.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the 3DSRBench format."""
    register(SRBENCH3D.key, SRBENCH3D, description=SRBENCH3D.description)
