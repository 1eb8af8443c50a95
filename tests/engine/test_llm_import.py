"""litellm is imported lazily and offline-safe (povagent/engine/llm_import.py)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(60)

CLEAN_ENV = {k: v for k, v in os.environ.items() if not k.startswith("LITELLM_")}


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=CLEAN_ENV, timeout=50)


def test_importing_the_cli_does_not_import_litellm():
    done = _python("import povagent.cli, sys; assert 'litellm' not in sys.modules, 'litellm imported'")
    assert done.returncode == 0, done.stderr


def test_help_does_not_import_litellm():
    code = (
        "import sys\n"
        "from povagent.cli import main\n"
        "sys.argv = ['povagent', '--help']\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "assert 'litellm' not in sys.modules, 'litellm imported'\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr
    assert "Usage" in done.stdout


def test_loading_every_builtin_plugin_does_not_import_litellm():
    code = (
        "import sys\n"
        "from povagent.plugins import build_plugin_host\n"
        "host = build_plugin_host(entry_points=False)\n"
        "assert 'litellm' in host.names('backend')\n"
        "assert 'litellm' not in sys.modules, 'litellm imported'\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr


def test_help_loads_no_heavy_library():
    """``povagent --help`` stays fast by what it imports, not by a wall-clock bound (the machine
    is shared): litellm alone takes seconds, scipy and the renderer's libraries a second more."""
    code = (
        "import sys\n"
        "from povagent.cli import main\n"
        "sys.argv = ['povagent', '--help']\n"
        "try:\n"
        "    main()\n"
        "except SystemExit as exit:\n"
        "    assert exit.code in (0, None), exit.code\n"
        "heavy = sorted(m for m in ('litellm', 'openai', 'scipy', 'trimesh', 'embreex', 'matplotlib', 'huggingface_hub') if m in sys.modules)\n"
        "assert not heavy, heavy\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr
