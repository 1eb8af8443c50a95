"""export-train end to end on a generated set: load what it wrote as a trainer would."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from povagent.dataset.loader import load_dataset
from povagent.train.export_options import ExportError, ExportOptions
from povagent.train.training_export import export_training_set


@pytest.fixture(scope="module", autouse=True)
def datasets():
    """The ``datasets`` package: this file's tests are skipped without it (the test extra). Imported
    when they run, not when the file is collected (every pytest-xdist worker collects every file)."""
    return pytest.importorskip("datasets", reason="the export tests load the hf folder with datasets (test extra)")


def hf_cache(out: Path) -> str:
    """A datasets cache beside the export, in the module's tmp folder: the default one, under
    the home folder, kept a converted copy of every export every run ever loaded."""
    return str(out.parent / "hf-cache")


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def files_of(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): sha(p.read_bytes()) for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def hf_export(generated_release: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    out = tmp_path_factory.mktemp("hf") / "out"
    report = export_training_set(generated_release, out, ExportOptions(format="hf", split="0.5,0.5,0", max_shard_bytes=6 * 2**20), check_release=False)
    return out, report


def test_the_hf_folder_loads_with_datasets_and_holds_every_teachable_instance(hf_export, datasets, generated_release: Path) -> None:
    out, report = hf_export
    loaded = datasets.load_dataset("parquet", data_dir=str(out / "data"), cache_dir=hf_cache(out))
    assert set(loaded) == {"train", "validation"}
    ids = [i for split in loaded.values() for i in split["id"]]
    assert len(ids) == len(set(ids)) == report.examples
    ds = load_dataset(generated_release)
    assert set(ids) | set(report.skipped) == {i.id for i in ds.instances()}
    assert report.counts["condition"] == {c: sum(1 for i in ids if i.endswith("/" + c)) for c in "abc"}


def test_images_are_the_datasets_own_bytes_in_the_benchmarks_order(hf_export, generated_release: Path) -> None:
    out, _ = hf_export
    import pyarrow.parquet as pq

    ds = load_dataset(generated_release)
    table = pq.read_table(sorted((out / "data").glob("*.parquet"))[0])
    for row in table.to_pylist()[:8]:
        inst = ds.instance(row["id"])
        assert [i["path"] for i in row["images"]] == [f"{inst.house_id}/{f.image_path}" for f in inst.frames]
        for image, frame in zip(row["images"], inst.frames):
            assert image["bytes"] == frame.file.read_bytes()
        n_placeholders = sum(1 for part in row["messages"][0]["content"] if part["type"] == "image")
        assert n_placeholders == len(row["images"])
        assert row["messages"][1]["content"][0]["text"].splitlines()[-1] == row["answer"]


def test_datasets_decodes_the_image_feature(hf_export, datasets) -> None:
    out, _ = hf_export
    row = datasets.load_dataset("parquet", data_dir=str(out / "data"), split="train", cache_dir=hf_cache(out))[0]
    assert row["images"][0].size == (512, 512)
    assert json.loads(row["answer"]).keys() >= {"x", "y"}


def test_shards_stay_under_the_cap_unless_one_example_is_larger(hf_export) -> None:
    out, _ = hf_export
    import pyarrow.parquet as pq

    shards = [(p.stat().st_size, pq.ParquetFile(p).metadata.num_rows) for p in (out / "data").glob("*.parquet")]
    assert len(shards) > 2 and max(rows for _, rows in shards) > 1
    for size, rows in shards:
        assert size <= 6 * 2**20 or rows == 1, (size, rows)


def test_the_card_names_counts_seed_and_exclusions(hf_export) -> None:
    out, report = hf_export
    card = (out / "README.md").read_text()
    assert card.startswith("---\n") and "configs:" in card and "list: image" in card
    assert "seed 3" in card
    for split, n in report.counts["split"].items():
        assert f"| {split} | {n:,} |" in card
    assert "Evaluation houses" in card


def test_a_house_is_in_one_split_only(hf_export, datasets) -> None:
    out, _ = hf_export
    loaded = datasets.load_dataset("parquet", data_dir=str(out / "data"), cache_dir=hf_cache(out))
    houses = {split: set(d["house_id"]) for split, d in loaded.items()}
    assert houses["train"] and houses["validation"]
    assert not houses["train"] & houses["validation"]


def test_messages_references_resolve_inside_the_export(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "msg"
    report = export_training_set(generated_release, out, ExportOptions(format="messages", rationale="cot"), check_release=False)
    lines = [json.loads(line) for p in sorted((out / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    assert len(lines) == report.examples
    root = out.resolve()
    ds = load_dataset(generated_release)
    for line in lines:
        inst = ds.instance(line["id"])
        assert len(line["images"]) == len(inst.frames)
        for ref, frame in zip(line["images"], inst.frames):
            path = (out / ref).resolve()
            assert path.is_relative_to(root) and path.read_bytes() == frame.file.read_bytes()
        assert line["conversations"][0]["value"].count("<image>") == len(line["images"])
        assert sum(1 for p in line["messages"][0]["content"] if p["type"] == "image") == len(line["images"])
        assert line["conversations"][1]["value"] == line["messages"][1]["content"][0]["text"]
    info = json.loads((out / "dataset_info.json").read_text())
    assert all((out / e["file_name"]).is_file() and e["formatting"] == "sharegpt" for e in info.values())


def test_an_evaluation_house_is_refused_even_renamed(generated_release: Path, tmp_path: Path) -> None:
    evaluation = tmp_path / "eval"
    house = sorted((generated_release / "artifacts").iterdir())[1]
    renamed = evaluation / "artifacts" / "train_house_00777"
    shutil.copytree(house, renamed)
    (renamed / f"{house.name}.json").rename(renamed / "train_house_00777.json")
    with pytest.raises(ExportError, match=house.name):
        export_training_set(generated_release, tmp_path / "out", ExportOptions(format="messages"), exclude=[evaluation], check_release=False)
    assert not (tmp_path / "out").exists()
    report = export_training_set(
        generated_release, tmp_path / "out", ExportOptions(format="messages"), exclude=[evaluation], drop_excluded=True, check_release=False
    )
    assert set(report.excluded) == {house.name}
    assert all(not line.startswith(f'{{"id": "{house.name}/') for p in (tmp_path / "out" / "messages").glob("*.jsonl") for line in p.read_text().splitlines())
    assert f"{house.name}: same house as" in (tmp_path / "out" / "README.md").read_text()


def test_a_generated_house_is_recognised_by_seed_and_index(generated_release: Path, tmp_path: Path) -> None:
    evaluation = tmp_path / "eval"
    shutil.copytree(generated_release, evaluation)
    first = sorted((evaluation / "artifacts").iterdir())[0]
    pair_file = first / f"{first.name}.json"
    data = json.loads(pair_file.read_text())
    data[0]["stage5"] = data[0]["stage5"]  # same content, another layout of the file
    pair_file.write_text(json.dumps(data, indent=3) + "\n\n")
    second = sorted((evaluation / "artifacts").iterdir())[1]
    (second / f"{second.name}.json").write_text(json.dumps(json.loads((second / f"{second.name}.json").read_text())[:1]))
    with pytest.raises(ExportError) as info:
        export_training_set(generated_release, tmp_path / "out", ExportOptions(format="messages"), exclude=[evaluation], check_release=False)
    # the first by content (whitespace does not matter), the second by (seed, index) although its content changed
    assert "2 house(s)" in str(info.value)


def test_other_options_over_an_export_are_refused_naming_the_option(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    export_training_set(generated_release, out, ExportOptions(format="messages", rationale="cot"), check_release=False)
    with pytest.raises(ExportError, match="rationale='cot'"):
        export_training_set(generated_release, out, ExportOptions(format="messages", rationale="s-cot"), check_release=False)
    again = export_training_set(generated_release, out, ExportOptions(format="messages", rationale="cot"), check_release=False)
    assert again.shards_written == 0


def test_an_export_written_by_another_version_is_not_resumed(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    export_training_set(generated_release, out, ExportOptions(format="messages"), check_release=False)
    manifest = json.loads((out / "export.json").read_text())
    (out / "export.json").write_text(json.dumps({**manifest, "version": manifest["version"] - 1}))
    with pytest.raises(ExportError, match="another version of export-train"):
        export_training_set(generated_release, out, ExportOptions(format="messages"), check_release=False)


def test_a_folder_that_is_not_an_export_is_refused(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "someone"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(ExportError, match="not empty"):
        export_training_set(generated_release, out, ExportOptions(format="messages"), check_release=False)
    assert (out / "notes.txt").read_text() == "mine"


def test_a_killed_export_resumes_to_the_same_bytes_without_duplicates(generated_release: Path, tmp_path: Path) -> None:
    clean = tmp_path / "clean"
    export_training_set(generated_release, clean, ExportOptions(format="hf", conditions=("a",), max_shard_bytes=2**20), check_release=False)
    killed = tmp_path / "killed"
    cmd = [sys.executable, "-m", "povagent.cli", "export-train", str(generated_release), "--out", str(killed), "--max-shard-mb", "1", "--conditions", "a"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if len(list((killed / "data").glob("*.parquet"))) >= 2:
            break
        time.sleep(0.05)
    assert proc.poll() is None, f"the export ended before it could be killed: {proc.stderr.read().decode() if proc.stderr else ''}"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    written_before = set(files_of(killed / "data"))
    assert 2 <= len(written_before) < len(files_of(clean / "data"))
    # resumed in this process with the command's options (a resume with others is refused, so
    # these are the killed command's); the command's own interpreter costs a second of imports
    export_training_set(generated_release, killed, ExportOptions(format="hf", conditions=("a",), max_shard_bytes=2**20))
    assert files_of(killed / "data") == files_of(clean / "data")
    import pyarrow.parquet as pq

    ids = [i for p in sorted((killed / "data").glob("*.parquet")) for i in pq.read_table(p, columns=["id"])["id"].to_pylist()]
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("fmt", ["hf", "messages"])
def test_an_export_holds_one_house_in_memory_at_a_time(generated_release: Path, tmp_path: Path, monkeypatch, fmt: str) -> None:
    # memory flat in the number of houses: whenever the export reads a house, the one it read
    # before may still be referenced, no other (a dataset of 4 houses: the 2 generated ones and
    # renamed copies of them)
    import gc
    import weakref

    import povagent.dataset.loader as loader

    root = tmp_path / "four"
    (root / "artifacts").mkdir(parents=True)
    shutil.copy(generated_release / "meta.json", root / "meta.json")
    for house in sorted((generated_release / "artifacts").iterdir()):
        for name in (house.name, house.name.replace("train_house_0000", "train_house_0001")):
            shutil.copytree(house, root / "artifacts" / name)
            if name != house.name:
                (root / "artifacts" / name / f"{house.name}.json").rename(root / "artifacts" / name / f"{name}.json")
    read: list[weakref.ref] = []
    most = [0]

    class CountedHouse(loader.House):
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            read.append(weakref.ref(self))
            alive = sum(1 for r in read if r() is not None)
            if alive > 2:  # a full collection only when it could matter (each costs the whole heap)
                gc.collect()
                alive = sum(1 for r in read if r() is not None)
            most[0] = max(most[0], alive)

    monkeypatch.setattr(loader, "House", CountedHouse)
    # condition C only (one observer view an example, not 12 exploration frames): every house is
    # still read to plan and again to write, for a twelfth of the image bytes
    report = export_training_set(root, tmp_path / "out", ExportOptions(format=fmt, conditions=("c",), split="1,0,0"), check_release=False)
    assert len(report.houses_by_split["train"]) == 4 and report.examples > 0
    assert len(read) >= 8  # each house read to plan and again to write
    assert most[0] <= 2


def test_export_json_meets_its_shipped_schema(hf_export) -> None:
    from importlib import resources

    from jsonschema import Draft202012Validator

    out, _ = hf_export
    schema = json.loads(resources.files("povagent").joinpath("schemas", "output_export.schema.json").read_text(encoding="utf-8"))
    assert list(Draft202012Validator(schema).iter_errors(json.loads((out / "export.json").read_text()))) == []
