"""The ``molmo`` parser: Molmo's XML-like point tags, v1 and Molmo2.

* Molmo v1: ``<point x="61.5" y="40.4" alt="...">label</point>`` and
  ``<points x1="..." y1="..." x2="..." y2="..." alt="...">label</points>``: **percent** (0-100)
  of the image.
* Molmo2: ``<points coords="1 1 073 160 2 080 170">label</points>`` (also ``<point coords=...>``):
  groups separated by tab, ``;``, ``,`` or ``:``; each group is the image index (**from 1**)
  followed by ``object-id x y`` triples with x, y on **0-1000** (3-4 digits). The first group's
  image is the selected frame, and only that group's points are scored (points of different
  images cannot be averaged).

MolmoPoint's special pointing tokens need its processor: out of scope for text parsing.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.answers.text import coerce_number, index_from_digits
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading

_TAG = re.compile(r"<(points?|tracks)\b([^<>]*?)/?>", re.IGNORECASE)
_ATTR = re.compile(r"""([A-Za-z_][\w-]*)\s*=\s*(?:"([^"]*)"|'([^']*)')""")
_XY = re.compile(r"^([xy])(\d*)$", re.IGNORECASE)
_GROUP_SPLIT = re.compile(r"[\t;,:]")
_TRIPLE = re.compile(r"(\d+)\s+(\d{3,4})\s+(\d{3,4})")


def _attributes(body: str) -> dict[str, str]:
    return {m.group(1).lower(): m.group(2) if m.group(2) is not None else m.group(3) for m in _ATTR.finditer(body)}


def percent_points(attrs: dict[str, str], spec: AnswerSpec) -> list[tuple[float, float]]:
    """Molmo v1 points from ``x``/``y`` or ``x1``/``y1``, ``x2``/``y2`` ... attributes (percent)."""
    xs: dict[str, float] = {}
    ys: dict[str, float] = {}
    for key, value in attrs.items():
        m = _XY.match(key)
        number = coerce_number(value)
        if m is None or number is None:
            continue
        (xs if m.group(1).lower() == "x" else ys)[m.group(2)] = number
    order = sorted(set(xs) & set(ys), key=lambda k: int(k) if k else 0)
    return [
        (relative_to_pixels(xs[k], 100, spec.width), relative_to_pixels(ys[k], 100, spec.height)) for k in order
    ]


def coords_points(coords: str, spec: AnswerSpec) -> tuple[int | None, list[tuple[float, float]]]:
    """Molmo2 ``coords``: the first group's 0-based image index and its points (0-1000)."""
    for group in _GROUP_SPLIT.split(coords):
        tokens = group.split()
        number = index_from_digits(tokens[0]) if len(tokens) >= 4 else None
        if number is None:
            continue
        image = number - 1
        points = [
            (relative_to_pixels(float(m.group(2)), 1000, spec.width), relative_to_pixels(float(m.group(3)), 1000, spec.height))
            for m in _TRIPLE.finditer(" ".join(tokens[1:]))
        ]
        if points:
            return (image if image >= 0 else None), points
    return None, []


class MolmoParser(NativeParser):
    """Molmo v1 percent points and Molmo2 ``coords`` (0-1000, image index from 1)."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "Molmo's native format, `<point>`/`<points>` tags, else `json`"
    beside_official = 'adds: a native format the official runner does not read'

    format_name = "Molmo point"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """The points of the first point tag that holds any, in pixels."""
        for tag in _TAG.finditer(text):
            attrs = _attributes(tag.group(2))
            if "coords" in attrs:
                image, points = coords_points(attrs["coords"], spec)
                if points:
                    return NativeReading(points, image, tag.group(0))
                continue
            points = percent_points(attrs, spec)
            if points:
                return NativeReading(points, None, tag.group(0))
        return None


@hookimpl
def register_parsers(register) -> None:
    """Contribute the molmo parser."""
    register("molmo", MolmoParser, description="Molmo <point>/<points> (percent) and Molmo2 coords (0-1000, image from 1)")
