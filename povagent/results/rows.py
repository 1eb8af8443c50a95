"""The result row: one (instance, run), as written to ``results.jsonl``.

A row holds everything needed to re-parse, re-score and report without calling a model again:
the raw answer(s), the parse, the scores, and the cost. Never image bytes: only hashes.
Rows are appended one JSON line each; a last line cut short by a crash or a full disk (at any
byte) is skipped on read (and the key is then run again on resume); a damaged line anywhere else
is an error naming the file and the line (see :func:`iter_rows`). Each row carries the format
version it was written in (``format_version``); a row of an older format is read through its
upgrade steps (:mod:`povagent.results.upgrade`), so every reader sees the current shape.
"""

from __future__ import annotations

import os
from array import array
from enum import StrEnum
from pathlib import Path
from typing import Any, Iterator, Sequence, overload

from pydantic import BaseModel, ConfigDict, Field, ValidationError
from pydantic_core import from_json

from povagent.answers.spec import ParsedAnswer
from povagent.errors import PredictionsError
from povagent.files.confined_read import open_regular
from povagent.results.output_check import check_output_text
from povagent.results.upgrade import FIELD, ROW_FORMAT, upgrade_row


class RowStatus(StrEnum):
    """Outcome of one row: ``answered``, ``parse_error`` (model answered, no point read) or
    ``infra_error`` (no answer: retries exhausted or a permanent API error)."""

    ANSWERED = "answered"
    PARSE_ERROR = "parse_error"
    INFRA_ERROR = "infra_error"


#: Each status's text, looked up (``status.value`` is a descriptor call: a run reads it for every row).
STATUS_TEXT = {status: status.value for status in RowStatus}

class ExchangeRecord(BaseModel):
    """One model call of a row (multi-turn strategies have several)."""

    request_hash: str
    #: The images of :attr:`prompt`, in order.
    image_hashes: list[str] = Field(default_factory=list)
    #: The request as sent (:meth:`povagent.exchange.messages.Request.as_text`): the transcript;
    #: with :attr:`prompt_continues`, only the messages it added to the previous exchange's.
    prompt: str | None = None
    #: Whether the request began with every message of the previous exchange's request, so
    #: :attr:`prompt` holds only the messages added after them (each message is kept once; the
    #: whole text is rebuilt by :func:`povagent.results.transcript.transcripts`).
    prompt_continues: bool = False
    raw: str | None = None
    latency_s: float = 0.0
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cost_usd: float | None = None
    retries: int = 0
    cached: bool = False


class Prediction(BaseModel):
    """The prediction as scored: pixels in the frame named by ``image_path`` (A/B)."""

    # an infinite or NaN coordinate (recorded as the official runner records it) stays one on disk
    model_config = ConfigDict(ser_json_inf_nan="constants")

    selected_image: int | None = None
    image_path: str | None = None
    x: float | None = None
    y: float | None = None
    #: The answer type the strategy asked for (``point``, a plugin's ``choice``) and the parse's
    #: value as that type reads it (:class:`povagent.answers.types.AnswerType`); ``None`` for no
    #: answer, or an untyped one (its x/y are what it answered).
    answer_type: str | None = None
    value: dict[str, Any] | None = None


class OfficialReading(BaseModel):
    """How the official runner reads a row's final answer: the parser, its parse, its scores
    (made by :func:`povagent.results.official_reading.read_officially`)."""

    model_config = ConfigDict(ser_json_inf_nan="constants")

    parser: str
    parse: ParsedAnswer
    scores: dict[str, dict[str, Any]] = Field(default_factory=dict)


class ResultRow(BaseModel):
    """One (instance, run)."""

    # NaN and infinity (an official parse's coordinate, a NaN error) stay themselves on disk.
    # Only field names are cached when a line is parsed: the parser's cache of string values
    # would keep up to 16,384 of the rows' ids, sentences and hashes alive in a reader that
    # keeps no row (the report)
    model_config = ConfigDict(extra="allow", ser_json_inf_nan="constants", cache_strings="keys")

    #: The row format it was written in (:data:`~povagent.results.upgrade.ROW_FORMAT`; a row read
    #: from a file is in the current one, whatever it was written in). First, so a reader knows a
    #: current row by its first bytes (:data:`CURRENT_ROW_START`).
    format_version: int = ROW_FORMAT
    key: str
    instance_id: str
    house_id: str
    pair_id: str
    direction: str
    condition: str
    run: int = 0
    sentence: str = ""
    backend: str = ""
    #: The model that answered: the litellm model string (or router group) a ``litellm`` row
    #: called, the backend's own name for a baseline (``center``); ``""``: not recorded (a
    #: report reads the run's config instead).
    model: str = ""
    #: The model profile the model was named by (``gpt-5.4``), or ``None``.
    profile: str | None = None
    strategy: str = ""
    parser: str = ""
    #: The system's name its pipeline gave (``label:``), or ``None`` (reports name it by its model).
    label: str | None = None
    config_hash: str = ""
    status: RowStatus
    exchanges: list[ExchangeRecord] = Field(default_factory=list)
    parse: ParsedAnswer | None = None
    prediction: Prediction = Field(default_factory=Prediction)
    scores: dict[str, dict[str, Any]] = Field(default_factory=dict)
    error_type: str | None = None
    error_message: str | None = None
    latency_s: float = 0.0
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cost_usd: float | None = None
    retries: int = 0
    started_at: str | None = None
    finished_at: str | None = None
    #: How the official runner reads the final answer, when the row's parser is a lenient one
    #: (see :mod:`povagent.results.official_reading`); ``None`` when the parser reads officially.
    official_reading: OfficialReading | None = None
    #: The category of the multiple-choice question the row answers (the set's question type,
    #: ``""`` for none), whatever became of the answer: a reply naming no option still counts in
    #: its category's slice. ``None``: the instance asks no multiple-choice question (a point).
    category: str | None = None
    #: The broader type the category belongs to, where the set has one (3DSRBench's
    #: ``orientation`` for ``orientation_viewpoint``): a slice of its own. ``None``: none.
    main_category: str | None = None

    @property
    def raw_response(self) -> str | None:
        """The final raw answer (the last exchange's)."""
        return self.exchanges[-1].raw if self.exchanges else None


def model_label(model: str, profile: str | None = None) -> str:
    """How a console or summary names the model that answered: ``gpt-5.4 = openai/gpt-5.4``
    for a profile, else the model string (``openai/gpt-5.4``, ``center``)."""
    if profile and profile != model:
        return f"{profile} = {model}" if model else profile
    return model


def row_json(row: ResultRow) -> str:
    """``row.model_dump_json()``: the same text, from the row's serializer with the same (default)
    options (the method's layer of keyword arguments cost a run ~1 us a row)."""
    return row.__pydantic_serializer__.to_json(row).decode()


def row_line(row: ResultRow, where: object, *, checked: bool | None = None) -> str:
    """``row`` as its ``results.jsonl`` line (newline included), checked against the shipped row
    schema while tests run (:mod:`povagent.results.output_check`; ``where``: the file;
    ``checked``: whether tests run, as the caller asked it already)."""
    line = row_json(row) + "\n"
    check_output_text("row", line, where, on=checked)
    return line


class ResultsWriter:
    """Appends rows to a JSONL file, flushing and fsyncing each, so a crash loses nothing written.

    The file is opened without following a link planted where it goes, nor a second name (see
    :mod:`povagent.files.confined_write`): once, not per row. ``root`` is the folder the user named
    (default: the file's own folder); the folders between it and the file are never followed.
    """

    def __init__(self, path: str | Path, root: str | Path | None = None) -> None:
        from povagent.files.confined_write import ConfinedFolder

        self.path = Path(path)
        base = Path(root) if root is not None else self.path.parent
        with ConfinedFolder(base, self.path.parent.relative_to(base)) as folder:
            self._fh = folder.open_append(self.path.name)
            self._repair_tail(folder)

    def _repair_tail(self, folder: Any) -> None:
        # A kill mid-write leaves a last line without its newline: cut it so the next append
        # starts on a fresh line (its key is simply run again).
        size = os.fstat(self._fh.fileno()).st_size
        if size == 0:
            return
        with folder.open_update(self.path.name) as fh:
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return
            fh.seek(0)
            data = fh.read()
            cut = data.rfind(b"\n") + 1
            fh.truncate(cut)

    def write(self, row: ResultRow) -> None:
        """Append one row durably."""
        self.write_lines(row_line(row, self.path))

    def write_lines(self, text: str) -> None:
        """Append already-serialized rows (each ending in a newline), then fsync once.

        The group commit of the runner: rows finished together share one fsync.
        """
        self._fh.write(text)
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def close(self) -> None:
        """Close the file."""
        self._fh.close()

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class StagedResults:
    """A results file written whole, for a file that is made in one go (``rescore``'s).

    Rows go to ``<name>.tmp`` beside ``path``, buffered; :meth:`commit` makes them durable with
    one fsync and moves the file into place (``os.replace``, then an fsync of the folder). A
    process killed at any moment before the move leaves ``path`` as it was (the previous
    complete file, or none): never part of the new rows, never a row twice. Leaving the
    ``with`` block without :meth:`commit` (an exception) removes the temporary file.

    Unlike :class:`ResultsWriter` (the journal of a run that is resumed key by key, where each
    row must be durable before it is reported), nothing here is reported row by row: the file
    counts only once it is complete, so one fsync at the end gives the same guarantee.
    """

    def __init__(self, path: str | Path, root: str | Path | None = None) -> None:
        from povagent.files.confined_write import ConfinedFolder

        self.path = Path(path)
        self.tmp = self.path.with_name(self.path.name + ".tmp")
        base = Path(root) if root is not None else self.path.parent
        # Made new beside the target (a leftover of a killed run, or a link planted there, is
        # removed, never followed); renamed over the target, which replaces a link there.
        self._folder = ConfinedFolder(base, self.path.parent.relative_to(base))
        try:
            self._staged = self._folder.staged(self.path.name)
        except BaseException:
            self._folder.close()
            raise
        self._fh = self._staged.file

    def write(self, row: ResultRow) -> None:
        """Append one row to the staged file (durable only at :meth:`commit`)."""
        self._fh.write(row_line(row, self.path))

    def commit(self) -> None:
        """Make the staged rows durable and put them in place of ``path`` (atomically)."""
        self._staged.commit(fsync=True)  # the rename itself is fsynced too: it survives a power cut

    def __enter__(self) -> StagedResults:
        return self

    def __exit__(self, *exc: object) -> None:
        self._staged.__exit__(*exc)
        self._folder.close()


#: The longest line a results file may hold (rows of format 0 reached hundreds of MiB).
MAX_LINE_BYTES = 512 << 20


def iter_rows(path: str | Path) -> Iterator[ResultRow]:
    """Rows of a results file, in file order.

    A last line without its newline is torn (a kill or a full disk cut the write somewhere, even
    inside a character): it is skipped, and the next writer cuts it. Blank lines are skipped.
    Any other line that is not a row (a byte that is not UTF-8, text that is not JSON, JSON that
    is not a row) stops the reading with a :class:`PredictionsError` naming the file and the
    line: povagent never writes such a line, and a reader cannot know which key it held, so
    skipping it would silently change a score, or make a resumed run answer that key twice.
    """
    p = Path(path)
    for number, _, line in _complete_lines(p):
        yield _read_line(p, number, line)


def _complete_lines(p: Path) -> Iterator[tuple[int, int, bytes]]:
    """``(line number, byte offset, line)`` of each complete, non-blank line (see :func:`iter_rows`)."""
    if not p.exists():
        return
    # a pipe or a device planted as the journal is refused, not waited on or read forever;
    # a line is read with its bound, so a file of one endless line cannot fill memory
    with open_regular(p, what="results file") as fh:
        offset = 0
        for number, line in enumerate(iter(lambda: fh.readline(MAX_LINE_BYTES + 1), b""), start=1):
            if len(line) > MAX_LINE_BYTES:
                raise PredictionsError(f"{p}: line {number}: longer than {MAX_LINE_BYTES >> 20} MiB, which no row is; move the line out of the file")
            if not line.endswith(b"\n"):
                return  # torn: only the last line can lack its newline
            if line.strip():
                yield number, offset, line
            offset += len(line)


#: How every row this release writes begins: a line that does is read straight into the row
#: model; any other (an older format, a hand-edited line) is parsed and upgraded first.
CURRENT_ROW_START = f'{{"{FIELD}":{ROW_FORMAT},'.encode()


def _read_line(path: Path, number: int, line: bytes) -> ResultRow:
    """One complete line of a results file as a row in the current format (upgraded from the
    format it was written in), or a one-line error naming file and line."""
    try:
        line.decode("utf-8")
    except UnicodeDecodeError as exc:
        problem = f"byte 0x{line[exc.start]:02x} at column {exc.start + 1} is not UTF-8"
    else:
        try:
            if line.startswith(CURRENT_ROW_START):
                row = ResultRow.model_validate_json(line)
                if row.format_version == ROW_FORMAT:  # a second "format_version" later in the line wins in JSON
                    return row
            try:
                data = from_json(line)
            except ValueError as exc:
                problem = f"not a result row (invalid JSON: {exc})"
            else:
                return ResultRow.model_validate(upgrade_row(data, f"{path}: line {number}"))
        except ValidationError as exc:
            first = exc.errors(include_url=False)[0]
            where = ".".join(str(part) for part in first["loc"])
            problem = f"not a result row ({where + ': ' if where else ''}{first['msg']})"
    raise PredictionsError(
        f"{path}: line {number}: {problem}; povagent never writes such a line (a damaged or hand-edited "
        f"file): move that line out of the file (the other rows stay good) and run the command again"
    )


class StoredRows(Sequence[ResultRow]):
    """The rows :func:`read_rows` returns (one per key, the last row of a key winning, in the
    order keys first appear), held as where each lies in the file: 12 bytes a row instead of
    the row, read and parsed again each time they are iterated, so a reader of any number of
    rows (the report) keeps none of them. Checked as :func:`iter_rows` checks them when made."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        last: dict[str, tuple[int, int, tuple[tuple[str, frozenset[str]], ...]]] = {}
        shapes: dict[tuple[tuple[str, frozenset[str]], ...], tuple[tuple[str, frozenset[str]], ...]] = {}
        for number, offset, line in _complete_lines(self.path):
            row = _read_line(self.path, number, line)
            shape = tuple((scorer, frozenset(fields)) for scorer, fields in row.scores.items())
            last[row.key] = (number, offset, shapes.setdefault(shape, shape))
        self._numbers = array("l", (n for n, _, _ in last.values()))
        self._offsets = array("q", (o for _, o, _ in last.values()))
        carried: dict[str, set[frozenset[str]]] = {}
        for _, _, shape in last.values():
            for scorer, fields in shape:
                carried.setdefault(scorer, set()).add(fields)
        #: Each scorer the rows carry (in the order the rows first carry it) with the sets of
        #: field names it wrote: what a reader asks of every row's scores, known without
        #: reading the rows again.
        self.carried_scores: dict[str, frozenset[frozenset[str]]] = {k: frozenset(v) for k, v in carried.items()}

    def __len__(self) -> int:
        return len(self._offsets)

    def __iter__(self) -> Iterator[ResultRow]:
        with open_regular(self.path, what="results file") as fh:
            for number, offset in zip(self._numbers, self._offsets):
                fh.seek(offset)
                yield _read_line(self.path, number, fh.readline(MAX_LINE_BYTES + 1))

    @overload
    def __getitem__(self, index: int) -> ResultRow: ...
    @overload
    def __getitem__(self, index: slice) -> list[ResultRow]: ...
    def __getitem__(self, index: int | slice) -> ResultRow | list[ResultRow]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        number, offset = self._numbers[index], self._offsets[index]
        with open_regular(self.path, what="results file") as fh:
            fh.seek(offset)
            return _read_line(self.path, number, fh.readline(MAX_LINE_BYTES + 1))


def read_rows(path: str | Path) -> list[ResultRow]:
    """All complete rows of a results file; when a key repeats, the last row wins."""
    by_key: dict[str, ResultRow] = {}
    for row in iter_rows(path):
        by_key[row.key] = row
    return list(by_key.values())
