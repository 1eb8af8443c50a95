"""Fetch a Hub repository's files into the Hugging Face cache, trusting nothing the server says.

huggingface_hub's :func:`~huggingface_hub.snapshot_download` builds cache paths from the
server's answers (the repository ``sha``, each file's ``ETag`` and ``X-Repo-Commit``) at every
per-file request, without checking them: a hostile ``HF_ENDPOINT`` could make it write anywhere.
Checking those values first and then calling it would not close that, since the server could
answer differently the second time. So this module asks for the metadata once, through
huggingface_hub's public API (:meth:`~huggingface_hub.HfApi.repo_info`,
:meth:`~huggingface_hub.HfApi.list_repo_tree`, :func:`~huggingface_hub.hf_hub_url`, its HTTP
session and headers), checks every value (:mod:`povagent.dataset.hub_checks`), and writes
huggingface_hub's own cache layout itself from the checked values only::

    <cache>/datasets--<owner>--<name>/
        blobs/<sha256 of an LFS file, or the git blob id>
        snapshots/<commit>/<file>  ->  ../../blobs/<...>      (relative symlinks)
        refs/<revision>            (holds the commit id)
        trees/<commit>.json        (the tree listing, huggingface_hub's format)

so huggingface_hub (offline) and every other tool read it as their own. Every path is checked to
stay inside the repository's cache folder before it is written (symlinks followed) and again
after. A file's bytes go to a temporary ``*.incomplete`` name first and become a blob only once
their size and hash match the tree listing (the sha256 of an LFS file, the git blob id of any
other); a file that sends more bytes than listed is cut off at once. The tree listing is written
before any file, so a snapshot cut short is seen as incomplete, never trusted. The refs file is
written last. Bounds (:class:`~povagent.dataset.hub_limits.DownloadLimits`): the listing's
sizes against the per-file and total caps before any byte is fetched, and one deadline for the
whole download, metadata included (the work runs in a daemon thread the caller stops waiting for).

Failures are :class:`~povagent.errors.DatasetError`; a value that fails its check is a
:class:`~povagent.dataset.hub_checks.HubValueError` (the caller names the repository); the Hub's
HTTP errors are huggingface_hub's own exceptions, mapped to messages by :mod:`povagent.dataset.hub`.
"""

from __future__ import annotations

import hashlib
import os
import stat
import threading
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from povagent.dataset.hub_budget import Budget, DeadlinePassed, run_parallel
from povagent.dataset.hub_checks import (
    COMMIT_ID,
    HubValueError,
    check_blob_name,
    check_commit_id,
    check_repo_path,
    check_sha256,
    check_size,
    shown,
)
from povagent.dataset.hub_limits import DownloadLimits
from povagent.errors import DatasetError

#: Most files a tree listing may name (the release has about 2,500).
MAX_LISTED = 200_000
#: Bytes per read of a file's body.
CHUNK = 1 << 20
#: The suffix of files being written (huggingface_hub never reads them).
INCOMPLETE = ".incomplete"



class MetadataUnavailable(Exception):
    """The Hub could not say what the revision holds (no connection, a timeout, an HTTP error
    other than "no such revision"): the caller may fall back to a cached copy. ``cause`` is the
    client's error."""

    def __init__(self, cause: Exception) -> None:
        super().__init__(str(cause))
        self.cause = cause


@dataclass(frozen=True)
class ListedFile:
    """One file of the tree listing, checked: where it goes and what its bytes must be."""

    path: str
    size: int
    #: The git blob id the listing gives (``oid``).
    blob_id: str
    #: The LFS sha256, for an LFS file.
    sha256: str | None = None

    @property
    def blob(self) -> str:
        """Its file name in ``blobs/``: huggingface_hub's (the ETag: the sha256 of an LFS file,
        else the git blob id)."""
        return self.sha256 or self.blob_id


def checked_listing(entries: Iterable[tuple[str, int, str, str | None, int | None]]) -> dict[str, ListedFile]:
    """The tree listing as ``{path: ListedFile}``, every value checked.

    ``entries`` are ``(path, size, blob_id, lfs_sha256, lfs_size)``. A name that is also a
    folder of another name (a file ``a`` beside ``a/b``) is refused, as are more than
    :data:`MAX_LISTED` files.
    """
    files: dict[str, ListedFile] = {}
    for path, size, blob_id, lfs_sha256, lfs_size in entries:
        if len(files) >= MAX_LISTED:
            raise HubValueError("tree listing", f"{len(files)}+ files", f"names more than {MAX_LISTED} files")
        check_repo_path(path)
        what = f"of {shown(path)} in the tree listing"
        check_blob_name(blob_id, f"git blob id {what}")
        if lfs_sha256 is not None:
            check_sha256(lfs_sha256, f"LFS sha256 {what}")
            size = check_size(lfs_size, f"LFS size {what}")
        else:
            size = check_size(size, f"size {what}")
        if path in files:
            raise HubValueError("file name in the tree listing", path, "is listed twice")
        files[path] = ListedFile(path, size, blob_id, lfs_sha256)
    folders = {p.rsplit("/", i)[0] for p in files for i in range(1, p.count("/") + 1)}
    clash = sorted(folders & files.keys())
    if clash:
        raise HubValueError("file name in the tree listing", clash[0], "is both a file and a folder of other files")
    return files


def inside(path: str | Path, root: str | Path, *, follow_last: bool = True) -> bool:
    """Whether ``path`` stays inside ``root``, lexically and with every symlink followed.

    ``follow_last=False`` follows the symlinks of the folders only, not of ``path`` itself (a
    snapshot's file is a link into ``blobs/``, outside the snapshot folder by design).
    """
    path, root = os.fspath(path), os.fspath(root)
    lexical = os.path.abspath(path)
    if follow_last:
        real = os.path.realpath(path)
    else:
        real = os.path.join(os.path.realpath(os.path.dirname(lexical)), os.path.basename(lexical))
    for candidate, base in ((lexical, os.path.abspath(root)), (real, os.path.realpath(root))):
        if os.path.commonpath([candidate, base]) != base or candidate == base:
            return False
    return True


def _confined(path: str, root: str, what: str, *, follow_last: bool = True) -> str:
    if not inside(path, root, follow_last=follow_last):
        raise DatasetError(f"refused to write {shown(path, 120)}: {what} would leave {root}")
    return path


def _git_blob_hasher(size: int) -> Any:
    h = hashlib.sha1()
    h.update(b"blob %d\0" % size)
    return h


def _normalize_etag(value: str) -> str:
    value = value.strip()
    if value.startswith("W/"):
        value = value[2:]
    return value.strip('"')


@dataclass
class CacheWriter:
    """Writes one repository's files into huggingface_hub's cache layout, inside ``storage`` only."""

    storage: str
    commit: str

    @property
    def snapshot(self) -> str:
        """``snapshots/<commit>``."""
        return os.path.join(self.storage, "snapshots", self.commit)

    def pointer(self, f: ListedFile) -> str:
        """Where a file appears in the snapshot (checked to stay inside it)."""
        path = os.path.join(self.snapshot, *f.path.split("/"))
        return _confined(path, self.snapshot, f"file {shown(f.path)}", follow_last=False)

    def blob(self, f: ListedFile) -> str:
        """Where a file's bytes are stored (checked to stay inside ``blobs/``)."""
        blobs = os.path.join(self.storage, "blobs")
        return _confined(os.path.join(blobs, f.blob), blobs, f"blob {shown(f.blob)}")

    def has(self, f: ListedFile) -> bool:
        """Whether the snapshot already holds this file (a link into ``blobs/`` of the listed size)."""
        pointer = self.pointer(f)
        if not os.path.isfile(pointer):
            return False
        return inside(os.path.realpath(pointer), os.path.join(self.storage, "blobs")) and os.path.getsize(pointer) == f.size

    def makedirs(self, folder: str) -> None:
        """Create ``folder`` (inside ``storage``), refusing one that leads outside through a symlink."""
        _confined(folder, self.storage, "a folder")
        os.makedirs(folder, exist_ok=True)
        _confined(folder, self.storage, "a folder")

    def link(self, f: ListedFile) -> None:
        """Point ``snapshots/<commit>/<file>`` at its blob, atomically (relative symlink, as
        huggingface_hub makes them)."""
        pointer, blob = self.pointer(f), self.blob(f)
        self.makedirs(os.path.dirname(pointer))
        tmp = f"{pointer}.{uuid.uuid4().hex[:8]}{INCOMPLETE}"
        try:
            os.symlink(os.path.relpath(blob, os.path.dirname(pointer)), tmp)
        except OSError:  # no symlinks here (some filesystems): a copy, as huggingface_hub falls back to
            with open(blob, "rb") as src, open(tmp, "xb") as dst:
                while chunk := src.read(CHUNK):
                    dst.write(chunk)
        os.replace(tmp, pointer)
        self.pointer(f)  # the written path, checked again, then with its symlink followed
        if not inside(os.path.realpath(pointer), os.path.join(self.storage, "blobs")):
            os.unlink(pointer)
            raise DatasetError(f"refused {shown(pointer, 120)}: it resolves outside {self.storage}")

    def write_ref(self, revision: str) -> None:
        """Record ``refs/<revision>`` (the revision is checked by the caller) as this commit."""
        refs = os.path.join(self.storage, "refs")
        path = _confined(os.path.join(refs, *revision.split("/")), refs, f"revision {shown(revision)}")
        self.makedirs(os.path.dirname(path))
        tmp = f"{path}.{uuid.uuid4().hex[:8]}.tmp"
        with open(tmp, "w", encoding="ascii") as out:
            out.write(self.commit)
        os.replace(tmp, path)
        _confined(path, refs, f"revision {shown(revision)}")


def fetch_blob(
    f: ListedFile,
    writer: CacheWriter,
    *,
    url: str,
    headers: dict[str, str],
    budget: Budget,
    progress: Callable[[int], Any],
) -> None:
    """Fetch one file into ``blobs/`` (if not there yet) and link it into the snapshot.

    The bytes are checked against the listing (size, then sha256 or git blob id) before they
    get the blob's name; headers that name a commit or an ETag must agree with it.
    """
    from huggingface_hub import get_session

    blob = writer.blob(f)
    if os.path.isfile(blob) and os.path.getsize(blob) == f.size:
        writer.link(f)
        return
    writer.makedirs(os.path.dirname(blob))
    tmp = f"{blob}.{uuid.uuid4().hex[:8]}{INCOMPLETE}"
    try:
        budget.check()
        with get_session().stream("GET", url, headers=headers, follow_redirects=True, timeout=budget.timeout()) as response:
            first = response.history[0] if response.history else response
            said_commit = first.headers.get("X-Repo-Commit")  # checked on an error answer too
            if said_commit is not None and check_commit_id(said_commit, f"X-Repo-Commit of {shown(f.path)}") != writer.commit:
                raise HubValueError(f"X-Repo-Commit of {shown(f.path)}", said_commit, f"differs from the commit {writer.commit}")
            if response.status_code != 200:  # the body is not read: its size is the server's choice
                reason = response.headers.get("X-Error-Message") or response.reason_phrase
                raise DatasetError(
                    f"{shown(f.path)}, a file of the tree listing, was answered with HTTP {response.status_code} "
                    f"({shown(reason)}); try again later"
                )
            said_etag = first.headers.get("X-Linked-Etag") or first.headers.get("ETag")
            if said_etag is not None:
                etag = _normalize_etag(said_etag)
                if check_blob_name(etag, f"ETag of {shown(f.path)}") not in (f.blob, f.blob_id):
                    raise HubValueError(f"ETag of {shown(f.path)}", etag, f"differs from the tree listing's {f.blob}")
            length = response.headers.get("Content-Length")
            if length is not None and length.isdigit() and int(length) > f.size:
                raise DatasetError(f"{f.path}: the server announced {int(length)} bytes, more than the tree listing's {f.size}")
            hasher = hashlib.sha256() if f.sha256 else _git_blob_hasher(f.size)
            received = 0
            with budget.create_unfinished(tmp) as out:
                for chunk in response.iter_bytes(CHUNK):
                    budget.check()
                    received += len(chunk)
                    if received > f.size:
                        raise DatasetError(f"{f.path}: the server sent more than the tree listing's {f.size} bytes")
                    out.write(chunk)
                    hasher.update(chunk)
                    progress(len(chunk))
        if received != f.size:
            raise DatasetError(f"{f.path}: the server sent {received} bytes, the tree listing says {f.size}")
        digest = hasher.hexdigest()
        if digest != (f.sha256 or f.blob_id):
            kind = "sha256" if f.sha256 else "git blob id"
            raise DatasetError(f"{f.path}: the bytes' {kind} {digest[:16]}... differs from the tree listing's {(f.sha256 or f.blob_id)[:16]}...")
        # readable as the folder's files are (not mkstemp's 0600): other users of a shared cache read it
        os.chmod(tmp, stat.S_IMODE(os.stat(os.path.dirname(tmp)).st_mode) & 0o666)
        with budget.lock:  # a download given up at the deadline keeps nothing it had not finished
            budget.check()
            os.replace(tmp, blob)
        _confined(blob, os.path.join(writer.storage, "blobs"), f"blob {shown(f.blob)}")
        budget.count(files=1, size=received)
    except Exception as exc:
        if budget.remaining() <= 0 and not isinstance(exc, DeadlinePassed):  # a read timed out at the deadline
            raise DeadlinePassed("deadline passed") from exc
        raise
    finally:
        budget.finish(tmp)
    writer.link(f)


def resolve_commit(api: Any, repo_id: str, revision: str, budget: Budget) -> str:
    """The commit id a revision stands for (a commit id stands for itself), checked."""
    if COMMIT_ID.fullmatch(revision):
        return revision
    info = api.repo_info(repo_id=repo_id, repo_type="dataset", revision=revision, timeout=budget.timeout())
    return check_commit_id(getattr(info, "sha", None))


def tree_listing(api: Any, repo_id: str, commit: str, storage: str, budget: Budget) -> dict[str, ListedFile]:
    """The commit's tree listing (from the cache's ``trees/<commit>.json`` if there), checked.

    A listing fetched from the Hub is written to ``trees/<commit>.json`` in huggingface_hub's
    format, before any file, so that a snapshot cut short is seen as incomplete.
    """
    from huggingface_hub._tree_cache import TreeCacheEntry, read_tree_cache, write_tree_cache
    from huggingface_hub.hf_api import RepoFile

    cached = read_tree_cache(storage, commit)
    if cached is not None:
        return checked_listing((p, e.size, e.blob_id, e.lfs_sha256, e.lfs_size) for p, e in cached.items())
    raw: list[tuple[str, int, str, str | None, int | None]] = []
    for entry in api.list_repo_tree(repo_id=repo_id, recursive=True, revision=commit, repo_type="dataset"):
        budget.check()
        if not isinstance(entry, RepoFile):
            continue
        lfs = entry.lfs
        raw.append((entry.path, entry.size, entry.blob_id, lfs.sha256 if lfs else None, lfs.size if lfs else None))
        if len(raw) > MAX_LISTED:
            break
    files = checked_listing(raw)
    trees = os.path.join(storage, "trees")
    _confined(os.path.join(trees, f"{commit}.json"), trees, "the tree listing")
    write_tree_cache(
        storage,
        commit,
        {
            f.path: TreeCacheEntry(size=f.size, blob_id=f.blob_id, lfs_sha256=f.sha256, lfs_size=f.size if f.sha256 else None)
            for f in files.values()
        },
    )
    return files


def check_caps(files: list[ListedFile], limits: DownloadLimits) -> None:
    """Refuse, before any byte is fetched, a file or a total the listing says is above the caps."""
    for f in files:
        if f.size > limits.max_file_bytes:
            raise DatasetError(
                f"{shown(f.path)} is {f.size / 2**20:.1f} MiB in the tree listing, above the cap of "
                f"{limits.max_file_mib:g} MiB a file (raise --max-file-mib, or dataset.download.max_file_mib)"
            )
    total = sum(f.size for f in files)
    if total > limits.max_total_bytes:
        raise DatasetError(
            f"the {len(files)} files are {total / 2**20:.1f} MiB in the tree listing, above the cap of "
            f"{limits.max_total_mib:g} MiB (raise --max-total-mib, or dataset.download.max_total_mib)"
        )


def fetch_snapshot(
    repo_id: str,
    revision: str,
    *,
    storage: str,
    endpoint: str | None,
    allow: list[str] | None,
    ignore: list[str] | None,
    budget: Budget,
    progress: bool,
) -> str:
    """Fetch the files of ``repo_id`` at ``revision`` the patterns select into ``storage``
    (the repository's folder in the cache); returns the snapshot folder.

    Runs in the calling thread; :func:`with_deadline` bounds it.
    """
    import httpx2
    from huggingface_hub import HfApi, hf_hub_url
    from huggingface_hub.errors import HfHubHTTPError, RevisionNotFoundError
    from huggingface_hub.utils import OfflineModeIsEnabled, build_hf_headers, filter_repo_objects
    from tqdm.auto import tqdm

    api = HfApi(endpoint=endpoint)
    try:  # as snapshot_download does: without the metadata, a complete cached copy may serve
        commit = resolve_commit(api, repo_id, revision, budget)
        budget.check()
        files = tree_listing(api, repo_id, commit, storage, budget)
    except RevisionNotFoundError:
        raise
    except (httpx2.ConnectError, httpx2.TimeoutException, OfflineModeIsEnabled, HfHubHTTPError) as exc:
        if budget.remaining() <= 0:
            raise DeadlinePassed("deadline passed") from exc
        raise MetadataUnavailable(exc) from exc
    chosen = [files[p] for p in filter_repo_objects(items=sorted(files), allow_patterns=allow, ignore_patterns=ignore)]
    check_caps(chosen, budget.limits)
    writer = CacheWriter(storage, commit)
    missing = [f for f in chosen if not writer.has(f)]
    headers = build_hf_headers()
    headers["Accept-Encoding"] = "identity"  # sizes and hashes are of the stored bytes
    bar = tqdm(
        total=sum(f.size for f in missing),
        unit="B",
        unit_scale=True,
        desc=f"Fetching {len(missing)} files",
        disable=not progress or not missing,
    )
    lock = threading.Lock()

    def advance(n: int) -> None:
        with lock:
            bar.update(n)

    def end_bar() -> None:
        with lock:
            bar.close()

    budget.on_abandon.append(end_bar)  # at the deadline, the bar's line ends before the error

    def one(f: ListedFile) -> None:
        url = hf_hub_url(repo_id, f.path, repo_type="dataset", revision=commit, endpoint=endpoint)
        fetch_blob(f, writer, url=url, headers=dict(headers), budget=budget, progress=advance)

    try:
        run_parallel(one, missing, budget)
    finally:
        end_bar()
    for f in chosen:  # after writing: every file is in place, inside the cache, of the listed size
        if not writer.has(f):
            raise DatasetError(f"{shown(f.path)}: not in the snapshot after the download (or not of the listed size)")
    if revision != commit:
        writer.write_ref(revision)
    return writer.snapshot
