"""The console-script checks of several command test files, run in one fresh process a test run.

``parse`` reading its stdin (test_parse_command.py), ``show-prompt`` of an unknown instance
(test_show_prompt_command.py) and ``score`` of a malformed predictions file
(test_dataset_commands.py) each need what only a real process shows: the console script's own
exit code, its error line, the real stdin. One child runs the console script's ``main`` once per
command line, each with its own argv, working folder and stdout and stderr files (file
descriptors 1 and 2 pointed at them), ``parse`` first, reading the child's stdin, a pipe as a
user's would be: each command is still the real command in a process of povagent's own, for one
interpreter start instead of three (about a second of CPU each). An exception escaping ``main``
is printed as the interpreter would print it (a traceback, exit status 1).

Under pytest-xdist each worker's basetemp is a folder of one shared root: the commands' folder
goes there, so the workers run the child once between them (the first under the lock, the
others waiting for it, then reading its files), as tests/shared_sets.py does for a generated set.
"""

from __future__ import annotations

import fcntl
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml
from console_child import IMPORT

#: What ``parse`` reads on its stdin: a Molmo point (percent of the image's width and height).
PARSE_INPUT = '<point x="50" y="25" alt="cup">cup</point>'

EACH_COMMAND = IMPORT + textwrap.dedent("""
    import json, os
    from povagent.cli import main

    cases, folder = json.loads(sys.argv[1]), sys.argv[2]
    codes = []
    for n, (args, cwd) in enumerate(cases):
        os.chdir(cwd)
        codes.append(run_as_console(main, ["povagent", *args], f"{folder}/{n}.out", f"{folder}/{n}.err"))
    with open(f"{folder}/codes.json", "w") as f:
        json.dump(codes, f)
""")


def _cases(folder: Path, mini_root: Path) -> dict[str, tuple[list[str], Path]]:
    """name -> (the command line after ``povagent``, its working folder), ``parse`` first."""
    show = folder / "show-prompt"
    show.mkdir(parents=True, exist_ok=True)
    (show / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)}, "backend": {"name": "center"}, "strategy": {"name": "basic"},
        "output": str(show / "run"),
    }))  # fmt: skip
    score = folder / "score"
    score.mkdir(exist_ok=True)
    (score / "bad.json").write_text('[{"house_id": "train_house_00000", "pair_id": 0, "direction": "left", ')
    return {
        "parse": (["parse", "--parser", "molmo", "--condition", "c"], folder),
        "show-prompt": (["show-prompt", str(show / "pipeline.yaml"), "--instance", "train_house_00000/0/rigth/a"], show),
        "score": (["score", "--predictions", str(score / "bad.json"), "--dataset", str(mini_root)], score),
    }


def console_script_once(tmp_path_factory: pytest.TempPathFactory, mini_root: Path) -> dict[str, subprocess.CompletedProcess[str]]:
    """name -> what the console script returned and printed for that command line (see the
    module's docstring), run once a test run."""
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "console-script-once"
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder.parent / "console-script-once.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        cases = _cases(folder / "in", mini_root) if not (folder / "codes.json").exists() else None
        if cases is not None:
            plan = [(args, str(cwd)) for args, cwd in cases.values()]
            (folder / "plan.json").write_text(json.dumps({"names": list(cases), "plan": plan}))
            child = subprocess.run([sys.executable, "-c", EACH_COMMAND, json.dumps(plan), str(folder)], input=PARSE_INPUT,
                                   capture_output=True, text=True, timeout=240)  # fmt: skip
            assert child.returncode == 0, child.stderr[-3000:]
    written = json.loads((folder / "plan.json").read_text())
    codes = json.loads((folder / "codes.json").read_text())
    return {
        name: subprocess.CompletedProcess(["povagent", *args], code, (folder / f"{n}.out").read_text(), (folder / f"{n}.err").read_text())
        for n, (name, (args, _), code) in enumerate(zip(written["names"], written["plan"], codes))
    }
