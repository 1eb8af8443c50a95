"""A config names plugin code only from its own folder (or below) or from installed packages.

Each attack is a real file that writes a marker when imported; each command is the real
``python -m povagent.cli`` (which puts the working directory first on ``sys.path``) run from a
working directory that holds a plugin of its own. The command must stop with one line (exit 2)
before anything runs, and the marker must not exist.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(120)

INSTANCE = "train_house_00000/0/right/a"


def plugin_source(marker: Path) -> str:
    """A plugin whose import leaves ``marker`` behind (and registers a strategy)."""
    return (
        "from pathlib import Path\n"
        f"Path({str(marker)!r}).write_text('imported')\n"
        "from povagent import hookimpl\n"
        "from povagent_plugins.strategies.basic import BasicStrategy\n"
        "@hookimpl\n"
        "def register_strategies(register):\n"
        "    register('hostile', BasicStrategy, description='hostile')\n"
    )


def _absolute(tmp: Path) -> str:
    return str(tmp / "outside" / "evil.py")


def _climbing(tmp: Path) -> str:
    return "../outside/evil.py"


def _symlink_out(tmp: Path) -> str:
    os.symlink(tmp / "outside" / "evil.py", tmp / "configs" / "looks_local.py")
    return "looks_local.py"


def _dotted_from_cwd(tmp: Path) -> str:
    return "evil_in_cwd"


ATTACKS = {
    "absolute path": _absolute,
    "../ path": _climbing,
    "symlink leading out": _symlink_out,
    "dotted name of a .py in the working directory": _dotted_from_cwd,
}

COMMANDS = {
    "run": lambda cfg: ["run", str(cfg / "pipeline.yaml"), "--quiet"],
    "sweep --dry-run": lambda cfg: ["sweep", str(cfg / "sweep.yaml"), "--dry-run"],
    "sweep": lambda cfg: ["sweep", str(cfg / "sweep.yaml"), "--quiet"],
    "show-prompt": lambda cfg: ["show-prompt", str(cfg / "pipeline.yaml"), "--instance", INSTANCE],
}


def setup(tmp: Path, mini_root: Path, attack) -> tuple[Path, Path, Path, str]:
    """The config folder, the working directory and the marker, with the attack written in."""
    marker = tmp / "IMPORTED"
    configs, outside, work = tmp / "configs", tmp / "outside", tmp / "work"
    for d in (configs, outside, work):
        d.mkdir()
    (outside / "evil.py").write_text(plugin_source(marker))
    (work / "evil_in_cwd.py").write_text(plugin_source(marker))
    entry = attack(tmp)
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": [entry], "dataset": str(mini_root), "backend": "center", "strategy": "hostile",
        "cache": False, "output": str(tmp / "runs" / "one"),
    }))
    (configs / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "pipeline.yaml", "output": str(tmp / "runs" / "sweep"), "axes": {"backend": ["center", "random"]},
    }))
    return configs, work, marker, entry


def povagent(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return subprocess.run([sys.executable, "-m", "povagent.cli", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=100)


@pytest.mark.parametrize("command", COMMANDS.values(), ids=COMMANDS.keys())
@pytest.mark.parametrize("attack", ATTACKS.values(), ids=ATTACKS.keys())
def test_a_plugin_from_outside_the_configs_folder_is_refused_before_it_is_imported(tmp_path, mini_root, attack, command):
    configs, work, marker, entry = setup(tmp_path, mini_root, attack)
    done = povagent(command(configs), work)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and repr(entry) in lines[0], done.stderr
    assert "refused" in lines[0] and "Traceback" not in done.stderr
    assert not marker.exists(), "the plugin was imported"
    assert not (tmp_path / "runs").exists(), "something ran"


def test_a_plugin_in_the_configs_folder_or_below_still_loads(tmp_path, mini_root):
    configs = tmp_path / "configs"
    (configs / "sub").mkdir(parents=True)
    marker = tmp_path / "IMPORTED"
    (configs / "sub" / "mine.py").write_text(plugin_source(marker))
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": ["sub/mine.py"], "dataset": str(mini_root), "backend": "center", "strategy": "hostile",
        "cache": False, "output": str(tmp_path / "out"),
    }))
    done = povagent(["show-prompt", str(configs / "pipeline.yaml"), "--instance", INSTANCE, "--out", str(tmp_path / "shown")], tmp_path)
    assert done.returncode == 0, done.stderr
    assert marker.read_text() == "imported"


def test_an_installed_dotted_module_still_loads(tmp_path, mini_root):
    # povagent_plugins is installed (a package of this distribution): a dotted name finds it
    configs = tmp_path / "configs"
    configs.mkdir()
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": ["povagent_plugins.strategies.basic"], "dataset": str(mini_root), "backend": "center",
        "cache": False, "output": str(tmp_path / "out"),
    }))
    done = povagent(["show-prompt", str(configs / "pipeline.yaml"), "--instance", INSTANCE, "--out", str(tmp_path / "shown")], tmp_path)
    assert done.returncode == 0, done.stderr
