"""A hostile Hub endpoint, met through the commands a user types: ``povagent download`` and a
pipeline with ``dataset: {hub: ...}`` run by ``povagent run``, with ``HF_ENDPOINT`` a loopback
:class:`HubServer` that lies (:class:`HubLies`).

Every attack must end with exit code 2 and one ``error:`` line naming the repository and the
bad value, no traceback, and nothing written outside the Hugging Face home (``HF_HOME``): the
tests plant a fake virtual environment's ``site-packages`` beside it (a ``.pth`` file there
runs code at the environment's next start) and scan the whole temporary tree.

The refusals are the download code's, so most attacks run the command in this process (the
``console_here`` fixture: typer's ``CliRunner``, with ``HF_*`` set for the call, which povagent
reads at each call), a :class:`~povagent.errors.PovagentError` shown as the console script
shows it (``error: <message>``, exit code 2). What only a real process shows (the console
script's own exit code and error line, the deadline met while a server stalls) is checked by
the stalled-server tests: one fresh process runs the console script's ``main`` once per
command; what a later process trusts of the cut snapshot is then asked from this one.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Callable, Protocol

import pytest
import yaml
from console_child import IMPORT

from povagent.testing.hub_server import HubLies, HubServer

REPO = "owl-owl/POVBench"
ENTRIES = ["download", "pipeline"]


@pytest.fixture
def site(tmp_path) -> Path:
    """A fake virtual environment's site-packages beside the HF home: the attacks' target."""
    folder = tmp_path / "venv" / "lib" / "python3.11" / "site-packages"
    folder.mkdir(parents=True)
    (folder / "keep.txt").write_text("there before\n")
    return folder


def storage(tmp_path: Path) -> Path:
    """The repository's folder in the Hugging Face cache the commands use."""
    return tmp_path / "hf" / "hub" / "datasets--owl-owl--POVBench"


def release_files(root: Path, extra: dict[str, bytes] | None = None) -> dict[str, bytes]:
    files = {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}
    return files | (extra or {})


def tree(root: Path) -> set[Path]:
    return {p for p in root.rglob("*") if p.is_file() or p.is_symlink()}


class Done(Protocol):
    """What a command did (a process, or conftest's ``Shown`` of an in-process call)."""

    returncode: int
    stdout: str
    stderr: str


def povagent(
    here: Callable[..., Done],
    entry: str,
    tmp_path: Path,
    endpoint: str,
    *,
    revision: str | None = None,
    options: tuple[str, ...] = (),
    download: dict | None = None,
    offline: bool = False,
) -> Done:
    """Run the command of ``entry`` as a user would, in this process through ``here`` (the
    ``console_here`` fixture), with only its own ``HF_*`` variables set."""
    args, hf = command_line(entry, tmp_path, endpoint, revision=revision, options=options, download=download, offline=offline)
    others = [k for k in os.environ if k.startswith(HF_PREFIXES)]
    return here(args, env=dict.fromkeys(others) | hf, cwd=tmp_path)


#: The variables that point huggingface_hub somewhere: each command is given only its own.
HF_PREFIXES = ("HF_", "HUGGINGFACE_", "TRANSFORMERS_")


def command_line(
    entry: str,
    tmp_path: Path,
    endpoint: str,
    *,
    revision: str | None = None,
    options: tuple[str, ...] = (),
    download: dict | None = None,
    offline: bool = False,
) -> tuple[list[str], dict[str, str]]:
    """The arguments of ``povagent`` for ``entry`` (a pipeline's YAML written under ``tmp_path``)
    and the ``HF_*`` variables it runs with."""
    hf = {"HF_HOME": str(tmp_path / "hf"), "HF_ENDPOINT": endpoint, "HF_HUB_DISABLE_TELEMETRY": "1"}
    if offline:
        hf["HF_HUB_OFFLINE"] = "1"
    if entry == "download":
        args = ["download", REPO, "-q", *(["--revision", revision] if revision is not None else []), *options]
    else:
        spec: dict = {"hub": REPO}
        if revision is not None:
            spec["revision"] = revision
        if download is not None:
            spec["download"] = download
        pipeline = tmp_path / "pipeline.yaml"
        pipeline.write_text(yaml.safe_dump({
            "dataset": spec, "instances": {"conditions": ["c"], "limit": 1}, "backend": {"name": "center"},
            "output": str(tmp_path / "run"),
        }))  # fmt: skip
        args = ["run", str(pipeline), "--quiet"]
    return args, hf


def assert_refused(done: Done, *named: str) -> str:
    """Exit code 2, one ``error:`` line that names the repository and each of ``named``, no traceback."""
    assert "Traceback" not in done.stderr, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 2 and len(errors) == 1, (done.returncode, done.stderr)
    assert f"error: {REPO} @ " in errors[0], errors[0]
    for value in named:
        assert value in errors[0], (value, errors[0])
    return errors[0]


def assert_nothing_outside(tmp_path: Path, before: set[Path], entry: str) -> None:
    """Nothing new in the temporary tree but under the HF home (and the run's own files)."""
    allowed = [tmp_path / "hf", tmp_path / "run", tmp_path / "pipeline.yaml"]
    new = {p for p in tree(tmp_path) - before if not any(p == a or a in p.parents for a in allowed)}
    assert not new, f"written outside the Hugging Face cache by {entry}: {sorted(map(str, new))}"


def attack(here, entry: str, tmp_path: Path, server: HubServer, **kw) -> tuple[Done, set[Path]]:
    before = tree(tmp_path)
    with server:
        done = povagent(here, entry, tmp_path, server.url, **kw)
    return done, before


# -- values the server sends that would become path parts ------------------------------------------
@pytest.mark.parametrize("entry", ENTRIES)
def test_an_etag_holding_a_path_writes_no_pth_file(console_here, entry, tmp_path, mini_root, site):
    target = site / "evil.pth"
    etag = os.path.relpath(target, storage(tmp_path) / "blobs")  # what huggingface_hub joins to blobs/
    server = HubServer(mini_root, lies=HubLies(etag=etag, served={"meta.json": b"import os; os.system('touch PWNED')\n"}))
    done, before = attack(console_here, entry, tmp_path, server)
    assert_nothing_outside(tmp_path, before, entry)
    assert_refused(done, "ETag", etag[:40])
    assert not target.exists()


@pytest.mark.parametrize("entry,absolute", [("download", False), ("download", True), ("pipeline", False)])
def test_a_repository_sha_holding_a_path_is_refused(console_here, entry, absolute, tmp_path, mini_root, site):
    target = site / "evil"
    sha = str(target) if absolute else os.path.relpath(target, storage(tmp_path) / "trees")
    done, before = attack(console_here, entry, tmp_path, HubServer(mini_root, lies=HubLies(sha=sha)))
    assert_nothing_outside(tmp_path, before, entry)
    assert_refused(done, "commit id", sha[:40])
    assert not (site / "evil.json").exists()


@pytest.mark.parametrize("entry,absolute", [("download", False), ("download", True), ("pipeline", True)])
def test_an_x_repo_commit_holding_a_path_is_refused(console_here, entry, absolute, tmp_path, mini_root, site):
    # huggingface_hub records a missing file under .no_exist/<X-Repo-Commit>/<file>
    lie = str(site) if absolute else os.path.relpath(site, storage(tmp_path) / ".no_exist")
    lies = HubLies(repo_commit=lie, missing=set(release_files(mini_root)))  # every file answers 404
    done, before = attack(console_here, entry, tmp_path, HubServer(mini_root, lies=lies))
    assert_nothing_outside(tmp_path, before, entry)
    assert_refused(done, "X-Repo-Commit", lie[:40])
    assert not (site / "meta.json").exists()


@pytest.mark.parametrize(
    "entry,name",
    [
        ("download", "../../../evil.pth"),
        ("pipeline", "../../../evil.pth"),
        ("download", "/tmp/evil.pth"),
        ("download", "artifacts\\..\\..\\evil.pth"),
        ("download", "artifacts/./x/../evil.pth"),
    ],
)
def test_a_listed_file_name_that_leaves_the_snapshot_is_one_line(console_here, entry, name, tmp_path, mini_root, site):
    server = HubServer(files=release_files(mini_root, {name: b"import this\n"}))
    done, before = attack(console_here, entry, tmp_path, server)
    assert_nothing_outside(tmp_path, before, entry)
    assert_refused(done, "file name in the tree listing", repr(name)[1:-1][:40])


@pytest.mark.parametrize("entry", ENTRIES)
def test_a_revision_that_climbs_out_of_refs_is_refused_before_any_request(console_here, entry, tmp_path, mini_root, site):
    revision = os.path.relpath(site / "evil.pth", storage(tmp_path) / "refs")
    server = HubServer(mini_root, lies=HubLies(any_revision=True))
    done, before = attack(console_here, entry, tmp_path, server, revision=revision)
    assert_nothing_outside(tmp_path, before, entry)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert revision[:40] in done.stderr and "revision" in done.stderr
    assert not server.requests  # refused before the Hub is asked anything
    assert not (site / "evil.pth").exists()


# -- bytes that differ from the tree listing -----------------------------------------------------
FRAME = "artifacts/train_house_00000/img_from_observer/pair_0.png"


@pytest.mark.parametrize(
    "lfs,change",
    [(False, "longer"), (False, "same size"), (True, "same size")],
    ids=["longer-than-listed", "git-blob-id-mismatch", "lfs-sha256-mismatch"],
)
def test_bytes_that_differ_from_the_listing_are_an_error_and_not_kept(console_here, lfs, change, tmp_path, mini_root):
    real = (mini_root / FRAME).read_bytes()
    served = real + b"\0" * 4096 if change == "longer" else bytes([real[0] ^ 0xFF]) + real[1:]
    server = HubServer(mini_root, lfs_patterns=["*.png"] if lfs else (), lies=HubLies(served={FRAME: served}))
    done, _ = attack(console_here, "download", tmp_path, server)
    line = assert_refused(done, FRAME)
    assert ("sha256" if lfs else "git blob id" if change == "same size" else "more than") in line
    # nothing of it is where a later offline run would trust it
    offline = povagent(console_here, "download", tmp_path, server.url, offline=True)
    assert offline.returncode == 2 and "Traceback" not in offline.stderr, offline.stderr
    assert not list(storage(tmp_path).rglob("*.incomplete"))
    assert not any(p.read_bytes() == served for p in (storage(tmp_path) / "blobs").iterdir())


def test_a_pipeline_refuses_bytes_that_differ_from_the_listing(console_here, tmp_path, mini_root):
    real = (mini_root / FRAME).read_bytes()
    server = HubServer(mini_root, lfs_patterns=["*.png"], lies=HubLies(served={FRAME: real + b"more"}))
    done, _ = attack(console_here, "pipeline", tmp_path, server)
    assert_refused(done, FRAME)
    assert not (tmp_path / "run" / "results.jsonl").exists()


# -- bounds --------------------------------------------------------------------------------------
# One child runs the console script's ``main`` once per command line, each with its own argv,
# working folder and ``HF_*`` variables (povagent reads them at each call) and its own stdout and
# stderr files (file descriptors 1 and 2 pointed at them): each command is still the real command
# in a process of povagent's own, for one interpreter start instead of one per command. Each
# command's time counts the child's start-up too, as a process of its own would. An exception
# escaping ``main`` is printed as the interpreter would print it (a traceback, exit status 1).
EACH_COMMAND = "import time\nstarted = time.monotonic()\n" + IMPORT + textwrap.dedent("""
    import json, os
    from povagent.cli import main

    start_up = time.monotonic() - started
    cases, folder = json.loads(sys.argv[1]), sys.argv[2]
    done = []
    for n, case in enumerate(cases):
        os.environ.update(case["env"])
        os.chdir(case["cwd"])
        began = time.monotonic()
        code = run_as_console(main, ["povagent", *case["args"]], f"{folder}/{n}.out", f"{folder}/{n}.err")
        took = time.monotonic() - began + start_up
        for name in case["env"]:
            del os.environ[name]
        done.append({"returncode": code, "took": took})
    print(json.dumps(done))
""")


@pytest.fixture(scope="module")
def stalled(tmp_path_factory, mini_root) -> dict[str, tuple[subprocess.CompletedProcess, float, Path, str]]:
    """entry -> (what its command did, the seconds it took, its folder, its server's URL): each
    entry's command against a Hub server of its own that stalls every file, with a 3 s deadline,
    both run in one fresh process (a fresh interpreter costs about a second of CPU)."""
    base = tmp_path_factory.mktemp("stalled")
    folders = {entry: base / entry for entry in ENTRIES}
    servers = {entry: HubServer(mini_root, lies=HubLies(stall_s=60), max_lifetime_s=90) for entry in ENTRIES}
    cases = []
    with contextlib.ExitStack() as serving:
        for entry in ENTRIES:
            folders[entry].mkdir()
            serving.enter_context(servers[entry])
            args, hf = command_line(entry, folders[entry], servers[entry].url, options=("--deadline", "3"), download={"deadline_s": 3})
            cases.append({"args": args, "env": hf, "cwd": str(folders[entry])})
        env = {k: v for k, v in os.environ.items() if not k.startswith(HF_PREFIXES)}
        child = subprocess.run([sys.executable, "-c", EACH_COMMAND, json.dumps(cases), str(base)], env=env,
                               capture_output=True, text=True, timeout=240)  # fmt: skip
    assert child.returncode == 0, child.stderr[-3000:]
    done = json.loads(child.stdout.splitlines()[-1])
    return {
        entry: (
            subprocess.CompletedProcess(case["args"], each["returncode"], (base / f"{n}.out").read_text(), (base / f"{n}.err").read_text()),
            each["took"], folders[entry], servers[entry].url,
        )
        for n, (entry, case, each) in enumerate(zip(ENTRIES, cases, done))
    }  # fmt: skip


@pytest.mark.parametrize("entry", ENTRIES)
def test_a_stalled_server_stops_at_the_deadline_and_keeps_nothing_unfinished(entry, stalled, console_here):
    done, took, folder, url = stalled[entry]
    line = assert_refused(done, "did not finish within 3 s")
    assert took < 30, took
    assert "nothing unfinished was kept" in line
    assert not list(storage(folder).rglob("*.incomplete"))
    offline = povagent(console_here, "download", folder, url, offline=True)  # a later process, this one
    assert offline.returncode == 2 and "Traceback" not in offline.stderr  # the cut snapshot is not trusted


def test_a_file_above_the_size_cap_is_refused_before_any_byte(console_here, tmp_path, mini_root):
    biggest = max((p for p in mini_root.rglob("*") if p.is_file()), key=lambda p: p.stat().st_size)
    cap = biggest.stat().st_size / 2**20 / 2
    server = HubServer(mini_root)
    done, _ = attack(console_here, "download", tmp_path, server, options=("--max-file-mib", f"{cap:.6f}"))
    assert_refused(done, biggest.relative_to(mini_root).as_posix(), "max-file-mib")
    assert server.fetched_files() == []


@pytest.mark.parametrize("entry", ENTRIES)
def test_a_download_above_the_total_cap_is_refused_before_any_byte(console_here, entry, tmp_path, mini_root):
    server = HubServer(mini_root)
    done, _ = attack(console_here, entry, tmp_path, server, options=("--max-total-mib", "0.01"), download={"max_total_mib": 0.01})
    assert_refused(done, "above the cap of 0.01 MiB", "max-total-mib")
    assert server.fetched_files() == []


def test_honest_lfs_files_are_checked_and_stored_under_their_sha256(console_here, tmp_path, mini_root):
    server = HubServer(mini_root, lfs_patterns=["*.png"])
    with server:
        done = povagent(console_here, "download", tmp_path, server.url)
    assert done.returncode == 0, done.stderr
    root = Path(done.stdout.strip().splitlines()[-1])
    link = root / FRAME
    assert link.is_symlink() and Path(os.path.realpath(link)).name == server._lfs[FRAME]
    assert link.read_bytes() == (mini_root / FRAME).read_bytes()
