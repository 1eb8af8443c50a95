"""The three perspective-taking sets' hand-written fixture files, copied beside tiny PNGs.

``tests/fixtures/perspective_sets`` holds a few records of each set in its published format;
the images they name are made here (a few pixels each: what a reader checks is that they are
sound images inside the set's folder, not what they show).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml
from PIL import Image

FIXTURES = Path(__file__).parents[2] / "fixtures" / "perspective_sets"
SET_FILES = {"viewspatial": "viewspatial.json", "mindcube": "mindcube.jsonl", "3dsrbench": "3dsrbench.tsv"}
OFFLINE_PLUGIN = Path(__file__).parents[2] / "run" / "offline_plugin.py"
IMAGES = ("scene_1", "scene_2a", "scene_2b", "scene_3", "room_1a", "room_1b", "room_2", "room_3a", "room_3b", "room_3c", "street_1")


def _write_set_folder(folder: Path) -> Path:
    (folder / "images").mkdir(parents=True)
    for name in SET_FILES.values():
        shutil.copy(FIXTURES / name, folder / name)
    for shade, name in enumerate(IMAGES):
        Image.new("RGB", (8, 6), (20 * shade, 40, 60)).save(folder / "images" / f"{name}.png")
    return folder


@pytest.fixture
def set_folder(tmp_path) -> Path:
    """A folder holding the three fixture files and every image they name."""
    return _write_set_folder(tmp_path / "sets")


@pytest.fixture
def set_file(set_folder):
    """``set_file(format) -> Path``: that set's fixture file."""
    return lambda format: set_folder / SET_FILES[format]


def _pipeline_maker(folder: Path, set_folder: Path, plugin: Path):
    def make(format: str, backend: str = "oracle", reply: str | None = None, scorers: tuple[str, ...] = ("choice",)) -> Path:
        data = {
            "plugins": [str(plugin)],
            "dataset": {"path": str(set_folder / SET_FILES[format]), "format": format},
            "backend": {"name": backend, **({"options": {"reply": reply}} if reply is not None else {})},
            "strategy": "choice",
            "scorers": list(scorers),
            "runs": 1,
            "concurrency": 2,
            "timeout": 5,
            "output": str(folder / f"run-{format}-{backend}-{reply}"),
        }
        path = folder / f"{format}-{backend}-{reply}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return make


@pytest.fixture
def choice_pipeline(tmp_path, set_folder, offline_plugin_file):
    """``choice_pipeline(format, backend, reply=None, scorers=...) -> Path``: a choice pipeline
    YAML over that set (``reply``: the ``test-center`` backend answering it every time)."""
    return _pipeline_maker(tmp_path, set_folder, offline_plugin_file)


@pytest.fixture(scope="module")
def module_choice_pipeline(tmp_path_factory):
    """:func:`choice_pipeline` over a set folder a module's tests share (for runs made once a
    module and only read by its tests)."""
    folder = tmp_path_factory.mktemp("choice-sets")
    plugin = folder / "offline_plugin.py"
    shutil.copy(OFFLINE_PLUGIN, plugin)  # the offline_plugin_file fixture's, for a module
    return _pipeline_maker(folder, _write_set_folder(folder / "sets"), plugin.resolve())
