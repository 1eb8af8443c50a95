"""litellm is imported lazily and offline-safe (povagent/engine/llm_import.py)."""

from __future__ import annotations

import os
import subprocess
import sys

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


def test_importing_while_the_background_import_runs_waits_for_it():
    # preload, then import at once from the main thread and three others (litellm's own
    # modules included): each waits for the background import, none meets a half-made module
    code = (
        "import sys, threading\n"
        "from povagent.engine.llm_import import import_litellm, preload_litellm, warm_up_litellm\n"
        "preload_litellm('openai/loopback')\n"
        "assert [t for t in threading.enumerate() if t.name == 'povagent-preload-litellm']\n"
        "got, errors = [], []\n"
        "def use():\n"
        "    try:\n"
        "        got.append(import_litellm())\n"
        "        import openai\n"
        "        from litellm import acompletion\n"
        "        warm_up_litellm('openai/loopback')\n"
        "    except BaseException as exc:\n"
        "        errors.append(repr(exc))\n"
        "threads = [threading.Thread(target=use) for _ in range(3)]\n"
        "for t in threads: t.start()\n"
        "use()\n"
        "for t in threads: t.join(60)\n"
        "assert not errors, errors\n"
        "assert len(got) == 4 and all(m is sys.modules['litellm'] for m in got), got\n"
        "assert got[0].suppress_debug_info is True and got[0].telemetry is False\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr[-3000:]


def test_litellm_loads_with_the_collector_paused_and_its_objects_frozen():
    """The import and warm-up create ~1M long-lived objects; collections walking them while they
    load cost a quarter of the import's CPU. After the load the collector is back on (a
    collection still frees cycles made later) and litellm's objects are out of its sight."""
    code = (
        "import gc\n"
        "from povagent.engine.llm_import import freeze_after_loading, import_litellm, warm_up_litellm\n"
        "freeze_after_loading()  # as the console script does\n"
        "started = gc.get_stats()[2]['collections']\n"
        "import_litellm()\n"
        "warm_up_litellm('openai/some-model')\n"
        "assert gc.isenabled()\n"
        "assert gc.get_stats()[2]['collections'] == started, 'a full collection ran during the load'\n"
        "assert gc.get_freeze_count() > 200_000, gc.get_freeze_count()\n"
        "class Cycle: pass\n"
        "c = Cycle(); c.me = c; del c\n"
        "assert gc.collect() >= 1  # cycles made after the load are still collected\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr


def test_a_program_embedding_povagent_gets_the_pause_but_no_freeze():
    """A robot app's objects of the moment must not be frozen with litellm's: a cycle among
    them that became garbage later would never be collected."""
    code = (
        "import gc\n"
        "from povagent.engine.llm_import import import_litellm\n"
        "started = gc.get_stats()[2]['collections']\n"
        "import_litellm()\n"
        "assert gc.isenabled() and gc.get_freeze_count() == 0, gc.get_freeze_count()\n"
        "assert gc.get_stats()[2]['collections'] == started, 'a full collection ran during the load'\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr


def test_the_console_script_freezes_what_litellm_loads():
    code = (
        "import gc, sys\n"
        "from povagent import cli\n"
        "from povagent.engine import llm_import\n"
        "sys.argv = ['povagent', '--help']\n"
        "try:\n    cli.main()\nexcept SystemExit:\n    pass\n"
        "assert llm_import._freeze_loaded\n"
    )
    done = _python(code)
    assert done.returncode == 0, done.stderr


def test_a_caller_who_turned_the_collector_off_keeps_it_off():
    import gc

    from povagent.engine.llm_import import collector_paused

    gc.disable()
    try:
        with collector_paused(freeze=True):
            assert not gc.isenabled()
        assert not gc.isenabled()
        gc.enable()
        with collector_paused(freeze=True):
            assert not gc.isenabled()
        assert gc.isenabled()
    finally:
        gc.enable()
        gc.unfreeze()  # this test process's objects go back to the collector's generations
