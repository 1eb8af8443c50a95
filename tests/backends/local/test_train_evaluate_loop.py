"""The loop of docs/how-to/local-models.md: generate -> export-train -> TRL SFTTrainer a few steps
on a tiny checkpoint -> povagent run with the saved checkpoint -> report. No glue in between."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(240)


@pytest.fixture(scope="module", autouse=True)
def _needs_trl() -> None:
    """These tests need TRL: skipped without it. Imported when they run, not when the file is
    collected (every pytest-xdist worker collects every file)."""
    pytest.importorskip("trl")


def povagent(*args: str) -> str:
    """Run a povagent command as the command line does (in this process: torch and
    transformers are imported once for the whole loop), returning what it printed."""
    from typer.testing import CliRunner

    from povagent.cli import app

    done = CliRunner().invoke(app, list(args))
    assert done.exit_code == 0, f"povagent {' '.join(args)} failed:\n{done.output}\n{done.exception!r}"
    return done.output


def sft(checkpoint: Path, export: Path, out: Path) -> list[float]:
    """A few SFT steps on the hf export, assistant turns only, as the how-to's recipe."""
    from datasets import load_dataset
    from transformers import AutoModelForImageTextToText, AutoProcessor
    from trl import SFTConfig, SFTTrainer

    # a datasets cache of the test's own: the default one, under the home folder, would keep a
    # converted copy of the export every run
    dataset = load_dataset("parquet", data_dir=str(export / "data"), split="train", cache_dir=str(out.parent / "hf-cache"))
    dataset = dataset.select_columns(["messages", "images"]).select(range(min(4, len(dataset))))
    processor = AutoProcessor.from_pretrained(checkpoint)
    model = AutoModelForImageTextToText.from_pretrained(checkpoint)
    config = SFTConfig(
        output_dir=str(out / "trainer"),
        max_steps=3,
        per_device_train_batch_size=2,
        learning_rate=1e-3,
        assistant_only_loss=True,
        max_length=None,
        logging_steps=1,
        report_to=[],
        save_strategy="no",
        use_cpu=True,
        dataloader_num_workers=0,
    )
    trainer = SFTTrainer(model=model, args=config, train_dataset=dataset, processing_class=processor)
    trainer.train()
    trainer.save_model(str(out))
    processor.save_pretrained(str(out))
    return [entry["loss"] for entry in trainer.state.log_history if "loss" in entry]


@pytest.fixture(scope="module")
def exported(tmp_path_factory, generated_release):
    """``exported(fmt) -> folder``: the generated release's condition-c training export in
    ``fmt``, written once per module (the tests read it, never write it)."""
    folders: dict[str, Path] = {}

    def export(fmt: str) -> Path:
        if fmt not in folders:
            folder = tmp_path_factory.mktemp(f"export-{fmt}") / "train-set"
            povagent("export-train", str(generated_release), "--out", str(folder), "--format", fmt,
                     "--rationale", "none", "--conditions", "c", "--split", "1,0,0")
            folders[fmt] = folder
        return folders[fmt]

    return export


def test_a_checkpoint_trained_on_the_export_is_evaluated_in_process(tmp_path, generated_release, tiny_idefics3, exported):
    losses = sft(tiny_idefics3, exported("hf"), tmp_path / "trained")
    assert len(losses) == 3 and all(loss == loss for loss in losses)  # trained, no NaN
    from povagent_plugins.backends.local_checkpoint import checkpoint_fingerprint

    assert checkpoint_fingerprint(tmp_path / "trained") != checkpoint_fingerprint(tiny_idefics3)
    doc = {
        "dataset": str(generated_release),
        "backend": {"name": "transformers", "options": {"model": str(tmp_path / "trained")}},
        "strategy": {"name": "basic", "options": {"max_tokens": 8}},
        "instances": {"conditions": ["c"], "limit": 2},
        "timeout": 60,
        "output": str(tmp_path / "eval"),
    }
    (tmp_path / "eval.yaml").write_text(yaml.safe_dump(doc))
    povagent("run", str(tmp_path / "eval.yaml"))
    rows = [json.loads(line) for line in (tmp_path / "eval" / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 2 and all(r["model"].startswith(str(tmp_path / "trained")) for r in rows)
    assert all(r["status"] in ("answered", "parse_error") for r in rows)
    report = povagent("report", str(tmp_path / "eval"))
    assert "given" in report.lower()


@pytest.mark.parametrize("fmt", ["hf", "messages"])
def test_trl_trains_on_an_export_loaded_by_its_folder_alone(tmp_path, exported, tiny_idefics3, fmt, monkeypatch):
    """What `trl sft --dataset_name EXPORT` does: `load_dataset(EXPORT)` from another working
    folder, every column as exported, straight into SFTTrainer (no column picking, no paths fixed)."""
    from datasets import load_dataset
    from transformers import AutoModelForImageTextToText, AutoProcessor
    from trl import SFTConfig, SFTTrainer

    export = exported(fmt)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    # a datasets cache of the test's own: the shared default one keeps rows of earlier runs
    dataset = load_dataset(str(export), split="train", cache_dir=str(tmp_path / "hf-cache")).select(range(2))
    assert {"messages", "images"} <= set(dataset.column_names)
    config = SFTConfig(output_dir=str(tmp_path / "trainer"), max_steps=1, per_device_train_batch_size=2,
                       assistant_only_loss=True, max_length=None, report_to=[], save_strategy="no", use_cpu=True)
    trainer = SFTTrainer(model=AutoModelForImageTextToText.from_pretrained(tiny_idefics3), args=config,
                         train_dataset=dataset, processing_class=AutoProcessor.from_pretrained(tiny_idefics3))
    result = trainer.train()
    assert result.global_step == 1 and result.training_loss == result.training_loss  # one step, no NaN
