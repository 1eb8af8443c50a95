"""A row's transcript, each message kept once, and each request's text rebuilt from it.

A multi-turn strategy's request usually repeats every earlier message and adds a few (the
active mode adds the model's calls, one tool result each, and the views). Kept whole in every
exchange, a row grew with the square of its turns (90 MB at 16 actions against a model sending
128 padded calls a turn). So an exchange whose request begins with every message of the
previous exchange's request keeps only the messages added after them
(:attr:`~povagent.results.rows.ExchangeRecord.prompt_continues`), and :func:`transcripts`
rebuilds each request's text, for a row written either way (each prompt whole, as in every
row of format 0, or continued).

What it must not do: decide what a request holds, or write files.
"""

from __future__ import annotations

from array import array
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import overload

from povagent.exchange.messages import Request, messages_images, messages_text
from povagent.results.model_construct import construct
from povagent.results.rows import ExchangeRecord, ResultRow


@dataclass
class RowTranscript:
    """The exchanges of one row, recorded as they happen (each request's new messages only)."""

    exchanges: list[ExchangeRecord] = field(default_factory=list)
    #: The request of the last exchange recorded (what the next one may continue).
    last: Request | None = None

    def record(
        self,
        request: Request,
        raw: str | None,
        *,
        latency_s: float = 0.0,
        prompt_tokens: int | None = None,
        completion_tokens: int | None = None,
        cost_usd: float | None = None,
        retries: int = 0,
        cached: bool = False,
    ) -> None:
        """Record an exchange: ``request``, the ``raw`` answer to it, and what it cost."""
        last = self.last
        if last is None:  # the first exchange (every single-turn key's only one): all of its messages
            continues, added = False, request.messages
        else:
            n = len(last.messages)
            continues = request.messages[:n] == last.messages
            added = request.messages[n:] if continues else request.messages
        # constructed: every field is built here with the right type (and named: a field left
        # out would quietly take its default); validating again cost ~0.1 ms a request.
        self.exchanges.append(
            construct(
                ExchangeRecord,
                request_hash=request.content_hash(),
                image_hashes=messages_images(added),
                prompt=messages_text(added),
                prompt_continues=continues,
                raw=raw,
                latency_s=latency_s,
                prompt_tokens=prompt_tokens,
                completion_tokens=completion_tokens,
                cost_usd=cost_usd,
                retries=retries,
                cached=cached,
            )
        )
        self.last = request


def transcripts(exchanges: Sequence[ExchangeRecord], keep: int | None = None) -> list[str | None]:
    """The text of each exchange's request as sent (``None`` where no request was kept).

    ``keep``: at most that many leading characters of each (what a page shows), so rebuilding a
    long episode costs memory in proportion to its turns, not to the square of them.
    """
    out: list[str | None] = []
    previous: str | None = None
    for exchange in exchanges:
        text = exchange.prompt
        if text is not None and exchange.prompt_continues and previous is not None:
            text = previous + "\n" + text if text else previous
        if text is not None and keep is not None:
            text = text[:keep]
        out.append(text)
        previous = text
    return out


class StoredTurns(Sequence[tuple[str | None, str | None]]):
    """A stored row's turns, ``(request as sent or None, raw answer or None)`` each, read from
    its results file only when they are looked at (the report's gallery, for the rows it
    shows): a report of any length holds no request texts. ``redact`` is applied to every
    text as it is read."""

    __slots__ = ("_rows", "_index", "_keep", "_redact")

    def __init__(self, rows: Sequence[ResultRow], index: int, keep: int | None = None, redact: Callable[[str], str] | None = None) -> None:
        self._rows, self._index, self._keep, self._redact = rows, index, keep, redact

    def _read(self) -> tuple[tuple[str | None, str | None], ...]:
        exchanges = self._rows[self._index].exchanges
        turns = tuple(zip(transcripts(exchanges, keep=self._keep), (e.raw for e in exchanges)))
        known = self._redact
        if known is None:
            return turns
        return tuple((known(p) if isinstance(p, str) else p, known(a) if isinstance(a, str) else a) for p, a in turns)

    def redacted(self, redact: Callable[[str], str]) -> StoredTurns:
        """The same turns, each text passed through ``redact`` as it is read."""
        return StoredTurns(self._rows, self._index, self._keep, redact)

    def __iter__(self) -> Iterator[tuple[str | None, str | None]]:
        return iter(self._read())

    def __len__(self) -> int:
        return len(self._rows[self._index].exchanges)

    @overload
    def __getitem__(self, index: int) -> tuple[str | None, str | None]: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[tuple[str | None, str | None]]: ...
    def __getitem__(self, index: int | slice) -> tuple[str | None, str | None] | Sequence[tuple[str | None, str | None]]:
        return self._read()[index]


class RunTurns:
    """Every row's turns of one results file, found by the row's instance and run and read only
    when looked at (:class:`StoredTurns`): what a report's observations of one run share, one
    object a run. A row's place is kept as 8 bytes (the hash of its instance and run, in the
    file's order), not an object a row; ``redact`` is applied to every text as it is read."""

    __slots__ = ("_rows", "_keep", "_redact", "_places")

    def __init__(self, rows: Sequence[ResultRow], keep: int | None = None, redact: Callable[[str], str] | None = None) -> None:
        self._rows, self._keep, self._redact = rows, keep, redact
        self._places = array("q")

    def add(self, instance_id: str, run: int) -> None:
        """The next row of the file (rows are added in the file's order, every one of them)."""
        self._places.append(hash((instance_id, run)))

    def of(self, instance_id: str, run: int) -> Sequence[tuple[str | None, str | None]]:
        """The turns of the row of ``instance_id`` and ``run`` (``()``: no such row); a row
        whose hash matches is read to check it is that row (two rows' hashes may collide)."""
        place, start = hash((instance_id, run)), 0
        while True:
            try:
                index = self._places.index(place, start)
            except ValueError:
                return ()
            row = self._rows[index]
            if row.instance_id == instance_id and row.run == run:
                return StoredTurns(self._rows, index, self._keep, self._redact)
            start = index + 1
