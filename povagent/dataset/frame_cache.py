"""Sampled video frames kept across runs: a scene video is decoded once, not once a run.

Sampling a VSI-Bench scene's frames decodes its video up to the last frame taken
(:func:`~povagent.dataset.video_frames.sample_frames`); a set names a few hundred scenes, and
every run, ``validate`` and resumed run decoded them all again. :class:`FrameCache` keeps the
PNG files a sampling wrote in the folder the user named (``dataset.options.cache_dir``), one
entry a (video, frame count, sampler), and :func:`cached_sample_frames` writes them from there
instead of decoding.

An entry's key is the SHA-256 of the video's bytes (never its path or its time: a video replaced
under the same name is decoded again, and a copy elsewhere hits), the number of frames ``N``,
and :func:`sampler`: this module's format, the sampling rule's version
(:data:`~povagent.dataset.video_frames.SAMPLING_VERSION`) and the PyAV and Pillow versions that
decode and encode the frames, so an entry is only ever the bytes this code would write. It is one
file, ``<key>.frames``: a magic line, a JSON header (the key's parts; each frame's size and
SHA-256) and the PNG files one after another.

The folder is untrusted once it exists: an entry is read without following a link
(:func:`~povagent.files.confined_read.open_at`), its header bounded (:data:`MAX_HEADER_BYTES`)
and its frames streamed a chunk at a time (:data:`CHUNK`), each checked against its digest as it
is copied; an entry that is unreadable, truncated, of another key or with a frame that does not
match is ignored (one log line names the file and why) and the video decoded again, its new entry
replacing it. Entries are written aside and renamed into place
(:class:`~povagent.files.confined_write.ConfinedFolder`), so a killed writer or two processes
writing one entry never leave a torn one. Nothing outside the named folders is read or written:
the cache folder, the video (confined by the caller) and the frames' folder. Entries are never
removed here: the folder is the user's to clear.
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from povagent.dataset.video_frames import MAX_SAMPLED, MAX_VIDEO_BYTES, SAMPLING_VERSION, VideoError, sample_frames
from povagent.errors import ReadTargetError, WriteTargetError

LOG = logging.getLogger("povagent.frame_cache")

#: The entry format's first line.
MAGIC = b"povagent-frames 1\n"
#: The largest header read (256 frames of digests are a few KB).
MAX_HEADER_BYTES = 1 << 16
#: The largest frame an entry may declare (a PNG of the largest frame a video may have, 8192 x 8192 RGB, with room).
MAX_FRAME_BYTES = 256 << 20
#: How much of a video or an entry is held at a time.
CHUNK = 1 << 20


@functools.cache
def sampler() -> str:
    """What, beside the video and ``N``, decides the bytes written: the sampling rule, PyAV and
    Pillow (asked once a process, when a cache is first used: importing PyAV costs ~17 MiB, which
    a run that opens no video must not pay)."""
    import PIL

    try:
        import av

        decoder = f"av/{av.__version__}"
    except ImportError:
        decoder = "av/none"  # no entry is written without it: sampling then fails first
    return f"sampling/{SAMPLING_VERSION} {decoder} pillow/{PIL.__version__}"


def video_digest(path: Path) -> str:
    """The SHA-256 of the video's bytes, read a chunk at a time (a regular file of at most
    :data:`~povagent.dataset.video_frames.MAX_VIDEO_BYTES`)."""
    from povagent.files.confined_read import open_regular

    digest = hashlib.sha256()
    read = 0
    with open_regular(path, what="video") as handle:
        while chunk := handle.read(CHUNK):
            read += len(chunk)
            if read > MAX_VIDEO_BYTES:
                raise VideoError(f"over {MAX_VIDEO_BYTES} bytes; a video may hold at most that")
            digest.update(chunk)
    return digest.hexdigest()


class _Unusable(ValueError):
    """An entry that cannot be used; the message says why."""


@dataclass(frozen=True)
class FrameCache:
    """Entries of sampled frames in ``folder`` (made when first written)."""

    folder: Path

    def entry_name(self, digest: str, n: int) -> str:
        """The file name of the entry for a video of SHA-256 ``digest`` sampled to ``n`` frames."""
        key = hashlib.sha256(f"{digest}\0{n}\0{sampler()}".encode()).hexdigest()
        return f"{key[:40]}.frames"

    def restore(self, digest: str, n: int, out_dir: Path) -> list[Path] | None:
        """The entry's frames written into ``out_dir`` as sampling writes them, or ``None`` when
        there is no usable entry (a bad one logged in one line)."""
        from povagent.files.confined_read import open_at
        from povagent.files.confined_write import ConfinedFolder

        if not self.folder.is_dir():
            return None
        name = self.entry_name(digest, n)
        with ConfinedFolder(self.folder, create=False) as folder:
            try:
                handle = open_at(folder, name, what="frame cache entry")
            except FileNotFoundError:
                return None
            except (ReadTargetError, OSError) as exc:
                LOG.warning("%s: frame cache entry ignored (%s); decoding the video again", self.folder / name, exc)
                return None
            with handle:
                try:
                    return _copy_frames(handle, {"video": digest, "n": n, "sampler": sampler()}, out_dir)
                except _Unusable as exc:
                    LOG.warning("%s: frame cache entry ignored (%s); decoding the video again", self.folder / name, exc)
                    return None

    def store(self, digest: str, frames: list[Path]) -> None:
        """Keep ``frames`` (what sampling wrote, in order) as the entry of the video of SHA-256
        ``digest``: written aside, then renamed into place."""
        from povagent.files.confined_write import ConfinedFolder

        listed = [{"bytes": f.stat().st_size, "sha256": _file_digest(f)} for f in frames]
        header = json.dumps({"video": digest, "n": len(frames), "sampler": sampler(), "frames": listed}).encode()
        with ConfinedFolder(self.folder) as folder, folder.staged(self.entry_name(digest, len(frames)), encoding=None, unique=True) as staged:
            staged.file.write(MAGIC + len(header).to_bytes(4, "big") + header)
            for frame in frames:
                with frame.open("rb") as source:
                    while chunk := source.read(CHUNK):
                        staged.file.write(chunk)
            staged.commit(fsync=False)  # a lost entry is decoded again: not worth a disk flush a video


def _file_digest(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        while chunk := handle.read(CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def _header(handle: IO[bytes], expected: dict[str, Any]) -> list[tuple[int, str]]:
    """The entry's frames ``(size, sha256)``, its header checked against ``expected``."""
    if handle.read(len(MAGIC)) != MAGIC:
        raise _Unusable("not a frame cache entry of this version")
    size = int.from_bytes(handle.read(4), "big")
    if not 0 < size <= MAX_HEADER_BYTES:
        raise _Unusable(f"a header of {size} bytes")
    try:
        header = json.loads(handle.read(size))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise _Unusable("its header is not JSON (truncated?)") from None
    if not isinstance(header, dict) or any(header.get(k) != v for k, v in expected.items()):
        raise _Unusable("its header names another video, frame count or sampler")
    frames = header.get("frames")
    if not isinstance(frames, list) or len(frames) != expected["n"] or not 1 <= len(frames) <= MAX_SAMPLED:
        raise _Unusable("its header lists the wrong number of frames")
    out = []
    for frame in frames:
        if not (isinstance(frame, dict) and type(frame.get("bytes")) is int and 0 < frame["bytes"] <= MAX_FRAME_BYTES and isinstance(frame.get("sha256"), str)):
            raise _Unusable("its header lists a frame without a size and digest")
        out.append((frame["bytes"], frame["sha256"]))
    return out


def _copy_frames(handle: IO[bytes], expected: dict[str, Any], out_dir: Path) -> list[Path]:
    """The entry's frames written into ``out_dir`` (``frame-<k>.png``), each checked as it is copied."""
    frames = _header(handle, expected)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for position, (size, want) in enumerate(frames):
        target = out_dir / f"frame-{position:03d}.png"
        digest = hashlib.sha256()
        left = size
        with target.open("wb") as sink:
            while left:
                chunk = handle.read(min(CHUNK, left))
                if not chunk:
                    raise _Unusable(f"truncated in frame {position}")
                digest.update(chunk)
                sink.write(chunk)
                left -= len(chunk)
        if digest.hexdigest() != want:
            raise _Unusable(f"frame {position} does not match its digest")
        written.append(target)
    if handle.read(1):
        raise _Unusable("bytes after its last frame")
    return written


def cached_sample_frames(path: Path, n: int, out_dir: Path, cache: FrameCache | None) -> list[Path]:
    """:func:`~povagent.dataset.video_frames.sample_frames`, the frames taken from ``cache``
    where it holds them for this video's bytes and ``n``, else decoded and kept there
    (``cache=None``: always decoded, nothing kept)."""
    if cache is None:
        return sample_frames(path, n, out_dir)
    if not 1 <= n <= MAX_SAMPLED:
        raise VideoError(f"frames: {n}; an item may be shown 1 to {MAX_SAMPLED} frames")
    digest = video_digest(path)
    restored = cache.restore(digest, n, out_dir)
    if restored is not None:
        return restored
    frames = sample_frames(path, n, out_dir)
    try:
        cache.store(digest, frames)
    except (WriteTargetError, OSError) as exc:  # the frames are sound: only the next run pays
        LOG.warning("%s: frame cache entry not written (%s)", cache.folder / cache.entry_name(digest, n), exc)
    return frames


__all__ = ["FrameCache", "cached_sample_frames", "sampler", "video_digest"]
