"""export-train says what it left out: every house and pair loading dropped, and why, on the
console and in the card's "Left out" list."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


@pytest.fixture(scope="module")
def planted(generated_release: Path, tmp_path_factory: pytest.TempPathFactory, copy_house, bomb_png) -> tuple[Path, str, str]:
    """A dataset of four houses: one with a truncated frame, one with a frame that is no image,
    one whose first pair's observer view claims 100,000 x 100,000 pixels, one sound; exported
    once with the CLI. Returns (export folder, console output, card)."""
    base = tmp_path_factory.mktemp("left-out")
    root = base / "data"
    (root / "artifacts").mkdir(parents=True)
    (root / "meta.json").write_bytes((generated_release / "meta.json").read_bytes())
    first, second = sorted(p for p in (generated_release / "artifacts").iterdir() if p.is_dir())
    truncated = copy_house(first, root, "train_house_00010")
    frame = sorted((truncated / "exploration_images").glob("*.png"))[0]
    frame.write_bytes(frame.read_bytes()[: frame.stat().st_size // 2])
    not_image = copy_house(second, root, "train_house_00011")
    sorted((not_image / "exploration_images").glob("*.png"))[1].write_bytes(b"these bytes are no image at all")
    bomb = copy_house(first, root, "train_house_00012")
    pair = json.loads((bomb / "train_house_00012.json").read_text())[0]
    (bomb / pair["rgb_path"]).write_bytes(bomb_png())
    copy_house(second, root, "train_house_00013")
    out = base / "out"
    result = runner.invoke(app, ["export-train", str(root), "--out", str(out), "--format", "messages", "--conditions", "c", "--split", "1,0,0"])
    assert result.exit_code == 0, result.output
    return out, result.output, (out / "README.md").read_text()


def test_a_house_with_a_truncated_frame_is_named_with_the_reason(planted) -> None:
    _out, console, card = planted
    for text in (console, card):
        line = next(line for line in text.splitlines() if "train_house_00010" in line)
        assert "truncated" in line and "exploration_log.json" in line


def test_a_house_with_a_frame_that_is_no_image_is_named_with_the_reason(planted) -> None:
    _out, console, card = planted
    for text in (console, card):
        line = next(line for line in text.splitlines() if "train_house_00011" in line)
        assert "not an image" in line


def test_a_pair_with_a_bomb_sized_observer_view_is_named_with_the_reason(planted) -> None:
    out, console, card = planted
    for text in (console, card):
        line = next(line for line in text.splitlines() if "train_house_00012 pair" in line)
        assert "100000x100000" in line and "rgb_path" in line
    # the rest of that house is exported
    rows = [json.loads(line) for p in (out / "messages").glob("*.jsonl") for line in p.read_text().splitlines()]
    assert any(r["house_id"] == "train_house_00012" for r in rows)


def test_a_sound_house_is_not_listed_as_left_out(planted) -> None:
    _out, console, card = planted
    assert "train_house_00013" not in console
    left_out = card.split("## Left out", 1)[1].split("## Evaluation houses", 1)[0]
    assert "train_house_00013" not in left_out and "train_house_00010" in left_out
