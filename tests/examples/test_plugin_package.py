"""The example plugin package: a clean install is discovered through its entry point and used in a sweep.

The package is built and installed with pip's defaults (an isolated build, as a user's
``pip install`` does) into a throwaway target folder, never into the shared environment; a
subprocess with that folder on ``PYTHONPATH`` then sees it exactly as an installed distribution.
"""

from __future__ import annotations

import base64
import io
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from povagent.testing.loopback_server import LoopbackServer

REPO = Path(__file__).resolve().parents[2]
PACKAGE = REPO / "examples" / "plugin_package"
MINI = REPO / "tests" / "fixtures" / "povbench_mini"
KEY_ENV = "POVAGENT_PLUGIN_TEST_KEY"
YELLOW = (255, 255, 0)


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """The package built from a copy of its folder (the repo stays clean) and installed into a target dir."""
    work = tmp_path_factory.mktemp("plugin")
    source = work / "src"
    shutil.copytree(PACKAGE, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    target = work / "site"
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-input", "--target", str(target), str(source)],
        capture_output=True, text=True, timeout=240,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return target


#: What the one interpreter that sees the installed package does, each step on its own so one
#: failing does not hide the others: the entry point's source (the first plugin host the process
#: builds), bad options refused, then a sweep of ``basic`` beside ``grid``.
CHILD = """
import json, sys, traceback
from povagent.errors import PluginError
from povagent.plugins import build_plugin_host
seen = {}
try:
    seen["source"] = build_plugin_host().entry("strategy", "grid").source
except Exception:
    seen["source"] = traceback.format_exc()
try:
    build_plugin_host().create("strategy", "grid", {"spacing": 3})
    seen["bad_options"] = "no PluginError raised"
except PluginError as exc:
    seen["bad_options"] = str(exc)
try:
    from povagent.run.sweep import run_sweep
    r = run_sweep(sys.argv[1], quiet=True)
    seen["rows"] = {c.name: r.results[c.name].summary.rows.model_dump() for c in r.cells}
except Exception:
    seen["sweep_error"] = traceback.format_exc()
print(json.dumps(seen))
"""


@pytest.fixture(scope="module")
def used(installed, tmp_path_factory) -> tuple[dict, list]:
    """(what the child saw, the requests the loopback model received): one fresh interpreter
    (each costs a second or two of imports) runs every check on the installed package."""
    tmp_path = tmp_path_factory.mktemp("used")
    with LoopbackServer(reply='{"selected_image": 0, "x": 256, "y": 256}', max_lifetime_s=200) as server:
        sweep = tmp_path / "sweep.yaml"
        sweep.write_text(
            json.dumps(
                {
                    "base": {
                        "dataset": {"path": str(MINI)},
                        "instances": {"conditions": ["a"], "limit": 2},
                        "backend": {
                            "name": "litellm",
                            "options": {"model": "openai/loopback", "api_base": server.url, "api_key_env": KEY_ENV},
                        },
                        "output": str(tmp_path / "unused"),
                    },
                    "output": str(tmp_path / "sweep"),
                    "axes": {"strategy": ["basic", "grid"]},
                }
            )
        )
        full_env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(installed), os.environ.get("PYTHONPATH", "")]), KEY_ENV: "test-key"}
        proc = subprocess.run([sys.executable, "-c", CHILD, str(sweep)], capture_output=True, text=True, timeout=240, env=full_env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        requests = list(server.requests)
    return json.loads(proc.stdout.strip().splitlines()[-1]), requests


def test_the_installed_distribution_registers_the_grid_strategy(used):
    seen, _ = used
    assert "entry point grid = povagent_grid from povagent-example-strategy 0.1.0" in seen["source"]


def test_bad_options_are_rejected_naming_the_plugin(used):
    seen, _ = used
    assert "strategy 'grid'" in seen["bad_options"] and "spacing must be" in seen["bad_options"]


def _images_of(request) -> list[Image.Image]:
    out = []
    for part in request.user_parts():
        if part.get("type") == "image_url":
            out.append(Image.open(io.BytesIO(base64.b64decode(part["image_url"]["url"].split(",", 1)[1]))).convert("RGB"))
    return out


def test_a_sweep_runs_the_grid_strategy_beside_basic(used):
    seen, requests = used
    assert "rows" in seen, seen.get("sweep_error")
    rows = seen["rows"]
    assert set(rows) == {"basic", "grid"}
    assert all(r["answered"] == r["total"] == 2 for r in rows.values())
    grid_prompts = [r for r in requests if any("grid" in p.get("text", "") for p in r.user_parts())]
    basic_prompts = [r for r in requests if r not in grid_prompts]
    assert len(grid_prompts) == 2 and len(basic_prompts) == 2
    # the grid strategy's frames carry the yellow line at x = 64; the basic frames do not
    gridded = _images_of(grid_prompts[0])[0]
    plain = _images_of(basic_prompts[0])[0]
    assert [gridded.getpixel((64, y)) for y in (100, 300, 500)] == [YELLOW] * 3
    assert plain.getpixel((64, 300)) != YELLOW
