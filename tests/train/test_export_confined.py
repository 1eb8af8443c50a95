"""export-train writes only inside ``--out``, under names it builds itself: an ``rgb_path`` that
climbs through a symlinked folder of the dataset, a link planted in an export folder, and two
exports into one folder (locked) cannot make it write anywhere else."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from povagent.errors import PovagentError
from povagent.train.export_options import ExportError, ExportOptions
from povagent.train.training_export import export_training_set


def _files(folder: Path) -> set[Path]:
    return {p for p in folder.rglob("*") if p.is_file() or p.is_symlink()}


def test_an_rgb_path_climbing_through_a_symlinked_folder_writes_nothing_outside_out(dataset_copy, tmp_path: Path) -> None:
    root = dataset_copy()
    house = sorted(p for p in (root / "artifacts").iterdir() if p.is_dir())[0]
    pairs = json.loads((house / f"{house.name}.json").read_text())
    deep = house / "views" / "a" / "b" / "c" / "d" / "e"
    deep.mkdir(parents=True)
    (house / "views" / "view.png").write_bytes((house / pairs[0]["rgb_path"]).read_bytes())
    os.symlink(deep, house / "hop")
    # read by the kernel: hop -> views/a/b/c/d/e, five levels up is views/, so views/view.png;
    # spelled below an export's images/<house>/ it would climb out of --out
    pairs[0]["rgb_path"] = "hop/../../../../../view.png"
    (house / f"{house.name}.json").write_text(json.dumps(pairs))
    out = tmp_path / "exports" / "x" / "out"
    before = _files(tmp_path)
    try:
        report = export_training_set(root, out, ExportOptions(format="messages", conditions=("c",), split="1,0,0"), check_release=False)
    except PovagentError as exc:  # refusing the dataset is fine too, in one line
        assert "\n" not in str(exc)
        report = None
    written = _files(tmp_path) - before
    assert written and all(p.is_relative_to(out) for p in written), sorted(map(str, written - _files(out)))
    if report is not None:
        names = {p.relative_to(out / "messages" / "images").as_posix() for p in (out / "messages" / "images").rglob("*.png")}
        assert all(len(n.split("/")) == 2 and len(n.split("/")[1]) == 64 + 4 for n in names)  # <aa>/<sha256>.png only


def test_a_link_planted_in_an_export_folder_is_not_followed(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    options = ExportOptions(format="messages", conditions=("c",), split="1,0,0")
    export_training_set(generated_release, out, options, check_release=False)
    victim = tmp_path / "victim"
    victim.mkdir()
    shard = next((out / "messages").glob("*.jsonl"))
    shard.unlink()
    images = out / "messages" / "images"
    os.rename(images, tmp_path / "moved-images")
    os.symlink(victim, images)  # the resumed export would store its images through this link
    with pytest.raises(PovagentError, match="symbolic link"):
        export_training_set(generated_release, out, options, check_release=False)
    assert list(victim.iterdir()) == []


def test_a_second_export_into_a_folder_being_written_is_refused(generated_release: Path, tmp_path: Path) -> None:
    from povagent.train.export_folder import export_folder, manifest

    out = tmp_path / "out"
    out.mkdir()
    with export_folder(out, manifest(ExportOptions(format="messages"), [], generated_release)):
        with pytest.raises(ExportError, match="another export-train is writing into this folder"):
            export_training_set(generated_release, out, ExportOptions(format="messages", conditions=("c",)), check_release=False)
        assert sorted(p.name for p in out.iterdir()) == [".lock", "export.json"]
