"""litellm is imported lazily and offline-safe (povagent/engine/llm_import.py)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
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


def test_help_is_fast():
    script = Path(sys.executable).with_name("povagent")
    cmd = [str(script), "--help"] if script.exists() else [sys.executable, "-c", "from povagent.cli import main; main()", "--help"]
    started = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=CLEAN_ENV, timeout=50)
    elapsed = time.perf_counter() - started
    assert done.returncode == 0, done.stderr
    # importing litellm alone takes 3-5 s here; help must stay well under that
    assert elapsed < 2.5, f"povagent --help took {elapsed:.2f} s"


def test_import_litellm_sets_offline_defaults_first():
    code = (
        "import os\n"
        "from povagent.engine.llm_import import import_litellm\n"
        "litellm = import_litellm()\n"
        "assert os.environ['LITELLM_LOCAL_MODEL_COST_MAP'] == 'True'\n"
        "assert os.environ['LITELLM_MODE'] == 'PRODUCTION'\n"
        "assert litellm.suppress_debug_info is True\n"
        "assert import_litellm() is litellm\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr


def test_user_exported_litellm_settings_win():
    env = {**CLEAN_ENV, "LITELLM_MODE": "DEV"}
    code = "import os\nfrom povagent.engine.llm_import import import_litellm\nimport_litellm()\nprint(os.environ['LITELLM_MODE'])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=50)
    assert done.stdout.strip() == "DEV", done.stderr


def test_base64_truncation_for_logging_stays_on():
    # off, every litellm logging callback would be handed whole images (see import_litellm);
    # a user with no callbacks may still export MAX_BASE64_LENGTH_FOR_LOGGING=0 themselves
    code = (
        "import os\n"
        "from povagent.engine.llm_import import import_litellm\n"
        "import_litellm()\n"
        "from litellm.litellm_core_utils import logging_utils\n"
        "assert 'MAX_BASE64_LENGTH_FOR_LOGGING' not in os.environ\n"
        "print(logging_utils.MAX_BASE64_LENGTH_FOR_LOGGING)\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr
    assert int(done.stdout.split()[-1]) > 0
