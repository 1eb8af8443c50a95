"""The ``images:`` section's transport options (povagent/config/models.py, ImagesSpec).

Bad combinations fail at load time with the file, the line and what to write instead; the
transport is not part of the pipeline's identity (changing it never makes a folder "another
pipeline").
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from povagent.config.models import ImagesSpec
from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError


def write(tmp_path: Path, mini_root: Path, images: dict) -> Path:
    doc = {"dataset": str(mini_root), "backend": "center", "output": str(tmp_path / "run"), "images": images}
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def test_inline_is_the_default():
    assert ImagesSpec().transport == "inline"


@pytest.mark.parametrize(
    "images",
    [
        {"transport": "file"},
        {"transport": "file", "cache_dir": "derived"},
        {"transport": "http", "bind": "127.0.0.1:8765"},
        {"transport": "http", "bind": "0.0.0.0:8765", "public_url": "http://gpu-box:8765"},
        {"transport": "http", "bind": "[::1]:0"},
    ],
)
def test_valid_transport_sections_load(tmp_path, mini_root, images):
    config = load_pipeline(write(tmp_path, mini_root, images))
    assert config.images.transport == images["transport"]


@pytest.mark.parametrize(
    "images, message",
    [
        ({"transport": "ftp"}, "'inline', 'file' or 'http'"),
        ({"transport": "http"}, "needs bind: host:port"),
        ({"transport": "http", "bind": "8765"}, "must be host:port"),
        ({"transport": "http", "bind": "0.0.0.0:8765"}, "give public_url"),
        ({"transport": "http", "bind": "127.0.0.1:1", "public_url": "gpu-box:8765"}, "http:// or https://"),
        ({"transport": "file", "bind": "127.0.0.1:8765"}, "apply to transport: http"),
        ({"cache_dir": "derived"}, "cache_dir applies to transport: file or http"),
        ({"transport": "file", "bind_address": "x"}, "unknown key 'bind_address'"),
    ],
)
def test_bad_transport_sections_name_the_file_line_and_fix(tmp_path, mini_root, images, message):
    path = write(tmp_path, mini_root, images)
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    text = str(err.value)
    assert message in text
    assert f"{path}, line" in text and "images" in text


def test_the_transport_is_not_part_of_the_pipeline_identity(tmp_path, mini_root):
    inline = load_pipeline(write(tmp_path, mini_root, {"transport": "inline"}))
    by_file = load_pipeline(write(tmp_path, mini_root, {"transport": "file"}))
    assert inline.config_hash() == by_file.config_hash()


def test_derived_images_go_under_the_output_unless_told_otherwise(tmp_path):
    assert ImagesSpec(transport="file").cache_folder(tmp_path / "run") == tmp_path / "run" / "image-cache"
    assert ImagesSpec(transport="file", cache_dir=tmp_path / "d").cache_folder(tmp_path / "run") == tmp_path / "d"
