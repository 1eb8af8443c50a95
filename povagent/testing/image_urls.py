"""Image URLs as an OpenAI-compatible server (vLLM) reads them: ``data:`` base64, ``file://``
beneath an allowed local media root only, and ``http(s)://`` from the loopback host only.

:class:`~povagent.testing.loopback_server.LoopbackServer` fetches a request's images with these
when told to, so a test sees what a real server would refuse. Each refusal is an
:class:`ImageFetchError` saying why.
"""

from __future__ import annotations

import base64
import binascii
import os
import stat
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass
from pathlib import Path

_LOOPBACK_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})


@dataclass(frozen=True)
class FetchedImage:
    """One image a request carried or referred to, as the server got it.

    ``scheme``: ``data``, ``file`` or ``http``; ``sha256`` and ``size`` of the bytes; ``data``
    the bytes themselves unless the server was told not to keep them.
    """

    scheme: str
    sha256: str
    size: int
    data: bytes | None = None


class ImageFetchError(Exception):
    """An image URL the server could not (or would not) fetch."""


def _opened_path(fd: int, path: Path) -> Path | None:
    """The real path of the file open as ``fd``: the kernel's answer where ``/proc`` has it
    (Linux), else ``path`` resolved; ``None`` when neither can say."""
    try:
        return Path(os.readlink(f"/proc/self/fd/{fd}"))
    except OSError:
        try:
            return path.resolve(strict=True)
        except (OSError, RuntimeError):
            return None


def decode_data_url(url: str) -> bytes:
    """The bytes of a ``data:...;base64,`` URL."""
    header, sep, payload = url.partition(",")
    if not sep or not header.endswith(";base64"):
        raise ImageFetchError("data URL is not base64")
    try:
        return base64.b64decode(payload, validate=True)
    except (binascii.Error, ValueError) as exc:
        raise ImageFetchError(f"bad base64 in data URL: {exc}") from None


def read_file_url(url: str, root: Path | None) -> bytes:
    """The bytes of a ``file://`` URL, as vLLM reads one: only when a local media ``root`` is
    allowed, and only beneath it."""
    if root is None:
        raise ImageFetchError("file:// URLs are not allowed (no local_media_root)")
    parsed = urllib.parse.urlparse(url)
    if parsed.netloc not in ("", "localhost"):
        raise ImageFetchError(f"file URL names a host ({parsed.netloc})")
    path = Path(urllib.request.url2pathname(parsed.path))
    # open first, then ask the kernel which file was opened (symlinks resolved): one
    # readlink instead of a component-by-component realpath walk, and no window between
    # the check and the read; O_NONBLOCK so a FIFO planted in the folder cannot stall us
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise ImageFetchError(f"cannot open {path}: {exc}") from None
    try:
        real = _opened_path(fd, path)
        if real is None or not real.is_relative_to(root):
            raise ImageFetchError(f"{path} is outside the allowed local media path {root}")
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise ImageFetchError(f"{path} is not a regular file")
        with os.fdopen(os.dup(fd), "rb") as f:
            return f.read()
    except OSError as exc:
        raise ImageFetchError(f"cannot read {path}: {exc}") from None
    finally:
        os.close(fd)


def download(url: str) -> bytes:
    """The bytes at an ``http(s)://`` URL on the loopback host (no other host is fetched from)."""
    host = urllib.parse.urlparse(url).hostname or ""
    if host not in _LOOPBACK_HOSTS:
        raise ImageFetchError(f"{url}: only 127.0.0.1 is fetched from (host {host!r})")
    try:
        with urllib.request.urlopen(url, timeout=10) as response:  # noqa: S310 - loopback only
            return response.read()
    except (urllib.error.URLError, OSError) as exc:
        raise ImageFetchError(f"cannot download {url}: {exc}") from None
