"""The ``vsibench`` format: VSI-Bench's questions (Parquet or JSONL) over its scene videos
(:mod:`povagent.dataset.choice_sets.vsibench_set`), asked in its own wording, read by its own
first-word rule and scored by accuracy and mean relative accuracy.

``dataset: {path: test.parquet, format: vsibench, options: {frames: 32}}``; the videos are
``<dataset>/<scene_name>.mp4`` under the file's folder, or under ``dataset.images``.
``options: {cache_dir: FOLDER}`` keeps each video's sampled frames in ``FOLDER`` across runs
(:mod:`povagent.dataset.frame_cache`), keyed by the video's bytes, so a second run decodes nothing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from povagent import hookimpl
from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.choice_sets.vsibench_records import PROFILE
from povagent.dataset.choice_sets.vsibench_set import DEFAULT_FRAMES, load_vsibench, validate_vsibench
from povagent.dataset.formats import DatasetFormat, DocsRow, FormatRead, PromptProfile
from povagent.dataset.problems import Problem
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import DatasetError
from povagent_plugins.parsers.vsibench.first_word import THINKING_IN_SPACE

#: The wording's source: ``vsibench_doc_to_text`` with the task's default kwargs.
SOURCE = f"{THINKING_IN_SPACE} lmms_eval/tasks/vsibench/utils.py vsibench_doc_to_text, vsibench.yaml's default prompts"
PRE_PROMPT = "These are frames of a video."
CHOICE_POST_PROMPT = "Answer with the option's letter from the given choices directly."
NUMBER_POST_PROMPT = "Please answer the question using a single word or phrase."
#: ``dataset.options`` a vsibench set takes: the frames a question shows, the frame cache's folder.
OPTION_NAMES = ("frames", "cache_dir")


def vsibench_text(question: Any) -> str:
    """The set's prompt after the frames: the pre-prompt, the question, then for a
    multiple-choice one ``Options:`` and the options one a line (``A. left``) and the
    instruction to answer a letter; for a numerical one the instruction to answer in a word."""
    if isinstance(question, ChoiceQuestion):
        options = "Options:\n" + "\n".join(f"{label}. {text}" for label, text in question.options)
        return "\n".join([PRE_PROMPT, question.question, options, CHOICE_POST_PROMPT])
    return f"{PRE_PROMPT}\n{question.question}\n{NUMBER_POST_PROMPT}"


def _frames(request: FormatRead) -> int:
    unknown = sorted(set(request.options) - set(OPTION_NAMES))
    if unknown:
        raise DatasetError(f"{request.path}: a vsibench set takes dataset.options {' and '.join(OPTION_NAMES)} only (got {', '.join(unknown)})")
    frames = request.options.get("frames", DEFAULT_FRAMES)
    if not isinstance(frames, int) or isinstance(frames, bool) or not 1 <= frames <= 256:
        raise DatasetError(f"{request.path}: dataset.options.frames must be a whole number from 1 to 256, got {frames!r}")
    return frames


def _frame_cache(request: FormatRead) -> Path | None:
    folder = request.options.get("cache_dir")
    if folder is None:
        return None
    if not isinstance(folder, (str, Path)) or not str(folder).strip():
        raise DatasetError(f"{request.path}: dataset.options.cache_dir must name a folder, got {folder!r}")
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise DatasetError(f"{request.path}: dataset.options.cache_dir {folder} is not a folder (it keeps the videos' sampled frames)")
    return path


def read(request: FormatRead) -> EvaluationSet:
    """The set ``request`` names, each question showing ``frames`` frames of its scene (decoded
    only where images are checked: rescoring and the report read the gold answers alone)."""
    return load_vsibench(request.path, _frames(request), videos=request.images, decode=request.check_images, frame_cache=_frame_cache(request))


def problems(request: FormatRead) -> list[Problem]:
    """Every problem of the set ``request`` names (each scene video decoded once)."""
    return validate_vsibench(request.path, _frames(request), videos=request.images, frame_cache=_frame_cache(request))


VSIBENCH = DatasetFormat(
    key="vsibench",
    description="VSI-Bench: spatial questions over indoor scene videos, answered with an option letter or a number",
    read=read,
    validate=problems,
    record_id=lambda item_id: f"record {item_id}",
    answer_type="choice-or-number",
    # the set's own first-word rule; lmms-eval's reading (extract_number for numbers) is vsibench-lmms
    official_parser="vsibench",
    official_scorer="vsibench",
    prompt_profile=PromptProfile(PROFILE, vsibench_text, SOURCE),
    source=THINKING_IN_SPACE,
    licence="Apache-2.0 (the dataset card; the scene videos keep ScanNet's, ScanNet++'s and ARKitScenes' terms)",
    docs_row=DocsRow(
        name="VSI-Bench",
        where="[`nyu-visionx/VSI-Bench`](https://huggingface.co/datasets/nyu-visionx/VSI-Bench)",
        path="the Parquet or JSONL file of questions, the scene videos `<dataset>/<scene_name>.mp4` beside it",
        how_to="how-to/vsibench.md",
    ),
    option_names=OPTION_NAMES,
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the VSI-Bench format."""
    register(VSIBENCH.key, VSIBENCH, description=VSIBENCH.description)


__all__ = ["VSIBENCH", "vsibench_text"]
