"""A results file whose last line is cut at any byte reads as its complete rows; a damaged line
anywhere else stops every reader with the file and the line named.

A full disk or a kill can cut the last write anywhere, also inside a multi-byte character: that
line is torn, skipped by readers and cut by the next writer (its key runs again). povagent never
writes a bad line before the last one, so such a line (a stray byte, hand editing) is not
guessed at: it is an error naming ``file: line N``, because skipping it would silently change a
score or make a resume answer its key twice.
"""

from __future__ import annotations

import pytest

from povagent.errors import PredictionsError
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus, iter_rows, read_rows
from povagent.run.journal import drop_rows

#: An answer of 1-, 2-, 3- and 4-byte characters, so cuts land inside characters of every width.
WIDE = "a é 中 😀 \u2028 <!-- </script> & “quoted”"


def row(key: str) -> ResultRow:
    iid = key.split("#")[0]
    return ResultRow(key=key, instance_id=iid, house_id="h", pair_id="0", direction="up", condition="c",
                     sentence=WIDE, status=RowStatus.ANSWERED, exchanges=[ExchangeRecord(request_hash="r", raw=WIDE)])


def line(r: ResultRow) -> bytes:
    return (r.model_dump_json() + "\n").encode()


def test_rows_hold_raw_multibyte_characters_so_a_cut_can_land_inside_one():
    # the premise of this file: rows are written as UTF-8, not as \u escapes
    assert "😀".encode() in line(row("a#0"))


def test_a_last_line_cut_at_any_byte_reads_as_the_rows_before_it(tmp_path):
    path = tmp_path / "results.jsonl"
    whole = line(row("a#0")) + line(row("b#0"))
    last = line(row("c#0"))
    inside_a_character = 0
    for cut in range(len(last)):  # every byte of the last line, newline excluded
        path.write_bytes(whole + last[:cut])
        try:
            last[:cut].decode()
        except UnicodeDecodeError:
            inside_a_character += 1
        assert [r.key for r in iter_rows(path)] == ["a#0", "b#0"], cut
    assert inside_a_character >= 6  # the cuts inside a 2-, 3- and 4-byte character were all tried


def test_the_next_writer_cuts_a_tail_torn_inside_a_character(tmp_path):
    path = tmp_path / "results.jsonl"
    whole = line(row("a#0"))
    last = line(row("b#0"))
    cut = last.index("😀".encode()) + 2
    path.write_bytes(whole + last[:cut])
    with ResultsWriter(path) as w:
        w.write(row("c#0"))
    assert [r.key for r in iter_rows(path)] == ["a#0", "c#0"]


def test_dropping_rows_reads_a_tail_torn_inside_a_character(tmp_path):
    path = tmp_path / "results.jsonl"
    keep, drop, last = line(row("a#0")), line(row("b#0")), line(row("c#0"))
    path.write_bytes(keep + drop + last[: last.index("中".encode()) + 1])
    drop_rows(path, {"b#0"})
    assert path.read_bytes() == keep


@pytest.mark.parametrize(
    ("bad", "says"),
    [
        (b"\xff\xfe not utf-8\n", "byte 0xff at column 1 is not UTF-8"),
        (line(row("x#0"))[:40] + b"\n", "not a result row"),
        (b'{"key": "x#0"}\n', "not a result row (instance_id: Field required)"),
        (b"[1, 2]\n", "not a result row"),
    ],
    ids=["a bad byte", "a torn line followed by a newline", "a JSON object that is not a row", "JSON that is not an object"],
)
def test_a_damaged_line_before_the_last_names_the_file_and_the_line(tmp_path, bad, says):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0")) + bad + line(row("b#0")))
    for reader in (lambda: list(iter_rows(path)), lambda: read_rows(path)):
        with pytest.raises(PredictionsError) as caught:
            reader()
        message = str(caught.value)
        assert message.startswith(f"{path}: line 2: ")
        assert says in message
        assert "\n" not in message


def test_a_bad_byte_inside_a_row_is_named_by_its_column(tmp_path):
    path = tmp_path / "results.jsonl"
    good = line(row("b#0"))
    at = good.index(b"sentence")
    path.write_bytes(line(row("a#0")) + good[:at] + b"\xc3" + good[at + 1 :] + line(row("c#0")))
    with pytest.raises(PredictionsError, match=rf"line 2: byte 0xc3 at column {at + 1} is not UTF-8"):
        read_rows(path)


def test_blank_lines_carry_no_row_and_are_skipped(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0")) + b"\n  \n" + line(row("b#0")))
    assert [r.key for r in iter_rows(path)] == ["a#0", "b#0"]


def test_the_next_writer_cuts_a_tail_of_one_byte_after_a_newline(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0")) + b"{")
    with ResultsWriter(path) as w:
        w.write(row("c#0"))
    assert path.read_bytes() == line(row("a#0")) + line(row("c#0"))


def _bytes_read() -> int:
    """Bytes this process has read through read() calls so far (Linux's /proc/self/io)."""
    with open("/proc/self/io", encoding="ascii") as io:
        return int(next(f for f in io if f.startswith("rchar:")).split()[1])


def test_opening_an_intact_journal_reads_its_last_byte_not_the_whole_file(tmp_path):
    # a resumed run opens its journal once per session: its cost must not grow with the file
    path = tmp_path / "results.jsonl"
    one = line(row("a#0"))
    path.write_bytes(one * (16 * 2**20 // len(one)))
    before = _bytes_read()
    with ResultsWriter(path):
        pass
    assert _bytes_read() - before < 2**20
    assert path.stat().st_size == len(one) * (16 * 2**20 // len(one))


class FsyncSpy:
    """Records what each os.fsync call was given: a regular file or a folder."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        import os
        import stat

        self.kinds: list[str] = []
        real = os.fsync

        def spy(fd: int) -> None:
            self.kinds.append("folder" if stat.S_ISDIR(os.fstat(fd).st_mode) else "file")
            real(fd)

        monkeypatch.setattr(os, "fsync", spy)


def test_staged_results_are_fsynced_then_renamed_in_with_the_folder_fsynced(tmp_path, monkeypatch):
    from povagent.results.rows import StagedResults

    spy = FsyncSpy(monkeypatch)
    with StagedResults(tmp_path / "results.jsonl") as staged:
        staged.write(row("a#0"))
        staged.commit()
    assert spy.kinds == ["file", "folder"]
    assert [r.key for r in iter_rows(tmp_path / "results.jsonl")] == ["a#0"]


def test_a_staging_that_fails_leaves_no_folder_open(tmp_path, monkeypatch):
    import os

    from povagent.files.confined_write import ConfinedFolder
    from povagent.results.rows import StagedResults

    def refuse(self, name, **kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ConfinedFolder, "staged", refuse)
    open_before = len(os.listdir("/proc/self/fd"))
    for _ in range(3):
        with pytest.raises(OSError):
            StagedResults(tmp_path / "results.jsonl")
    assert len(os.listdir("/proc/self/fd")) == open_before
