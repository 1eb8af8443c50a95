"""litellm is imported lazily and offline-safe (povagent/engine/llm_import.py).

What a fresh interpreter imports and how its collector stands are observed in two children,
each shared by the module's tests through fixtures that return its reports (JSON objects of
observations), and asserted one observation per test:

* ``light``: the CLI imported, ``povagent --help`` run through the console entry, every
  built-in plugin loaded; litellm never imported;
* ``console``: then, in the same process, now povagent's own (``freeze_after_loading``, as the
  console script calls it), litellm is preloaded, imported at once from four threads, then
  warmed up for a second model in the foreground;
* ``embedding``: a program embedding povagent imports litellm once (no freeze), with
  ``LITELLM_MODE`` exported by the user.

``light`` is observed before anything imports litellm, so the console case may go on in its
interpreter as the console script does after start-up. A freeze is process-wide, so the
console and embedding cases cannot share one interpreter.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.timeout(120)

CLEAN_ENV = {k: v for k, v in os.environ.items() if not k.startswith("LITELLM_")}

HEAVY = ("litellm", "openai", "scipy", "trimesh", "embreex", "matplotlib", "huggingface_hub")

# Each child writes its observations to the JSON file named by its first argument; the light
# observations go to the second one's, before the console case goes on (LIGHT + CONSOLE).
LIGHT = f"""
import contextlib, io, json, sys
report, seen, argv = sys.argv[2], {{}}, sys.argv
import povagent.cli
seen["cli_imports_litellm"] = "litellm" in sys.modules
from povagent import cli
from povagent.engine import llm_import
sys.argv = ["povagent", "--help"]
out = io.StringIO()
with contextlib.redirect_stdout(out):
    try:
        cli.main()
    except SystemExit as exit:
        seen["help_exit"] = exit.code
sys.argv = argv
seen["help_stdout"] = out.getvalue()
seen["help_heavy"] = sorted(m for m in {HEAVY!r} if m in sys.modules)
seen["help_freezes"] = llm_import._freeze_loaded
from povagent.plugins import build_plugin_host
host = build_plugin_host(entry_points=False)
seen["litellm_backend_registered"] = "litellm" in host.names("backend")
seen["plugins_import_litellm"] = "litellm" in sys.modules
json.dump(seen, open(report, "w"))
"""

CONSOLE = """
import gc, json, sys, threading
from povagent.engine.llm_import import freeze_after_loading, import_litellm, preload_litellm, warm_up_litellm
seen = {}
freeze_after_loading()  # as the console script does
started = gc.get_stats()[2]["collections"]
# preload, then import at once from the main thread and three others (litellm's own modules
# included): each waits for the background import, none meets a half-made module
preload_litellm("openai/loopback")
seen["preload_thread"] = any(t.name == "povagent-preload-litellm" for t in threading.enumerate())
got, errors = [], []
def use():
    try:
        got.append(import_litellm())
        import openai
        from litellm import acompletion
        warm_up_litellm("openai/loopback")
    except BaseException as exc:
        errors.append(repr(exc))
threads = [threading.Thread(target=use) for _ in range(3)]
for t in threads: t.start()
use()
for t in threads: t.join(60)
seen["errors"] = errors
seen["got"] = [m is sys.modules["litellm"] for m in got]
seen["quiet"] = [got[0].suppress_debug_info, got[0].telemetry] if got else None
warm_up_litellm("openai/some-model")  # a warm-up in the foreground, after the background one
seen["collector_on"] = gc.isenabled()
seen["full_collections"] = gc.get_stats()[2]["collections"] - started
seen["frozen"] = gc.get_freeze_count()
class Cycle: pass
c = Cycle(); c.me = c; del c
seen["collected_after"] = gc.collect()
json.dump(seen, open(sys.argv[1], "w"))
"""

EMBEDDING = """
import gc, json, os, sys
from povagent.engine.llm_import import import_litellm
seen = {}
started = gc.get_stats()[2]["collections"]
import_litellm()
seen["collector_on"] = gc.isenabled()
seen["frozen"] = gc.get_freeze_count()
seen["full_collections"] = gc.get_stats()[2]["collections"] - started
seen["litellm_mode"] = os.environ["LITELLM_MODE"]
from litellm.litellm_core_utils import logging_utils
seen["base64_exported"] = "MAX_BASE64_LENGTH_FOR_LOGGING" in os.environ
seen["base64_length"] = logging_utils.MAX_BASE64_LENGTH_FOR_LOGGING
json.dump(seen, open(sys.argv[1], "w"))
"""


def _observe(tmp_path_factory, name: str, code: str, reports: int = 1, **env: str) -> list[dict]:
    folder = tmp_path_factory.mktemp(name)
    paths = [folder / f"seen-{n}.json" for n in range(reports)]
    done = subprocess.run([sys.executable, "-c", code, *map(str, paths)], capture_output=True, text=True,
                          env={**CLEAN_ENV, **env}, timeout=100, cwd=folder)  # fmt: skip
    assert done.returncode == 0 and all(p.exists() for p in paths), done.stderr[-3000:]
    return [json.loads(p.read_text()) for p in paths]


@pytest.fixture(scope="module")
def light_then_console(tmp_path_factory) -> list[dict]:
    """[console, light]: one interpreter, observed light first (a fresh interpreter costs a
    second of CPU before it imports litellm)."""
    return _observe(tmp_path_factory, "light-then-console", LIGHT + CONSOLE, reports=2)


@pytest.fixture(scope="module")
def light(light_then_console) -> dict:
    return light_then_console[1]


@pytest.fixture(scope="module")
def console(light_then_console) -> dict:
    return light_then_console[0]


@pytest.fixture(scope="module")
def embedding(tmp_path_factory) -> dict:
    return _observe(tmp_path_factory, "embedding", EMBEDDING, LITELLM_MODE="DEV")[0]


def test_importing_the_cli_does_not_import_litellm(light):
    assert light["cli_imports_litellm"] is False, "litellm imported"


def test_help_does_not_import_litellm(light):
    assert "litellm" not in light["help_heavy"], "litellm imported"
    assert "Usage" in light["help_stdout"]


def test_loading_every_builtin_plugin_does_not_import_litellm(light):
    assert light["litellm_backend_registered"] is True
    assert light["plugins_import_litellm"] is False, "litellm imported"


def test_help_loads_no_heavy_library(light):
    """``povagent --help`` stays fast by what it imports, not by a wall-clock bound (the machine
    is shared): litellm alone takes seconds, scipy and the renderer's libraries a second more."""
    assert light["help_exit"] in (0, None), light["help_exit"]
    assert not light["help_heavy"], light["help_heavy"]


def test_user_exported_litellm_settings_win(embedding):
    assert embedding["litellm_mode"] == "DEV"


def test_base64_truncation_for_logging_stays_on(embedding):
    # off, every litellm logging callback would be handed whole images (see import_litellm);
    # a user with no callbacks may still export MAX_BASE64_LENGTH_FOR_LOGGING=0 themselves
    assert embedding["base64_exported"] is False
    assert embedding["base64_length"] > 0


def test_importing_while_the_background_import_runs_waits_for_it(console):
    assert console["preload_thread"] is True
    assert not console["errors"], console["errors"]
    assert console["got"] == [True] * 4, console["got"]
    assert console["quiet"] == [True, False]  # suppress_debug_info on, telemetry off


def test_litellm_loads_with_the_collector_paused_and_its_objects_frozen(console):
    """The import and warm-up create ~1M long-lived objects; collections walking them while they
    load cost a quarter of the import's CPU. After the load the collector is back on (a
    collection still frees cycles made later) and litellm's objects are out of its sight."""
    assert console["collector_on"] is True
    assert console["full_collections"] == 0, "a full collection ran during the load"
    assert console["frozen"] > 200_000, console["frozen"]
    assert console["collected_after"] >= 1  # cycles made after the load are still collected


def test_a_program_embedding_povagent_gets_the_pause_but_no_freeze(embedding):
    """A robot app's objects of the moment must not be frozen with litellm's: a cycle among
    them that became garbage later would never be collected."""
    assert embedding["collector_on"] is True and embedding["frozen"] == 0, embedding["frozen"]
    assert embedding["full_collections"] == 0, "a full collection ran during the load"


def test_the_console_script_freezes_what_litellm_loads(light):
    assert light["help_freezes"] is True


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
