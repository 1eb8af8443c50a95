"""The compiled loops: built wherever the install found a C compiler, and switched off on request."""

from __future__ import annotations

import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from povagent.generate import compiled_loops
from povagent.generate.compiled_loops import LOOPS, PURE_NUMPY, built_loops, compiled_loop

ROOT = Path(__file__).resolve().parents[2]


def test_every_loop_setup_py_builds_is_one_the_loader_knows():
    text = (ROOT / "setup.py").read_text()
    listed = sorted(line.split('"')[1].rsplit(".", 1)[1] for line in text.splitlines() if line.strip().startswith('("povagent.generate._'))
    assert listed == sorted(LOOPS)
    for name in LOOPS:
        assert (ROOT / "povagent" / "generate" / f"{name.lstrip('_')}.c").is_file()


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler on this machine: the install takes numpy's path")
def test_an_install_with_a_c_compiler_and_pythons_headers_builds_every_loop():
    assert Path(sysconfig.get_paths()["include"], "Python.h").is_file(), "the compiler is there but not Python's headers"
    assert built_loops() == dict.fromkeys(LOOPS, True)


def test_the_environment_variable_takes_numpys_path(monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv(PURE_NUMPY, "1")
    assert all(compiled_loop(name) is None for name in LOOPS)
    monkeypatch.setenv(PURE_NUMPY, "0")
    assert [compiled_loop(name) is not None for name in LOOPS] == list(built_loops().values())


def test_a_name_that_is_not_a_loop_is_refused():
    with pytest.raises(ValueError, match="not one of the compiled loops"):
        compiled_loops.compiled_loop("os")


def test_a_fresh_process_with_the_variable_set_renders_without_the_loops():
    code = "from povagent.generate import frame_png; print(frame_png._COMPILED is None)"
    out = subprocess.run([sys.executable, "-c", code], env={**_env(), PURE_NUMPY: "1"}, capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == "True"


def _env() -> dict[str, str]:
    import os

    return {k: v for k, v in os.environ.items() if k != PURE_NUMPY}
