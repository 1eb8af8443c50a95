"""``dataset: {path: F, format: NAME, images: DIR}`` in a pipeline: what is accepted, and a
POVBench pipeline's config.yaml unchanged by the new keys."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from povagent.config.models import DatasetSpec
from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError


def test_a_format_names_the_sets_file():
    spec = DatasetSpec.model_validate({"path": "sets/ViewSpatial-Bench.json", "format": "viewspatial", "images": "sets"})
    assert spec.model_dump(mode="json") == {"path": "sets/ViewSpatial-Bench.json", "generate": None, "hub": None, "revision": None,
                                                 "download": None, "strict": False, "format": "viewspatial", "images": "sets"}  # fmt: skip


def test_a_povbench_dataset_dumps_without_format_or_images():
    assert set(DatasetSpec.model_validate({"path": "povbench"}).model_dump(mode="json")) == {"path", "generate", "hub", "revision", "download", "strict"}


def test_an_unknown_format_is_refused_in_one_line_naming_the_file_and_the_field(tmp_path):
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text("dataset:\n  path: x.json\n  format: viewspatail\nmodel: gpt-5.4\noutput: runs/x\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(pipeline)
    (line,) = [ln for ln in str(err.value).splitlines() if "format" in ln]
    assert line.startswith(f"{pipeline}, line 3:") and "dataset.format: unknown format 'viewspatail' (did you mean 'viewspatial'?)" in line
    assert "3dsrbench, generated, mindcube, povbench, realworld, viewspatial" in line


def test_images_without_a_format_is_refused():
    with pytest.raises(ValidationError, match=r"dataset\.images needs dataset\.format"):
        DatasetSpec.model_validate({"path": "povbench", "images": "elsewhere"})


def test_a_format_without_a_path_is_refused():
    with pytest.raises(ValidationError, match=r"needs dataset\.path"):
        DatasetSpec.model_validate({"hub": "lidingm/ViewSpatial-Bench", "format": "viewspatial"})
