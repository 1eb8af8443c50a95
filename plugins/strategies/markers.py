"""The ``o-plot`` and ``oa-plot`` strategies: the basic prompt over frames with visual markers.

O-Plot draws a circle at the observer object's position; O&A-Plot also draws a box around the
anchor. Positions come from the dataset's 3D metadata projected into each frame's own camera:

* observer: ``observer_object.position``, drawn only when it is in front of the camera and
  inside the frame;
* anchor: the 8 corner points of its axis-aligned bounding box; the box drawn is the 2D bounding
  rectangle of the projected corners that are in front of the camera, clipped to the frame, and
  drawn only when some of it lies inside. (With corners behind the camera the rectangle covers
  only the visible corners: an approximation, the same one a renderer's 2D box makes.)

There is no occlusion test: the release carries no depth maps, so a marker is drawn where its
point projects even when a wall stands between it and the camera (the observer object may be
in the next room).

Marker style (options, with defaults): ``observer_color`` ``"red"``, ``anchor_color`` ``"blue"``
(any Pillow colour name, ``#rrggbb`` or an ``[r, g, b]`` list), ``radius`` 10 px (circle),
``line_width`` 3 px (circle outline and box), ``observer_filled`` false (true: a solid dot).
Sizes are in pixels of the frame as the camera describes it.

Marked frames are derived images of the run's image store, keyed by the source hash plus a
recipe key holding the style and the projected positions, so each is drawn and encoded once.
A frame where nothing is visible is shown unchanged (same hash, nothing re-encoded). This module
must not change the prompt text: that is the basic prompt, as in the paper.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from typing import Any, Sequence

import numpy as np
from PIL import Image, ImageColor, ImageDraw

from povagent import hookimpl
from povagent.dataset.instances import Frame, Instance
from povagent.geometry.camera import Camera
from povagent.exchange.images import ImageStore
from povagent_plugins.strategies.basic import BasicStrategy

RGB = tuple[int, int, int]


def parse_color(value: Any, option: str) -> RGB:
    """An RGB triple from a colour name, ``#rrggbb`` or a 3-list; ``ValueError`` names the option."""
    if isinstance(value, str):
        try:
            rgb = ImageColor.getrgb(value)
        except ValueError:
            raise ValueError(f"strategy option {option}: unknown colour {value!r}") from None
        return (int(rgb[0]), int(rgb[1]), int(rgb[2]))
    if isinstance(value, (list, tuple)) and len(value) == 3 and all(isinstance(c, int) and 0 <= c <= 255 for c in value):
        return (int(value[0]), int(value[1]), int(value[2]))
    raise ValueError(f"strategy option {option}: expected a colour name, '#rrggbb' or [r, g, b], got {value!r}")


@dataclass(frozen=True)
class MarkerStyle:
    """How markers look (see the module docstring for the options)."""

    observer_color: RGB = (255, 0, 0)
    anchor_color: RGB = (0, 0, 255)
    radius: float = 10.0
    line_width: int = 3
    observer_filled: bool = False


@dataclass(frozen=True)
class FrameMarkers:
    """Where markers go in one frame, in pixels: the observer point and the anchor rectangle
    ``(x0, y0, x1, y1)``; ``None`` where nothing is visible."""

    observer: tuple[float, float] | None = None
    anchor_box: tuple[float, float, float, float] | None = None

    @property
    def empty(self) -> bool:
        """True when nothing is drawn in this frame."""
        return self.observer is None and self.anchor_box is None


def observer_point(camera: Camera, position: Sequence[float]) -> tuple[float, float] | None:
    """The observer position in pixels, or ``None`` when behind the camera or outside the frame."""
    p = camera.project(np.asarray(position, dtype=float))
    if not bool(p.in_frame):
        return None
    u, v = (float(c) for c in p.normalized)
    return (u * camera.width, v * camera.height)


def anchor_rectangle(camera: Camera, corners: Sequence[Sequence[float]]) -> tuple[float, float, float, float] | None:
    """The clipped 2D bounding rectangle of the box corners in front of the camera, or ``None``."""
    p = camera.project(np.asarray(corners, dtype=float))
    front = p.normalized[p.in_front] * np.array([camera.width, camera.height], dtype=float)
    if len(front) == 0:
        return None
    x0, y0 = front.min(axis=0)
    x1, y1 = front.max(axis=0)
    max_x, max_y = camera.width - 1, camera.height - 1
    if x1 < 0 or y1 < 0 or x0 > max_x or y0 > max_y:
        return None
    return (
        float(min(max(x0, 0.0), max_x)),
        float(min(max(y0, 0.0), max_y)),
        float(min(max(x1, 0.0), max_x)),
        float(min(max(y1, 0.0), max_y)),
    )


def frame_markers(instance: Instance, frame: Frame, with_anchor: bool) -> FrameMarkers:
    """The markers of one frame: the observer point, plus the anchor box when ``with_anchor``."""
    observer = observer_point(frame.camera, instance.observer_object.position.as_tuple())
    box = None
    if with_anchor:
        box = anchor_rectangle(frame.camera, instance.anchor_object.raw_metadata.axisAlignedBoundingBox.cornerPoints)
    return FrameMarkers(observer, box)


def draw_markers(image: Image.Image, markers: FrameMarkers, style: MarkerStyle, frame_size: tuple[int, int]) -> Image.Image:
    """A copy of ``image`` with ``markers`` drawn (positions given for ``frame_size``, scaled to the image)."""
    out = image.convert("RGB").copy()
    sx, sy = out.width / frame_size[0], out.height / frame_size[1]
    draw = ImageDraw.Draw(out)
    width = max(1, round(style.line_width * sx))
    if markers.anchor_box is not None:
        x0, y0, x1, y1 = markers.anchor_box
        draw.rectangle([x0 * sx, y0 * sy, x1 * sx, y1 * sy], outline=style.anchor_color, width=width)
    if markers.observer is not None:
        u, v = markers.observer[0] * sx, markers.observer[1] * sy
        r = style.radius * sx
        fill = style.observer_color if style.observer_filled else None
        draw.ellipse([u - r, v - r, u + r, v + r], outline=style.observer_color, fill=fill, width=width)
    return out


def recipe_key(kind: str, style: MarkerStyle, markers: FrameMarkers, frame_size: tuple[int, int]) -> str:
    """Everything that determines a marked frame besides its source: kind, style, positions."""

    def rounded(values: Sequence[float] | None) -> list[float] | None:
        return None if values is None else [round(float(v), 3) for v in values]

    return json.dumps(
        {
            "kind": kind,
            "style": asdict(style),
            "frame_size": list(frame_size),
            "observer": rounded(markers.observer),
            "anchor_box": rounded(markers.anchor_box),
        },
        sort_keys=True,
        separators=(",", ":"),
    )


class ObserverPlotStrategy(BasicStrategy):
    """O-Plot: the basic prompt; a circle at the observer object's position on every frame."""

    #: Whether the anchor box is drawn too (O&A-Plot).
    with_anchor = False
    kind = "o-plot"

    def __init__(
        self,
        max_tokens: int | None = None,
        temperature: float | None = None,
        observer_color: Any = "red",
        anchor_color: Any = "blue",
        radius: float = 10.0,
        line_width: int = 3,
        observer_filled: bool = False,
    ) -> None:
        super().__init__(max_tokens=max_tokens, temperature=temperature)
        if not isinstance(radius, (int, float)) or isinstance(radius, bool) or radius <= 0:
            raise ValueError(f"strategy option radius must be a positive number of pixels, got {radius!r}")
        if not isinstance(line_width, int) or isinstance(line_width, bool) or line_width < 1:
            raise ValueError(f"strategy option line_width must be a positive integer, got {line_width!r}")
        self.style = MarkerStyle(
            observer_color=parse_color(observer_color, "observer_color"),
            anchor_color=parse_color(anchor_color, "anchor_color"),
            radius=float(radius),
            line_width=line_width,
            observer_filled=bool(observer_filled),
        )

    def images_for(self, instance: Instance, images: ImageStore) -> list[str]:
        """The frames with markers drawn (derived once per source and recipe)."""
        hashes = []
        for frame in instance.frames:
            source = images.add_file(frame.file).image_hash
            markers = frame_markers(instance, frame, self.with_anchor)
            if markers.empty:
                hashes.append(source)
                continue
            size = (frame.camera.width, frame.camera.height)
            key = recipe_key(self.kind, self.style, markers, size)
            derived = images.derive(
                source, key, lambda im, m=markers, s=size: draw_markers(im, m, self.style, s)
            )
            hashes.append(derived.image_hash)
        return hashes


class ObserverAnchorPlotStrategy(ObserverPlotStrategy):
    """O&A-Plot: O-Plot plus a box around the anchor object."""

    with_anchor = True
    kind = "oa-plot"


@hookimpl
def register_strategies(register) -> None:
    """Contribute the O-Plot and O&A-Plot strategies."""
    register("o-plot", ObserverPlotStrategy, description="Basic prompt; red circle at the observer object on each frame")
    register(
        "oa-plot",
        ObserverAnchorPlotStrategy,
        description="Basic prompt; red circle at the observer object and blue box around the anchor on each frame",
    )
