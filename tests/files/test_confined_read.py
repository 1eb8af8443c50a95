"""The confined reader: regular files only, never more than a bound, never waiting on a pipe."""

from __future__ import annotations

import os
import time

import pytest

from povagent.errors import ReadTargetError
from povagent.files.confined_read import check_regular, open_regular, read_at, read_inside, read_regular
from povagent.files.confined_write import ConfinedFolder

pytestmark = pytest.mark.timeout(20)


@pytest.fixture
def folder(tmp_path):
    path = tmp_path / "run"
    path.mkdir()
    return path


def test_a_regular_file_within_its_bound_is_read_whole(folder):
    (folder / "config.json").write_bytes(b'{"a": 1}')
    assert read_regular(folder / "config.json", 8, what="config") == b'{"a": 1}'


def test_a_fifo_is_refused_at_once_not_waited_on(folder):
    os.mkfifo(folder / "model.safetensors.index.json")
    started = time.monotonic()
    with pytest.raises(ReadTargetError, match=r"index\.json: weights index is a named pipe \(FIFO\), not a regular file"):
        read_regular(folder / "model.safetensors.index.json", 1024, what="weights index")
    assert time.monotonic() - started < 2


def test_a_link_to_dev_zero_is_refused_before_a_byte_is_read(folder):
    os.symlink("/dev/zero", folder / "config.json")
    with pytest.raises(ReadTargetError, match=r"config\.json: config is a device"):
        read_regular(folder / "config.json", 1 << 30, what="config")


def test_a_folder_where_a_file_goes_is_refused(folder):
    (folder / "config.json").mkdir()
    with pytest.raises(ReadTargetError, match="is a folder"):
        read_regular(folder / "config.json", 10)


def test_a_file_over_its_bound_is_refused_from_its_size(folder):
    (folder / "big.json").write_bytes(b"x" * 101)
    with pytest.raises(ReadTargetError, match=r"big\.json: file holds 101 bytes, more than the 100 bytes it may hold"):
        read_regular(folder / "big.json", 100)


def test_a_missing_file_stays_a_file_not_found_error(folder):
    with pytest.raises(FileNotFoundError):
        read_regular(folder / "nothing.json", 10)


def test_open_regular_streams_a_regular_file_and_refuses_a_fifo(folder):
    (folder / "results.jsonl").write_bytes(b"one\ntwo\n")
    with open_regular(folder / "results.jsonl") as fh:
        assert fh.readlines() == [b"one\n", b"two\n"]
    os.mkfifo(folder / "log.jsonl")
    with pytest.raises(ReadTargetError, match="named pipe"):
        open_regular(folder / "log.jsonl", what="log")


def test_check_regular_gives_the_size_of_a_file_another_library_opens(folder):
    (folder / "model.safetensors").write_bytes(b"\0" * 64)
    assert check_regular(folder / "model.safetensors", what="weights") == 64
    os.symlink("/dev/zero", folder / "other.safetensors")
    with pytest.raises(ReadTargetError, match="device"):
        check_regular(folder / "other.safetensors", what="weights")


def test_read_inside_refuses_a_link_planted_below_the_folder(folder, tmp_path):
    outside = tmp_path / "outside.png"
    outside.write_bytes(b"not yours")
    (folder / "views").mkdir()
    os.symlink(outside, folder / "views" / "key.png")
    with pytest.raises(ReadTargetError, match=r"key\.png: view leads through a symbolic link"):
        read_inside(folder, "views/key.png", 1024, what="view")


def test_read_inside_refuses_a_linked_folder_below_the_root(folder, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "key.png").write_bytes(b"not yours")
    os.symlink(elsewhere, folder / "views")
    with pytest.raises(ReadTargetError, match=r"views: view leads through a symbolic link"):
        read_inside(folder, "views/key.png", 1024, what="view")


def test_read_inside_reads_a_plain_file_and_follows_the_named_root(folder, tmp_path):
    (folder / "views").mkdir()
    (folder / "views" / "key.png").write_bytes(b"png")
    os.symlink(folder, tmp_path / "named")
    assert read_inside(tmp_path / "named", "views/key.png", 3, what="view") == b"png"


def test_read_at_reads_a_file_of_a_held_folder_and_refuses_a_link_a_pipe_and_an_oversize_one(tmp_path):
    (tmp_path / "views").mkdir()
    (tmp_path / "views" / "ok").write_bytes(b"view")
    (tmp_path / "outside").write_bytes(b"secret")
    os.symlink(tmp_path / "outside", tmp_path / "views" / "link")
    os.mkfifo(tmp_path / "views" / "pipe")
    with ConfinedFolder(tmp_path, "views", create=False) as views:
        assert read_at(views, "ok", 4) == b"view"
        for name, refusal in (("link", "symbolic link"), ("pipe", "not a regular file")):
            with pytest.raises(ReadTargetError, match=refusal):
                read_at(views, name, 100)
        with pytest.raises(ReadTargetError, match="more than"):
            read_at(views, "ok", 3)
