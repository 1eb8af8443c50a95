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
script's own exit code and error line, the deadline met while a server stalls, what a later
process trusts) is checked by the stalled-server tests, each a fresh ``python -m povagent.cli``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Protocol

import pytest
import yaml

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
    here: Callable[..., Done] | None,
    entry: str,
    tmp_path: Path,
    endpoint: str,
    *,
    revision: str | None = None,
    options: tuple[str, ...] = (),
    download: dict | None = None,
    offline: bool = False,
    timeout: float = 120,
) -> Done:
    """Run the command of ``entry`` as a user would: in this process through ``here`` (the
    ``console_here`` fixture), or with ``here=None`` in a fresh process."""
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
    others = [k for k in os.environ if k.startswith(("HF_", "HUGGINGFACE_", "TRANSFORMERS_"))]
    if here is not None:
        return here(args, env=dict.fromkeys(others) | hf, cwd=tmp_path)
    env = {k: v for k, v in os.environ.items() if k not in others} | hf
    done = subprocess.run(
        [sys.executable, "-m", "povagent.cli", *args], env=env, capture_output=True, text=True, timeout=timeout, cwd=tmp_path
    )
    return done


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
@pytest.mark.parametrize("entry", ENTRIES)
def test_a_stalled_server_stops_at_the_deadline_and_keeps_nothing_unfinished(entry, tmp_path, mini_root):
    server = HubServer(mini_root, lies=HubLies(stall_s=60), max_lifetime_s=90)
    start = time.monotonic()
    done, _ = attack(None, entry, tmp_path, server, options=("--deadline", "3"), download={"deadline_s": 3})
    took = time.monotonic() - start
    line = assert_refused(done, "did not finish within 3 s")
    assert took < 30, took
    assert "nothing unfinished was kept" in line
    assert not list(storage(tmp_path).rglob("*.incomplete"))
    offline = povagent(None, "download", tmp_path, server.url, offline=True)
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
