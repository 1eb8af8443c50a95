"""Frames of a scene video, sampled as VSI-Bench's own evaluation samples them, decoded with PyAV.

VSI-Bench's code (vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8) hands
the model a video and lets the model's loader pick frames; the models of its results table
(``lmms_eval/models/llava_onevision.py`` and ``llava_vid.py``, ``load_video``) read the video with
decord and take ``np.linspace(0, total - 1, N, dtype=int)``: N indices spread evenly over the
video's frames, first and last included, truncated towards zero; N larger than the video's frame
count repeats frames, as there (lmms-eval @ 75571cfe's own sampler caps N at the count instead).
``total`` is the number of the video stream's packets, as decord counts a video's frames from
its index; the frames are decoded in presentation order and taken at those indices.

A video is untrusted input: it is opened as a regular file only
(:func:`~povagent.files.confined_read.open_regular`, after the caller confined its path), at most
:data:`MAX_VIDEO_BYTES`, with at most :data:`MAX_PACKETS` packets and frames at most
:data:`MAX_SIDE` pixels a side; anything else is a :class:`VideoError`, one line saying what.
PyAV is imported only here and only when a video is read: without it, one line names the extra.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from povagent.errors import PovagentError

#: The largest video read (VSI-Bench's scene videos are tens of MB).
MAX_VIDEO_BYTES = 4 << 30
#: The most packets a video's stream may hold (a 30 fps video of 9 hours).
MAX_PACKETS = 1_000_000
#: The longest side a frame may have.
MAX_SIDE = 8192
#: The most frames an item may be shown (``frames:``).
MAX_SAMPLED = 256
MISSING_PYAV = "reading a video needs PyAV: pip install 'povagent[video]'"
#: The sampling rule's version: raised whenever the frames :func:`sample_frames` writes for a video
#: change (which indices, the decoding, the encoding), so no frame cache entry of the old rule is
#: read (:mod:`povagent.dataset.frame_cache`).
SAMPLING_VERSION = 1

#: Videos opened with PyAV in this process, counting and sampling alike: what a frame cache saves
#: (:func:`videos_opened`; a benchmark and the tests read it).
_opened = 0


class VideoError(ValueError):
    """A video that cannot be read or sampled; the message says why, in one line."""


def _av() -> Any:
    try:
        import av
    except ImportError:
        raise PovagentError(MISSING_PYAV) from None
    return av


def sample_indices(total: int, n: int) -> list[int]:
    """The frame indices VSI-Bench's models take: ``linspace(0, total - 1, n)`` truncated to int
    (module docstring). ``total`` >= 1, ``n`` >= 1."""
    return [int(i) for i in np.linspace(0, total - 1, n, dtype=int)]


def videos_opened() -> int:
    """How many times this process has opened a video to count or decode its frames."""
    return _opened


def _open(path: Path) -> Any:
    from povagent.files.confined_read import open_regular

    global _opened
    _opened += 1
    handle = open_regular(path, what="video")
    size = os.fstat(handle.fileno()).st_size
    if size > MAX_VIDEO_BYTES:
        handle.close()
        raise VideoError(f"{size} bytes; a video may hold at most {MAX_VIDEO_BYTES}")
    return handle


def _stream(container: Any) -> Any:
    if not container.streams.video:
        raise VideoError("holds no video stream")
    stream = container.streams.video[0]
    width, height = stream.codec_context.width, stream.codec_context.height
    if not (0 < width <= MAX_SIDE and 0 < height <= MAX_SIDE):
        raise VideoError(f"frames of {width}x{height}; a side may be 1 to {MAX_SIDE} pixels")
    return stream


def count_frames(path: Path) -> int:
    """The number of frames of the video at ``path``: its video stream's packets holding data."""
    av = _av()
    with _open(path) as handle:
        try:
            with av.open(handle) as container:
                stream = _stream(container)
                total = 0
                for packet in container.demux(stream):
                    if packet.size:
                        total += 1
                        if total > MAX_PACKETS:
                            raise VideoError(f"more than {MAX_PACKETS} frames")
        except av.FFmpegError as exc:
            raise VideoError(f"cannot be decoded: {exc}") from None
    return total


def sample_frames(path: Path, n: int, out_dir: Path) -> list[Path]:
    """The ``n`` frames VSI-Bench's models see (:func:`sample_indices`), written as PNG files
    ``frame-<k>.png`` (k their position, 0 first) into ``out_dir``; their paths in order."""
    if not 1 <= n <= MAX_SAMPLED:
        raise VideoError(f"frames: {n}; an item may be shown 1 to {MAX_SAMPLED} frames")
    total = count_frames(path)
    if total == 0:
        raise VideoError("holds no frame")
    wanted: dict[int, list[int]] = {}
    for position, index in enumerate(sample_indices(total, n)):
        wanted.setdefault(index, []).append(position)
    av = _av()
    out_dir.mkdir(parents=True, exist_ok=True)
    written: dict[int, Path] = {}
    last = max(wanted)
    with _open(path) as handle:
        try:
            with av.open(handle) as container:
                stream = _stream(container)
                for index, frame in enumerate(container.decode(stream)):
                    if index in wanted:
                        image = frame.to_image()  # RGB, as decord's asnumpy() gives it
                        for position in wanted[index]:
                            target = out_dir / f"frame-{position:03d}.png"
                            image.save(target, format="PNG")
                            written[position] = target
                    if index >= last:
                        break
        except av.FFmpegError as exc:
            raise VideoError(f"cannot be decoded: {exc}") from None
    if len(written) != n:
        raise VideoError(f"{total} frames counted but fewer decoded; frames {sorted(set(range(n)) - set(written))[:5]} missing")
    return [written[k] for k in range(n)]
