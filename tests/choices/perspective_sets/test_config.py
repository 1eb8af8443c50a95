"""``dataset: {path: F, format: NAME, images: DIR}`` in a pipeline: what is accepted, and a
POVBench pipeline's config.yaml unchanged by the new keys."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from povagent.config.models import DatasetSpec


def test_a_format_names_the_sets_file():
    spec = DatasetSpec.model_validate({"path": "sets/ViewSpatial-Bench.json", "format": "viewspatial", "images": "sets"})
    assert spec.model_dump(mode="json") == {"path": "sets/ViewSpatial-Bench.json", "generate": None, "hub": None, "revision": None,
                                                 "download": None, "strict": False, "format": "viewspatial", "images": "sets"}  # fmt: skip


def test_a_povbench_dataset_dumps_without_format_or_images():
    assert set(DatasetSpec.model_validate({"path": "povbench"}).model_dump(mode="json")) == {"path", "generate", "hub", "revision", "download", "strict"}


def test_an_unknown_format_is_refused():
    with pytest.raises(ValidationError, match="viewspatial"):
        DatasetSpec.model_validate({"path": "x.json", "format": "vsibench"})


def test_images_without_a_format_is_refused():
    with pytest.raises(ValidationError, match=r"dataset\.images needs dataset\.format"):
        DatasetSpec.model_validate({"path": "povbench", "images": "elsewhere"})


def test_a_format_without_a_path_is_refused():
    with pytest.raises(ValidationError, match=r"needs dataset\.path"):
        DatasetSpec.model_validate({"hub": "lidingm/ViewSpatial-Bench", "format": "viewspatial"})
