"""The run-wide image store: each image read and encoded once, shared by every request.

Images are named by the SHA-256 of their encoded bytes. A file is read once (its path is
memoized; the runner reads files in a worker thread ahead of the strategy); a derived image (a
frame with markers drawn on it) is made once per (source hash, recipe key). Encoded bytes and base64 data URLs are kept in an LRU bounded by bytes; an evicted
entry is rebuilt from its recipe (the file, or the derivation) on next use, which the counters
record, so a benchmark can check "one encode per distinct image" when memory suffices.
In-memory images (:meth:`ImageStore.add_pil`) have nothing to be rebuilt from: their bytes stay
for the store's lifetime. An image its owner names and encodes itself (:meth:`ImageStore.add_unencoded`:
the agent's frames, named by their pixels) is encoded only when its bytes are first asked for,
so a backend that never looks at pixels never pays for an encode.

A run also tells the store when it is done with files (:meth:`ImageStore.hold_files`,
:meth:`ImageStore.release_files`): a house's frames are held while any of its keys is pending
and let go after its last one, so the store keeps the houses in flight, not the houses seen.
Bytes kept long after their last use would sit between the transient request bodies (several
MB each) and hold the heap open: the LRU bound caps them, a release frees them when they are
done with. A released image is rebuilt from its file if it is used again (counted in
``rebuilds``); holds are counted, so runs sharing one store (a sweep's cells) keep each
other's images.

A file that is not a sound image (truncated, corrupt, not an image) is refused when added, with
an error naming the file: the bytes are checked as they are read (a PNG's chunks and checksums,
other formats decoded), once per file, never when a request is built.
"""

from __future__ import annotations

import base64
import functools
import hashlib
import io
import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Protocol, cast

from PIL import Image, UnidentifiedImageError

from povagent.dataset.image_files import ImageFileError, check_image_bytes
from povagent.errors import DatasetError, ReadTargetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular

#: Default memory bound for encoded bytes plus data URLs.
DEFAULT_MAX_BYTES = 256 * 1024 * 1024


def encode_png(image: Image.Image) -> bytes:
    """``image`` as the PNG every in-memory image is sent as (the store's own and the agent's
    frames): compress level 1, several times faster than the default and a little larger."""
    buf = io.BytesIO()
    image.save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


@dataclass(frozen=True)
class StoredImage:
    """What the store knows about one image without holding its bytes."""

    image_hash: str
    width: int
    height: int
    media_type: str


@dataclass
class ImageStoreStats:
    """Counters: file reads, PNG encodes (derived images), base64 encodes, rebuilds after eviction."""

    file_reads: int = 0
    png_encodes: int = 0
    base64_encodes: int = 0
    rebuilds: int = 0


class StoreTransport(Protocol):
    """How images travel, as the store sees it (an :class:`~povagent.exchange.transport.ImageTransport`):
    a name (``inline``, ``file``, ``http``) and the URL a model is sent for one image. The store
    names only this, so it never depends on the transports built on top of it."""

    @property
    def name(self) -> str:
        """The transport's name, as a pipeline's ``images.transport`` gives it."""
        ...

    def url(self, images: ImageStore, image_hash: str) -> str:
        """The URL of one image of ``images``."""
        ...


class ImageStore:
    """Content-addressed images for one run or sweep (thread-safe)."""

    def __init__(self, max_bytes: int = DEFAULT_MAX_BYTES) -> None:
        self.max_bytes = max_bytes
        self.stats = ImageStoreStats()
        self._lock = threading.RLock()
        self._by_path: dict[Path, StoredImage] = {}
        self._by_hash: dict[str, StoredImage] = {}
        self._recipes: dict[str, Callable[[], bytes]] = {}
        #: Images registered by :meth:`add_unencoded` whose bytes were never asked for yet.
        self._unencoded: set[str] = set()
        #: The file an image was first read from (named in decode errors).
        self._sources: dict[str, str] = {}
        self._derived: dict[tuple[str, str], str] = {}
        self._cache: OrderedDict[tuple[str, str], bytes | str] = OrderedDict()
        self._cached_bytes = 0
        # the file each file-backed image was first read from (what file:// and http:// refer to)
        self._files: dict[str, Path] = {}
        #: How many runs hold each file (:meth:`hold_files`); its bytes are dropped at zero.
        self._holds: dict[Path, int] = {}
        #: How :meth:`url` sends images (see :mod:`povagent.exchange.transport`); ``None``:
        #: inline data URLs. The runner sets it for the length of a run.
        self.transport: StoreTransport | None = None

    # -- adding -------------------------------------------------------------------------------
    def add_file(self, path: str | Path, data: bytes | None = None) -> StoredImage:
        """Register an image file (read once per run); returns its hash and size. ``data``: the
        file's bytes, when the caller has just read them itself (read confined and hashed, as
        the active mode's views are), so they are not read a second time.

        Safe to call from a worker thread (the runner reads a house's frames off the event
        loop): the file is read and hashed outside the store's lock, so a slow disk never
        blocks another caller.
        """
        # Frames are shared Path objects: skip re-parsing a Path (pathlib parsing dominated
        # the per-request cost when 30 frames are looked up per instance).
        p = path if isinstance(path, Path) else Path(path)
        known = self._by_path.get(p)
        if known is not None:
            return known
        if data is None:
            data = self._read_file(p)
        try:
            facts = check_image_bytes(data)
        except ImageFileError as exc:
            raise DatasetError(f"{p}: image {exc}") from None
        h = hashlib.sha256(data).hexdigest()
        # Bytes let go (a released house, an evicted entry) are read again from the file: only
        # the very bytes checked and hashed now may come back under this hash.
        info = self._remember(data, facts.size, facts.media_type, functools.partial(self._read_again, p, h, len(data)), h)
        with self._lock:
            self._sources.setdefault(info.image_hash, str(p))
        with self._lock:
            self._files.setdefault(info.image_hash, p)
            # Another thread may have registered the same path meanwhile: one entry either way.
            return self._by_path.setdefault(p, info)

    def knows_file(self, path: Path) -> bool:
        """Whether ``path`` was already read (then :meth:`add_file` is a dictionary lookup)."""
        return path in self._by_path

    def has_bytes(self, path: Path) -> bool:
        """Whether ``path`` was read and its bytes are still held (not released or evicted)."""
        info = self._by_path.get(path)
        return info is not None and (info.image_hash, "bytes") in self._cache

    def load_file(self, path: Path) -> StoredImage:
        """:meth:`add_file`, and the bytes read again if they were let go since: what a worker
        thread calls so that building a request never reads a file on the event loop."""
        info = self.add_file(path)
        self.encoded_bytes(info.image_hash)  # a cache hit unless they were let go
        return info

    def add_pil(self, image: Image.Image) -> StoredImage:
        """Register an in-memory image (encoded once as PNG)."""
        data = self._encode_png(image)
        return self._remember(data, image.size, "image/png", functools.partial(bytes, data))

    def add_unencoded(
        self, image_hash: str, size: tuple[int, int], encode: Callable[[], bytes], path: Path | None = None
    ) -> StoredImage:
        """Register a PNG image under a name its owner gives it (``image_hash``: a digest of its
        content, e.g. of its pixels), without its bytes: ``encode`` makes them the first time
        they are asked for (:meth:`encoded_bytes`, :meth:`data_url`). ``path``: the file name
        strategies know the image by (:meth:`add_file` then answers without reading a file)."""
        with self._lock:
            info = self._by_hash.get(image_hash)
            if info is None:
                info = StoredImage(image_hash, size[0], size[1], "image/png")
                self._by_hash[image_hash] = info
                self._recipes[image_hash] = encode
                self._unencoded.add(image_hash)
            if path is not None:
                self._by_path.setdefault(path, info)
            return info

    def derive(self, source_hash: str, recipe_key: str, draw: Callable[[Image.Image], Image.Image]) -> StoredImage:
        """The image made by ``draw`` from ``source_hash``, made once per ``recipe_key``.

        ``recipe_key`` must identify the drawing completely (e.g. marker positions and style);
        it is what makes a second request for the same derivation free.
        """
        with self._lock:
            known = self._derived.get((source_hash, recipe_key))
            if known is not None:
                return self._by_hash[known]

            def build() -> bytes:
                with self.open(source_hash) as src:
                    return self._encode_png(draw(src.convert("RGB")))

            data = build()
            with Image.open(io.BytesIO(data)) as im:
                size = im.size
            info = self._remember(data, size, "image/png", build)
            self._derived[(source_hash, recipe_key)] = info.image_hash
            return info

    # -- holding ------------------------------------------------------------------------------
    def hold_files(self, paths: Iterable[Path]) -> None:
        """Say that ``paths`` will be used (again): their bytes are kept until released."""
        with self._lock:
            for p in paths:
                self._holds[p] = self._holds.get(p, 0) + 1

    def release_files(self, paths: Iterable[Path]) -> int:
        """Let go of ``paths`` (one hold each); a file no one holds any more loses its cached
        bytes and data URL (what is known of it stays: a later use rebuilds them). Returns the
        bytes dropped. An image whose content another held file shares is kept."""
        dropped = 0
        with self._lock:
            let_go = []
            for p in paths:
                n = self._holds.get(p, 0) - 1
                if n > 0:
                    self._holds[p] = n
                else:
                    self._holds.pop(p, None)
                    let_go.append(p)
            held = {self._by_path[q].image_hash for q in self._holds if q in self._by_path}
            for p in let_go:
                info = self._by_path.get(p)
                if info is None or info.image_hash in held:
                    continue
                for kind in ("bytes", "url"):
                    value = self._cache.pop((info.image_hash, kind), None)
                    if value is not None:
                        self._cached_bytes -= len(value)
                        dropped += len(value)
        return dropped

    # -- reading ------------------------------------------------------------------------------
    def info(self, image_hash: str) -> StoredImage:
        """Size and media type of a stored image."""
        return self._by_hash[image_hash]

    def __contains__(self, image_hash: object) -> bool:
        return image_hash in self._by_hash

    @property
    def cached_bytes(self) -> int:
        """Bytes the store holds now (encoded images and data URLs), at most :attr:`max_bytes`."""
        return self._cached_bytes

    @property
    def distinct(self) -> int:
        """The number of distinct images (by content) the store has seen."""
        return len(self._by_hash)

    def encoded_bytes(self, image_hash: str) -> bytes:
        """The encoded bytes of an image."""
        with self._lock:
            hit = self._cache_get((image_hash, "bytes"))
            if hit is not None:
                return cast(bytes, hit)  # "bytes" entries hold bytes
            if image_hash in self._unencoded:
                self._unencoded.discard(image_hash)  # a first build, not a rebuild
            else:
                self.stats.rebuilds += 1
            data = self._recipes[image_hash]()
            self._cache_put((image_hash, "bytes"), data)
            return data

    def data_url(self, image_hash: str) -> str:
        """``data:<media type>;base64,...`` for the image, encoded once while it stays cached."""
        with self._lock:
            hit = self._cache_get((image_hash, "url"))
            if hit is not None:
                return cast(str, hit)  # "url" entries hold str
            info = self._by_hash[image_hash]
            url = f"data:{info.media_type};base64," + base64.b64encode(self.encoded_bytes(image_hash)).decode("ascii")
            self.stats.base64_encodes += 1
            self._cache_put((image_hash, "url"), url)
            return url

    def url(self, image_hash: str) -> str:
        """The URL a model is sent for the image: by :attr:`transport`, else its data URL."""
        transport = self.transport
        return self.data_url(image_hash) if transport is None else transport.url(self, image_hash)

    def source_file(self, image_hash: str) -> Path | None:
        """The file the image was read from, or ``None`` for a derived or in-memory image."""
        return self._files.get(image_hash)

    def open(self, image_hash: str) -> Image.Image:
        """A decoded PIL image (a new object: callers may draw on it); an image that does not
        decode is a :class:`DatasetError` naming its file."""
        try:
            im = Image.open(io.BytesIO(self.encoded_bytes(image_hash)))
            im.load()
        except (OSError, SyntaxError, ValueError, EOFError) as exc:
            source = self._sources.get(image_hash, f"image {image_hash[:12]}")
            # Pillow's own message names the in-memory buffer (<_io.BytesIO ...>), not the file
            reason = "not an image" if isinstance(exc, UnidentifiedImageError) else f"{type(exc).__name__}: {str(exc)[:200]}"
            raise DatasetError(f"{source}: image cannot be decoded ({reason})") from None
        return im

    # -- internals ----------------------------------------------------------------------------
    def _read_file(self, path: Path, size: int | None = None) -> bytes:
        """The bytes of a regular file, through the confined reader (a FIFO or a device planted
        where a frame was is refused at once, never waited on or streamed); ``size``: exactly
        that many are expected (a file grown since is told apart by the caller)."""
        try:
            data = read_regular(path, MAX_IMAGE_FILE_BYTES, what="image")
        except ReadTargetError as exc:
            raise DatasetError(str(exc)) from None
        with self._lock:
            self.stats.file_reads += 1
        return data

    def _read_again(self, path: Path, image_hash: str, size: int) -> bytes:
        """A file's bytes read again after they were let go: they must be the bytes first read.

        The first read checked the image and named it by its hash; a file changed since (or
        swapped for a link to another file) would otherwise be sent under that old hash. A
        change is a :class:`DatasetError` naming the file (the request that needed it fails, and
        its row records why), never a different image.
        """
        try:
            data = self._read_file(path, size)
        except OSError as exc:
            raise DatasetError(f"{path}: image cannot be read again ({exc.strerror or exc}); not sent") from None
        if len(data) != size or hashlib.sha256(data).hexdigest() != image_hash:
            raise DatasetError(
                f"{path}: image changed since it was first read and checked (its bytes are not those of "
                f"sha256 {image_hash[:12]}...); not sent: restore the file, or run again to read it afresh"
            )
        return data

    def _encode_png(self, image: Image.Image) -> bytes:
        data = encode_png(image)
        self.stats.png_encodes += 1
        return data

    def _remember(
        self, data: bytes, size: tuple[int, int], media_type: str, recipe: Callable[[], bytes], h: str | None = None
    ) -> StoredImage:
        h = h or hashlib.sha256(data).hexdigest()
        with self._lock:
            known = self._by_hash.get(h)
            if known is not None:
                return known
            info = StoredImage(h, size[0], size[1], media_type)
            self._by_hash[h] = info
            self._recipes[h] = recipe
            self._cache_put((h, "bytes"), data)
            return info

    def _cache_get(self, key: tuple[str, str]) -> bytes | str | None:
        value = self._cache.get(key)
        if value is not None:
            self._cache.move_to_end(key)
        return value

    def _cache_put(self, key: tuple[str, str], value: bytes | str) -> None:
        self._cache[key] = value
        self._cache.move_to_end(key)
        self._cached_bytes += len(value)
        while self._cached_bytes > self.max_bytes and len(self._cache) > 1:
            _, old = self._cache.popitem(last=False)
            self._cached_bytes -= len(old)
