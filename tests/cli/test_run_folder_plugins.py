"""A run folder is untrusted: ``rescore``, ``report``, ``export`` and ``compare`` never import the
code its ``config.yaml`` names, only what ``--plugin`` names on their command line.

The run folder is real (made by ``povagent run``), its ``config.yaml`` then names a ``.py`` that
leaves a marker file when imported; every command runs as ``python -m povagent.cli`` from inside
the run folder (``rescore .``), as a user who received the folder would type it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(180)


def povagent(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, "-m", "povagent.cli", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=150)


@pytest.fixture
def shared_run(tmp_path, dataset_copy) -> tuple[Path, Path, Path]:
    """(run folder, the hostile plugin, its marker): a finished run whose config.yaml was then
    edited to name ``hostile.py`` (in the run folder itself, and as ``plugins:`` of its own)."""
    pipeline = tmp_path / "pipeline.yaml"
    run = tmp_path / "run"
    pipeline.write_text(yaml.safe_dump({
        "dataset": str(dataset_copy), "instances": {"limit": 4}, "backend": "center", "cache": False, "output": str(run),
    }))
    done = povagent("run", str(pipeline), "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
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
