"""The confined writer: targets below a named folder are opened without following planted links."""

from __future__ import annotations

import os

import pytest

from povagent.errors import WriteTargetError
from povagent.files.confined_write import ConfinedFolder, open_inside, write_inside


@pytest.fixture
def outside(tmp_path):
    """A file of the user's outside the folder: it must come out of every test byte for byte."""
    path = tmp_path / "precious.txt"
    path.write_text("keep me\n")
    return path


@pytest.fixture
def folder(tmp_path):
    path = tmp_path / "run"
    path.mkdir()
    return path


def test_appending_to_a_file_that_is_a_planted_symlink_is_refused_naming_it(folder, outside):
    os.symlink(outside, folder / "log.jsonl")
    with pytest.raises(WriteTargetError, match=r"log\.jsonl: is a symbolic link"):
        open_inside(folder, "log.jsonl", "a")
    assert outside.read_text() == "keep me\n"


def test_writing_whole_over_a_planted_symlink_replaces_the_link_not_its_target(folder, outside):
    os.symlink(outside, folder / "summary.json")
    write_inside(folder, "summary.json", "{}\n")
    assert not (folder / "summary.json").is_symlink() and (folder / "summary.json").read_text() == "{}\n"
    assert outside.read_text() == "keep me\n"


def test_a_staged_temporary_file_planted_as_a_symlink_is_removed_not_followed(folder, outside):
    os.symlink(outside, folder / "results.jsonl.tmp")
    with ConfinedFolder(folder) as f, f.staged("results.jsonl") as staged:
        staged.file.write("row\n")
        staged.commit()
    assert (folder / "results.jsonl").read_text() == "row\n" and not (folder / "results.jsonl.tmp").exists()
    assert outside.read_text() == "keep me\n"


def test_a_folder_part_that_is_a_symlink_is_refused_and_nothing_is_written_beyond_it(folder, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    os.symlink(elsewhere, folder / "report")
    with pytest.raises(WriteTargetError, match=r"report: is a symbolic link"):
        write_inside(folder, "report/report.html", "<html>")
    assert list(elsewhere.iterdir()) == []


def test_the_named_folder_itself_may_be_a_symlink_the_user_chose(tmp_path):
    real = tmp_path / "scratch"
    real.mkdir()
    os.symlink(real, tmp_path / "link")
    write_inside(tmp_path / "link", "a/b.txt", "x")
    assert (real / "a" / "b.txt").read_text() == "x"


def test_a_hard_link_to_a_file_elsewhere_is_not_appended_to(folder, outside):
    os.link(outside, folder / "results.jsonl")
    with pytest.raises(WriteTargetError, match="hard link"):
        open_inside(folder, "results.jsonl", "a")
    assert outside.read_text() == "keep me\n"


def test_a_file_where_a_folder_goes_is_one_line(folder):
    (folder / "rescored-official").write_text("not a folder")
    with pytest.raises(WriteTargetError, match=r"rescored-official: is a file where povagent keeps a folder"):
        ConfinedFolder(folder, "rescored-official")


def test_a_folder_where_a_temporary_file_goes_is_one_line(folder):
    (folder / "results.jsonl.tmp").mkdir()
    with pytest.raises(WriteTargetError, match=r"results\.jsonl\.tmp: is a folder where povagent writes a file"):
        write_inside(folder, "results.jsonl", "x")


def test_missing_folders_are_made_and_an_append_adds_to_what_is_there(folder):
    with open_inside(folder, "a/b/log.jsonl", "a") as fh:
        fh.write("one\n")
    with open_inside(folder, "a/b/log.jsonl", "a") as fh:
        fh.write("two\n")
    assert (folder / "a" / "b" / "log.jsonl").read_text() == "one\ntwo\n"


def test_a_path_climbing_out_of_the_folder_is_a_bug_not_a_write(folder):
    with pytest.raises(ValueError, match="climbing"):
        write_inside(folder, "../x.txt", "x")


def test_a_refused_walk_leaves_no_descriptor_open(folder, tmp_path):
    os.symlink(tmp_path, folder / "report")
    before = len(os.listdir("/proc/self/fd"))
    for _ in range(20):
        with pytest.raises(WriteTargetError):
            ConfinedFolder(folder, "report/images")
    assert len(os.listdir("/proc/self/fd")) == before
