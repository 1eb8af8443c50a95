"""The point reader: a model's own extract_image_points, else the text parser."""

from __future__ import annotations

import json

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline
from povagent_plugins.backends.point_reader import point_answer

pytestmark = pytest.mark.timeout(120)


def test_the_first_point_is_answered_as_the_benchmarks_json():
    assert json.loads(point_answer([[0, 2, 10.5, 20.0], [1, 0, 1.0, 1.0]], n_images=3)) == {"selected_image": 2, "x": 10.5, "y": 20.0}
    assert json.loads(point_answer([[0, 0, 10.5, 20.0]], n_images=1)) == {"x": 10.5, "y": 20.0}


@pytest.mark.parametrize("points", [None, [], [[0, 1]], [["a", 1, 2, 3]], [[0, 0, float("nan"), 3]]])
def test_no_well_formed_point_is_no_answer(points):
    assert point_answer(points, n_images=2) is None


def test_a_model_exposing_extract_image_points_is_read_by_the_point_reader(tmp_path, mini_root, tiny_pointing):
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "transformers", "options": {"model": str(tiny_pointing)}},
        "strategy": {"name": "basic", "options": {"max_tokens": 4, "prompts": "molmopoint"}},
        "parser": "molmo",
        "instances": {"conditions": ["a"], "houses": ["train_house_00000"], "directions": ["left"]},
        "timeout": 60,
        "output": str(tmp_path / "run"),
    }
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(tmp_path / "p.yaml"), trust_remote_code=True)
    (row,) = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    answer = json.loads(row["exchanges"][0]["raw"])
    n_frames = len(row["exchanges"][0]["image_hashes"])
    # the test checkpoint points into the last image, half-way down (its images' own pixels)
    assert answer["selected_image"] == n_frames - 1 and row["status"] == "answered"
    assert row["prediction"]["selected_image"] == n_frames - 1
