"""How images travel to a model: inline data URLs, ``file://`` URLs, or a static server's URLs.

``images: {transport: inline}`` (the default) sends each image base64-encoded in the request,
as every provider accepts. A model server that can read the images itself is spared that
(7.5 MB of JSON per 30-frame request, encoded by the client and decoded by the server):

* ``file``: ``file://`` URLs of the dataset's own files, for a vLLM server on the same machine
  or a shared file system (vLLM's ``--allowed-local-media-path`` must cover them);
* ``http``: URLs of a small read-only server (:mod:`povagent.exchange.image_server`) bound
  where the user says, for a model server on another host.

Images without a file of their own (frames with markers drawn on them, letterboxed images)
are written once to a cache folder, named by content hash, and referenced the same way.

Requests name images by hash whatever the transport (the cache key, the rows and resuming
never see a URL), so a run may change transport between sessions and resume from the cache.
This module builds URLs and owns the static server's lifetime; it never calls a model.
"""

from __future__ import annotations

import abc
import contextlib
import os
import secrets
import threading
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar, Iterator, Literal

from povagent.errors import ConfigError
from povagent.exchange.image_server import ImageReferenceError, StaticImageServer

if TYPE_CHECKING:
    from povagent.config.models import ImagesSpec
    from povagent.exchange.images import ImageStore

__all__ = [
    "TRANSPORTS",
    "FileTransport",
    "HttpTransport",
    "ImageReferenceError",
    "ImageTransport",
    "InlineTransport",
    "image_transport",
    "make_transport",
    "open_image_transport",
]

TransportName = Literal["inline", "file", "http"]
#: The transports a pipeline may name.
TRANSPORTS: tuple[TransportName, ...] = ("inline", "file", "http")

_SUFFIXES = {"image/png": ".png", "image/jpeg": ".jpeg", "image/webp": ".webp", "image/gif": ".gif"}


class ImageTransport(abc.ABC):
    """Turns an image hash into the URL a model receives."""

    name: ClassVar[TransportName]

    @abc.abstractmethod
    def url(self, images: ImageStore, image_hash: str) -> str:
        """The URL of one image of ``images`` (raises :class:`ImageReferenceError` when it cannot be sent)."""

    def close(self) -> None:  # noqa: B027 -- optional hook: most transports hold nothing
        """Release what the transport holds (the static server); called when the run ends."""


class InlineTransport(ImageTransport):
    """``data:image/png;base64,...`` URLs: the image travels inside the request."""

    name: ClassVar[TransportName] = "inline"

    def url(self, images: ImageStore, image_hash: str) -> str:
        """The image's data URL (encoded once while the store keeps it)."""
        return images.data_url(image_hash)


class _ByReference(ImageTransport):
    """Images as files: the dataset's own, or derived ones written once to ``cache_dir``."""

    def __init__(self, cache_dir: str | Path) -> None:
        self.cache_dir = Path(cache_dir).absolute()
        self._urls: dict[str, str] = {}
        self._lock = threading.Lock()
        self.written = 0

    def url(self, images: ImageStore, image_hash: str) -> str:
        """The image's URL, made once per hash."""
        known = self._urls.get(image_hash)
        if known is not None:
            return known
        path = images.source_file(image_hash)
        if path is None:
            path = self._write(images, image_hash)
        url = self._url_of(path.absolute(), image_hash, images.info(image_hash).media_type)
        with self._lock:
            return self._urls.setdefault(image_hash, url)

    @abc.abstractmethod
    def _url_of(self, path: Path, image_hash: str, media_type: str) -> str:
        """The URL of a file holding the image."""

    def _write(self, images: ImageStore, image_hash: str) -> Path:
        """The derived image's file under ``cache_dir`` (written once; named by its hash)."""
        suffix = _SUFFIXES.get(images.info(image_hash).media_type, ".png")
        target = self.cache_dir / f"{image_hash}{suffix}"
        if target.is_file() and not target.is_symlink():  # content-addressed: it holds these very bytes
            return target  # (a link planted under the name would have the server read elsewhere: replaced below)
        self.cache_dir.mkdir(parents=True, exist_ok=True)
        # written aside and renamed, so a model server never reads a half-written file; made
        # as an ordinary file is (0666 less the umask: 0644 under umask 022), not mkstemp's
        # 0600, so a model server running as another user can read what it is sent
        tmp = str(self.cache_dir / f".{image_hash[:16]}-{os.getpid()}-{secrets.token_hex(6)}.part")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(images.encoded_bytes(image_hash))
            os.replace(tmp, target)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
        with self._lock:
            self.written += 1
        return target


class FileTransport(_ByReference):
    """``file:///...`` URLs, for a model server that reads this machine's files."""

    name: ClassVar[TransportName] = "file"

    def _url_of(self, path: Path, image_hash: str, media_type: str) -> str:
        return path.as_uri()


class HttpTransport(_ByReference):
    """URLs of a :class:`StaticImageServer` that serves the dataset and ``cache_dir`` read-only."""

    name: ClassVar[TransportName] = "http"

    def __init__(self, cache_dir: str | Path, server: StaticImageServer) -> None:
        super().__init__(cache_dir)
        self.server = server

    def _url_of(self, path: Path, image_hash: str, media_type: str) -> str:
        return self.server.publish(path, image_hash, media_type)

    def close(self) -> None:
        """Stop the static server."""
        self.server.stop()


def make_transport(
    name: TransportName,
    *,
    dataset_root: str | Path,
    cache_dir: str | Path,
    bind: str | None = None,
    public_url: str | None = None,
) -> ImageTransport:
    """The transport called ``name``; ``http`` starts its static server (bound at ``bind``)."""
    if name == "inline":
        return InlineTransport()
    if name == "file":
        return FileTransport(cache_dir)
    if name == "http":
        Path(cache_dir).mkdir(parents=True, exist_ok=True)  # a served root must exist to resolve
        bind = bind or "127.0.0.1:0"
        server = StaticImageServer([dataset_root, cache_dir], bind=bind, public_url=public_url)
        try:
            server.start()
        except OSError as exc:  # a taken port, an address not on this machine
            raise ConfigError(f"images: bind {bind}: the image server cannot listen there: {exc.strerror or exc}") from None
        return HttpTransport(cache_dir, server)
    raise ValueError(f"unknown image transport {name!r}; known: {', '.join(TRANSPORTS)}")


@contextlib.contextmanager
def image_transport(images: ImageStore, transport: ImageTransport) -> Iterator[ImageTransport]:
    """Send ``images`` by ``transport`` for the duration of the block, then close it."""
    previous = images.transport
    images.transport = transport
    try:
        yield transport
    finally:
        images.transport = previous
        transport.close()


@contextlib.contextmanager
def open_image_transport(
    spec: ImagesSpec, images: ImageStore, *, dataset_root: str | Path, output: str | Path
) -> Iterator[ImageTransport]:
    """The pipeline's ``images:`` transport, attached to ``images`` for a run; closed after it.

    ``http`` starts the static server (serving ``dataset_root`` and the cache folder) here and
    stops it when the block ends, however it ends.
    """
    cache_dir = spec.cache_folder(Path(output))
    if spec.transport != "inline" and cache_dir.is_relative_to(Path(output)):
        from povagent.files.confined_write import ConfinedFolder

        # the default folder lies in the run folder (untrusted): a link planted there would have
        # derived images written, and served, elsewhere
        ConfinedFolder(Path(output), cache_dir.relative_to(Path(output))).close()
    transport = make_transport(
        spec.transport,
        dataset_root=dataset_root,
        cache_dir=cache_dir,
        bind=spec.bind,
        public_url=spec.public_url,
    )
    with image_transport(images, transport):
        yield transport
