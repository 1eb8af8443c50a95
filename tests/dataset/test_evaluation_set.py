"""One loader choice for every command: a real-world set by its ``realworld.json``, any other
folder (a release, a generated set) by the release loader."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from povagent import hookimpl
from povagent.dataset.evaluation_set import format_of, open_evaluation_set
from povagent.dataset.formats import FormatRead
from povagent.dataset.loader import Dataset
from povagent.dataset.realworld_set import RealWorldDataset
from povagent.errors import DatasetError
from povagent_plugins.formats.povbench import POVBENCH

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


def test_a_folder_holding_realworld_json_opens_as_a_real_world_set():
    assert isinstance(open_evaluation_set(DEMO), RealWorldDataset)


def test_a_release_layout_folder_opens_with_the_release_loader(mini_root):
    assert isinstance(open_evaluation_set(mini_root, check_images=False), Dataset)


def test_strict_reaches_the_release_loader(mini_root):
    with pytest.raises(DatasetError, match="--strict"):
        open_evaluation_set(mini_root, strict=True)


# -- the format a folder is read in, from the registry ---------------------------------------------
def test_a_folder_is_found_as_its_registered_format(mini_root, tmp_path):
    generated = tmp_path / "generated"
    shutil.copytree(mini_root, generated)
    house = next(p for p in (generated / "artifacts").iterdir() if p.is_dir())
    (house / "_generated.json").write_text("{}")
    assert [format_of(root, None).key for root in (DEMO, mini_root, generated)] == ["realworld", "povbench", "generated"]


def test_an_unknown_format_is_one_line_naming_the_file_and_the_nearest_format(tmp_path):
    with pytest.raises(DatasetError) as err:
        open_evaluation_set(tmp_path / "set.json", format="viewspatail")
    assert str(err.value).startswith(f"{tmp_path / 'set.json'}: unknown format 'viewspatail' (did you mean 'viewspatial'?); known format names: ")


def test_a_format_a_plugin_registers_claims_its_folders_before_the_release_layout(povagent_host, mini_root, tmp_path):
    claimed = tmp_path / "claimed"
    shutil.copytree(mini_root, claimed)
    (claimed / "toy.marker").write_text("")
    seen: list[FormatRead] = []
    toy = replace(POVBENCH, key="toy", detect=lambda root: (root / "toy.marker").is_file(), detect_order=50, read=lambda r: seen.append(r) or "read")

    class Toy:
        @hookimpl
        def register_dataset_formats(self, register):
            register("toy", toy)

    povagent_host.add_plugin(Toy(), name="toy")
    try:
        assert open_evaluation_set(claimed, check_images=False, options={"width": 512}) == "read"
        assert seen == [FormatRead(claimed, check_images=False, options={"width": 512})]
        assert isinstance(open_evaluation_set(mini_root, check_images=False), Dataset)
    finally:
        povagent_host.remove_plugin("toy")


def test_opening_a_release_by_detection_imports_no_generator(mini_root):
    """Telling a generated set from a release reads the record's name, not the generator (whose
    meshes bring SciPy and Embree: half a second and 60 MiB a run never needs), nor a video
    decoder (PyAV, ~17 MiB: only a set of videos needs it)."""
    import subprocess
    import sys

    code = (
        "import sys\nfrom povagent.dataset.evaluation_set import open_evaluation_set\n"
        f"open_evaluation_set({str(mini_root)!r})\n"
        "print(sorted(m for m in ('povagent.generate.house_pipeline', 'scipy', 'embreex', 'av') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "[]"
