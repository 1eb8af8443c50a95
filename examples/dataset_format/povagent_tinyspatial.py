"""TinySpatial, a fourth multiple-choice set, as one plugin module: its reader, its official rule
and its format, registered through the ``povagent`` entry point of the distribution that ships it.

A record is one JSON line: ``{"id", "images": [paths], "question", "options": [texts], "answer":
"B", "category"}``, image paths relative to the file's folder. The set's own rule reads the last
``Answer: X`` of a reply (``X`` a letter A-D, any case).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from povagent import hookimpl
from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.dataset.choice_sets import ChoiceFiles, ChoiceReader
from povagent.dataset.choice_sets.external import Item, text_problems
from povagent.dataset.formats import DatasetFormat, DocsRow, PromptProfile
from povagent.dataset.json_files import TooDeepError, loads_dataset_json
from povagent.dataset.problems import Problem
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular
from povagent.interfaces import Parser

LABELS = "ABCD"
PROFILE = "tinyspatial"
_ANSWER = re.compile(r"Answer:\s*([A-D])\b", re.IGNORECASE)


def record_id(item_id: str) -> str:
    """How a problem names a record: by its id."""
    return f"record {item_id}"


def read_records(file: Path, cache: Path) -> tuple[list[Item], list[Problem]]:
    """Every sound line of the JSONL file as an item, one problem per bad line (never an image opened)."""
    items: list[Item] = []
    problems: list[Problem] = []
    seen: set[str] = set()
    text = read_regular(file, MAX_DOCUMENT_BYTES, what="TinySpatial file").decode("utf-8", errors="replace")
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        where = f"line {number}"
        try:
            record = loads_dataset_json(line)
        except (json.JSONDecodeError, TooDeepError) as exc:
            problems.append(Problem(str(file), where, f"not valid JSON: {exc}"))
            continue
        not_text = text_problems(str(file), where, record)
        if not_text:  # a lone surrogate is not text: the record is left out
            problems += not_text
            continue
        item = _item(record, where)
        if isinstance(item, tuple):
            problems.append(Problem(str(file), *item))
        elif item.id in seen:
            problems.append(Problem(str(file), f"{where}.id", f"{item.id!r} is used by an earlier record; this one left out"))
        else:
            seen.add(item.id)
            items.append(item)
    return items, problems


def _item(record: object, where: str) -> Item | tuple[str, str]:
    """The record as an item, or ``(where, what is wrong)``."""
    if not isinstance(record, dict):
        return where, "a record must be a JSON object"
    for key in ("id", "question", "answer", "category"):
        if not isinstance(record.get(key), str) or not record[key]:
            return f"{where}.{key}", "required, a non-empty string"
    options, images = record.get("options"), record.get("images")
    if not isinstance(options, list) or not 2 <= len(options) <= len(LABELS) or not all(isinstance(o, str) for o in options):
        return f"{where}.options", f"required, a list of 2 to {len(LABELS)} option texts"
    if not isinstance(images, list) or not 1 <= len(images) <= 8 or not all(isinstance(p, str) and p for p in images):
        return f"{where}.images", "required, a list of 1 to 8 image paths"
    try:
        question = ChoiceQuestion(record["question"], tuple(zip(LABELS, options)), record["answer"], category=record["category"], profile=PROFILE)
    except ValueError as exc:  # a gold label that is no option's
        return f"{where}.answer", str(exc)
    return Item(record["id"], question, tuple(images))


def prompt_text(question: ChoiceQuestion) -> str:
    """The set's wording: the question, the options one a line, and how to answer."""
    return f"{question.question}\n{question.options_block()}\nEnd your reply with 'Answer: X', X the option's letter."


class TinySpatialParser(Parser):
    """TinySpatial's own rule: the last ``Answer: X`` of the reply."""

    answer_types = frozenset({"choice"})

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The label of the last ``Answer: X``; no such line is no answer (never raises)."""
        found = _ANSWER.findall(text or "")
        if not found:
            return unparseable("no 'Answer: X' in the reply", span=(text or "")[:200] or None)
        return ParsedAnswer(status=ParseStatus.OK, choice=found[-1].upper(), span=(text or "")[:200])


FILES = ChoiceFiles(key="tinyspatial", records=read_records, record_id=record_id)
READER = ChoiceReader(FILES)
TINYSPATIAL = DatasetFormat(
    key="tinyspatial",
    description="TinySpatial: multiple-choice left/right questions about a few photos",
    read=READER,
    validate=READER.problems,
    record_id=record_id,
    answer_type="choice",
    official_parser="tinyspatial-official",
    official_scorer="choice",
    prompt_profile=PromptProfile(PROFILE, prompt_text, "TinySpatial's eval.py @ 0123456789abcdef0123456789abcdef01234567"),
    source="example/TinySpatial@0123456789abcdef0123456789abcdef01234567",
    licence="CC-BY-4.0",
    docs_row=DocsRow(
        "TinySpatial", "[`example/TinySpatial`](https://huggingface.co/datasets/example/TinySpatial)", "the JSONL file", "how-to/extend-povagent.md"
    ),
)


@hookimpl
def register_parsers(register) -> None:
    """The set's official rule."""
    register("tinyspatial-official", TinySpatialParser, description="TinySpatial's rule: the last 'Answer: X' of the reply")


@hookimpl
def register_dataset_formats(register) -> None:
    """The set's format."""
    register(TINYSPATIAL.key, TINYSPATIAL, description=TINYSPATIAL.description)
