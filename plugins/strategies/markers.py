"""The ``o-plot`` and ``oa-plot`` strategies: the basic prompt over frames with visual markers,
drawn as the authors' ablation scripts drew them (``run_vlm_eval_ab1.py``, ``ab2.py``).

Rules, per exploration frame (positions projected into that frame's own camera):

* observer (both strategies): a filled red disc with a 2 px white outline, radius
  ``max(8, int(min(w, h) * 0.022))`` (11 px at 512), centred on the observer object's
  ``raw_metadata.position`` (its box centre when the release gives no position), the projected
  pixel truncated with ``int()``. Drawn only when the observer is in the frame's
  ``object_in_frame_hits`` (the renderer saw it) and in front of the camera; a centre projected
  just outside the frame still draws the part of the disc that falls inside.
* anchor (O&A-Plot only), drawn after the disc (over it): when the anchor is in the frame's hits,
  the 3 px blue rectangle spanning its box corners that lie in front of the camera (each
  truncated), clipped to ``[0, w-1] x [0, h-1]``, drawn only when it keeps a positive width and
  height. An anchor without corner points gets a 3 px blue circle of radius
  ``max(15, int(min(w, h) * 0.04))`` (20 px at 512) at its position, only when that lies inside
  the frame.

The prompt tells the model what the marks mean (the runner's note, inserted after the sentence
on image labels; not with ``prompts: appendix``, whose text the paper prints without it). The
authors showed the first 30 frames. They ran neither strategy on Given: the observer view carries
no ``object_in_frame_hits``, so a C instance is sent unmarked with the basic Given prompt,
outside the paper's protocol.

Marked frames are derived images of the run's image store, keyed by the source hash plus a
recipe key holding the marker positions, so each is drawn and encoded once. A frame with nothing
to draw is shown unchanged (same hash, nothing re-encoded).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import asdict, dataclass
from typing import Sequence

from PIL import Image, ImageDraw

from povagent import hookimpl
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import Condition, SceneObject
from povagent.exchange.images import ImageStore
from povagent.exchange.prompts import load_template
from povagent.geometry.camera import Camera
from povagent_plugins.strategies.basic import ABLATION_MAX_FRAMES, BasicStrategy

RGB = tuple[int, int, int]
RED: RGB = (255, 0, 0)
WHITE: RGB = (255, 255, 255)
BLUE: RGB = (0, 0, 255)
#: Outline widths in pixels: the disc's white rim, the anchor's rectangle (or circle).
DISC_OUTLINE_WIDTH = 2
ANCHOR_LINE_WIDTH = 3
#: Bump when the drawing changes, so derived images cached under the old look are not reused.
DRAWING_VERSION = "runner-ab1-ab2"

#: The sentence after which the runner inserts its note on the marks.
NOTE_AFTER = "Each image is preceded by its label"


def disc_radius(width: int, height: int) -> int:
    """The observer disc's radius: ``max(8, int(min(w, h) * 0.022))``."""
    return max(8, int(min(width, height) * 0.022))


def anchor_circle_radius(width: int, height: int) -> int:
    """The fallback anchor circle's radius: ``max(15, int(min(w, h) * 0.04))``."""
    return max(15, int(min(width, height) * 0.04))


def object_point(obj: SceneObject) -> tuple[float, float, float] | None:
    """Where a marker points at an object: ``raw_metadata.position``, else its box centre."""
    raw = obj.raw_metadata
    if raw.position is not None:
        return raw.position.as_tuple()
    box = getattr(raw, "axisAlignedBoundingBox", None)
    return box.center.as_tuple() if box is not None and box.center is not None else None


def projected_pixel(camera: Camera, point: Sequence[float]) -> tuple[float, float] | None:
    """``point`` in pixels of ``camera`` (unclamped), or ``None`` when it is not in front of it."""
    nu, nv, _ = camera.project_point(point)
    if math.isnan(nu) or math.isnan(nv):
        return None
    # width and height are powers of two on the release, so u/W*W gives u back exactly
    return (nu * camera.width, nv * camera.height)


def truncated_pixel(camera: Camera, point: Sequence[float]) -> tuple[int, int] | None:
    """The projected pixel truncated toward zero with ``int()`` (as the runner's markers)."""
    p = projected_pixel(camera, point)
    return None if p is None else (int(p[0]), int(p[1]))


def anchor_box(camera: Camera, corners: Sequence[Sequence[float]]) -> tuple[int, int, int, int] | None:
    """The rectangle over the box corners in front of the camera, clipped to the frame, or
    ``None`` when no corner is in front or nothing of positive size is left."""
    pixels = [p for p in (truncated_pixel(camera, c) for c in corners) if p is not None]
    if not pixels:
        return None
    us, vs = [p[0] for p in pixels], [p[1] for p in pixels]
    x0, y0 = max(0, min(us)), max(0, min(vs))
    x1, y1 = min(camera.width - 1, max(us)), min(camera.height - 1, max(vs))
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


@dataclass(frozen=True)
class FrameMarkers:
    """What is drawn on one frame, in pixels: the observer disc's centre, the anchor rectangle
    ``(x0, y0, x1, y1)`` or, for an anchor without corners, the anchor circle's centre."""

    observer: tuple[int, int] | None = None
    anchor_box: tuple[int, int, int, int] | None = None
    anchor_circle: tuple[int, int] | None = None

    @property
    def empty(self) -> bool:
        """True when nothing is drawn in this frame."""
        return self.observer is None and self.anchor_box is None and self.anchor_circle is None


def _anchor_markers(camera: Camera, anchor: SceneObject) -> tuple[tuple[int, int, int, int] | None, tuple[int, int] | None]:
    box = getattr(anchor.raw_metadata, "axisAlignedBoundingBox", None)
    corners = getattr(box, "cornerPoints", None) if box is not None else None
    if corners:
        return anchor_box(camera, corners), None
    point = object_point(anchor)
    pixel = projected_pixel(camera, point) if point is not None else None
    if pixel is None or not (0 <= pixel[0] <= camera.width - 1 and 0 <= pixel[1] <= camera.height - 1):
        return None, None
    return None, (int(pixel[0]), int(pixel[1]))


def frame_markers(instance: Instance, frame: Frame, with_anchor: bool) -> FrameMarkers:
    """The markers of one frame: the observer disc, plus the anchor's when ``with_anchor``."""
    hits = frame.in_frame_hits
    observer = None
    if instance.observer_object.objectId in hits:
        point = object_point(instance.observer_object)
        observer = truncated_pixel(frame.camera, point) if point is not None else None
    box = circle = None
    if with_anchor and instance.anchor_object.objectId in hits:
        box, circle = _anchor_markers(frame.camera, instance.anchor_object)
    return FrameMarkers(observer, box, circle)


def _draw(markers: FrameMarkers, frame_size: tuple[int, int], image: Image.Image) -> Image.Image:
    # draw_markers with the image last, for functools.partial
    return draw_markers(image, markers, frame_size)


def draw_markers(image: Image.Image, markers: FrameMarkers, frame_size: tuple[int, int]) -> Image.Image:
    """A copy of ``image`` with ``markers`` drawn: the observer disc first, the anchor over it."""
    out = image.convert("RGB").copy()
    draw = ImageDraw.Draw(out)
    if markers.observer is not None:
        u, v = markers.observer
        r = disc_radius(*frame_size)
        draw.ellipse([u - r, v - r, u + r, v + r], fill=RED, outline=WHITE, width=DISC_OUTLINE_WIDTH)
    if markers.anchor_box is not None:
        draw.rectangle(list(markers.anchor_box), outline=BLUE, width=ANCHOR_LINE_WIDTH)
    elif markers.anchor_circle is not None:
        u, v = markers.anchor_circle
        r = anchor_circle_radius(*frame_size)
        draw.ellipse([u - r, v - r, u + r, v + r], outline=BLUE, width=ANCHOR_LINE_WIDTH)
    return out


def recipe_key(kind: str, markers: FrameMarkers, frame_size: tuple[int, int]) -> str:
    """Everything that determines a marked frame besides its source: kind, drawing, positions."""
    return json.dumps(
        {"kind": kind, "drawing": DRAWING_VERSION, "frame_size": list(frame_size), **asdict(markers)},
        sort_keys=True,
        separators=(",", ":"),
    )


def with_marker_note(prompt: str, note: str) -> str:
    """``prompt`` with ``note`` on its own line after the line on image labels (the runner's place)."""
    at = prompt.find(NOTE_AFTER)
    if at < 0:
        raise ValueError(f"the prompt has no line {NOTE_AFTER!r} to put the marker note after")
    end = prompt.index("\n", at) + 1
    return prompt[:end] + note + "\n" + prompt[end:]


class ObserverPlotStrategy(BasicStrategy):
    """O-Plot: the basic prompt and its note; a red disc on the observer object, first 30 frames."""

    #: Whether the anchor is marked too (O&A-Plot).
    with_anchor = False
    kind = "o-plot"
    #: The template holding the note on the marks.
    note_template = "o_plot_note"
    default_max_frames = ABLATION_MAX_FRAMES
    paper_conditions = (Condition.INFERRED, Condition.STATED)

    def _check_prompts(self) -> None:
        if not self.prompts.has_interventions:
            raise ValueError(
                f"strategy option prompts: {self.prompts.name!r} has no {self.kind} prompt "
                "(the authors ran the marker ablations with their standard prompt only); use runner or appendix"
            )

    def prompt_text(self, instance: Instance) -> str:
        """The basic prompt with the runner's note on the marks (A/B, ``prompts: runner``)."""
        text = super().prompt_text(instance)
        if instance.povbench_condition.uses_exploration_frames and self.prompts.marker_notes:
            text = with_marker_note(text, load_template(self.note_template))
        return text

    def images_for(self, instance: Instance, images: ImageStore) -> list[str]:
        """The frames shown, with markers drawn (derived once per source and recipe)."""
        hashes = []
        for frame in self.shown_frames(instance):
            source = images.add_file(frame.file).image_hash
            markers = frame_markers(instance, frame, self.with_anchor)
            if markers.empty:
                hashes.append(source)
                continue
            size = (frame.camera.width, frame.camera.height)
            derived = images.derive(
                source, recipe_key(self.kind, markers, size), functools.partial(_draw, markers, size)
            )
            hashes.append(derived.image_hash)
        return hashes


class ObserverAnchorPlotStrategy(ObserverPlotStrategy):
    """O&A-Plot: O-Plot plus a blue box around the anchor object, and the note on both marks."""

    with_anchor = True
    kind = "oa-plot"
    note_template = "oa_plot_note"


@hookimpl
def register_strategies(register) -> None:
    """Contribute the O-Plot and O&A-Plot strategies."""
    register(
        "o-plot",
        ObserverPlotStrategy,
        description="Basic prompt with the runner's note; red disc on the observer object (first 30 frames; A/B only in the paper)",
    )
    register(
        "oa-plot",
        ObserverAnchorPlotStrategy,
        description="O-Plot plus a blue box around the anchor and the note on both marks (first 30 frames; A/B only in the paper)",
    )
