"""docs/how-to/realworld.md documents the realworld.json format: its example is a set the
loader reads, and every field of the format is in its table."""

from __future__ import annotations

import json
import re
from pathlib import Path

from PIL import Image

from povagent.dataset.realworld_set import Command, Mark, RealWorldHouse, RealWorldSet, Scenario, load_realworld, read_realworld

PAGE = Path(__file__).resolve().parents[2] / "docs" / "how-to" / "realworld.md"


def example() -> dict:
    (body,) = re.findall(r"```json\n(.*?)```", PAGE.read_text(), re.S)
    return json.loads(body)


def test_the_pages_example_is_a_set_the_loader_reads_and_runs(tmp_path):
    doc = example()
    (tmp_path / "realworld.json").write_text(json.dumps(doc))
    for house in doc["houses"]:
        for frame in house["frames"]:
            (tmp_path / frame).parent.mkdir(parents=True, exist_ok=True)
            Image.new("RGB", (1280, 720), (90, 90, 90)).save(tmp_path / frame)
    rw = read_realworld(tmp_path)
    assert [c.condition.value for c in rw.houses[0].scenarios[0].commands] == ["a", "b", "c"]
    assert len(load_realworld(tmp_path, cache_dir=tmp_path / "cache").instances()) == 3


def test_every_field_of_the_format_is_in_the_pages_table():
    table = {m.group(1) for m in re.finditer(r"^\| `(\w+)` \|", PAGE.read_text(), re.M)}
    fields = set().union(*(model.model_fields for model in (RealWorldSet, RealWorldHouse, Scenario, Command, Mark)))
    assert fields == table
