"""A run folder is untrusted: ``rescore``, ``report``, ``export`` and ``compare`` never import the
code its ``config.yaml`` names, only what ``--plugin`` names on their command line.

The run folder is real (made by ``povagent run``), its ``config.yaml`` then names a ``.py`` that
leaves a marker file when imported; every command runs as ``python -m povagent.cli`` from inside
the run folder (``rescore .``), as a user who received the folder would type it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(180)


def povagent(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, "-m", "povagent.cli", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=150)


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory, mini_root) -> Path:
    """A finished run folder made once by ``povagent run`` (a child process, seconds of CPU): each
    test works on its own copy, so the commands it runs there never meet another test's edits."""
    tmp = tmp_path_factory.mktemp("finished-run")
    dataset = tmp / "ds"
    (dataset / "artifacts").mkdir(parents=True)
    shutil.copy(mini_root / "meta.json", dataset / "meta.json")
    for house in ("train_house_00000", "train_house_00001"):  # its good houses (as the dataset_copy fixture)
        shutil.copytree(mini_root / "artifacts" / house, dataset / "artifacts" / house)
    pipeline = tmp / "pipeline.yaml"
    run = tmp / "run"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(dataset), "instances": {"limit": 4}, "backend": "center", "cache": False, "output": str(run),
    }))
    done = povagent("run", str(pipeline), "--quiet", cwd=tmp)
    assert done.returncode == 0, done.stderr
    return run


@pytest.fixture
def shared_run(tmp_path, finished_run) -> tuple[Path, Path, Path]:
    """(run folder, the hostile plugin, its marker): a copy of the finished run whose config.yaml
    was then edited to name ``hostile.py`` (in the run folder itself, and as ``plugins:`` of its own)."""
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    marker = tmp_path / "IMPORTED"
    plugin = run / "hostile.py"
    plugin.write_text(
        "from pathlib import Path\n"
        f"Path({str(marker)!r}).write_text('imported')\n"
        "from povagent import hookimpl\n"
        "from povagent_plugins.strategies.basic import BasicStrategy\n"
        "@hookimpl\n"
        "def register_strategies(register):\n"
        "    register('hostile', BasicStrategy, description='hostile')\n"
    )
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["plugins"] = [str(plugin), "hostile"]  # by path, and by a dotted name the cwd would answer
    (run / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    return run, plugin, marker


COMMANDS = {
    "rescore .": lambda run: ["rescore", "."],
    "report .": lambda run: ["report", ".", "--bootstrap", "0", "--no-gallery"],
    "export .": lambda run: ["export", "."],
    "export --format long-csv": lambda run: ["export", ".", "--format", "long-csv"],
    "compare . .": lambda run: ["compare", ".", ".", "--bootstrap", "0"],
}


@pytest.mark.parametrize("command", COMMANDS.values(), ids=COMMANDS.keys())
def test_a_command_reading_a_run_folder_never_imports_the_code_its_config_names(shared_run, command):
    run, _, marker = shared_run
    done = povagent(*command(run), cwd=run)
    assert done.returncode == 0, done.stdout + done.stderr
    assert not marker.exists(), "the run folder's plugin was imported"


def test_rescore_of_a_run_made_with_a_plugin_says_which_plugin_to_pass(shared_run):
    run, plugin, marker = shared_run
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["strategy"] = {"name": "hostile", "options": {}}
    (run / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))

    done = povagent("rescore", ".", cwd=run)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "strategy 'hostile'" in lines[0] and f"--plugin {plugin}" in lines[0], done.stderr
    assert not marker.exists()

    # named on the command line, the same file is trusted: the user chose it
    done = povagent("rescore", ".", "--plugin", str(plugin), cwd=run)
    assert done.returncode == 0, done.stderr
    assert marker.exists()
