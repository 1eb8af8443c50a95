"""lmms-eval's ``--log_samples`` file (``<date>_samples_<task>.jsonl``), read as logged replies.

At the pinned commit (EvolvingLMMs-Lab/lmms-eval@75571cfe, ``lmms_eval/evaluator.py`` and
``loggers/evaluation_tracker.py`` ``save_results_samples``) each line is one document:
``doc_id``, ``target`` (``doc_to_target`` as text: ``"A. right"``, ``"B"``), ``input`` (the
prompt text, which lists the options), ``filtered_resps`` (the reply after the task's filter and
lmms-eval's reasoning-tag strip), ``resps`` (the reply before the strip; left out when it equals
``filtered_resps``), ``token_counts``, ``doc_hash`` and each metric ``process_results`` returned
(``{"score": 1.0, "question_type": ...}``). A one-request document's lists are flattened (a reply
is a string, or a list of repeats whose first is read). ``doc`` is dropped by the pinned writer;
an older lmms-eval (or a patched one) keeps it, and it is read where present.

What a record gives:

- reply: ``resps`` (the model's text), else ``filtered_resps`` (equal, so dropped);
- gold: the label ``target`` names (:func:`~.harness_logs.gold_label`), else the ``doc``'s
  ``gt_answer`` / ``answer``; a ``target`` that is a number, where the prompt lists no options,
  makes the record a numerical question (VSI-Bench's ``ground_truth``: ``"3.2"``);
- options: the lines of ``input`` labelled ``A.``, ``B.``... (else the ``doc``'s ``A``-``D``);
- category: the first of :data:`CATEGORY_KEYS` in a metric's dict (what the task's own
  aggregation groups by), else in ``doc``; the main category (:data:`MAIN_CATEGORY_KEYS`) and
  ``qid`` likewise.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

from povagent.dataset.problems import Problem, not_text_problems
from povagent.errors import PredictionsError, ReadTargetError
from povagent.results.harness_logs import (
    MAX_ITEM_CHARS,
    MAX_LOG_BYTES,
    MAX_LOG_LINE_BYTES,
    MAX_RECORDS,
    MAX_REPLY_CHARS,
    HarnessLog,
    LoggedReply,
    checked_reply,
    gold_label,
    gold_number,
    options_in_prompt,
    with_gold,
)

#: The keys a task's per-sample metric (or its ``doc``) names a question's category by, in order
#: (at lmms-eval@75571cfe: viewspatial's ``question_type``, 3dsrbench's ``category``, mindcube's
#: ``type``, omni_spatial's ``sub_task_type``, omnispatial_test's ``sub_task``, mmsi_bench's
#: ``l2_category``, vsibench's ``question_type``).
CATEGORY_KEYS = ("question_type", "category", "sub_task_type", "sub_task", "type", "l2_category")
#: The keys naming the broader type a category belongs to (3dsrbench's, omni_spatial's
#: ``task_type``, omnispatial_test's ``task``).
MAIN_CATEGORY_KEYS = ("main_category", "task_type", "task")
#: What lmms-eval writes besides the metrics.
_FIXED_KEYS = frozenset({"doc_id", "doc", "target", "arguments", "resps", "filtered_resps", "token_counts", "doc_hash", "input", "input_media"})


def read_lmms_eval_log(file: Path) -> HarnessLog:
    """Every scorable record of an lmms-eval samples file, and one problem per record that is not."""
    from povagent.dataset.json_files import TooDeepError, loads_dataset_json
    from povagent.files.confined_read import check_regular, open_regular

    log = HarnessLog(file, "lmms-eval", reply_field="resps", filtered_field="filtered_resps")
    name = str(file)
    try:
        check_regular(file, MAX_LOG_BYTES, what="lmms-eval samples file")
        handle = open_regular(file, what="lmms-eval samples file")
    except (ReadTargetError, OSError) as exc:
        raise PredictionsError(f"{file}: cannot be read: {exc}") from None
    seen: set[str] = set()
    with handle:
        for number, raw in enumerate(iter(lambda: handle.readline(MAX_LOG_LINE_BYTES + 1), b""), start=1):
            where = f"line {number}"
            if len(raw) > MAX_LOG_LINE_BYTES:
                log.problems.append(Problem(name, where, f"longer than {MAX_LOG_LINE_BYTES} bytes; this line and the rest of the file are not read"))
                break
            if not raw.strip():
                continue
            if len(log.replies) >= MAX_RECORDS:
                log.problems.append(Problem(name, where, f"more than {MAX_RECORDS} records; the rest of the file is not read"))
                break
            try:
                record = loads_dataset_json(raw.decode("utf-8"))
            except UnicodeDecodeError as exc:
                log.problems.append(Problem(name, where, f"byte {exc.start + 1} is not UTF-8; record left out"))
                continue
            except (json.JSONDecodeError, TooDeepError) as exc:
                log.problems.append(Problem(name, where, f"not a JSON record ({str(exc).split(':')[0]}); record left out"))
                continue
            if lone := not_text_problems(name, record):  # "\ud800" reads as a str no file or console can hold
                path = lone[0].json_path
                log.problems.append(Problem(name, where + (path[1:] if path.startswith("$") else path), f"{lone[0].message}; record left out"))
                continue
            read = _reply(record, where)
            if isinstance(read, tuple):
                log.problems.append(Problem(name, *read))
            elif read.item in seen:
                log.problems.append(Problem(name, f"{where}.doc_id", f"{read.item!r} is logged by an earlier line; this one left out"))
            else:
                seen.add(read.item)
                log.replies.append(read)
    return log


def _first_text(value: Any) -> Any:
    """A flattened reply: a string as is; of a list of repeats (or of one request's list), the first."""
    for _ in range(3):  # [[reply, ...]] at most, as lmms-eval nests it
        if isinstance(value, list) and value:
            value = value[0]
    return value


def _metric_field(record: Mapping[str, Any], keys: tuple[str, ...]) -> str:
    """The first of ``keys`` a metric's dict (or the ``doc``) holds as text, else ``""``."""
    dicts = [v for k, v in record.items() if k not in _FIXED_KEYS and isinstance(v, dict)]
    doc = record.get("doc")
    for source in [*dicts, doc if isinstance(doc, dict) else {}]:
        for key in keys:
            value = source.get(key)
            if isinstance(value, (str, int)) and not isinstance(value, bool) and str(value):
                return str(value)
    return ""


def _doc_options(doc: Any) -> tuple[tuple[str, str], ...]:
    """A logged ``doc``'s option columns ``A``, ``B``... (VLMEvalKit-style sets), in order."""
    if not isinstance(doc, dict):
        return ()
    options = []
    for label in "ABCDEFGH":
        text = doc.get(label)
        if not isinstance(text, str) or not text.strip() or text.strip().lower() == "nan":
            break
        options.append((label, text.strip()))
    return tuple(options)


def _reply(record: Any, where: str) -> LoggedReply | tuple[str, str]:
    """The record as a logged reply, or ``(where, message)`` saying which field is wrong."""
    if not isinstance(record, dict):
        return where, f"a record must be a JSON object (got {type(record).__name__}); record left out"
    doc_id = record.get("doc_id")
    if isinstance(doc_id, bool) or not isinstance(doc_id, (int, str)) or not 0 < len(str(doc_id)) <= MAX_ITEM_CHARS:
        return f"{where}.doc_id", f"required, a number or text of at most {MAX_ITEM_CHARS} characters naming the document; record left out"
    filtered = checked_reply(_first_text(record.get("filtered_resps")))
    if "filtered_resps" not in record or filtered is None:
        return f"{where}.filtered_resps", f"required, the reply as text of at most {MAX_REPLY_CHARS} characters; record left out"
    reply = checked_reply(_first_text(record["resps"])) if "resps" in record else filtered
    if reply is None:
        return f"{where}.resps", f"the reply must be text of at most {MAX_REPLY_CHARS} characters; record left out"
    doc = record.get("doc")
    target = record.get("target")
    gold = gold_label(target) if isinstance(target, str) else None
    if gold is None and isinstance(doc, dict):
        gold = next((g for key in ("gt_answer", "answer") if isinstance(doc.get(key), str) and (g := gold_label(doc[key]))), None)
    prompt = record.get("input")
    options = options_in_prompt(prompt) if isinstance(prompt, str) else ()
    number = gold_number(target) if gold is None and isinstance(target, str) and not options else None
    if number is not None and isinstance(target, str):  # a numerical question (VSI-Bench's): no options, the target a number
        return LoggedReply(
            item=str(doc_id),
            where=where,
            reply=reply,
            options=(),
            gold=target.strip(),
            category=_metric_field(record, CATEGORY_KEYS),
            main_category=_metric_field(record, MAIN_CATEGORY_KEYS),
            question_id=str(doc_id),
            filtered=filtered,
            gold_number=number,
        )
    if gold is None:
        return f"{where}.target", f"{str(target)[:60]!r} names no option label A-Z (nor a number, with no options in the prompt); record left out"
    options = with_gold(options or _doc_options(doc), gold)
    if gold not in {label for label, _ in options}:
        return (
            f"{where}.target",
            f"the gold label {gold!r} is not among the options the prompt lists ({', '.join(label for label, _ in options)}); record left out",
        )
    return LoggedReply(
        item=str(doc_id),
        where=where,
        reply=reply,
        options=options,
        gold=gold,
        category=_metric_field(record, CATEGORY_KEYS),
        main_category=_metric_field(record, MAIN_CATEGORY_KEYS),
        question_id=_metric_field(record, ("qid",)) or str(doc_id),
        filtered=filtered,
    )
