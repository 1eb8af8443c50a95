"""A config names plugin code only from its own folder or below or from installed packages.

Each attack is a real file that writes a marker when imported; each command is the real
console entry (:func:`povagent.cli.main`, with the working directory first on ``sys.path`` as
``python -m povagent.cli`` puts it) run from a working directory that holds a plugin of its own.
The command must stop with one line (exit 2) before anything runs, and the marker must not exist.

Every command of every case runs in ONE fresh interpreter (the module's ``commands`` fixture):
each case's files are laid out in a folder of their own first, then a child runs the commands one
after another, each as the console script would (``main()`` with its ``sys.argv``, its stdout,
stderr and exit code recorded), and reports them all; each test asserts its own case. A
refusal imports nothing, so the cases cannot leak into each other; the two cases that load a
plugin run last.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.timeout(120)

INSTANCE = "train_house_00000/0/right/a"

#: Every plugin here leaves the file named by this variable behind when imported; the child
#: sets it to the marker of the case whose command it runs.
MARKER_VARIABLE = "POVAGENT_TEST_PLUGIN_MARKER"

PLUGIN_SOURCE = (
    "import os\n"
    "from pathlib import Path\n"
    f"Path(os.environ[{MARKER_VARIABLE!r}]).write_text('imported')\n"
    "from povagent import hookimpl\n"
    "from povagent_plugins.strategies.basic import BasicStrategy\n"
    "@hookimpl\n"
    "def register_strategies(register):\n"
    "    register('hostile', BasicStrategy, description='hostile')\n"
)

# The child: each job is one console-script call (main() as `python -m povagent.cli` runs it,
# the working directory first on sys.path); its exit code, stdout and stderr are recorded,
# and the report is rewritten after each job. A run or sweep that (wrongly) ran to its end
# would end the process at once (povagent.cli.process_exit): here it ends the ordinary way, so
# the later jobs still run and each case reports its own outcome.
CHILD = """
import contextlib, io, json, os, sys
sys.path[0] = os.getcwd()  # what `python -m` puts first (`-c` puts '')
from povagent.cli import main, process_exit
from povagent.cli.process_exit import exit_code_of
process_exit.allow_fast_exit = lambda: None
jobs_file, report_file = sys.argv[1:3]
jobs, report = json.loads(open(jobs_file).read()), {}
for job in jobs:
    os.environ["POVAGENT_TEST_PLUGIN_MARKER"] = job["marker"]
    sys.argv = ["povagent", *job["args"]]
    out, err, code = io.StringIO(), io.StringIO(), 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main()
        except SystemExit as done:
            code = exit_code_of(done.code)
    report[job["id"]] = {"code": code, "stdout": out.getvalue(), "stderr": err.getvalue()}
    with open(report_file, "w") as f:
        json.dump(report, f)
"""


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


def setup(tmp: Path, mini_root: Path, attack) -> tuple[Path, str]:
    """The config folder of one attack in ``tmp``, with the attack written in, and its entry."""
    configs, outside = tmp / "configs", tmp / "outside"
    for d in (configs, outside):
        d.mkdir(parents=True)
    (outside / "evil.py").write_text(PLUGIN_SOURCE)
    entry = attack(tmp)
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": [entry], "dataset": str(mini_root), "backend": "center", "strategy": "hostile",
        "cache": False, "output": str(tmp / "runs" / "one"),
    }))
    (configs / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "pipeline.yaml", "output": str(tmp / "runs" / "sweep"), "axes": {"backend": ["center", "random"]},
    }))
    return configs, entry


def loads_from_below(tmp: Path, mini_root: Path) -> list[str]:
    """A config whose plugin lies in a folder below its own: the command that must load it."""
    configs = tmp / "configs"
    (configs / "sub").mkdir(parents=True)
    (configs / "sub" / "mine.py").write_text(PLUGIN_SOURCE)
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": ["sub/mine.py"], "dataset": str(mini_root), "backend": "center", "strategy": "hostile",
        "cache": False, "output": str(tmp / "out"),
    }))
    return ["show-prompt", str(configs / "pipeline.yaml"), "--instance", INSTANCE, "--out", str(tmp / "shown")]


def loads_installed(tmp: Path, mini_root: Path) -> list[str]:
    """A config naming an installed module by its dotted name (povagent_plugins is a package of
    this distribution): the command that must load it."""
    configs = tmp / "configs"
    configs.mkdir(parents=True)
    (configs / "pipeline.yaml").write_text(yaml.safe_dump({
        "plugins": ["povagent_plugins.strategies.basic"], "dataset": str(mini_root), "backend": "center",
        "cache": False, "output": str(tmp / "out"),
    }))
    return ["show-prompt", str(configs / "pipeline.yaml"), "--instance", INSTANCE, "--out", str(tmp / "shown")]


@pytest.fixture(scope="module")
def commands(tmp_path_factory, mini_root) -> dict[str, dict]:
    """Every case's folder and entry, and what its command did (run in one child, see above)."""
    base = tmp_path_factory.mktemp("plugin_rule")
    work = base / "work"  # the working directory, holding a plugin of its own
    work.mkdir()
    (work / "evil_in_cwd.py").write_text(PLUGIN_SOURCE)
    cases: dict[str, dict] = {}
    for a, attack in ATTACKS.items():
        for c, command in COMMANDS.items():
            tmp = base / f"case{len(cases)}"
            configs, entry = setup(tmp, mini_root, attack)
            cases[f"{a}-{c}"] = {"tmp": tmp, "entry": entry, "args": command(configs)}
    for name, make in (("below", loads_from_below), ("installed", loads_installed)):
        tmp = base / name
        cases[name] = {"tmp": tmp, "args": make(tmp, mini_root)}
    jobs = [{"id": k, "args": v["args"], "marker": str(v["tmp"] / "IMPORTED")} for k, v in cases.items()]
    (base / "jobs.json").write_text(json.dumps(jobs))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    child = subprocess.run([sys.executable, "-c", CHILD, str(base / "jobs.json"), str(base / "report.json")],
                           cwd=work, env=env, capture_output=True, text=True, timeout=100)  # fmt: skip
    report = json.loads((base / "report.json").read_text()) if (base / "report.json").exists() else {}
    for key, case in cases.items():
        case["done"] = report.get(key, {"code": None, "stdout": "", "stderr": f"no report: the child ended {child.stderr[-2000:]}"})
    return cases


@pytest.mark.parametrize("command", COMMANDS.keys())
@pytest.mark.parametrize("attack", ATTACKS.keys())
def test_a_plugin_from_outside_the_configs_folder_is_refused_before_it_is_imported(commands, attack, command):
    case = commands[f"{attack}-{command}"]
    done, entry, tmp = case["done"], case["entry"], case["tmp"]
    assert done["code"] == 2, done["stdout"] + done["stderr"]
    lines = done["stderr"].strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and repr(entry) in lines[0], done["stderr"]
    assert "refused" in lines[0] and "Traceback" not in done["stderr"]
    assert not (tmp / "IMPORTED").exists(), "the plugin was imported"
    assert not (tmp / "runs").exists(), "something ran"


def test_a_plugin_in_the_configs_folder_or_below_still_loads(commands):
    case = commands["below"]
    assert case["done"]["code"] == 0, case["done"]["stderr"]
    assert (case["tmp"] / "IMPORTED").read_text() == "imported"


def test_an_installed_dotted_module_still_loads(commands):
    case = commands["installed"]
    assert case["done"]["code"] == 0, case["done"]["stderr"]
