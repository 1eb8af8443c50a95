"""The forms a value from a Hub server (or a revision from a config) must have before it becomes
part of a cache path: one case per rule, accepted and refused."""

from __future__ import annotations

import pytest

from povagent.dataset.hub_checks import (
    HubValueError,
    check_blob_name,
    check_commit_id,
    check_repo_path,
    check_revision,
    check_size,
    shown,
)
from povagent.dataset.hub_transfer import checked_listing

SHA1 = "0123456789abcdef0123456789abcdef01234567"
SHA256 = "0123456789abcdef" * 4


@pytest.mark.parametrize("value", [SHA1, "f" * 40])
def test_a_commit_id_is_40_lowercase_hex_digits(value):
    assert check_commit_id(value) == value


@pytest.mark.parametrize("value", [SHA1.upper(), SHA1[:-1], SHA1 + "0", "../" + SHA1[3:], "/" + SHA1[1:], None, 7, SHA256])
def test_anything_else_is_not_a_commit_id(value):
    with pytest.raises(HubValueError, match="is not a commit id"):
        check_commit_id(value)


@pytest.mark.parametrize("value", [SHA1, SHA256])
def test_a_blob_name_is_a_git_id_or_a_sha256(value):
    assert check_blob_name(value, "ETag") == value


@pytest.mark.parametrize("value", ["../../evil.pth", "/abs/evil.pth", SHA256 + "/x", "W/" + SHA1, ""])
def test_an_etag_that_is_not_an_id_is_refused(value):
    with pytest.raises(HubValueError, match="ETag"):
        check_blob_name(value, "ETag")


@pytest.mark.parametrize("value", ["main", "v1.0", "refs/pr/4", "release/2026-01", "feature_x", "été", SHA1])
def test_branch_tag_and_commit_names_git_accepts_are_revisions(value):
    assert check_revision(value) == value


@pytest.mark.parametrize(
    "value",
    ["", "..", "../x", "a/../b", "a..b", ".hidden", "a/.b", "x.lock", "a/b.lock", "/main", "main/", "a//b", "main.",
     "@", "a@{1}", "a b", "a\\b", "a:b", "a~1", "a^", "a?", "a*", "a[", "a\nb", "a\x7fb", "x" * 256],
)  # fmt: skip
def test_a_revision_git_would_refuse_is_refused(value):
    with pytest.raises(HubValueError, match="revision"):
        check_revision(value)


@pytest.mark.parametrize("value", ["meta.json", "artifacts/h/exploration_images/frame_000.png", "a b/c d.json", "..a/b..", ".gitattributes"])
def test_a_relative_file_name_inside_the_repository_is_accepted(value):
    assert check_repo_path(value) == value


@pytest.mark.parametrize(
    "value",
    ["", "/etc/passwd", "../x", "a/../../x", "a/./b", "a//b", "a/", "a\\..\\b", "C:evil", "c:/evil", "a\x00b", "a\nb",
     "x" * 1025, "a/" + "y" * 256],
)  # fmt: skip
def test_a_file_name_that_could_leave_the_snapshot_is_refused(value):
    with pytest.raises(HubValueError, match="file name in the tree listing"):
        check_repo_path(value)


@pytest.mark.parametrize("value", [-1, True, 1.5, "10", None])
def test_a_size_is_a_non_negative_integer(value):
    with pytest.raises(HubValueError, match="size"):
        check_size(value, "size")


def test_a_refused_value_is_quoted_on_one_line_and_cut_short():
    text = shown("../" * 100 + "\n\x1b[31m")
    assert "\n" not in text and "\x1b" not in text and text.endswith("(306 characters)") and len(text) < 100


def test_a_listing_with_a_file_that_is_also_a_folder_is_refused():
    with pytest.raises(HubValueError, match="both a file and a folder"):
        checked_listing([("a", 1, SHA1, None, None), ("a/b", 1, SHA1, None, None)])


def test_a_listing_naming_a_file_twice_is_refused():
    with pytest.raises(HubValueError, match="listed twice"):
        checked_listing([("a", 1, SHA1, None, None), ("a", 2, SHA1, None, None)])


def test_an_lfs_file_is_stored_under_its_sha256_with_its_lfs_size():
    (entry,) = checked_listing([("x.png", 130, SHA1, SHA256, 5000)]).values()
    assert entry.blob == SHA256 and entry.size == 5000
