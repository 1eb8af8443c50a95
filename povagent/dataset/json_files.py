"""Reading one JSON file of a dataset: the boundary every value read from a dataset crosses.

What it is for: loading (:mod:`povagent.dataset.loader`) and ``povagent validate``
(:mod:`povagent.dataset.validate`) read a dataset's JSON files through
:func:`read_dataset_json`, so both refuse the same files for the same reasons in the same
words: a file leading outside the dataset (never opened), a missing or unreadable one, one that
is not a regular file or is too large (a pipe, a device: refused, never waited on:
:mod:`povagent.files.confined_read`), bytes that are not UTF-8, text that is not JSON or nests too deeply, and strings that are not text
(a lone surrogate such as ``"\\ud800"``, which no results, report or export file can hold:
:func:`~povagent.dataset.problems.not_text_problems`). Each refusal is a :class:`Problem`
naming the file (and, for a string, its JSON path), and the file reads as ``None``. What it
must not do: judge what the values mean (the models and the shipped schemas do that).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from povagent.dataset.paths import is_inside
from povagent.dataset.problems import Problem, not_text_problems
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular

#: What a document nesting deeper than Python's parser follows is told (a hostile file may nest
#: lists 100,000 deep: one line, never a ``RecursionError``).
TOO_DEEP = "nests lists or objects too deeply to be a release file"


class TooDeepError(ValueError):
    """JSON text nesting too deeply to be read (the message is :data:`TOO_DEEP`)."""


def loads_dataset_json(text: str) -> Any:
    """``text`` parsed as JSON, by the rule every dataset reader shares (the release layout, the
    multiple-choice sets): :class:`json.JSONDecodeError` for text that is not JSON, and
    :class:`TooDeepError` for text nesting deeper than the parser can follow. The value's strings
    are checked by :func:`~povagent.dataset.problems.not_text_problems`, which walks without
    recursion."""
    try:
        return json.loads(text)
    except RecursionError:
        raise TooDeepError(TOO_DEEP) from None


def read_dataset_json(path: Path, rel: str, real_root: Path, problems: list[Problem]) -> Any:
    """The parsed JSON of the dataset file ``path`` (named ``rel`` in problems), or ``None``
    when it is refused, each reason appended to ``problems``; ``real_root`` is the dataset's
    real location (:func:`~povagent.dataset.paths.dataset_root`)."""
    if (path.exists() or path.is_symlink()) and not is_inside(real_root, path):
        problems.append(Problem(rel, "$", "leads outside the dataset folder (a symlink); not opened"))
        return None
    try:
        text = read_regular(path, MAX_DOCUMENT_BYTES, what="dataset file").decode("utf-8")
    except ReadTargetError as exc:  # a pipe, a device, a folder or a huge file: never waited on
        problems.append(Problem(rel, "$", exc.reason))
        return None
    except FileNotFoundError:
        problems.append(Problem(rel, "$", "file is missing"))
        return None
    except UnicodeDecodeError as exc:
        problems.append(Problem(rel, "$", f"is not UTF-8 text (byte {exc.start})"))
        return None
    except OSError as exc:
        problems.append(Problem(rel, "$", f"cannot be read: {exc.strerror or exc}"))
        return None
    try:
        data = loads_dataset_json(text)
    except json.JSONDecodeError as exc:
        problems.append(Problem(rel, "$", f"is not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}"))
        return None
    except TooDeepError as exc:
        problems.append(Problem(rel, "$", str(exc)))
        return None
    not_text = not_text_problems(rel, data)
    if not_text:
        problems.extend(not_text)
        return None
    return data
