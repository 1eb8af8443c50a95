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


def run_python(code: str, site: Path, **env: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter that sees the installed package."""
    full_env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]), **env}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=240, env=full_env)


def test_the_installed_distribution_registers_the_grid_strategy(installed):
    proc = run_python(
        "from povagent.plugins import build_plugin_host\n"
        "e = build_plugin_host().entry('strategy', 'grid')\n"
        "print(e.source)",
        installed,
    )
    assert proc.returncode == 0, proc.stderr
    assert "entry point grid = povagent_grid from povagent-example-strategy 0.1.0" in proc.stdout


def test_bad_options_are_rejected_naming_the_plugin(installed):
    proc = run_python(
        "from povagent.plugins import build_plugin_host\n"
        "from povagent.errors import PluginError\n"
        "try:\n"
        "    build_plugin_host().create('strategy', 'grid', {'spacing': 3})\n"
        "except PluginError as exc:\n"
        "    print(exc)",
        installed,
    )
    assert "strategy 'grid'" in proc.stdout and "spacing must be" in proc.stdout


def _images_of(request) -> list[Image.Image]:
    out = []
    for part in request.user_parts():
        if part.get("type") == "image_url":
            out.append(Image.open(io.BytesIO(base64.b64decode(part["image_url"]["url"].split(",", 1)[1]))).convert("RGB"))
    return out


def test_a_sweep_runs_the_grid_strategy_beside_basic(installed, tmp_path):
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
        proc = run_python(
            "import json, sys\n"
            "from povagent.run.sweep import run_sweep\n"
            f"r = run_sweep({str(sweep)!r}, quiet=True)\n"
            "print(json.dumps({c.name: r.results[c.name].summary.rows.model_dump() for c in r.cells}))",
            installed,
            **{KEY_ENV: "test-key"},
        )
        assert proc.returncode == 0, proc.stderr[-3000:]
        rows = json.loads(proc.stdout.strip().splitlines()[-1])
        requests = list(server.requests)

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
