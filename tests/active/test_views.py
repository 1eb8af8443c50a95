"""Views are stored content-addressed in the run folder, and found again without rendering."""

from __future__ import annotations

import hashlib

from povagent.active.pose import Pose
from povagent.active.views import ViewStore


def test_a_view_is_stored_by_its_sha256_and_found_again_without_rendering(tmp_path):
    renders = []

    def render(pose: Pose) -> bytes:
        renders.append(pose)
        return b"png-bytes"

    pose = Pose(1.0, 0.9, 2.0, 90.0, 30.0)
    sha, path = ViewStore(tmp_path).view("train_house_00000", pose, render)
    assert sha == hashlib.sha256(b"png-bytes").hexdigest() and path == tmp_path / f"{sha}.png"
    again = ViewStore(tmp_path).view("train_house_00000", pose, render)  # a resumed run: a new store
    assert again == (sha, path) and len(renders) == 1


def test_a_damaged_index_entry_renders_again(tmp_path):
    store = ViewStore(tmp_path)
    pose = Pose(1.0, 0.9, 2.0, 90.0, 30.0)
    sha, path = store.view("h", pose, lambda p: b"a")
    path.unlink()
    assert store.view("h", pose, lambda p: b"a") == (sha, path) and store.rendered == 2
