"""Exports load with no glue: the ``messages`` folder with ``datasets.load_dataset`` as it is,
from any working folder (images decoded, in order); the ``openai`` format as OpenAI's chat
fine-tuning JSONL (``image_url`` parts with data URLs); an ``hf`` export streamed with
``datasets`` and left early exits the interpreter cleanly."""

from __future__ import annotations

import base64
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from povagent.dataset.loader import load_dataset
from povagent.train.export_options import ExportOptions
from povagent.train.training_export import export_training_set


@pytest.fixture(scope="module", autouse=True)
def datasets():
    """The ``datasets`` package: this file's tests are skipped without it (the test extra). Imported
    when they run, not when the file is collected (every pytest-xdist worker collects every file)."""
    return pytest.importorskip("datasets", reason="the export tests load the exports with datasets (test extra)")


@pytest.fixture(scope="module")
def messages_export(generated_release: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    out = tmp_path_factory.mktemp("messages") / "train-set"
    report = export_training_set(generated_release, out, ExportOptions(format="messages", conditions=("a", "c"), split="0.5,0.5,0"), check_release=False)
    return out, report


def test_the_messages_folder_loads_its_conversations_with_datasets_from_any_folder(
    messages_export, datasets, generated_release: Path, tmp_path: Path, monkeypatch
) -> None:
    out, report = messages_export
    monkeypatch.chdir(tmp_path)  # not the export folder: the images must resolve anyway
    # a cache of this test's own: datasets keeps the resolved image paths of a load in its cache
    loaded = datasets.load_dataset(str(out), cache_dir=str(tmp_path / "hf-cache"))
    assert set(loaded) == {"train", "validation"}
    assert sum(len(split) for split in loaded.values()) == report.examples
    ds = load_dataset(generated_release)
    row = loaded["train"][0]
    inst = ds.instance(row["id"])
    assert sum(1 for part in row["messages"][0]["content"] if part["type"] == "image") == len(row["images"]) == len(inst.frames)
    for image, frame in zip(row["images"], inst.frames):
        assert isinstance(image, Image.Image)
        with Image.open(frame.file) as original:
            assert np.array_equal(np.asarray(image.convert("RGB")), np.asarray(original.convert("RGB")))


def test_the_messages_lines_keep_paths_llama_factory_resolves_from_the_export_folder(messages_export) -> None:
    out, _ = messages_export
    line = json.loads(next((out / "messages").glob("train-*.jsonl")).read_text().splitlines()[0])
    assert line["images"] and all((out / ref).is_file() for ref in line["images"])
    assert [f"messages/{name}" for name in line["images_file_names"]] == line["images"]


def test_the_openai_format_is_chat_fine_tuning_jsonl_with_data_urls(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "openai"
    report = export_training_set(generated_release, out, ExportOptions(format="openai", conditions=("c", "a"), split="1,0,0"), check_release=False)
    lines = [json.loads(line) for p in sorted((out / "openai").glob("*.jsonl")) for line in p.read_text().splitlines()]
    assert len(lines) == report.examples
    ds = load_dataset(generated_release)
    instances = {i.id: i for i in ds.instances()}
    # each frame file read once, not once for every line checked and every instance compared
    frame_bytes: dict[Path, bytes] = {}

    def read(frame) -> bytes:
        if frame.file not in frame_bytes:
            frame_bytes[frame.file] = frame.file.read_bytes()
        return frame_bytes[frame.file]

    for line in lines[:6] + lines[-6:]:
        assert list(line) == ["messages"]
        user, assistant = line["messages"]
        assert user["role"] == "user" and assistant["role"] == "assistant"
        assert isinstance(assistant["content"], str) and json.loads(assistant["content"].splitlines()[-1]).keys() >= {"x", "y"}
        urls = [p["image_url"]["url"] for p in user["content"] if p["type"] == "image_url"]
        assert all(set(p) == {"type", "text"} for p in user["content"] if p["type"] == "text")
        sent = [base64.b64decode(u.removeprefix("data:image/png;base64,")) for u in urls]
        assert all(u.startswith("data:image/png;base64,") for u in urls)
        # which instance: the frames sent, in the benchmark's order, are its frames' bytes
        matches = [i for i in instances.values() if [read(f) for f in i.frames] == sent]
        assert matches, "the images are no instance's frames in order"
    assert not (out / "images").exists() and not (out / "messages").exists()


STREAM = textwrap.dedent("""
    import sys
    import datasets

    stream = datasets.load_dataset("parquet", data_dir=sys.argv[1], split="train", streaming=True)
    for n, row in enumerate(stream, 1):
        if n == 2:
            break
    print("read", n, flush=True)
""")


def test_a_streamed_read_of_an_hf_export_left_early_exits(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "hf"
    # Inferred only: every example holds all 12 frames, so the one shard is large enough to have
    # been cut into many 16 MB row groups
    export_training_set(generated_release, out, ExportOptions(format="hf", conditions=("a",), split="1,0,0"), check_release=False)
    shards = list((out / "data").glob("*.parquet"))
    assert len(shards) == 1 and shards[0].stat().st_size > 80 * 2**20
    try:
        done = subprocess.run([sys.executable, "-c", STREAM, str(out / "data")], capture_output=True, text=True, timeout=150)
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"the streamed read did not exit: {exc.stdout!r}") from None
    assert done.returncode == 0 and "read 2" in done.stdout, done.stderr[-2000:]
