"""``dataset.options``: a format's own reader options, each key one the format names
(``DatasetFormat.option_names``); anything else is refused at its line, and a POVBench pipeline's
``config.yaml`` is unchanged by the key."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from povagent.config.models import DatasetSpec
from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError


def _pipeline(tmp_path, dataset: str):
    path = tmp_path / "pipeline.yaml"
    path.write_text(f"dataset:\n{dataset}backend: center\noutput: runs/x\n")
    return path


def test_an_option_the_format_does_not_take_is_refused_at_its_line(tmp_path):
    path = _pipeline(tmp_path, "  path: set.json\n  format: viewspatial\n  options:\n    frames: 8\n")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 5: dataset.options.frames: format 'viewspatial' has no option 'frames'; it takes none" in str(err.value)


def test_an_option_the_format_takes_reaches_the_config(tmp_path):
    path = _pipeline(tmp_path, "  path: release\n  format: povbench\n  options: {width: 640, height: 480}\n")
    assert load_pipeline(path).dataset.options == {"width": 640, "height": 480}


def test_options_without_a_format_are_refused():
    with pytest.raises(ValidationError, match=r"dataset\.options needs dataset\.format"):
        DatasetSpec.model_validate({"path": "povbench", "options": {"width": 640}})


def test_a_dataset_without_options_dumps_without_the_key():
    assert "options" not in DatasetSpec.model_validate({"path": "set.json", "format": "mindcube"}).model_dump(mode="json")
