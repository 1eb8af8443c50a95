"""The POVBench release from the Hugging Face Hub: ``dataset: {hub: ...}`` and ``povagent download``.

The release is the dataset repository ``owl-owl/POVBench``. It is fetched into the standard
Hugging Face cache (``HF_HOME``, ``HF_HUB_CACHE``), in huggingface_hub's own layout, so every
tool that reads that cache shares one copy, a second fetch only checks the revision, and a
machine without network reads it offline (``HF_HUB_OFFLINE=1``, through
:func:`huggingface_hub.snapshot_download`). The fetch itself is
:mod:`povagent.dataset.hub_transfer`'s: huggingface_hub would build cache paths from what the
server answers without checking it, so povagent checks every value a server sends
(:mod:`povagent.dataset.hub_checks`), the revision asked for, every path written, and the bytes
against the tree listing, within the bounds of :class:`~povagent.dataset.hub_limits.DownloadLimits`.

Only what the chosen conditions read is fetched (``allow_patterns``): a Given-only run does not
download the exploration frames (most of the release's 516 MiB). Every condition needs
``meta.json``, each house's ``<house>.json`` and its ``exploration_log.json`` (the loader reads a
house's log to know its frames; the file is a few KiB); Inferred and Stated add the frames in
``exploration_images/`` and ``per_image_visible_objects.json``; Given adds ``img_from_observer/``.

The release root is the folder inside the snapshot that holds ``artifacts/`` (the snapshot
itself, or one folder below it if the repository nests the release).

Failures are :class:`~povagent.errors.DatasetError` naming the repository and the revision:
a revision or repository that does not exist, no network and no cached copy, offline with an
incomplete cache, a value from the server that fails its check (named, quoted, cut short), a
file whose size or hash differs from the tree listing, a cap or the deadline passed.

huggingface_hub reads ``HF_ENDPOINT``, ``HF_HOME``/``HF_HUB_CACHE`` and ``HF_HUB_OFFLINE`` once,
when it is first imported (litellm may import it long before a download). This module reads them
itself at each call and passes them on explicitly (``endpoint=``, ``cache_dir=``,
``local_files_only=``), so a variable set later in the process still counts.

This module fetches and locates files; loading them is :mod:`povagent.dataset.loader`'s job.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

from povagent.dataset.hub_checks import COMMIT_ID, HubValueError, check_revision, shown
from povagent.dataset.hub_limits import DownloadLimits
from povagent.dataset.hub_transfer import inside
from povagent.dataset.release_models import CONDITIONS, Condition
from povagent.errors import DatasetError

#: The official release on the Hub.
RELEASE_REPO = "owl-owl/POVBench"

#: Folder of a release root that marks it (``<root>/artifacts/<house>/...``).
ARTIFACTS = "artifacts"

_NAMES = {"a": "a", "b": "b", "c": "c", "inferred": "a", "stated": "b", "given": "c"}

# Patterns are matched against repository paths with fnmatch, where ``*`` also crosses ``/``:
# the leading ``*`` lets the release sit at the repository root or one folder down.
_COMMON = ["meta.json", "*/meta.json", f"*{ARTIFACTS}/*/*.json"]
_FRAMES = [f"*{ARTIFACTS}/*/exploration_images/*"]
_OBSERVER = [f"*{ARTIFACTS}/*/img_from_observer/*"]
#: House-level files only A/B read (the common ``*.json`` pattern would otherwise take them).
_AB_ONLY_JSON = ["*/per_image_visible_objects.json"]


@dataclass(frozen=True)
class HubRelease:
    """A fetched release: where it is and which commit it is."""

    repo_id: str
    #: The revision asked for (``main`` when none was given).
    revision: str
    #: The commit hash the revision resolved to (the snapshot folder's name).
    commit: str
    #: The snapshot folder in the Hugging Face cache.
    snapshot: Path
    #: The release root inside it: the folder holding ``artifacts/``.
    root: Path

    def describe(self) -> str:
        """One line for a console: repository, revision, commit and the local root."""
        rev = self.revision if self.revision == self.commit else f"{self.revision} (commit {self.commit[:12]})"
        return f"{self.repo_id} @ {rev} -> {self.root}"


def parse_conditions(conditions: Iterable[Condition | str] | None) -> tuple[Condition, ...]:
    """Conditions by letter or paper name (``a``, ``stated``, ``C``...); ``None`` means all three.

    A comma-separated string item is split (``"a,b"``), as a command line gives it.
    """
    if conditions is None:
        return CONDITIONS
    if isinstance(conditions, str):  # one name (a Condition is a str too)
        conditions = [conditions]
    chosen: set[Condition] = set()
    for item in conditions:
        for name in str(item.value if isinstance(item, Condition) else item).split(","):
            key = name.strip().lower()
            if not key:
                continue
            if key not in _NAMES:
                raise DatasetError(f"condition {name.strip()!r}: unknown (use a/inferred, b/stated, c/given)")
            chosen.add(Condition(_NAMES[key]))
    if not chosen:
        return CONDITIONS
    return tuple(c for c in CONDITIONS if c in chosen)


def release_patterns(conditions: Iterable[Condition | str] | None = None) -> tuple[list[str] | None, list[str] | None]:
    """``(allow_patterns, ignore_patterns)`` for :func:`huggingface_hub.snapshot_download`.

    All three conditions: ``(None, None)``, the whole repository. Otherwise only what the
    conditions read (see the module docstring).
    """
    chosen = parse_conditions(conditions)
    if set(chosen) == set(CONDITIONS):
        return None, None
    allow = list(_COMMON)
    ignore: list[str] | None = None
    if any(c.uses_exploration_frames for c in chosen):
        allow += _FRAMES
    else:
        ignore = list(_AB_ONLY_JSON)
    if Condition.GIVEN in chosen:
        allow += _OBSERVER
    return allow, ignore


def find_release_root(snapshot: str | Path, what: str = "") -> Path:
    """The folder holding ``artifacts/`` inside a snapshot (itself, or a folder below it).

    ``what`` names the source in the error (e.g. ``owl-owl/POVBench @ main``). No such folder, or
    several, is a :class:`DatasetError`.
    """
    snapshot = Path(snapshot)
    label = f"{what}: " if what else ""
    if (snapshot / ARTIFACTS).is_dir():
        return snapshot
    found = sorted(p.parent for p in snapshot.glob(f"*/{ARTIFACTS}") if p.is_dir())
    if len(found) == 1:
        return found[0]
    if found:
        listing = ", ".join(str(p.relative_to(snapshot)) for p in found)
        raise DatasetError(f"{label}{snapshot} holds several releases ({listing}); expected one folder holding {ARTIFACTS}/")
    raise DatasetError(
        f"{label}no folder holding {ARTIFACTS}/ in {snapshot} (expected the POVBench release layout: meta.json, "
        f"{ARTIFACTS}/<house>/...); is this the POVBench dataset repository?"
    )


def release_size(root: str | Path) -> tuple[int, int]:
    """``(files, bytes)`` under a release root (the cache's symlinks followed to their blobs)."""
    files = size = 0
    for p in Path(root).rglob("*"):
        if p.is_file():
            files += 1
            size += p.stat().st_size
    return files, size


def _env_true(name: str) -> bool:
    return os.environ.get(name, "").strip().upper() in {"1", "ON", "YES", "TRUE"}


def cache_dir_requested() -> str | None:
    """The cache folder ``HF_HUB_CACHE`` or ``HF_HOME`` name now (``None``: huggingface_hub's default)."""
    if os.environ.get("HF_HUB_CACHE"):
        return os.path.expanduser(os.path.expandvars(os.environ["HF_HUB_CACHE"]))
    if os.environ.get("HF_HOME"):
        return os.path.join(os.path.expanduser(os.path.expandvars(os.environ["HF_HOME"])), "hub")
    return None


def offline_requested() -> bool:
    """Whether ``HF_HUB_OFFLINE`` (or ``TRANSFORMERS_OFFLINE``) is set now, as huggingface_hub reads it."""
    return _env_true("HF_HUB_OFFLINE") or _env_true("TRANSFORMERS_OFFLINE")


def download_release(
    repo_id: str = RELEASE_REPO,
    *,
    revision: str | None = None,
    conditions: Iterable[Condition | str] | None = None,
    cache_dir: str | Path | None = None,
    endpoint: str | None = None,
    offline: bool | None = None,
    progress: bool = True,
    limits: DownloadLimits | None = None,
) -> HubRelease:
    """Fetch the release (or the part ``conditions`` need) into the Hugging Face cache.

    ``revision`` is a branch, tag or commit (default: ``main``). ``endpoint`` defaults to
    ``HF_ENDPOINT``, ``cache_dir`` to ``HF_HUB_CACHE`` or ``HF_HOME/hub``, ``offline`` to
    ``HF_HUB_OFFLINE``, each as set at this call (then to huggingface_hub's defaults); offline,
    only the cache is read. ``progress`` shows a progress bar. ``limits`` bound the download
    (default: :class:`DownloadLimits`'s). Nothing the server says is trusted: see
    :mod:`povagent.dataset.hub_transfer`. Returns where the release is; a failure is a
    :class:`DatasetError` naming the repository and revision.
    """
    from huggingface_hub import constants

    from povagent.dataset.hub_budget import Budget, DeadlinePassed, with_deadline
    from povagent.dataset.hub_transfer import MetadataUnavailable, fetch_snapshot

    asked = revision or constants.DEFAULT_REVISION
    check_repo_id(repo_id)
    try:
        check_revision(asked)
    except HubValueError as exc:
        raise DatasetError(f"{repo_id} @ {shown(asked)}: {exc}; give a branch, tag or commit of the repository") from None
    limits = limits or DownloadLimits()
    endpoint = endpoint or os.environ.get("HF_ENDPOINT") or None
    if endpoint:
        endpoint = endpoint.rstrip("/")
    hub_url = endpoint or constants.ENDPOINT
    cache_dir = cache_dir if cache_dir is not None else cache_dir_requested()
    cache = str(Path(cache_dir if cache_dir is not None else constants.HF_HUB_CACHE).expanduser().resolve())
    storage = os.path.join(cache, "datasets--" + repo_id.replace("/", "--"))
    offline = offline_requested() if offline is None else offline
    chosen = parse_conditions(conditions)
    allow, ignore = release_patterns(chosen)
    where = f"{repo_id} @ {asked}"
    fetch = f"povagent download {repo_id}" + (f" --revision {revision}" if revision else "")
    if allow is not None:
        fetch += " --conditions " + ",".join(c.value for c in chosen)
    budget = Budget(limits)
    try:
        if offline:
            snapshot = _from_cache(repo_id, asked, cache, allow, ignore, None)
        else:
            try:
                snapshot = with_deadline(
                    lambda: fetch_snapshot(
                        repo_id,
                        asked,
                        storage=storage,
                        endpoint=endpoint,
                        allow=allow,
                        ignore=ignore,
                        budget=budget,
                        progress=progress,
                    ),
                    budget,
                )
            except MetadataUnavailable as unavailable:
                snapshot = _from_cache(repo_id, asked, cache, allow, ignore, unavailable.cause)
    except HubValueError as exc:
        raise DatasetError(
            f"{where}: refused what the Hub at {hub_url} sent: {exc}; nothing was written from it "
            "(is HF_ENDPOINT a Hugging Face Hub?)"
        ) from None
    except DeadlinePassed:
        raise DatasetError(
            f"{where}: the download from {hub_url} did not finish within {limits.deadline_s:g} s (--deadline, "
            f"dataset.download.deadline_s); {budget.fetched_files} files ({budget.fetched_bytes / 2**20:.1f} MiB) "
            "were fetched and checked, nothing unfinished was kept; run it again to go on"
        ) from None
    except DatasetError as exc:
        raise DatasetError(f"{where}: from the Hub at {hub_url}: {exc}") from None
    except Exception as exc:
        error = _user_error(exc, where, repo_id, hub_url, cache, offline, fetch)
        if error is None:
            raise  # not a download failure a user can act on: a bug, keep its traceback
        raise error from exc
    path = Path(snapshot)
    commit = path.name
    if not COMMIT_ID.fullmatch(commit) or not inside(path, storage):
        raise DatasetError(f"{where}: the cached snapshot {shown(str(path), 120)} is not a commit folder of {storage}")
    return HubRelease(repo_id, asked, commit, path, find_release_root(path, where))


def check_repo_id(repo_id: str) -> str:
    """``repo_id`` if it is ``owner/name`` (letters, digits, ``_.-``; no ``..`` or ``--``), the
    form huggingface_hub turns into the cache folder ``datasets--owner--name``."""
    if not re.fullmatch(r"[\w.-]{1,96}/[\w.-]{1,96}", repo_id) or ".." in repo_id or "--" in repo_id:
        raise DatasetError(f"{shown(repo_id)} is not a Hub repository id: give owner/name (e.g. {RELEASE_REPO})")
    return repo_id


def _from_cache(
    repo_id: str, revision: str, cache: str, allow: list[str] | None, ignore: list[str] | None, api_error: Exception | None
) -> str:
    """The cached snapshot of ``revision`` (huggingface_hub's offline reader), complete for the
    patterns; ``api_error`` is why the Hub was not asked (``None``: offline mode)."""
    from huggingface_hub import snapshot_download
    from huggingface_hub.errors import GatedRepoError, HfHubHTTPError, LocalEntryNotFoundError, RepositoryNotFoundError

    try:
        return snapshot_download(
            repo_id,
            repo_type="dataset",
            revision=revision,
            cache_dir=cache,
            local_files_only=True,
            allow_patterns=allow,
            ignore_patterns=ignore,
        )
    except LocalEntryNotFoundError:
        if api_error is None:
            raise
        unauthorized = isinstance(api_error, HfHubHTTPError) and api_error.response is not None and api_error.response.status_code == 401
        if isinstance(api_error, (RepositoryNotFoundError, GatedRepoError)) or unauthorized:
            raise api_error from None
        raise LocalEntryNotFoundError(f"Got: {type(api_error).__name__}: {api_error}") from api_error


def _user_error(
    exc: Exception, where: str, repo_id: str, endpoint: str, cache: str | Path, offline: bool, fetch: str
) -> DatasetError | None:
    """A :class:`DatasetError` saying what went wrong and what to do, or ``None`` for a bug."""
    from huggingface_hub.errors import (
        GatedRepoError,
        HfHubHTTPError,
        IncompleteSnapshotError,
        LocalEntryNotFoundError,
        RepositoryNotFoundError,
        RevisionNotFoundError,
    )

    if isinstance(exc, RevisionNotFoundError):
        return DatasetError(
            f"{where}: the revision does not exist in the dataset repository {repo_id} on {endpoint}; "
            "give a branch, tag or commit hash of that repository (or leave revision out for main)"
        )
    if isinstance(exc, GatedRepoError):
        return DatasetError(f"{where}: the dataset repository is gated on {endpoint}; accept its terms on the Hub and set HF_TOKEN")
    if isinstance(exc, RepositoryNotFoundError):
        return DatasetError(
            f"{where}: no dataset repository {repo_id} on {endpoint} (or it is private: set HF_TOKEN); "
            f"the POVBench release is {RELEASE_REPO}"
        )
    if isinstance(exc, IncompleteSnapshotError):
        missing = str(exc).split(" is incomplete: ", 1)[-1].split(". ", 1)[0]
        return DatasetError(
            f"{where}: the cached copy in {cache} lacks files these conditions need ({missing}), and the Hub "
            f"cannot be used ({'offline mode' if offline else 'no connection'}); fetch them once with network "
            f"access: {fetch}"
        )
    if isinstance(exc, LocalEntryNotFoundError):
        if offline:
            return DatasetError(
                f"{where}: not in the Hugging Face cache {cache}, and offline mode is on (HF_HUB_OFFLINE=1); "
                f"fetch it once with network access: {fetch}"
            )
        cause = exc.__cause__ or exc.__context__
        detail = str(cause if cause is not None else exc).strip().splitlines()
        reason = f"{type(cause).__name__}: {detail[0] if detail else ''}" if cause is not None else (detail[0] if detail else "")
        if isinstance(cause, HfHubHTTPError):
            return DatasetError(
                f"{where}: the Hub at {endpoint} answered with an error ({reason}) and no complete copy is in the "
                f"cache {cache}; try again later, or run where the release is cached"
            )
        return DatasetError(
            f"{where}: cannot reach the Hub at {endpoint} ({reason}) and no complete copy is in the cache {cache}; "
            "check the network connection (and HF_ENDPOINT), or run where the release is cached"
        )
    if isinstance(exc, HfHubHTTPError):
        status = exc.response.status_code if exc.response is not None else "?"
        return DatasetError(f"{where}: the Hub at {endpoint} answered HTTP {status}; try again later ({str(exc).splitlines()[0]})")
    transfer_error: type[Exception]
    try:  # huggingface_hub's HTTP client; a transfer cut mid-file surfaces as its error
        from httpx2 import HTTPError as Httpx2Error

        transfer_error = Httpx2Error
    except ImportError:  # pragma: no cover - an older huggingface_hub on httpx
        from httpx import HTTPError as HttpxError

        transfer_error = HttpxError
    if isinstance(exc, transfer_error):
        return DatasetError(f"{where}: the download from {endpoint} failed ({type(exc).__name__}: {exc}); try again")
    return None
