"""One gallery image, drawn: a frame with its ground truth (a green ring, dashed when the ground
truth is behind the camera, an arrow at the border when it is off the frame), the prediction
(a red cross) and a real-world set's hand-made marks.

:class:`Drawing` says what an image shows; :func:`render` draws it; :func:`image_error` says
why a source image could not be drawn. Choosing the rows, naming
and caching the files and the page's data are :mod:`povagent.report.gallery`'s job.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from PIL import Image, ImageDraw, UnidentifiedImageError

from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular

#: Bumped when the drawing changes, so cached images are redrawn.
RECIPE_VERSION = 3

GT_COLOUR = (0, 200, 83)
PRED_COLOUR = (255, 45, 45)


@dataclass(frozen=True)
class Drawing:
    """What one gallery image shows: a source frame plus markers, in pixels of that frame."""

    source: Path
    gt: tuple[float, float] | None
    gt_state: str  # "in", "out" (in front, outside the frame), "behind"; real-world: "marked", "unmarked"
    pred: tuple[float, float] | None
    #: Hand-made marks (real-world sets): ``("point", (x, y), radius or None)``,
    #: ``("box", (x0, y0, x1, y1))`` or ``("region", ((x, y), ...))``, in this frame's pixels.
    marks: tuple[tuple[Any, ...], ...] = ()

    def recipe(self) -> dict[str, Any]:
        """The drawing's parameters (hashed with the source's bytes to name the files)."""
        r = lambda p: None if p is None else [round(p[0], 2), round(p[1], 2)]  # noqa: E731
        out = {"v": RECIPE_VERSION, "gt": r(self.gt), "state": self.gt_state, "pred": r(self.pred)}
        if self.marks:  # only then: official drawings keep their names (and their cached files)
            out["marks"] = _rounded(self.marks)
        return out


def _rounded(value: Any) -> Any:
    """Nested tuples of numbers as lists rounded to 0.01 px (a stable hash input)."""
    if isinstance(value, (tuple, list)):
        return [_rounded(v) for v in value]
    return round(value, 2) if isinstance(value, float) else value


def _draw_marks(im: Image.Image, marks: tuple[tuple[Any, ...], ...], scale: float, lw: int) -> Image.Image:
    """Marks as a light green fill (the hit zone) under a green outline with a white halo."""
    fill = Image.new("RGBA", im.size, (0, 0, 0, 0))
    f = ImageDraw.Draw(fill)
    zone = GT_COLOUR + (70,)
    for shape in marks:
        if shape[0] == "point" and shape[2] is not None:
            (x, y), r = shape[1], shape[2]
            f.ellipse([x - r, y - r, x + r, y + r], fill=zone)
        elif shape[0] == "box":
            f.rectangle(list(shape[1]), fill=zone)
        elif shape[0] == "region":
            f.polygon(list(shape[1]), fill=zone)
    im = Image.alpha_composite(im.convert("RGBA"), fill).convert("RGB")
    d = ImageDraw.Draw(im)
    for shape in marks:
        for col, width in (((255, 255, 255), lw + 3), (GT_COLOUR, lw)):
            if shape[0] == "point":
                (x, y), r = shape[1], (shape[2] if shape[2] is not None else 16 * scale)
                _ring(d, x, y, r, col, width)
            elif shape[0] == "box":
                d.rectangle(list(shape[1]), outline=col, width=width)
            else:
                d.line(list(shape[1]) + [shape[1][0]], fill=col, width=width, joint="curve")
        if shape[0] == "point":
            x, y = shape[1]
            d.ellipse([x - 3 * scale, y - 3 * scale, x + 3 * scale, y + 3 * scale], fill=GT_COLOUR)
    return im


def _ring(d: ImageDraw.ImageDraw, x: float, y: float, r: float, col, width: int, dashed: bool = False) -> None:
    if not dashed:
        d.ellipse([x - r, y - r, x + r, y + r], outline=col, width=width)
        return
    for k in range(0, 360, 30):
        d.arc([x - r, y - r, x + r, y + r], k, k + 18, fill=col, width=width)


def _off_frame_arrow(d: ImageDraw.ImageDraw, gx: float, gy: float, w: int, h: int, scale: float) -> None:
    """A thick arrow pointing from inside the frame at a GT beyond its border.

    Drawn to be read on the 256 px thumbnail (half the size of a 512 px frame): a 9 px shaft
    and a 30 px head, green on a black outline on a white halo, so it shows on light walls
    and dark floors alike.
    """
    margin = 4 * scale
    bx, by = min(w - margin, max(margin, gx)), min(h - margin, max(margin, gy))
    vx, vy = gx - w / 2.0, gy - h / 2.0
    n = max(1e-6, (vx * vx + vy * vy) ** 0.5)
    ux, uy = vx / n, vy / n
    head, half, length = 30 * scale, 16 * scale, 90 * scale
    base = (bx - ux * head, by - uy * head)
    tail = (bx - ux * length, by - uy * length)
    tip = (bx, by)
    wing_a = (base[0] - uy * half, base[1] + ux * half)
    wing_b = (base[0] + uy * half, base[1] - ux * half)
    shaft = max(3, int(round(9 * scale)))
    for col, grow in (((255, 255, 255), 7), ((0, 0, 0), 4), (GT_COLOUR, 0)):
        g = grow * scale
        d.line([tail, base], fill=col, width=shaft + int(round(2 * g)))
        if grow:
            # the outline of the head: the same triangle pushed out by ``g``
            d.polygon([(tip[0] + ux * g, tip[1] + uy * g), (wing_a[0] - ux * g / 2 - uy * g, wing_a[1] - uy * g / 2 + ux * g),
                       (wing_b[0] - ux * g / 2 + uy * g, wing_b[1] - uy * g / 2 - ux * g)], fill=col)
        else:
            d.polygon([tip, wing_a, wing_b], fill=col)


def render(drawing: Drawing) -> Image.Image:
    """The frame with its markers drawn (full size, RGB)."""
    with open_frame(drawing.source) as src:
        im = src.convert("RGB")
    w, h = im.size
    scale = max(1.0, w / 512.0)
    lw = max(2, int(round(3 * scale)))
    if drawing.marks:
        im = _draw_marks(im, drawing.marks, scale, lw)
    d = ImageDraw.Draw(im)
    if drawing.gt is not None:
        gx, gy = drawing.gt
        if drawing.gt_state == "out":
            _off_frame_arrow(d, gx, gy, w, h, scale)
        else:
            r = 16 * scale
            dashed = drawing.gt_state == "behind"
            # a white halo under the green keeps the ring visible on green or dark frames
            _ring(d, gx, gy, r + 1, (255, 255, 255), lw + 3, dashed)
            _ring(d, gx, gy, r, GT_COLOUR, lw + 1, dashed)
            d.ellipse([gx - 3 * scale, gy - 3 * scale, gx + 3 * scale, gy + 3 * scale], fill=GT_COLOUR)
    if drawing.pred is not None:
        px, py = min(w - 1.0, max(0.0, drawing.pred[0])), min(h - 1.0, max(0.0, drawing.pred[1]))
        a = 11 * scale
        for col, width in (((0, 0, 0), lw + 3), (PRED_COLOUR, lw)):
            d.line([(px - a, py - a), (px + a, py + a)], fill=col, width=width)
            d.line([(px - a, py + a), (px + a, py - a)], fill=col, width=width)
    return im


#: What reading or decoding a bad source image raises (Pillow: OSError for truncated or
#: unidentified files, SyntaxError/ValueError/EOFError from some decoders, the bomb error).
IMAGE_ERRORS = (OSError, SyntaxError, ValueError, EOFError, Image.DecompressionBombError, ReadTargetError)


def open_frame(path: Path) -> Image.Image:
    """A source image the report draws from (a dataset's frame, an episode's view), read through
    the confined reader: a pipe or a device there is one of :data:`IMAGE_ERRORS`, never a wait."""
    return Image.open(io.BytesIO(read_regular(path, MAX_IMAGE_FILE_BYTES, what="image")))


def image_error(source: Path, exc: BaseException, root: Path | None = None) -> str:
    """The sentence a card shows for a source image that could not be drawn (file named)."""
    try:
        name = str(source.relative_to(root)) if root is not None else str(source)
    except ValueError:
        name = str(source)
    if isinstance(exc, UnidentifiedImageError):
        reason = "not an image file"  # Pillow's own text names a buffer, not the file
    elif isinstance(exc, FileNotFoundError):
        reason = "file not found"
    elif "truncated" in str(exc):
        reason = "the file is truncated"
    else:
        reason = f"{type(exc).__name__}: {str(exc)[:200]}"
    return f"{name}: {reason}"
