"""The self-contained HTML page: tables, inline SVG plots and the filterable gallery.

One file plus its ``images/`` folder; it opens from disk with no server and no CDN (all CSS
and JS are inline, from ``assets/report.html``). The gallery's data is JSON in the page and
names images by hash (``images/<sha256>.t.jpg``): no base64 image data, so a 2,439-instance
report stays a few megabytes and renders one page of cards at a time.

Only markup: the numbers, figures and images are made elsewhere and passed in.
"""

from __future__ import annotations

import html
import json
import math
import re
from datetime import UTC, datetime
from importlib.resources import files
from typing import Any, Iterable

from povagent.geometry.directions import DIRECTION_NAMES
from povagent.report.tables import Table, to_html

TEMPLATE = "report.html"

#: How to read a gallery drawing (markup), for official-metric rows.
OFFICIAL_LEGEND = (
    "Each image is the frame the answer was scored in: the model's selected frame (Inferred, Stated) or the observer view (Given).\n"
    '<span class="g">Green ring</span>: ground truth (a dashed ring at the centre when the GT is behind the camera: the official '
    "metric scores it there; an arrow at the border when it is outside the frame).\n"
    '<span class="p">Red cross</span>: the predicted point. Click a card for the full-size frame and the raw answer.\n'
    "Under an Inferred or Stated image, the strip of the house's exploration frames in order: "
    '<span class="p">red outline</span>, the frame the model selected; <span class="g">&#10003;</span>, a frame that shows the GT '
    "(it projects in front of the camera and inside the frame, the metric's own test, and the exploration log saw the anchor there); "
    '<b style="background:#ffc400;padding:0 3px">?</b>, the GT falls within the frame but the anchor was not seen: a wall may hide it.'
)

#: How to read the diagnostics' additions to the gallery (rows scored by ``diagnose``).
DIAGNOSIS_LEGEND = (
    "Diagnosed answers (scorers diagnose, relation; an addition): <b>Failure step</b> keeps the answers whose first failing "
    'step is the one chosen; <b>Egocentric / mirrored: drawn</b> marks the egocentric target (<b style="color:#D55E00">E</b>, '
    'a ring) and the mirrored target (<b style="color:#7B3294">M</b>, a square) beside the green ground truth, where the '
    "official metric places them in that frame (clamped to its border, at its centre when behind the camera). See the "
    "section Why it fails."
)

#: What a strip's tick means, for official rows (shown in an opened card).
OFFICIAL_STRIP_TICK = "the GT projects inside that frame, in front of its camera, and the anchor was seen there"

#: The same for a real-world set's rows (hand-marked ground truth, hit or miss).
SUCCESS_LEGEND = (
    "Each image is the letterboxed frame the model saw and selected (Inferred, Stated) or the observer view (Given).\n"
    '<span class="g">Green</span>: the ground truth marked in that frame: a point with its hit radius, a box or a region '
    "(none drawn when the selected frame carries no mark).\n"
    '<span class="p">Red cross</span>: the predicted point. <b>Hit</b>: the answer is within a mark; <b>miss</b> otherwise, '
    "and always when unanswered. Click a card for the full-size frame and the raw answer.\n"
    "Under an Inferred or Stated image, the strip of the house's frames in order: "
    '<span class="p">red outline</span>, the frame the model selected; <span class="g">&#10003;</span>, a frame with a hand-made mark.'
)

#: What a strip's tick means, for real-world rows.
SUCCESS_STRIP_TICK = "that frame carries a hand-made mark of the target"


def template() -> str:
    """The page template shipped with the package."""
    return files("povagent.report").joinpath("assets", TEMPLATE).read_text(encoding="utf-8")


#: Characters written as JSON ``\\u`` escapes in data embedded in the page: ``<``, ``>`` and ``&``
#: could open ``</script>``, ``<!--`` or ``<script`` inside a script element (HTML reads those
#: before JavaScript does); U+2028 and U+2029 end a line in older JavaScript. Each may stand
#: only inside a JSON string, where its escape decodes to the same character.
SCRIPT_ESCAPES = str.maketrans({c: f"\\u{ord(c):04x}" for c in "<>&\u2028\u2029"})


def script_json(data: Any) -> str:
    """``data`` as JSON that is safe inside a ``<script>`` element and reads back as ``data``:
    no markup character, whatever text a sentence or a model answer holds (see
    :data:`SCRIPT_ESCAPES`); both the page's embedded data and the answers files use it.

    A number that is not finite (an official reading's overflowing coordinate) has no JSON
    form: it is written as its JavaScript name, ``"Infinity"``, ``"-Infinity"`` or ``"NaN"``,
    which the page's ``Number()`` reads back as the number."""
    try:
        text = json.dumps(data, ensure_ascii=False, separators=(",", ":"), allow_nan=False)
    except ValueError:  # a number that is not finite: named (the walk costs only then)
        text = json.dumps(_finite(data), ensure_ascii=False, separators=(",", ":"), allow_nan=False)
    return text.translate(SCRIPT_ESCAPES)


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def tables_section(tables: Iterable[Table], downloads: dict[str, list[tuple[str, str]]] | None = None) -> str:
    """The tables, each followed by links to its Markdown/CSV/LaTeX files."""
    tables = list(tables)
    folded: dict[str, list[Table]] = {}
    for t in tables:
        if t.folded_under is not None and any(u.key == t.folded_under for u in tables):
            folded.setdefault(t.folded_under, []).append(t)
    parts = ['<section id="tables"><h2>Tables</h2>']

    def one(t: Table) -> None:
        # a table wider than the page scrolls inside its own box, never the whole page
        parts.append(f'<div class="table-box">{to_html(t)}</div>')
        links = (downloads or {}).get(t.key)
        if links:
            parts.append('<div class="downloads">' + " · ".join(f'<a href="{html.escape(href)}">{html.escape(name)}</a>' for name, href in links) + "</div>")

    for t in tables:
        if any(t in under for under in folded.values()):
            continue
        one(t)
        for inner in folded.get(t.key, []):  # one click away, under the table it details
            parts.append(f'<details class="folded" id="folded-{html.escape(inner.key)}"><summary>{html.escape(inner.title)}</summary>')
            one(inner)
            parts.append("</details>")
    parts.append("</section>")
    return "".join(parts)


def figures_section(figures: dict[str, tuple[str, str]]) -> str:
    """The plots as inline SVG with captions; scatter plots side by side."""
    parts = ['<section id="plots"><h2>Plots</h2>']
    scatters = {k: v for k, v in figures.items() if k.startswith("scatter_")}
    for name, (caption, svg) in figures.items():
        if name in scatters:
            continue
        parts.append(f'<figure id="fig-{html.escape(name)}">{svg}<figcaption>{html.escape(caption)}</figcaption></figure>')
    if scatters:
        parts.append('<h3>Predicted vs ground truth</h3><div class="plots-row">')
        for name, (caption, svg) in scatters.items():
            parts.append(f'<figure id="fig-{html.escape(name)}">{svg}<figcaption>{html.escape(caption)}</figcaption></figure>')
        parts.append("</div>")
    parts.append("</section>")
    return "".join(parts)


def notes_section(notes: Iterable[str], title: str = "How to read this report") -> str:
    """A bulleted list of notes (protocol, computed baselines, caveats)."""
    items = "".join(f"<li>{html.escape(n)}</li>" for n in notes)
    return f'<section id="notes"><h2>{html.escape(title)}</h2><ul class="notes">{items}</ul></section>'


def render_page(
    title: str,
    subtitle: str,
    body: str,
    gallery: dict[str, Any] | None,
    nav: list[tuple[str, str]] | None = None,
    sort_extra: str = "",
    legend: str = OFFICIAL_LEGEND,
) -> str:
    """The whole page: ``gallery`` is ``{"systems": [...], "entries": [...], ...}`` or ``None``;
    ``legend`` (markup) says how to read its drawings."""
    nav = list(nav or [])
    if gallery is not None:
        nav.append(("#gallery-section", "Gallery"))
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    page = template()
    fields = {
        "{{TITLE}}": html.escape(title),
        "{{SUBTITLE}}": html.escape(subtitle) + f" · generated {stamp}",
        "{{NAV}}": "".join(f'<a href="{html.escape(h)}">{html.escape(n)}</a>' for h, n in nav),
        "{{BODY}}": body,
        "{{GALLERY_HIDDEN}}": "" if gallery is not None else "hidden",
        "{{LEGEND}}": legend,
        "{{RUN_NOTE}}": html.escape((gallery or {}).get("run_note") or ""),
        "{{SORT_EXTRA}}": sort_extra,
        "{{DIRECTION_OPTIONS}}": "".join(f"<option>{html.escape(name)}</option>" for name in DIRECTION_NAMES),
        "{{GALLERY_JSON}}": script_json(gallery or {"entries": [], "systems": []}),
    }
    # one pass, so text inserted for one placeholder is never read as another placeholder
    return re.sub(r"\{\{[A-Z_]+\}\}", lambda m: fields.get(m.group(0), m.group(0)), page)
