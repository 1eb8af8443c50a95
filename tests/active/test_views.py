"""Views are stored content-addressed in the run folder, found again without rendering, and
nothing planted in the folder is followed, waited on, read whole or trusted without its hash."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest

from povagent.active.pose import Pose
from povagent.active.views import MAX_VIEW_BYTES, ViewStore, camera_key
from povagent.errors import WriteTargetError

POSE = Pose(1.0, 0.9, 2.0, 90.0, 30.0)
PNG = b"png-bytes"
SHA = hashlib.sha256(PNG).hexdigest()


class Renders:
    """A stand-in renderer counting its calls."""

    def __init__(self, data: bytes = PNG) -> None:
        self.data = data
        self.count = 0

    def __call__(self, pose: Pose) -> bytes:
        self.count += 1
        return self.data


def test_a_view_is_stored_by_its_sha256_and_found_again_without_rendering(tmp_path):
    render = Renders()
    view = ViewStore(tmp_path).view("train_house_00000", POSE, render)
    assert (view.sha256, view.path, view.png) == (SHA, tmp_path / "views" / f"{SHA}.png", PNG)
    again = ViewStore(tmp_path).view("train_house_00000", POSE, render)  # a resumed run: a new store
    assert again == view and render.count == 1


def test_a_damaged_index_entry_renders_again(tmp_path):
    store = ViewStore(tmp_path)
    view = store.view("h", POSE, Renders())
    view.path.unlink()
    assert store.view("h", POSE, Renders()) == view and store.rendered == 2


@pytest.mark.parametrize("planted", ["views", "views/cameras"])
def test_a_views_folder_planted_as_a_link_is_refused_and_nothing_is_written_outside(tmp_path, planted):
    outside = tmp_path / "outside"
    outside.mkdir()
    run = tmp_path / "run"
    (run / "views").mkdir(parents=True) if planted != "views" else run.mkdir()
    (run / planted).symlink_to(outside, target_is_directory=True)
    with pytest.raises(WriteTargetError, match="symbolic link"):
        ViewStore(run)
    assert list(outside.iterdir()) == []


def _plant(path: Path, kind: str, outside: Path) -> None:
    path.unlink(missing_ok=True)
    if kind == "a link to a file outside with the right bytes":
        (outside / "view.png").write_bytes(PNG if path.suffix == ".png" else SHA.encode())
        path.symlink_to(outside / ("view.png"))
    elif kind == "other bytes":
        path.write_bytes(b"other bytes" if path.suffix == ".png" else hashlib.sha256(b"other").hexdigest().encode())
    elif kind == "a FIFO":
        os.mkfifo(path)
    elif kind == "a link to /dev/zero":
        path.symlink_to("/dev/zero")
    elif kind == "a file too large":
        with open(path, "wb") as fh:
            fh.truncate(MAX_VIEW_BYTES + 1)  # sparse: costs no disk
    else:
        raise AssertionError(kind)


KINDS = ["a link to a file outside with the right bytes", "other bytes", "a FIFO", "a link to /dev/zero", "a file too large"]


@pytest.mark.timeout(20)
@pytest.mark.parametrize("where", ["index", "view"])
@pytest.mark.parametrize("kind", KINDS)
def test_a_planted_view_or_index_file_is_rendered_again_once_and_replaced(tmp_path, where, kind):
    outside = tmp_path / "outside"
    outside.mkdir()
    run = tmp_path / "run"
    ViewStore(run).view("h", POSE, Renders())
    target = run / "views" / ("cameras/" + camera_key("h", POSE) if where == "index" else f"{SHA}.png")
    _plant(target, kind, outside)
    before = {p.name: p.read_bytes() for p in outside.iterdir()}
    resumed, render = ViewStore(run), Renders()
    view = resumed.view("h", POSE, render)
    assert (view.sha256, view.png, render.count) == (SHA, PNG, 1)
    assert target.is_file() and not target.is_symlink()  # the planted entry is replaced by ours
    assert resumed.view("h", POSE, render) == view and render.count == 1  # and found again from now on
    assert {p.name: p.read_bytes() for p in outside.iterdir()} == before
