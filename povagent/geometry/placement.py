"""Observer-relative placement from perceived estimates, and the frame that shows the result.

The geometric solver's last two steps, kept pure: given where the anchor is (its box) and
where the observer was, the target is placed by the benchmark's own rules
(:func:`povagent.geometry.ground_truth.target_point`, never a second copy of them), with the
surface the target rests on given as one of three kinds; then the frame that shows the target
best is chosen: inside the image, then in front of the camera, then nearest the image centre.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from povagent.geometry.camera import ViewCamera
from povagent.geometry.ground_truth import AnchorBox, anchor_keywords, surface_names_anchor, target_point

#: The surfaces a target may rest on, as the solver asks: the floor, the anchor itself, or some
#: other object (whose top the benchmark takes to be the anchor's, having no other box).
SURFACE_KINDS: tuple[str, ...] = ("floor", "anchor", "other")


def surface_phrase(kind: str, anchor_type: str) -> str:
    """A stage-3 style surface phrase for ``kind`` (``"on the floor"``, ``"on the sofa"``...)."""
    if kind == "floor":
        return "on the floor"
    if kind == "anchor":
        return f"on the {anchor_keywords(anchor_type)[0]}"
    return "on another object"


def surface_kind(surface: str | None, anchor_type: str) -> str:
    """The kind of a release's surface phrase: ``floor`` when it says floor (the benchmark's
    first test), ``anchor`` when it names the anchor, else ``other``."""
    text = (surface or "").lower()
    if "floor" in text:
        return "floor"
    if surface_names_anchor(text, anchor_type):
        return "anchor"
    return "other"


@dataclass(frozen=True)
class AnchorEstimate:
    """The anchor as perceived: box centre and half sizes ``(hx, hy, hz)`` in metres."""

    centre: tuple[float, float, float]
    half: tuple[float, float, float]

    @property
    def box(self) -> AnchorBox:
        """The box as the ground-truth rules read it."""
        cx, cy, cz = self.centre
        return AnchorBox((cx, cz), (self.half[0], self.half[2]), cy + self.half[1])


def place_target(direction: str, anchor: AnchorEstimate, anchor_type: str, observer_position: Sequence[float] | np.ndarray, surface: str) -> np.ndarray:
    """The 3D target for ``direction`` from the perceived anchor and observer (``surface`` is one
    of :data:`SURFACE_KINDS`), by the benchmark's ground-truth rules."""
    centre = np.asarray(anchor.centre, dtype=float)
    return target_point(
        direction,
        anchor.box,
        anchor_type,
        centre,
        np.asarray(observer_position, dtype=float),
        "appropriate",
        surface_phrase(surface, anchor_type),
        centre,
    )


@dataclass(frozen=True)
class FrameChoice:
    """The frame chosen to answer in, and the target's pixel there (clamped into the image).

    ``placement`` is ``"in frame"``, ``"in front, outside the frame"`` (clamped to the border)
    or ``"behind every camera"`` (the image centre of the frame looking most towards it).
    """

    index: int
    pixel: tuple[float, float]
    placement: str


def choose_frame(target: Sequence[float] | np.ndarray, cameras: Sequence[ViewCamera]) -> FrameChoice:
    """The frame showing ``target`` best: inside the image (its content: not on a letterbox's
    padding) first, then in front of the camera, then behind it; among equals, the one where it
    lies nearest the image centre."""
    best: tuple[tuple[int, float], int, float, float] | None = None
    for i, cam in enumerate(cameras):
        u, v, depth = cam.project_point(target)
        if depth > 1e-6:
            left, top, right, bottom = cam.content_box
            inside = left / cam.width <= u <= right / cam.width and top / cam.height <= v <= bottom / cam.height
            key = (0 if inside else 1, (u - 0.5) ** 2 + (v - 0.5) ** 2)
        else:
            # behind: prefer the camera whose view direction is closest to the target's
            d = np.asarray(target, dtype=float) - np.asarray(cam.position)
            fwd = cam.optical_axes()[2]
            key = (2, -float(d @ fwd) / max(1e-9, float(np.linalg.norm(d))))
            u = v = 0.5
        if best is None or key < best[0]:
            best = (key, i, u, v)
    if best is None:
        raise ValueError("choose_frame needs at least one camera")
    (tier, _), i, u, v = best
    cam = cameras[i]
    left, top, right, bottom = cam.content_box
    x = min(max(u * cam.width, left), right - 1.0)
    y = min(max(v * cam.height, top), bottom - 1.0)
    placement = ("in frame", "in front, outside the frame", "behind every camera")[tier]
    return FrameChoice(i, (x, y), placement)
