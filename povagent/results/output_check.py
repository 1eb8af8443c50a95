"""What povagent writes, checked against the JSON Schemas it ships, at the moment it is written.

Every writer of a file with a shipped schema (:mod:`povagent.run.output_schemas`: a run's and a
rescore's ``summary.json``, each ``results.jsonl`` row, ``sweep.json``, ``export.json``) hands
the JSON text it is about to write to :func:`check_output_text`. With ``POVAGENT_CHECK_OUTPUTS=1`` in the
environment the JSON is validated against the shipped schema file and a mismatch raises
:class:`OutputSchemaError` naming the file, the JSON path and what is wrong, before anything is
written. A row's typed prediction (``prediction.value``) is checked likewise against its answer
type's ``value_schema`` when the score step makes it (:func:`check_answer_value`). The test
suite sets the variable for itself and for every process it starts, so every such file any test
makes is checked; a user's run does not pay for it (one environment lookup per call, or per run
for a run's rows and per chunk of answers for their typed values: a lookup costs more than a
microsecond, and a choice run makes two a key otherwise).
"""

from __future__ import annotations

import functools
import json
import os
from importlib import resources
from typing import Any, Mapping

#: The environment variable that turns the check on (``1``).
ENV = "POVAGENT_CHECK_OUTPUTS"


class OutputSchemaError(RuntimeError):
    """A file povagent was about to write does not meet its shipped schema (a povagent bug)."""


def checking() -> bool:
    """Whether written outputs are checked (``POVAGENT_CHECK_OUTPUTS=1``)."""
    return os.environ.get(ENV) == "1"


@functools.cache
def _validator(name: str) -> Any:
    from jsonschema import Draft202012Validator

    text = resources.files("povagent").joinpath("schemas", f"output_{name}.schema.json").read_text(encoding="utf-8")
    return Draft202012Validator(json.loads(text))


def schema_errors(name: str, data: Any, limit: int = 3) -> list[str]:
    """The first ``limit`` ways ``data`` misses output ``name``'s shipped schema (``[]``: it meets
    it), each as ``JSON path: message``."""
    from jsonschema.exceptions import best_match

    errors = sorted(_validator(name).iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path])
    # an error under "any of" (a field that may be null) is told by its most relevant branch
    deepest = [best_match([e]) for e in errors[:limit]]
    return [f"{e.json_path}: {e.message[:300]}" for e in deepest if e is not None]


def check_answer_value(answer_type: str, schema: Mapping[str, Any], value: Any, where: object, *, on: bool | None = None) -> None:
    """When :func:`checking`, validate a prediction's typed ``value`` against the JSON Schema its
    answer type ``answer_type`` declares (``AnswerType.value_schema``); :class:`OutputSchemaError`
    when it misses it: a type's reader and its published shape never drift apart in a test.
    ``on``: :func:`checking` as the caller asked it already (a run's chunk of answers asks once)."""
    if not (checking() if on is None else on) or value is None:
        return
    from jsonschema import Draft202012Validator

    errors = sorted(Draft202012Validator(dict(schema)).iter_errors(value), key=lambda e: [str(p) for p in e.absolute_path])
    if errors:
        shown = "; ".join(f"$.prediction.value{e.json_path[1:]}: {e.message[:300]}" for e in errors[:3])
        raise OutputSchemaError(f"{where}: a {answer_type!r} value misses the answer type's value_schema: {shown}")


def check_output_text(name: str, text: str, where: object, *, on: bool | None = None) -> None:
    """When :func:`checking`, validate the JSON ``text`` about to be written to ``where`` (a
    results row as serialized, a whole summary) against output ``name``'s shipped schema;
    :class:`OutputSchemaError` when it misses it. ``on``: :func:`checking` as the caller asked
    it already (a run's row journal asks once)."""
    if not (checking() if on is None else on):
        return
    errors = schema_errors(name, json.loads(text))
    if errors:
        raise OutputSchemaError(f"{where}: povagent was about to write a {name} that misses its shipped schema: " + "; ".join(errors))
