"""The ``internvl`` parser: InternVL's grounding boxes, ``<box>[[x1, y1, x2, y2]]</box>``.

Coordinates are 0-1000; a box is read as its centre. A box tag may hold several boxes
(``[[...], [...]]``) and the text several tags: the prediction is the centroid of the centres.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent.answers.text import NUMBER, normalize_minus
from povagent.answers.validation import relative_to_pixels
from povagent_plugins.parsers.native import NativeParser, NativeReading

#: A box tag; its content never holds ``<``, which keeps the scan linear on a text full of
#: unclosed ``<box>`` tags (a lazy ``.*?`` would rescan to the end from each one).
_BOX_TAG = re.compile(r"<box>([^<]*)</box>", re.IGNORECASE)
_BOX = re.compile(rf"\[\s*({NUMBER})\s*,\s*({NUMBER})\s*,\s*({NUMBER})\s*,\s*({NUMBER})\s*\]")


class InternVLParser(NativeParser):
    """InternVL ``<box>`` centres on 0-1000."""

    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "InternVL's native format, `<box>[[x1, y1, x2, y2]]</box>` centres on 0-1000, else `json`"
    beside_official = 'adds: a native format the official runner does not read'

    format_name = "InternVL box"

    def read(self, text: str, spec: AnswerSpec) -> NativeReading | None:
        """The centre of every box in every ``<box>`` tag, in pixels."""
        points = []
        spans = []
        for tag in _BOX_TAG.finditer(text):
            for m in _BOX.finditer(tag.group(1)):
                x1, y1, x2, y2 = (float(normalize_minus(g)) for g in m.groups())
                points.append(
                    (relative_to_pixels((x1 + x2) / 2, 1000, spec.width), relative_to_pixels((y1 + y2) / 2, 1000, spec.height))
                )
            spans.append(tag.group(0))
        if not points:
            return None
        return NativeReading(points, None, "".join(spans))


@hookimpl
def register_parsers(register) -> None:
    """Contribute the internvl parser."""
    register("internvl", InternVLParser, description="InternVL <box>[[x1,y1,x2,y2]]</box> centre on 0-1000")
