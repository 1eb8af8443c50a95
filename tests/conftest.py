"""Shared fixtures: the hand-made release-layout fixture."""

from __future__ import annotations

import os
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

# Every summary.json, results row, sweep.json and export.json that povagent writes while the tests
# run (in this process and in every process they start) is checked against its shipped schema as
# it is written (povagent.results.output_check).
os.environ["POVAGENT_CHECK_OUTPUTS"] = "1"

# The Dask processes the tests start (tests/cluster's scheduler and workers, a LocalCluster's)
# inherit this environment. Idle, each wakes every 20 ms to time its event loop and every 0.5 s
# to sample its memory, and a worker samples its busy thread's stack every 10 ms: CPU that grows
# with the wall time a loaded machine stretches a test to (2 s per idle minute of a 2-worker
# cluster). None of it is tested here; a value set outside the tests wins.
for _key, _value in {
    "DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "1s",
    "DASK_DISTRIBUTED__ADMIN__SYSTEM_MONITOR__INTERVAL": "5s",
    "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False",
}.items():
    os.environ.setdefault(_key, _value)

# huggingface_hub reads HF_HOME / HF_HUB_CACHE once, when first imported, into its default cache
# folder (povagent falls back to it when neither is set at a call). Imported here, before any
# test points HF_HOME at its tmp folder (the hub tests do, with monkeypatch), so one test's cache
# never becomes the default of every later test in that worker (4 ms).
import huggingface_hub.constants  # noqa: E402,F401

# Hypothesis: no per-example deadline and no "too slow" health check (both wall-clock budgets
# that the machine's load moves: a property either holds or not, however long an example
# takes; a hang is pytest-timeout's), and no example database (it would be written into the
# checkout). Tests that set their own settings keep them.
settings.register_profile("povagent", deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("povagent")

# Our own fixtures for plugin authors are opt-in (no pytest11 entry point): we opt in here.
pytest_plugins = ["povagent.testing.pytest_plugin"]


def pytest_configure(config: pytest.Config) -> None:
    # under pytest-xdist's loadfile, tests/cluster runs in one worker as one unit (work_units.py)
    from work_units import register

    register(config)


FIXTURES = Path(__file__).resolve().parent / "fixtures"
MINI = FIXTURES / "povbench_mini"


#: Debian's chromium (the README's test command installs it; never a downloaded build), headless.
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
BROWSER_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking"]


@pytest.fixture(scope="session")
def session_chromium():
    """The session's one headless chromium, in a thread of its own (tests/session_browser.py says
    why): launched when a test first needs it, closed when the session ends."""
    pytest.importorskip("playwright.sync_api", reason="the test extra installs playwright")
    if not Path(CHROMIUM).exists():
        pytest.fail(f"chromium not found at {CHROMIUM}: the README's test command installs it")
    from session_browser import BrowserThread

    chromium = BrowserThread(lambda p: p.chromium.launch(executable_path=CHROMIUM, headless=True, args=BROWSER_ARGS))
    try:
        yield chromium
    finally:
        chromium.close()


@pytest.fixture(scope="module")
def browser(session_chromium):
    """The session's chromium, for a module's tests (the annotation page's, the report gallery's):
    ``browser.new_page(...)`` and ``browser.new_context(...)`` open a context of their own. The
    contexts a module leaves open are closed when it ends, so no state reaches the next module;
    all but the session's kept page (tests/session_browser.py's ``kept_page``), which each use
    first takes to a blank page and whose loads are each checked to leave nothing behind."""
    from session_browser import OnBrowserThread, is_kept

    raw = session_chromium.browser
    before = set(session_chromium.call(lambda: raw.contexts))
    try:
        yield OnBrowserThread(raw, session_chromium)
    finally:
        session_chromium.call(lambda: [c.close() for c in raw.contexts if c not in before and not is_kept(c)])


@pytest.fixture(scope="session")
def mini_root() -> Path:
    """The hand-made dataset: two good houses and one broken house (train_house_00002)."""
    return MINI


@pytest.fixture(scope="session")
def mini_dataset(mini_root):
    """The hand-made dataset, loaded (the broken house is reported and skipped)."""
    from povagent.dataset import load_dataset

    return load_dataset(mini_root)


@pytest.fixture
def write_answered_run(mini_root):
    """``write_answered_run(folder, answers) -> folder``: a finished run folder over the
    hand-made dataset (center backend, basic strategy, parsed with ``json``, official scorer)
    whose rows are ``answered`` with the given raw answers, ``answers`` being
    ``[(instance id, raw text), ...]``: what re-parsing and re-scoring commands read.
    ``backend`` (a pipeline's ``backend:`` mapping) names who answered instead of ``center``."""
    import yaml

    from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus

    def write(folder: Path, answers, backend=None) -> Path:
        folder.mkdir(parents=True)
        (folder / "config.yaml").write_text(yaml.safe_dump({
            "dataset": {"path": str(mini_root)},
            "backend": backend or {"name": "center", "options": {}},
            "strategy": {"name": "basic", "options": {}},
            "parser": {"name": "json", "options": {}},
            "scorers": [{"name": "official", "options": {}}],
            "output": str(folder),
        }))  # fmt: skip
        with ResultsWriter(folder / "results.jsonl") as w:
            for inst_id, raw in answers:
                house, pair, direction, cond = inst_id.split("/")
                w.write(ResultRow(key=f"{inst_id}#0", instance_id=inst_id, house_id=house, pair_id=pair, direction=direction,
                                  condition=cond, status=RowStatus.ANSWERED, parser="json",
                                  exchanges=[ExchangeRecord(request_hash="h", raw=raw)]))  # fmt: skip
        return folder

    return write


@pytest.fixture(scope="session")
def generated_release(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two generated houses with 12 exploration frames each, in the release layout (real files,
    made once a session): the geometry, solver, simulator, agent and bird's-eye tests share it."""
    from shared_sets import made_once

    from povagent.generate import generate_dataset

    # nearly every xdist worker asks for it: made once between them (~4 s of CPU each time)
    def make(root: Path) -> None:
        generate_dataset(root, houses=2, seed=3, frames=12, jobs=1, progress=False)

    return made_once(tmp_path_factory, "geometric-generated", make)


@dataclass
class CommandOutput:
    """A dataset ``povagent generate`` wrote, and what the command printed."""

    root: Path
    output: str


@pytest.fixture(scope="session")
def two_houses(tmp_path_factory: pytest.TempPathFactory) -> CommandOutput:
    """Two houses (seed 5, one exploration frame: its ``meta.json`` says so) written by the
    ``generate`` command in this process (``--jobs 1``): the command's own test reads it, the
    determinism tests compare a worker pool's bytes with it, the resume tests copy its finished
    houses and tests/cluster compares the houses made on a cluster with it. Read only: tests that
    change it copy it.

    Those test files run in several xdist workers: the set is made once between them, and what
    the command printed is kept beside it (``command-output.txt``) for the workers that read it."""
    from shared_sets import made_once
    from typer.testing import CliRunner

    from povagent.cli import app

    def make(root: Path) -> None:
        args = ["generate", "--out", str(root), "--houses", "2", "--seed", "5", "--frames", "1", "--jobs", "1"]
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 0, result.output
        (root.parent / "command-output.txt").write_text(result.output)

    root = made_once(tmp_path_factory, "two-houses", make)
    return CommandOutput(root, (root.parent / "command-output.txt").read_text())


#: The hand-made fixture's houses without a planted problem.
GOOD_HOUSES = ("train_house_00000", "train_house_00001")


@pytest.fixture
def dataset_copy(tmp_path, mini_root) -> Path:
    """A writable copy of the fixture's two good houses (no problem at all) under ``tmp_path/ds``."""
    root = tmp_path / "ds"
    (root / "artifacts").mkdir(parents=True)
    shutil.copy(mini_root / "meta.json", root / "meta.json")
    for house in GOOD_HOUSES:
        shutil.copytree(mini_root / "artifacts" / house, root / "artifacts" / house)
    return root


OFFLINE_PLUGIN_SOURCE = Path(__file__).resolve().parent / "run" / "offline_plugin.py"


@pytest.fixture
def offline_plugin_file(tmp_path) -> Path:
    """``tests/run/offline_plugin.py`` copied into ``tmp_path``: a pipeline YAML written there may
    name it (a config loads ``.py`` plugins only from its own folder or below)."""
    path = tmp_path / "offline_plugin.py"
    shutil.copy(OFFLINE_PLUGIN_SOURCE, path)
    return path.resolve()


# -- the checkout is left as it was found -------------------------------------------------------
# Every test writes under its tmp folder. A file a test leaves in the checkout (a command's
# default output folder written relative to the working directory, say) fails the run here,
# naming the paths, whichever test wrote them.
_CHECKOUT = Path(__file__).resolve().parent.parent


def _checkout_status() -> set[str] | None:
    import subprocess

    if not (_CHECKOUT / ".git").exists():
        return None  # an installed copy of the tests, not a checkout: nothing to compare
    try:
        done = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all", "--ignored=no"], cwd=_CHECKOUT,
                              capture_output=True, text=True, timeout=60)  # fmt: skip
    except (OSError, subprocess.TimeoutExpired):
        return None
    return set(done.stdout.splitlines()) if done.returncode == 0 else None


def pytest_sessionstart(session: pytest.Session) -> None:
    session.config.stash[_STATUS_KEY] = _checkout_status()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    before = session.config.stash.get(_STATUS_KEY, None)
    if before is None or hasattr(session.config, "workerinput"):
        return
    after = _checkout_status()
    if after is None:
        return
    changed = sorted(after - before)
    if changed:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        message = "the tests changed the checkout (every test writes under its tmp folder): " + ", ".join(changed[:20])
        if reporter is not None:
            reporter.write_line(message, red=True)
        else:
            print(message, file=sys.stderr)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


_STATUS_KEY = pytest.StashKey[set[str] | None]()
