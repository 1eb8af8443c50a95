"""What an export is asked for is settled before anything is written: conditions named twice are
one condition (the card agrees with the shards), and a missing extra is said before
``export.json`` exists, so the next try with another format is not refused."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from povagent.errors import PovagentError
from povagent.train.export_options import ExportOptions
from povagent.train.training_export import export_training_set


def test_conditions_named_twice_are_exported_once_and_the_card_agrees(generated_release: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    report = export_training_set(generated_release, out, ExportOptions(format="messages", conditions=("a", "c", "c", "a"), split="1,0,0"), check_release=False)
    rows = [json.loads(line) for p in sorted((out / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    ids = [r["id"] for r in rows]
    assert len(ids) == len(set(ids)) == report.examples
    by_condition = {c: sum(1 for r in rows if r["condition"] == c) for c in ("a", "c")}
    card = (out / "README.md").read_text()
    for condition, n in by_condition.items():
        assert f"| {condition} | {n:,} |" in card
    assert json.loads((out / "export.json").read_text())["options"]["conditions"] == ["a", "c"]


@pytest.mark.parametrize("missing, cluster", [("pyarrow", None), ("distributed", "local:1")])
def test_a_missing_extra_is_said_before_anything_is_written(generated_release: Path, tmp_path: Path, monkeypatch, missing: str, cluster) -> None:
    out = tmp_path / "out"
    with monkeypatch.context() as m:
        for name in [n for n in sys.modules if n == missing or n.startswith(missing + ".")] + [missing]:
            m.setitem(sys.modules, name, None)  # import raises ImportError, as without the extra
        with pytest.raises(PovagentError, match=r"pip install 'povagent\[(train|cluster)\]'"):
            export_training_set(generated_release, out, ExportOptions(format="hf", conditions=("c",)), check_release=False, cluster=cluster)
    assert not out.exists()
    # the next try, with another format, is not refused for the first one's options
    report = export_training_set(generated_release, out, ExportOptions(format="messages", conditions=("c",)), check_release=False)
    assert report.examples > 0
