"""pytest plugin for povagent and its plugin authors (loaded only when a conftest opts in).

Fixtures:

* ``povagent_host``: a fresh :class:`~povagent.plugins.PluginHost` that every
  :func:`~povagent.plugins.get_plugin_host` call returns for the test; register throwaway
  plugins with ``povagent_host.add_plugin(obj)``; they are removed when the test ends.
* ``queued_backend``: a backend registered as ``queued`` that answers canned replies in order
  (a queued exception is raised instead), and records every request it was sent.
* ``tiny_dataset``: a builder writing a synthetic dataset in the release layout under the
  test's ``tmp_path`` (see :func:`write_release`).
* ``loopback_server``: a running :class:`~povagent.testing.loopback_server.LoopbackServer` (an
  OpenAI-compatible server on 127.0.0.1 that records requests and injects faults) answering a
  valid A/B answer; point a litellm backend at ``loopback_server.url``. It stops when the test
  ends, or after 60 s whatever happens.

:func:`write_release` is also what the runner benchmarks use for a full-size synthetic set.
This module must not be imported by the library itself.
"""

from __future__ import annotations

import io
import json
import math
import struct
import zlib
from collections import deque
from pathlib import Path
from typing import Any, Iterator, Mapping

import pytest

from povagent import hookimpl
from povagent.exchange.messages import Request, Response, Usage
from povagent.geometry.directions import DIRECTION_NAMES
from povagent.interfaces import Backend, PermanentBackendError

#: The directions a synthetic pair takes, first ones first (the registry's order).
DIRECTIONS = DIRECTION_NAMES


# -- synthetic release ---------------------------------------------------------------------------
def _box(cx: float, cy: float, cz: float, sx: float, sy: float, sz: float) -> dict[str, Any]:
    corners = [[cx + dx * sx / 2, cy + dy * sy / 2, cz + dz * sz / 2] for dx in (-1, 1) for dy in (-1, 1) for dz in (-1, 1)]
    return {"center": {"x": cx, "y": cy, "z": cz}, "size": {"x": sx, "y": sy, "z": sz}, "cornerPoints": corners}


def _object(object_id: str, otype: str, pos: tuple[float, float, float], size: tuple[float, float, float]) -> dict[str, Any]:
    p = {"x": pos[0], "y": pos[1], "z": pos[2]}
    return {
        "objectId": object_id,
        "assetId": f"{otype}_1",
        "position": p,
        "raw_metadata": {"objectType": otype, "position": p, "axisAlignedBoundingBox": _box(*pos, *size)},
    }


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def tagged_png(base: bytes, tag: str) -> bytes:
    """``base`` (a PNG) with a ``tEXt`` chunk carrying ``tag``: same pixels, distinct bytes.

    Lets a benchmark write thousands of realistic-size, distinct images without encoding each.
    """
    ihdr_end = 8 + 4 + 4 + 13 + 4  # signature + IHDR chunk
    return base[:ihdr_end] + _png_chunk(b"tEXt", b"povagent\x00" + tag.encode()) + base[ihdr_end:]


def base_png(size: tuple[int, int] = (512, 512), noise_rows: int = 0, seed: int = 0) -> bytes:
    """A PNG of ``size``: flat grey, with ``noise_rows`` rows of noise to reach a realistic file size."""
    import numpy as np
    from PIL import Image

    w, h = size
    arr = np.full((h, w, 3), 128, dtype=np.uint8)
    if noise_rows:
        arr[: min(noise_rows, h)] = np.random.default_rng(seed).integers(0, 256, (min(noise_rows, h), w, 3), dtype=np.uint8)
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


def write_release(
    root: str | Path,
    *,
    houses: int = 2,
    pairs: int | None = None,
    pair_directions: int | None = None,
    frames: int = 3,
    size: tuple[int, int] = (512, 512),
    noise_rows: int = 0,
) -> Path:
    """Write a synthetic dataset in the POVBench release layout; returns ``root``.

    ``pairs`` (default two per house) are spread over the houses; ``pair_directions`` valid
    (pair, direction) combinations in all (default every direction of every pair), so each
    condition has that many instances. Each house has ``frames`` exploration frames around
    the anchor; every image is distinct (a tag in its bytes). The full-size shape of the real
    release is ``houses=47, pairs=288, pair_directions=813, frames=30``.
    """
    root = Path(root)
    pairs = 2 * houses if pairs is None else pairs
    pair_directions = 4 * pairs if pair_directions is None else pair_directions
    if not pairs <= pair_directions <= 4 * pairs:
        raise ValueError("pair_directions must be between pairs and 4 * pairs")
    w, h = size
    base = base_png(size, noise_rows)
    (root / "artifacts").mkdir(parents=True, exist_ok=True)
    (root / "meta.json").write_text(json.dumps({"version": "synthetic", "houses": houses, "pairs": pairs}) + "\n")
    per_pair = [pair_directions // pairs + (1 if i < pair_directions % pairs else 0) for i in range(pairs)]
    for hi in range(houses):
        house_id = f"train_house_{hi:05d}"
        folder = root / "artifacts" / house_id
        (folder / "exploration_images").mkdir(parents=True, exist_ok=True)
        (folder / "img_from_observer").mkdir(parents=True, exist_ok=True)
        log: list[dict[str, Any]] = []
        visible: dict[str, list[Any]] = {}
        for fi in range(frames):
            rel = f"exploration_images/frame_{fi:03d}.png"
            (folder / rel).write_bytes(tagged_png(base, f"{house_id}/{rel}"))
            yaw = 360.0 * fi / frames
            log.append({"image_path": rel, "camera": {"cam_pos": [0.0, 0.9, 0.0], "cam_yaw": yaw, "cam_horizon": 30.0, "fov": 100.0},
                        "object_in_frame_hits": []})
            visible[rel] = []
        entries = []
        for pi in range(hi, pairs, houses):
            dirs = DIRECTIONS[: per_pair[pi]]
            angle = 2 * math.pi * pi / max(pairs, 1)
            ax, az = 3.0 * math.sin(angle), 3.0 * math.cos(angle)
            rgb = f"img_from_observer/pair_{pi}.png"
            (folder / rgb).write_bytes(tagged_png(base, f"{house_id}/{rgb}"))
            entries.append({
                "pair_id": pi,
                "landmark_type": "Bed",
                "object_landmark": _object(f"Bed|{pi}", "Bed", (ax, 0.3, az), (2.0, 0.6, 2.0)),
                "object_observer": _object(f"FloorLamp|{pi}", "FloorLamp", (ax * 0.5, 0.8, az * 0.5), (0.4, 1.6, 0.4)),
                "camera": {"cam_pos": [0.0, 1.55, 0.0], "cam_yaw": math.degrees(angle), "cam_horizon": 20.0, "fov": 100.0,
                           "screen_width": w, "screen_height": h},
                "rgb_path": rgb,
                "stage3": {d: {"verdict": "appropriate", "surface": "on the floor"} for d in dirs},
                "stage5": {d: {"type_a": f"While reading, I left the book {d} of the bed.",
                               "type_b": f"While reading by the floor lamp, I left the book {d} of the bed."} for d in dirs},
                "stage6": {d: {"type_c": f"The book was {d} of the bed."} for d in dirs},
                "placements": {d: {"position": {"x": ax + 1.0, "y": 0.2, "z": az}} for d in dirs},
            })
        (folder / f"{house_id}.json").write_text(json.dumps(entries))
        (folder / "exploration_log.json").write_text(json.dumps(log))
        (folder / "per_image_visible_objects.json").write_text(json.dumps(visible))
    return root


# -- a backend answering canned replies ----------------------------------------------------------
class QueuedBackend(Backend):
    """Answers the queued replies in order; a queued exception is raised instead of answered.

    Every request is kept in ``requests``. An empty queue is a permanent error (the test queued
    too few replies), so a run records it instead of hanging.
    """

    cacheable = True

    def __init__(self, replies: deque | None = None, requests: list | None = None, name: str = "queued") -> None:
        self.replies: deque = replies if replies is not None else deque()
        self.requests: list[Request] = requests if requests is not None else []
        self.name = name

    def identity(self) -> Mapping[str, Any]:
        """Names the backend only: every queued reply is a different answer anyway."""
        return {"backend": self.name}

    async def complete(self, request: Request, images: Any) -> Response:
        """Pop the next reply."""
        self.requests.append(request)
        if not self.replies:
            raise PermanentBackendError("queued backend: no reply queued", status=400)
        reply = self.replies.popleft()
        if isinstance(reply, BaseException):
            raise reply
        return Response(text=reply, usage=Usage(prompt_tokens=10, completion_tokens=5), model=self.name)


class QueuedBackendHandle:
    """What the ``queued_backend`` fixture gives a test: queue replies, read requests."""

    def __init__(self) -> None:
        self.replies: deque = deque()
        self.requests: list[Request] = []

    def queue(self, *replies: Any) -> None:
        """Queue replies (strings, or exceptions to raise)."""
        self.replies.extend(replies)

    def factory(self, **options: Any) -> QueuedBackend:
        """The registered factory: every instance shares this handle's queue."""
        return QueuedBackend(self.replies, self.requests)


# -- fixtures ------------------------------------------------------------------------------------
@pytest.fixture
def povagent_host() -> Iterator[Any]:
    """A fresh plugin host used by every ``get_plugin_host()`` call during the test."""
    from povagent import plugins

    host = plugins.build_plugin_host(strict=False)
    previous = plugins._OVERRIDE
    plugins._OVERRIDE = host
    try:
        yield host
    finally:
        plugins._OVERRIDE = previous


@pytest.fixture
def queued_backend(povagent_host: Any) -> Iterator[QueuedBackendHandle]:
    """A backend named ``queued`` answering canned replies in order (see :class:`QueuedBackend`)."""
    handle = QueuedBackendHandle()

    class _Plugin:
        @hookimpl
        def register_backends(self, register: Any) -> None:
            register("queued", handle.factory, description="canned replies (tests)")

    name = povagent_host.add_plugin(_Plugin(), name="povagent-testing-queued-backend")
    try:
        yield handle
    finally:
        povagent_host.remove_plugin(name)


@pytest.fixture
def tiny_dataset(tmp_path: Path) -> Any:
    """``tiny_dataset(houses=2, pairs=None, frames=3, ...) -> Path``: a synthetic release under tmp_path."""
    counter = iter(range(1_000_000))

    def make(**kwargs: Any) -> Path:
        return write_release(tmp_path / f"dataset_{next(counter)}", **kwargs)

    return make


@pytest.fixture
def loopback_server() -> Iterator[Any]:
    """A loopback OpenAI-compatible server answering ``{"selected_image": 0, "x": 10, "y": 20}``."""
    from povagent.testing.loopback_server import LoopbackServer

    with LoopbackServer(reply='{"selected_image": 0, "x": 10, "y": 20}', max_lifetime_s=60) as server:
        yield server
