"""A Hugging Face Hub file server on 127.0.0.1 for tests and plugin authors.

It serves one folder as a dataset repository at one commit, speaking the part of the Hub's
HTTP API that :func:`huggingface_hub.snapshot_download` uses:

* ``GET /api/datasets/<repo>/revision/<rev>``: the repository's info (``sha``, ``siblings``);
* ``GET /api/datasets/<repo>/tree/<rev>?recursive=...``: the file listing, in pages linked
  by a ``Link: <...>; rel="next"`` header as the Hub pages them;
* ``HEAD`` and ``GET /datasets/<repo>/resolve/<rev>/<path>``: a file, with the headers the
  client checks (``ETag``, ``X-Repo-Commit``, ``Content-Length``) and byte ranges.

Errors carry the Hub's ``X-Error-Code`` header (``RepoNotFound``, ``RevisionNotFound``,
``EntryNotFound``), which is how the client tells them apart. A revision is a branch or tag
name from ``revisions`` (default ``main``) or the commit hash itself.

Point a client at it with ``endpoint=server.url`` (or ``HF_ENDPOINT``, which huggingface_hub
reads when it is first imported: set it before that, e.g. in a subprocess). Every request is
recorded (method and path), so a test can check which files were fetched.

Files matching ``lfs_patterns`` are served as the Hub serves LFS files: listed with
``lfs: {oid: <sha256>, size, pointerSize}`` (their ``oid`` is the git id of the LFS pointer) and
answered with ``X-Linked-Etag: <sha256>`` and ``X-Linked-Size``.

A test can make it hostile through :attr:`HubServer.lies` (a :class:`HubLies`): a repository
``sha``, an ``ETag`` or an ``X-Repo-Commit`` holding paths, bytes that differ from the tree
listing (longer, or the same length with other bytes), listed files that answer 404, any
revision accepted, a file transfer that stalls. A repository file name may itself be hostile
(``files={"../x.pth": ...}``): it is listed as given. Nothing of that is reachable from the
command line, which serves a folder honestly.

Bounded like :class:`povagent.testing.loopback_server.LoopbackServer`: loopback only, stops by
itself after ``max_lifetime_s``; a folder's files are hashed once at start and read from disk
when asked for.
"""

from __future__ import annotations

import argparse
import fnmatch
import hashlib
import json
import re
import socket
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler
from pathlib import Path
from typing import Any, Iterable, Mapping
from urllib.parse import parse_qs, quote, unquote, urlsplit

from povagent.testing.background_server import BackgroundServer, TrackedHTTPServer

__all__ = ["HubLies", "HubRequest", "HubServer"]


@dataclass(frozen=True)
class HubRequest:
    """One request the server received: method, path (decoded, without the query) and query."""

    method: str
    path: str
    query: dict[str, list[str]]
    received_at: float


@dataclass
class HubLies:
    """What a hostile Hub answers instead of the truth (every field off by default).

    For tests of a client's distrust: each field is one lie a mirror or a hostile
    ``HF_ENDPOINT`` could tell.
    """

    #: The repository ``sha`` that ``revision`` answers (the server then accepts it as a revision).
    sha: str | None = None
    #: The ``ETag`` of every ``resolve`` answer (an LFS file's ``X-Linked-Etag`` too).
    etag: str | None = None
    #: The ``X-Repo-Commit`` of every ``resolve`` answer, a 404 included.
    repo_commit: str | None = None
    #: Bytes served for a repository path instead of its own (the listing still describes its own).
    served: dict[str, bytes] = field(default_factory=dict)
    #: Listed paths whose ``resolve`` answers 404 ``EntryNotFound``.
    missing: set[str] = field(default_factory=set)
    #: Every revision resolves (to the commit), whatever it is.
    any_revision: bool = False
    #: Seconds a file's ``GET`` stalls after its headers and half its body (a server that hangs).
    stall_s: float = 0.0


def lfs_pointer(data: bytes) -> bytes:
    """The git LFS pointer file of ``data`` (what git stores, and what the listing's ``oid`` hashes)."""
    return f"version https://git-lfs.github.com/spec/v1\noid sha256:{hashlib.sha256(data).hexdigest()}\nsize {len(data)}\n".encode()


def git_blob_id(data: bytes) -> str:
    """The git object id of a file's bytes: the Hub's ``oid`` and ``ETag`` of a non-LFS file."""
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


_API = re.compile(r"^/api/(?P<kind>datasets|models)/(?P<repo>[^/]+/[^/]+)/(?P<what>revision|tree)/(?P<rest>.+)$")
_RESOLVE = re.compile(r"^/(?P<prefix>datasets/)?(?P<repo>[^/]+/[^/]+)/resolve/(?P<rev>[^/]+)/(?P<path>.+)$")


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    server: _Server

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib signature
        """Silence the stdlib's per-request stderr log."""

    def do_HEAD(self) -> None:  # noqa: N802 - stdlib name
        """File metadata (``resolve`` URLs only)."""
        self._route("HEAD")

    def do_GET(self) -> None:  # noqa: N802 - stdlib name
        """Repository info, tree listing or file bytes."""
        self._route("GET")

    # -- routing --------------------------------------------------------------------------
    def _route(self, method: str) -> None:
        owner = self.server.owner
        split = urlsplit(self.path)
        # the client quotes the revision (and paths); match on raw segments, decode each
        raw_path = split.path
        query = parse_qs(split.query)
        owner._record(HubRequest(method, unquote(raw_path), query, time.monotonic()))
        if owner.fail_status is not None:
            self._error(owner.fail_status, "injected failure", None)
            return
        m = _API.match(raw_path)
        if m and method == "GET":
            if not self._repo_ok(m["kind"], unquote(m["repo"])):
                return
            if m["what"] == "revision":
                self._repo_info(unquote(m["rest"]))
            else:
                rev, _, sub = m["rest"].partition("/")
                self._tree(unquote(rev), unquote(sub), query)
            return
        m = _RESOLVE.match(raw_path)
        if m:
            kind = "datasets" if m["prefix"] else "models"
            if not self._repo_ok(kind, unquote(m["repo"])):
                return
            self._file(method, unquote(m["rev"]), unquote(m["path"]))
            return
        self._error(404, "Sorry, we can't find the page you are looking for.", None)

    def _repo_ok(self, kind: str, repo: str) -> bool:
        owner = self.server.owner
        if kind != owner.kind or repo != owner.repo_id:
            self._error(404, "Repository not found", "RepoNotFound")
            return False
        return True

    def _commit(self, revision: str) -> str | None:
        owner = self.server.owner
        lies = owner.lies
        if revision in (owner.commit, lies.sha) or revision in owner.revisions or lies.any_revision:
            return lies.sha or owner.commit
        self._error(404, f"Invalid rev id: {revision}", "RevisionNotFound")
        return None

    # -- endpoints --------------------------------------------------------------------------
    def _repo_info(self, revision: str) -> None:
        owner = self.server.owner
        commit = self._commit(revision)
        if commit is None:
            return
        self._json(
            {
                "_id": commit[:24],
                "id": owner.repo_id,
                "author": owner.repo_id.split("/")[0],
                "sha": commit,  # the lie, if the server tells one
                "private": False,
                "gated": False,
                "disabled": False,
                "lastModified": "2026-01-01T00:00:00.000Z",
                "tags": [],
                "siblings": [{"rfilename": p} for p in owner.paths],
            }
        )

    def _tree(self, revision: str, under: str, query: Mapping[str, list[str]]) -> None:
        owner = self.server.owner
        if self._commit(revision) is None:
            return
        recursive = query.get("recursive", ["false"])[0].lower() == "true"
        entries = owner.tree_entries(under, recursive)
        cursor = query.get("cursor", ["0"])[0]
        if not cursor.isdigit():
            self._error(400, f"Invalid cursor: {cursor}", None)
            return
        start = int(cursor)
        page = entries[start : start + owner.page_size]
        headers = {}
        if start + owner.page_size < len(entries):
            # the Hub pages long listings with a cursor carried in a Link header
            rev = quote(revision, safe="")
            sub = "/" + quote(under, safe="") if under else ""
            nxt = (
                f"{owner.url}/api/{owner.kind}/{owner.repo_id}/tree/{rev}{sub}"
                f"?recursive={str(recursive).lower()}&expand=false&cursor={start + owner.page_size}"
            )
            headers["Link"] = f'<{nxt}>; rel="next"'
        self._json(page, headers)

    def _file(self, method: str, revision: str, path: str) -> None:
        owner = self.server.owner
        commit = self._commit(revision)
        if commit is None:
            return
        lies = owner.lies
        said_commit = lies.repo_commit or commit
        if path not in owner.files or path in lies.missing:
            self._error(404, "Entry not found", "EntryNotFound", {"X-Repo-Commit": said_commit})
            return
        data = lies.served.get(path) if path in lies.served else None
        if data is None:
            data = owner.read(path) if method == "GET" else b""
            size = owner._sizes[path]
        else:
            size = len(data)
        sha256 = owner._lfs.get(path)
        etag = f'"{lies.etag or (sha256 or owner._oids[path])}"'
        status, length, extra = 200, size, {}
        first, last = 0, size - 1
        rng = re.fullmatch(r"bytes=(\d+)-(\d*)", self.headers.get("Range", ""))
        if rng:
            first = int(rng[1])
            last = min(int(rng[2]), size - 1) if rng[2] else size - 1
            length = max(0, last - first + 1)
            status, extra = 206, {"Content-Range": f"bytes {first}-{first + length - 1}/{size}"}
        self.send_response(status)
        self.send_header("Content-Type", "application/octet-stream")
        self.send_header("Content-Length", str(length))
        self.send_header("ETag", etag)
        if sha256 is not None:  # an LFS file: the Hub names its blob by the linked sha256
            self.send_header("X-Linked-Etag", f'"{lies.etag or sha256}"')
            self.send_header("X-Linked-Size", str(size))
        self.send_header("X-Repo-Commit", said_commit)
        self.send_header("Accept-Ranges", "bytes")
        for k, v in extra.items():
            self.send_header(k, v)
        self.end_headers()
        if method == "GET":
            body = data[first : first + length]
            if lies.stall_s > 0:
                half = len(body) // 2
                self.wfile.write(body[:half])
                self.wfile.flush()
                owner._stopping.wait(lies.stall_s)  # a stop() ends the stall at once
                body = body[half:]
            try:
                self.wfile.write(body)
            except OSError:  # the client gave up during a stall
                pass

    # -- sending ----------------------------------------------------------------------------
    def _json(self, payload: Any, headers: Mapping[str, str] | None = None) -> None:
        data = json.dumps(payload).encode()
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(data)

    def _error(self, status: int, message: str, code: str | None, headers: Mapping[str, str] | None = None) -> None:
        data = json.dumps({"error": message}).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        if code is not None:
            self.send_header("X-Error-Code", code)
            self.send_header("X-Error-Message", message)
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(data)


class _Server(TrackedHTTPServer):
    request_queue_size = 64
    owner: HubServer


class HubServer(BackgroundServer):
    """Serve ``folder`` as the Hub repository ``repo_id`` on 127.0.0.1, in a background thread.

    ``files`` may be given instead of ``folder`` (a mapping of repository path to bytes). The
    folder's contents are taken as they are at start (its commit hash depends on them).
    ``revisions`` are the branch or tag names that resolve to the one commit (its hash, derived
    from the files, resolves too). ``page_size`` is the tree listing's page length (the Hub's is
    1000). ``repo_type`` is ``dataset`` or ``model``. Set :attr:`fail_status` to answer every
    request with that status (a Hub outage). The server stops itself after
    ``max_lifetime_s`` seconds; use it as a context manager.
    """

    server_class = _Server
    handler = _Handler
    thread_name = "hub-server"
    # a stopped Hub cuts both ways: a pooled keep-alive connection must look like a network failure
    cut_connections = socket.SHUT_RDWR

    def __init__(
        self,
        folder: str | Path | None = None,
        *,
        repo_id: str = "owl-owl/POVBench",
        files: Mapping[str, bytes] | None = None,
        revisions: Iterable[str] = ("main",),
        repo_type: str = "dataset",
        page_size: int = 1000,
        port: int = 0,
        max_lifetime_s: float = 120.0,
        lfs_patterns: Iterable[str] = (),
        lies: HubLies | None = None,
    ) -> None:
        if (folder is None) == (files is None):
            raise ValueError("give exactly one of folder or files")
        if repo_type not in ("dataset", "model"):
            raise ValueError(f"repo_type {repo_type!r}: only 'dataset' and 'model' are served")
        super().__init__(port, max_lifetime_s)
        self.repo_id = repo_id
        self.kind = repo_type + "s"
        # a folder's files are read when asked for (a full-size release is hundreds of MiB)
        self.files: dict[str, bytes | Path] = dict(files) if files is not None else dict(_list_folder(Path(folder or "")))
        self.paths = sorted(self.files)
        self._oids = {p: git_blob_id(self.read(p)) for p in self.paths}
        self._sizes = {p: len(b) if isinstance(b, bytes) else b.stat().st_size for p, b in self.files.items()}
        patterns = tuple(lfs_patterns)
        #: sha256 of each file served as an LFS file.
        self._lfs = {
            p: hashlib.sha256(self.read(p)).hexdigest() for p in self.paths if any(fnmatch.fnmatch(p, pat) for pat in patterns)
        }
        self._pointer_sizes: dict[str, int] = {}
        for p in self._lfs:  # git holds the pointer; the listing's oid is the pointer's
            pointer = lfs_pointer(self.read(p))
            self._oids[p], self._pointer_sizes[p] = git_blob_id(pointer), len(pointer)
        self.revisions = tuple(revisions)
        self.commit = hashlib.sha1(b"".join(p.encode() + b"\0" + self._oids[p].encode() for p in self.paths)).hexdigest()
        self.page_size = max(1, page_size)
        #: When set, every request is answered with this HTTP status (a Hub outage: 500, 503...).
        self.fail_status: int | None = None
        #: What the server lies about (nothing by default); may be changed while it serves.
        self.lies = lies or HubLies()
        self.requests: list[HubRequest] = []

    @property
    def url(self) -> str:
        """The endpoint clients use (``HF_ENDPOINT`` / ``endpoint=``): ``http://127.0.0.1:<port>``."""
        return f"http://127.0.0.1:{self.port}"

    # -- what was asked ------------------------------------------------------------------------
    def _record(self, request: HubRequest) -> None:
        with self._lock:
            self.requests.append(request)

    def read(self, path: str) -> bytes:
        """The bytes of a repository file (``KeyError`` if there is none)."""
        source = self.files[path]
        return source if isinstance(source, bytes) else source.read_bytes()

    def fetched_files(self) -> list[str]:
        """Repository paths whose bytes were sent (``GET`` on a ``resolve`` URL), in order."""
        out = []
        with self._lock:
            requests = list(self.requests)
        for r in requests:
            m = _RESOLVE.match(r.path)
            if r.method == "GET" and m:
                out.append(m["path"])
        return out

    def tree_entries(self, under: str = "", recursive: bool = True) -> list[dict[str, Any]]:
        """The tree listing under a folder, as the Hub's ``tree`` endpoint returns it."""
        prefix = under.strip("/") + "/" if under.strip("/") else ""
        folders: set[str] = set()
        files: list[dict[str, Any]] = []
        for p in self.paths:
            if not p.startswith(prefix):
                continue
            rest = p[len(prefix) :]
            parts = rest.split("/")
            for i in range(1, len(parts)):
                if recursive or i == 1:
                    folders.add(prefix + "/".join(parts[:i]))
            if recursive or len(parts) == 1:
                entry: dict[str, Any] = {"type": "file", "oid": self._oids[p], "size": self._sizes[p], "path": p}
                if p in self._lfs:
                    entry["lfs"] = {"oid": self._lfs[p], "size": self._sizes[p], "pointerSize": self._pointer_sizes[p]}
                files.append(entry)
        dirs = [{"type": "directory", "oid": hashlib.sha1(d.encode()).hexdigest(), "path": d} for d in sorted(folders)]
        return sorted(dirs + files, key=lambda e: e["path"])


def _list_folder(folder: Path) -> dict[str, Path]:
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder}: not a folder")
    return {p.relative_to(folder).as_posix(): p for p in sorted(folder.rglob("*")) if p.is_file()}


def argument_parser() -> argparse.ArgumentParser:
    """The options of ``python -m povagent.testing.hub_server``, each explained."""
    from povagent.testing.server_command import port_number

    ap = argparse.ArgumentParser(
        prog="python -m povagent.testing.hub_server",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Serve a folder as a Hugging Face Hub dataset repository on 127.0.0.1, so\n"
        "that povagent download and huggingface_hub fetch it without the network. The\n"
        "first line it prints is the HF_ENDPOINT to export; it serves until Ctrl-C or\n"
        "--lifetime.",
        epilog="example:\n"
        "  python -m povagent.testing.hub_server data/povbench --port 8001\n"
        "  HF_ENDPOINT=http://127.0.0.1:8001 povagent download     (in another shell)",
    )
    ap.add_argument("folder", type=Path, metavar="FOLDER", help="the folder to serve (e.g. a dataset in the release layout)")
    ap.add_argument("--repo", default="owl-owl/POVBench", metavar="OWNER/NAME",
                    help="the dataset repository name clients ask for (default: %(default)s)")
    ap.add_argument("--port", type=port_number, default=0, metavar="N",
                    help="port on 127.0.0.1 to listen on (default: 0, any free port)")
    ap.add_argument("--lifetime", type=float, default=3600.0, metavar="SECONDS",
                    help="stop after this many seconds (default: %(default).0f)")
    return ap


def main(argv: list[str] | None = None) -> None:
    """Serve a folder as a Hub dataset repository until interrupted
    (``python -m povagent.testing.hub_server FOLDER``).

    A missing folder, bad options and a port that cannot be bound end with a one-line message
    and exit code 2, never a traceback.
    """
    from povagent.testing.server_command import bind_failure

    ap = argument_parser()
    args = ap.parse_args(argv)
    if not args.folder.is_dir():
        ap.error(f"{args.folder}: not a folder")
    server = HubServer(args.folder, repo_id=args.repo, port=args.port, max_lifetime_s=args.lifetime)
    try:
        server.start()
    except OSError as exc:
        ap.exit(2, f"{ap.prog}: error: {bind_failure(args.port, exc)}\n")
    print(f"HF_ENDPOINT={server.url}  ({args.repo} at {server.commit})", flush=True)
    try:
        while server._server is not None:
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()


if __name__ == "__main__":
    main()
