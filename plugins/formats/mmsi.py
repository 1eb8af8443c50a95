"""The ``mmsi`` format: MMSI-Bench's ``MMSI_Bench.parquet``, images embedded (:mod:`povagent.dataset.choice_sets.mmsi_records`),
asked in the set's own wording and read by its own rule (lmms-eval's ``mmsi-lmms`` and VLMEvalKit's
``vlmevalkit-spatial`` with ``choice-vlmevalkit`` are alternatives a pipeline names)."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.mmsi_records import PROFILE, read_mmsi
from povagent.dataset.formats import DocsRow, PromptProfile
from povagent_plugins.parsers.mcq.upstream import MMSI_BENCH
from povagent_plugins.strategies import spatial_set_profiles

# the reader names a bad row by its position ("row 3"); a bad image found later, by the row's id
FILES = ChoiceFiles(key="mmsi", records=read_mmsi, repository_file="MMSI_Bench.parquet")

MMSI = choice_set_format(
    FILES,
    description="MMSI-Bench: multiple-choice spatial reasoning over several real-world images per question",
    # the set's own extract_single_choice_with_word_boundary; lmms-eval's reading is mmsi-lmms
    official_parser="mmsi-official",
    official_scorer="choice",
    prompt_profile=PromptProfile(PROFILE, spatial_set_profiles.mmsi_text, spatial_set_profiles.MMSI_SOURCE),
    source=MMSI_BENCH,
    licence="CC-BY-NC-4.0",
    docs_row=DocsRow(
        name="MMSI-Bench",
        where="[`RunsenXu/MMSI-Bench`](https://huggingface.co/datasets/RunsenXu/MMSI-Bench)",
        path="`MMSI_Bench.parquet` (images embedded)",
        how_to="how-to/mmsi-bench.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the MMSI-Bench format."""
    register(MMSI.key, MMSI, description=MMSI.description)


__all__ = ["FILES", "MMSI"]
