"""VLMEvalKit's prediction file (``<model>_<dataset>.xlsx``, or ``.tsv`` with ``PRED_FORMAT=tsv``),
read as logged replies.

At the pinned commit (open-compass/VLMEvalKit@e8e78f05, ``vlmeval/inference.py``
``infer_data_job`` and ``vlmeval/smp/file.py`` ``dump``) the file is the dataset's table without its
``image`` column, plus ``prediction`` (the reply as text; with ``SPLIT_THINK`` set, the text after
``</think>``, the reasoning in ``thinking``: the log then says so in a note): an xlsx sheet written by pandas (header row first), or
a tab-separated file with every cell quoted (``csv.QUOTE_ALL``), cells free to hold newlines.
Columns read: ``index``, ``answer``, ``prediction``, the options (``A``, ``B``... or, for
ViewSpatial-Bench and VSI-Bench, ``candidates``: ``"A. right\\nB. left"`` or a list of them), the category
(``question_type``, as VLMEvalKit groups ViewSpatial-Bench, else ``category``, else
OmniSpatialBench's ``sub_task_type``), ``main_category``, ``l2-category`` or ``task_type`` where
present, and ``qid`` (3DSRBench's copies). A row with no options whose ``answer`` is a number is a
numerical question (VSI-Bench's counts and distances: ``VsiBench``'s ``answer`` holds the
``ground_truth``, a letter or a number as text). An xlsx file needs
``openpyxl`` (``pip install 'povagent[xlsx]'``).
"""

from __future__ import annotations

import ast
import csv
import io
import zipfile
from pathlib import Path
from typing import Any, Iterable

from povagent.dataset.problems import Problem
from povagent.errors import PredictionsError, ReadTargetError
from povagent.results.harness_logs import (
    MAX_ITEM_CHARS,
    MAX_LOG_BYTES,
    MAX_OPTIONS,
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

#: The columns every prediction file has.
REQUIRED = ("index", "answer", "prediction")
#: The columns a question's category is read from, in order (OmniSpatialBench groups by
#: ``sub_task_type`` within ``task_type``).
CATEGORY_COLUMNS = ("question_type", "category", "sub_task_type")
#: The columns the broader type a category belongs to is read from, in order.
MAIN_CATEGORY_COLUMNS = ("main_category", "l2-category", "task_type")
#: The most bytes an xlsx file may unpack to (its XML is several times its zipped size).
MAX_XLSX_UNPACKED = 4 << 30
#: The longest options cell read as a list literal.
MAX_LIST_CELL = 1 << 16


def read_vlmevalkit_predictions(file: Path) -> HarnessLog:
    """Every scorable row of a VLMEvalKit prediction file, and one problem per row that is not."""
    from povagent.files.confined_read import read_regular

    try:
        data = read_regular(file, MAX_LOG_BYTES, what="VLMEvalKit prediction file")
    except (ReadTargetError, OSError) as exc:
        raise PredictionsError(f"{file}: cannot be read: {exc}") from None
    rows = _xlsx_rows(file, data) if data[:4] == b"PK\x03\x04" else _tsv_rows(file, data)
    log = HarnessLog(file, "vlmevalkit", reply_field="prediction", gold_field="answer")
    header: list[str] | None = None
    seen: set[str] = set()
    thought = 0  # rows whose reasoning VLMEvalKit moved to the thinking column
    name = str(file)
    for number, cells in rows:
        if header is None:
            header = [str(c).strip() if c is not None else "" for c in cells]
            missing = [c for c in REQUIRED if c not in header]
            if missing:
                raise PredictionsError(f"{file}: row 1: no column {', '.join(missing)} (a VLMEvalKit prediction file has {', '.join(REQUIRED)})")
            continue
        where = f"row {number}"
        if len(log.replies) >= MAX_RECORDS:
            log.problems.append(Problem(name, where, f"more than {MAX_RECORDS} rows; the rest of the file is not read"))
            break
        row = dict(zip(header, cells))
        if all(_text(v) == "" for v in row.values()):
            continue
        thought += bool(_text(row.get("thinking")))
        read = _reply(row, where)
        if isinstance(read, tuple):
            log.problems.append(Problem(name, *read))
        elif read.item in seen:
            log.problems.append(Problem(name, f"{where}.index", f"{read.item!r} is used by an earlier row; this one left out"))
        else:
            seen.add(read.item)
            log.replies.append(read)
    if header is None:
        raise PredictionsError(f"{file}: holds no header row (a VLMEvalKit prediction file has {', '.join(REQUIRED)})")
    if thought:
        log.notes.append(
            f"rows keeping reasoning in a thinking column: {thought} (VLMEvalKit's SPLIT_THINK); prediction, what every rule "
            "reads here, is the text after </think>, so a rule that reads the whole reply as written sees less than it would"
        )
    return log


def _tsv_rows(file: Path, data: bytes) -> Iterable[tuple[int, list[Any]]]:
    """The rows of a tab-separated file as pandas writes it (quoted cells may hold tabs and newlines)."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise PredictionsError(f"{file}: byte {exc.start + 1} is not UTF-8 (a VLMEvalKit .tsv is UTF-8 text)") from None
    limit = csv.field_size_limit()
    csv.field_size_limit(MAX_LOG_BYTES)  # the file is bounded already; a long reply is a bad row, named below
    try:
        reader = csv.reader(io.StringIO(text, newline=""), dialect="excel-tab")
        rows = []
        try:
            for cells in reader:
                rows.append((reader.line_num, list(cells)))
        except csv.Error as exc:
            raise PredictionsError(f"{file}: line {reader.line_num}: not tab-separated text as VLMEvalKit writes it ({exc})") from None
        return rows
    finally:
        csv.field_size_limit(limit)


def _xlsx_rows(file: Path, data: bytes) -> Iterable[tuple[int, list[Any]]]:
    """The rows of the first sheet of an xlsx file, its size unpacked checked first."""
    try:
        import openpyxl
    except ImportError:
        raise PredictionsError(f"{file}: reading an .xlsx file needs openpyxl: pip install 'povagent[xlsx]' (or save it as .tsv)") from None
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as packed:
            unpacked = sum(info.file_size for info in packed.infolist())
    except zipfile.BadZipFile as exc:
        raise PredictionsError(f"{file}: not an xlsx file ({exc})") from None
    if unpacked > MAX_XLSX_UNPACKED:
        raise PredictionsError(f"{file}: unpacks to {unpacked} bytes, over the {MAX_XLSX_UNPACKED} an xlsx prediction file may")
    try:
        book = openpyxl.load_workbook(io.BytesIO(data), read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many kinds on a damaged file: one line, not a traceback
        raise PredictionsError(f"{file}: not an xlsx file openpyxl can read ({type(exc).__name__}: {exc})") from None
    try:
        sheet = book.worksheets[0]
        return [(number, list(cells)) for number, cells in enumerate(sheet.iter_rows(values_only=True), start=1)]
    finally:
        book.close()


def _text(value: Any) -> str:
    """A cell as text: ``""`` for an empty cell (pandas writes NaN so), an integral float as an integer."""
    if value is None:
        return ""
    if isinstance(value, float):
        if value != value:
            return ""
        if value.is_integer():
            return str(int(value))
    return str(value).strip() if not isinstance(value, str) else value.strip()


def _listed_options(cell: str) -> tuple[tuple[str, str], ...]:
    """Options in one cell: lines ``A. right``, or a list literal of them (``['A. right', ...]``),
    labelled ``A``, ``B``... in order where its items carry no label."""
    listed = options_in_prompt(cell)
    if listed or not cell.startswith("[") or len(cell) > MAX_LIST_CELL:
        return listed
    try:
        items = ast.literal_eval(cell)  # a literal only: nothing in the cell is run
    except (ValueError, SyntaxError, RecursionError, MemoryError, TypeError):
        return ()
    if not isinstance(items, list) or not items or len(items) > MAX_OPTIONS or not all(isinstance(i, str) for i in items):
        return ()
    labelled = options_in_prompt("\n".join(items))
    return labelled if len(labelled) == len(items) else tuple((chr(ord("A") + k), item.strip()) for k, item in enumerate(items))


def _reply(row: dict[str, Any], where: str) -> LoggedReply | tuple[str, str]:
    """The row as a logged reply, or ``(where, message)`` saying which cell is wrong."""
    index = _text(row.get("index"))
    if not 0 < len(index) <= MAX_ITEM_CHARS:
        return f"{where}.index", f"required, the row's index (at most {MAX_ITEM_CHARS} characters); row left out"
    prediction = row.get("prediction")
    reply = checked_reply(_text(prediction) if not isinstance(prediction, str) else prediction)
    if reply is None:
        return f"{where}.prediction", f"the reply must be text of at most {MAX_REPLY_CHARS} characters; row left out"
    answer = _text(row.get("answer"))
    gold = gold_label(answer)
    options: tuple[tuple[str, str], ...] = ()
    for label in (chr(ord("A") + k) for k in range(MAX_OPTIONS)):
        text = _text(row.get(label))
        if label not in row or not text or text.lower() == "nan":
            break
        options += ((label, text),)
    if not options:
        cell = next((_text(row[c]) for c in ("candidates", "choices", "options") if _text(row.get(c))), "")
        # else the question's own "Options: A: ..., B: ..." (the MMSI-Bench authors' table)
        options = _listed_options(cell) or options_in_prompt(_text(row.get("question")))
    category = next((_text(row[c]) for c in CATEGORY_COLUMNS if _text(row.get(c))), "")
    main = next((_text(row[c]) for c in MAIN_CATEGORY_COLUMNS if _text(row.get(c))), "")
    number = gold_number(answer) if gold is None and not options else None
    if number is not None:  # a numerical question (VSI-Bench's): no options, the answer a number
        return LoggedReply(
            item=index,
            where=where,
            reply=reply,
            options=(),
            gold=answer,
            category=category,
            main_category=main,
            question_id=_text(row.get("qid")) or index,
            gold_number=number,
        )
    if gold is None:
        unread = "names no option label A-Z" if options else "is neither an option label A-Z nor a number (the row lists no options)"
        return f"{where}.answer", f"{answer[:60]!r} {unread}; row left out"
    options = with_gold(options, gold)
    if gold not in {label for label, _ in options}:
        return f"{where}.answer", f"the gold label {gold!r} is not among the row's options ({', '.join(label for label, _ in options)}); row left out"
    return LoggedReply(
        item=index, where=where, reply=reply, options=options, gold=gold, category=category, main_category=main, question_id=_text(row.get("qid")) or index
    )
