"""export-train's bad input ends in one line naming the file or option, with nothing half-written:
a bad ``--split``, an ``--out`` that is a file or cannot be made, an ``export.json`` of the wrong
shape, an observer view named relative to the root in another house (valid: exported), and a
disk that fills up mid-shard (no temporary file left holding the space)."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import PovagentError


def invoke(*args: object) -> tuple[int, str]:
    """Run ``povagent`` as a user would: (exit code, what it printed or raised as one line)."""
    result = CliRunner().invoke(app, [str(a) for a in args])
    exc = result.exception
    if exc is not None and not isinstance(exc, SystemExit):
        assert isinstance(exc, PovagentError), f"traceback instead of a message: {type(exc).__name__}: {exc}"
        assert "\n" not in str(exc)
        return 2, result.output + f"error: {exc}"
    return result.exit_code, result.output


@pytest.mark.parametrize("split", ["0.5,0.6", "train=²:3", "train=0:" + "9" * 5000, "test=5:1"])
def test_a_bad_split_is_one_line_naming_the_option(generated_release: Path, tmp_path: Path, split: str) -> None:
    code, text = invoke("export-train", generated_release, "--out", tmp_path / "out", "--split", split)
    assert code == 2 and "--split" in text
    assert not (tmp_path / "out").exists()


def test_an_out_that_is_a_file_is_one_line_and_the_file_is_kept(generated_release: Path, tmp_path: Path) -> None:
    target = tmp_path / "notes.txt"
    target.write_text("mine")
    code, text = invoke("export-train", generated_release, "--out", target)
    assert code == 2 and f"--out {target}" in text and "is a file" in text
    assert target.read_text() == "mine"


@pytest.mark.parametrize("where", ["under-a-file", "proc"])
def test_an_out_that_cannot_be_made_is_one_line_naming_it(generated_release: Path, tmp_path: Path, where: str) -> None:
    (tmp_path / "file").write_text("x")
    out = tmp_path / "file" / "out" if where == "under-a-file" else Path("/proc/povagent-export-test")
    code, text = invoke("export-train", generated_release, "--out", out, "--format", "messages")
    assert code == 2 and f"--out {out}" in text


@pytest.mark.parametrize("options", [[], "cot", None, 3])
def test_an_export_json_whose_options_are_not_an_object_is_named(generated_release: Path, tmp_path: Path, options: object) -> None:
    out = tmp_path / "out"
    out.mkdir()
    from povagent.train.export_folder import MANIFEST_VERSION

    manifest = json.dumps({"version": MANIFEST_VERSION, "options": options, "shards": []})
    (out / "export.json").write_text(manifest)
    code, text = invoke("export-train", generated_release, "--out", out, "--format", "messages", "--conditions", "c")
    assert code == 2 and "export.json" in text and "'options'" in text
    # nothing written but the folder's (empty) lock file
    assert (out / "export.json").read_text() == manifest
    assert sorted(p.name for p in out.iterdir()) == [".lock", "export.json"] and (out / ".lock").stat().st_size == 0


def test_an_observer_view_named_from_the_root_in_another_house_is_exported(dataset_copy, tmp_path: Path) -> None:
    root = dataset_copy()
    first, second = sorted(p for p in (root / "artifacts").iterdir() if p.is_dir())
    other_view = json.loads((first / f"{first.name}.json").read_text())[0]["rgb_path"]
    pairs = json.loads((second / f"{second.name}.json").read_text())
    pairs[0]["rgb_path"] = f"artifacts/{first.name}/{other_view}"  # relative to the root, as some releases write it
    (second / f"{second.name}.json").write_text(json.dumps(pairs))
    code, text = invoke("validate", root)
    assert code == 0, text
    out = tmp_path / "out"
    code, text = invoke("export-train", root, "--out", out, "--format", "messages", "--conditions", "c", "--split", "1,0,0")
    assert code == 0, text
    rows = [json.loads(line) for p in (out / "messages").glob("*.jsonl") for line in p.read_text().splitlines()]
    row = next(r for r in rows if r["house_id"] == second.name and r["pair_id"] == str(pairs[0]["pair_id"]))
    assert (out / row["images"][0]).read_bytes() == (first / other_view).read_bytes()
    assert (out / row["images"][0]).resolve().is_relative_to(out.resolve())


def _limit_file_size() -> None:
    # every file this process writes stops at 400 kB: a frame copy fits, the JSONL shard does
    # not (the kernel's EFBIG stands for a disk that fills up mid-shard)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (400_000, 400_000))


def test_a_full_disk_mid_shard_names_the_file_and_leaves_no_temporary(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "povagent.cli", "export-train", str(generated_release), "--out", str(out), "--format", "messages", "--split", "1,0,0"],
        capture_output=True, text=True, timeout=240, preexec_fn=_limit_file_size,
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "messages/train-00000-of-00001.jsonl" in done.stderr
    left = [p.name for p in out.rglob("*") if ".tmp" in p.name]
    assert left == []
    assert not (out / "messages" / "train-00000-of-00001.jsonl").exists()
    os.sync()


@pytest.mark.parametrize("fmt", ["hf", "messages", "openai"])
def test_a_lone_surrogate_in_a_sentence_leaves_its_house_out_of_every_format(mini_root: Path, tmp_path: Path, fmt: str) -> None:
    import shutil

    root = tmp_path / "ds"
    for house in ("train_house_00000", "train_house_00001"):
        shutil.copytree(mini_root / "artifacts" / house, root / "artifacts" / house)
    pairs = root / "artifacts" / "train_house_00001" / "train_house_00001.json"
    data = json.loads(pairs.read_text())
    data[0]["stage5"]["front"]["type_a"] = "the remote \ud800"  # no file can hold it: it crashed every format
    pairs.write_text(json.dumps(data))
    code, text = invoke("export-train", root, "--out", tmp_path / "out", "--format", fmt)
    assert code == 0, text
    assert "left out train_house_00001: artifacts/train_house_00001/train_house_00001.json: $[0].stage5.front.type_a" in text
    assert "out: 12 examples" in text  # the other house's 12 instances
    card = (tmp_path / "out" / "README.md").read_text(encoding="utf-8")
    assert "- train_house_00001: artifacts/train_house_00001/train_house_00001.json: $[0].stage5.front.type_a" in card
