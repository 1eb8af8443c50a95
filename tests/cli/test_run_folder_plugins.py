"""A run folder is untrusted: ``rescore``, ``report``, ``export`` and ``compare`` never import the
code its ``config.yaml`` names, only what ``--plugin`` names on their command line.

The run folder is real (made by ``povagent run``), its ``config.yaml`` then names a ``.py`` that
leaves a marker file when imported; every command runs as the console script runs it
(``povagent.cli.main``, in a fresh interpreter whose sys.path starts with the current folder) from
inside its own copy of the run folder (``rescore .``), as a user who received the folder would type it.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(180)


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory, mini_root) -> Path:
    """A finished run folder made once by ``povagent run`` (in this process: only the commands
    that read it must start fresh): each test works on its own copy, so the commands it runs
    there never meet another test's edits."""
    from typer.testing import CliRunner

    from povagent.cli import app
    from povagent.cli.process_exit import fast_exit_allowed

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
    with contextlib.chdir(tmp):
        done = CliRunner().invoke(app, ["run", str(pipeline), "--quiet"])
    fast_exit_allowed()  # only the console script ends its process early: nothing stays allowed here
    assert done.exit_code == 0, done.output
    return run


def hostile_copy(tmp_path: Path, finished_run: Path) -> tuple[Path, Path, Path]:
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
    "rescore .": ["rescore", "."],
    "report .": ["report", ".", "--bootstrap", "0", "--no-gallery"],
    "export .": ["export", "."],
    "export --format long-csv": ["export", ".", "--format", "long-csv"],
    "compare . .": ["compare", ".", ".", "--bootstrap", "0"],
}

# One interpreter runs every command, as ``python -m povagent.cli`` would (``main()``, the
# current folder first on sys.path), each from inside its own copy of the run folder, its
# stdout/stderr caught at the file descriptors; a module loaded from a copy is forgotten after
# its command, so a later command that imported its own copy's plugin would leave its marker too.
CHILD = r"""
import json, os, sys
from pathlib import Path
from povagent.cli import main
plan_file = Path(sys.argv[1])
plan = json.loads(plan_file.read_text())
results = {}
for step in plan:
    folder = Path(step["cwd"])
    out, err = folder.parent / (step["name"].replace(" ", "_") + ".out"), folder.parent / (step["name"].replace(" ", "_") + ".err")
    os.chdir(folder)
    sys.argv = ["povagent", *step["args"]]
    saved = os.dup(1), os.dup(2)
    with open(out, "w") as o, open(err, "w") as e:
        os.dup2(o.fileno(), 1); os.dup2(e.fileno(), 2)
        try:
            main()
            code = 0
        except SystemExit as done:
            code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
        except BaseException:
            import traceback; traceback.print_exc(); code = 1
        sys.stdout.flush(); sys.stderr.flush()
        os.dup2(saved[0], 1); os.dup2(saved[1], 2)
    for name, module in list(sys.modules.items()):
        if str(getattr(module, "__file__", None) or "").startswith(step["root"]):
            del sys.modules[name]
    results[step["name"]] = {"returncode": code, "stdout": out.read_text(), "stderr": err.read_text(), "imported": Path(step["marker"]).exists()}
plan_file.with_suffix(".done.json").write_text(json.dumps(results))
"""


@pytest.fixture(scope="module")
def commands_run(tmp_path_factory, finished_run) -> dict:
    """name -> {returncode, stdout, stderr, imported}: every command of :data:`COMMANDS` on its own
    copy of the hostile run folder, then ``rescore`` of a copy whose config names the plugin's
    strategy, without and then with ``--plugin``; one child process for all (a fresh
    interpreter costs about a second of CPU)."""
    root = tmp_path_factory.mktemp("commands")
    plan = []
    for index, (name, args) in enumerate(COMMANDS.items()):
        run, _, marker = hostile_copy(root / f"case{index}", finished_run)
        plan.append({"name": name, "args": args, "cwd": str(run), "marker": str(marker), "root": str(root)})
    run, plugin, marker = hostile_copy(root / "strategy", finished_run)
    config = yaml.safe_load((run / "config.yaml").read_text())
    config["strategy"] = {"name": "hostile", "options": {}}
    (run / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    step = {"cwd": str(run), "marker": str(marker), "root": str(root)}
    plan.append({**step, "name": "rescore without --plugin", "args": ["rescore", "."]})
    plan.append({**step, "name": "rescore --plugin", "args": ["rescore", ".", "--plugin", str(plugin)], "plugin": str(plugin)})
    (root / "plan.json").write_text(json.dumps(plan))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run([sys.executable, "-c", CHILD, str(root / "plan.json")], cwd=root, env=env, capture_output=True, text=True, timeout=150)
    assert done.returncode == 0, done.stdout + done.stderr
    results = json.loads((root / "plan.done.json").read_text())
    results["plugin"] = str(plugin)
    return results


@pytest.mark.parametrize("name", COMMANDS)
def test_a_command_reading_a_run_folder_never_imports_the_code_its_config_names(commands_run, name):
    done = commands_run[name]
    assert done["returncode"] == 0, done["stdout"] + done["stderr"]
    assert not done["imported"], "the run folder's plugin was imported"


def test_rescore_of_a_run_made_with_a_plugin_says_which_plugin_to_pass(commands_run):
    plugin = commands_run["plugin"]
    done = commands_run["rescore without --plugin"]
    assert done["returncode"] == 2, done["stdout"] + done["stderr"]
    lines = done["stderr"].strip().splitlines()
    assert len(lines) == 1 and "strategy 'hostile'" in lines[0] and f"--plugin {plugin}" in lines[0], done["stderr"]
    assert not done["imported"]

    # named on the command line, the same file is trusted: the user chose it
    done = commands_run["rescore --plugin"]
    assert done["returncode"] == 0, done["stderr"]
    assert done["imported"]
