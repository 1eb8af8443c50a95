"""Release-layout output: deterministic JSON and PNG files of one generated house.

What it is for: write exactly the files the POVBench release has (the house's pair list,
``exploration_images/``, ``img_from_observer/``, ``exploration_log.json``,
``per_image_visible_objects.json``) plus, on request, a ``_render/`` folder with depth maps and
instance masks. Same inputs give the same bytes: keys sorted, floats rounded to 4 decimals,
PNGs as Pillow writes them with a fixed compression level and no metadata, no timestamps anywhere
(the JSON through :mod:`povagent.generate.deterministic_json`).
What it must not do: decide content (pairs, sentences, cameras come in finished).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from povagent.generate.deterministic_json import write_json
from povagent.generate.frame_png import PNG_COMPRESS_LEVEL, encode_frame_png
from povagent.generate.pairs import Pair
from povagent.generate.renderer import Frame
from povagent.generate.scene import House
from povagent.geometry.camera import Camera

#: Pixels an object needs in a frame to count as hit (``object_in_frame_hits``).
MIN_HIT_PIXELS = 20


def write_png(path: Path, image: np.ndarray) -> None:
    """Write an RGB (uint8) or 16-bit single-channel image as PNG, without metadata."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8:  # a frame: Pillow's bytes, faster
        path.write_bytes(encode_frame_png(image))
        return
    # uint16 arrays become Pillow's "I;16" mode and round-trip exactly
    Image.fromarray(np.ascontiguousarray(image)).save(path, format="PNG", compress_level=PNG_COMPRESS_LEVEL)


def camera_record(camera: Camera, with_size: bool) -> dict[str, Any]:
    """A camera as the release stores it (observer cameras also carry the screen size)."""
    record: dict[str, Any] = {
        "cam_pos": list(camera.position),
        "cam_yaw": camera.yaw,
        "cam_horizon": camera.horizon,
        "fov": camera.fov,
    }
    if with_size:
        record["screen_width"] = camera.width
        record["screen_height"] = camera.height
    return record


def hits(house: House, frame: Frame) -> list[str]:
    """objectIds showing in a frame (by the instance mask), in objectId order."""
    counts = frame.pixel_counts()
    return sorted(house.objects[k].object_id for k, n in counts.items() if n >= MIN_HIT_PIXELS)


def pair_entry(pair: Pair) -> dict[str, Any]:
    """One pair as the release's house file lists it."""
    entry: dict[str, Any] = {
        "pair_id": pair.pair_id,
        "landmark_type": pair.anchor.object_type,
        "object_landmark": pair.anchor.to_record(),
        "object_observer": pair.observer.to_record(),
        "camera": camera_record(pair.camera, with_size=True),
        "rgb_path": f"img_from_observer/{pair.pair_id}.png",
        "stage3": {},
        "stage5": {},
        "stage6": {},
        "placements": {},
    }
    for q in pair.queries:
        entry["stage3"][q.direction] = {"verdict": q.verdict.verdict, "surface": q.verdict.surface}
        entry["stage5"][q.direction] = {"type_a": q.type_a, "type_b": q.type_b}
        entry["stage6"][q.direction] = {"type_c": q.type_c}
        entry["placements"][q.direction] = {
            "position": dict(zip("xyz", q.position)),
            "object_type": q.target_type,
            "surface_pool": q.target_pool,
        }
    return entry


def write_house(
    root: Path, house: House, frames: list[Frame], pairs: list[Pair], with_render: bool = False
) -> dict[str, int]:
    """Write one house's files into the folder ``root``; returns counts of what was written."""
    log, visible = [], {}
    for k, frame in enumerate(frames):
        rel = f"exploration_images/frame_{k:03d}.png"
        write_png(root / rel, frame.rgb)
        ids = hits(house, frame)
        log.append({"image_path": rel, "camera": camera_record(frame.camera, with_size=False), "object_in_frame_hits": ids})
        types = sorted({house.by_id(i).object_type for i in ids})
        visible[rel] = types
        if with_render:
            _write_render(root / "_render" / f"frame_{k:03d}", frame)
    for pair in pairs:
        write_png(root / f"img_from_observer/{pair.pair_id}.png", pair.frame.rgb)
        if with_render:
            _write_render(root / "_render" / pair.pair_id, pair.frame)
    if with_render:
        write_json(root / "_render" / "instances.json", {str(k + 1): o.object_id for k, o in enumerate(house.objects)})
    write_json(root / "exploration_log.json", log)
    write_json(root / "per_image_visible_objects.json", visible)
    write_json(root / f"{house.house_id}.json", [pair_entry(p) for p in pairs])
    return {"frames": len(frames), "observer_views": len(pairs)}


def _write_render(stem: Path, frame: Frame) -> None:
    """Depth (float16 .npy, metres along the optical axis) and instance mask (16-bit PNG)."""
    stem.parent.mkdir(parents=True, exist_ok=True)
    np.save(stem.with_name(stem.name + ".depth.npy"), frame.depth.astype(np.float16), allow_pickle=False)
    write_png(stem.with_name(stem.name + ".instance.png"), frame.instance)
