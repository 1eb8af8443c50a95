"""An evaluation house is recognised by its frames too: a near copy whose pair file differs
(an extra key, a re-saved float, a reworded sentence, a camera yaw moved by 1e-9) still shares
its exploration frames and observer views with the evaluation house, and is refused."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from povagent.train.export_options import ExportError, ExportOptions
from povagent.train.training_export import export_training_set


def _extra_key(pairs: list[dict[str, Any]]) -> None:
    pairs[0]["annotator_note"] = "checked twice"


def _resaved_float(pairs: list[dict[str, Any]]) -> None:
    pairs[0]["camera"]["cam_horizon"] = float(f"{pairs[0]['camera']['cam_horizon']:.2f}") + 1e-4


def _reworded_sentence(pairs: list[dict[str, Any]]) -> None:
    direction = next(iter(pairs[0]["stage5"]))
    pairs[0]["stage5"][direction]["type_a"] = "Reworded: " + pairs[0]["stage5"][direction]["type_a"]


def _nudged_yaw(pairs: list[dict[str, Any]]) -> None:
    pairs[0]["camera"]["cam_yaw"] += 1e-9


@pytest.mark.parametrize("change", [_extra_key, _resaved_float, _reworded_sentence, _nudged_yaw], ids=lambda f: f.__name__.strip("_"))
def test_a_near_copy_of_an_evaluation_house_is_refused(
    change: Callable[[list[dict[str, Any]]], None], generated_release: Path, tmp_path: Path, copy_house
) -> None:
    house = sorted(p for p in (generated_release / "artifacts").iterdir() if p.is_dir())[0]
    evaluation = tmp_path / "eval"
    copied = copy_house(house, evaluation, "eval_house_00500")  # another name, no meta.json: no seed to match
    pair_file = copied / "eval_house_00500.json"
    pairs = json.loads(pair_file.read_text())
    change(pairs)
    pair_file.write_text(json.dumps(pairs))
    with pytest.raises(ExportError, match=f"{house.name} .*eval_house_00500"):
        export_training_set(generated_release, tmp_path / "out", ExportOptions(format="messages", conditions=("c",)), exclude=[evaluation], check_release=False)
    assert not (tmp_path / "out").exists()


def test_a_house_sharing_one_observer_view_with_an_evaluation_house_is_one(generated_release: Path, tmp_path: Path, copy_house) -> None:
    house = sorted(p for p in (generated_release / "artifacts").iterdir() if p.is_dir())[1]
    evaluation = tmp_path / "eval"
    (evaluation / "artifacts" / "eval_house_00001" / "img_from_observer").mkdir(parents=True)
    view = json.loads((house / f"{house.name}.json").read_text())[0]["rgb_path"]
    (evaluation / "artifacts" / "eval_house_00001" / "img_from_observer" / "view.png").write_bytes((house / view).read_bytes())
    (evaluation / "artifacts" / "eval_house_00001" / "eval_house_00001.json").write_text(json.dumps([{"rgb_path": "img_from_observer/view.png"}]))
    report = export_training_set(
        generated_release, tmp_path / "out", ExportOptions(format="messages", conditions=("c",)), exclude=[evaluation], drop_excluded=True, check_release=False
    )
    assert list(report.excluded) == [house.name]
    assert "shares 1 frame" in report.excluded[house.name]
