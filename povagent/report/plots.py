"""The report's plots as inline SVG strings: grouped bars with CIs, scatter, histogram.

SVG rather than PNG: it is sharp at any zoom, a few kilobytes, needs no plotting library and
sits inside the HTML (and in ``plots/*.svg`` for a paper). Every function is pure: data in,
an ``<svg>`` string out; nothing is written here.
"""

from __future__ import annotations

import hashlib
import html
import math
from dataclasses import dataclass
from typing import Sequence

from povagent.report.statistics import Estimate

#: Okabe-Ito colours (distinguishable with the common colour-vision deficiencies), black left
#: out: it would read as the near-black baseline.
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442")
#: Baselines (center, random, oracle, ...): grey, brown, near-black, light grey. Apart from the
#: models' hues, and apart from each other in lightness too, so a grey print still tells them apart.
REFERENCE_COLOURS = ("#7a7a7a", "#8c510a", "#1a1a1a", "#bdbdbd")
#: Marker shapes: models filled, baselines hollow (a legend entry and its bars or lines share
#: it, so colour is never the only cue). Model ``i`` is colour ``i mod 7`` with shape ``i mod 5``:
#: 7 and 5 share no factor, so the first 35 models each get their own pair, and neighbours
#: differ in both.
MODEL_MARKERS = ("circle", "square", "triangle", "diamond", "triangle-down")
REFERENCE_MARKERS = ("diamond", "square", "triangle", "triangle-down")
#: How many models get a pair of their own (then pairs come round again).
DISTINCT_MODEL_STYLES = len(PALETTE) * len(MODEL_MARKERS)
#: Where a one-row legend ends (its rows are 17 px apart).
LEGEND_ROW_BOTTOM = 38 + 14
FONT = 'font-family="system-ui, -apple-system, Segoe UI, Helvetica, Arial, sans-serif"'


def colour(i: int) -> str:
    """The i-th series colour."""
    return PALETTE[i % len(PALETTE)]


@dataclass(frozen=True)
class SeriesStyle:
    """How one series is drawn: colour, marker shape, and whether it is a baseline (hollow
    markers, hatched bars, dashed lines)."""

    colour: str
    marker: str
    reference: bool


def series_styles(series: Sequence[tuple]) -> list[SeriesStyle]:
    """A style per ``(name, values, is_reference)`` series: palette hues and filled markers for
    models; baseline colours, hollow markers and hatching for baselines."""
    out, models, refs = [], 0, 0
    for _, _, ref in series:
        if ref:
            k = refs % len(REFERENCE_COLOURS)
            out.append(SeriesStyle(REFERENCE_COLOURS[k], REFERENCE_MARKERS[k], True))
            refs += 1
        else:
            out.append(SeriesStyle(colour(models), MODEL_MARKERS[models % len(MODEL_MARKERS)], False))
            models += 1
    return out


def marker(style: SeriesStyle, x: float, y: float, r: float = 4.5) -> str:
    """The series' marker centred at ``(x, y)``: filled for a model, hollow for a baseline."""
    fill = "#fff" if style.reference else style.colour
    paint = f'fill="{fill}" stroke="{style.colour}" stroke-width="1.6"'
    if style.marker == "square":
        return f'<rect class="marker" x="{x - r:.1f}" y="{y - r:.1f}" width="{2 * r:.1f}" height="{2 * r:.1f}" {paint}/>'
    if style.marker == "triangle":
        return f'<path class="marker" d="M{x:.1f} {y - r * 1.15:.1f}L{x + r:.1f} {y + r * 0.85:.1f}H{x - r:.1f}Z" {paint}/>'
    if style.marker == "triangle-down":
        return f'<path class="marker" d="M{x:.1f} {y + r * 1.15:.1f}L{x + r:.1f} {y - r * 0.85:.1f}H{x - r:.1f}Z" {paint}/>'
    if style.marker == "diamond":
        q = r * 1.25
        return f'<path class="marker" d="M{x:.1f} {y - q:.1f}L{x + q:.1f} {y:.1f}L{x:.1f} {y + q:.1f}L{x - q:.1f} {y:.1f}Z" {paint}/>'
    return f'<circle class="marker" cx="{x:.1f}" cy="{y:.1f}" r="{r:.1f}" {paint}/>'


def _hatch_defs(styles: Sequence[SeriesStyle], uid: str) -> str:
    """SVG patterns hatching baseline bars in their colour (a model's bar is solid)."""
    parts = []
    for i, st in enumerate(styles):
        if st.reference:
            angle = (45, -45, 0, 90)[i % 4]
            parts.append(
                f'<pattern id="{uid}-h{i}" width="6" height="6" patternUnits="userSpaceOnUse" patternTransform="rotate({angle})">'
                f'<rect width="6" height="6" fill="#fff"/><rect width="3" height="6" fill="{st.colour}"/></pattern>'
            )
    return "<defs>" + "".join(parts) + "</defs>" if parts else ""


def _bar_fill(st: SeriesStyle, i: int, uid: str) -> str:
    return f'fill="url(#{uid}-h{i})" stroke="{st.colour}" stroke-width="1"' if st.reference else f'fill="{st.colour}"'


def _e(text: str) -> str:
    return html.escape(text, quote=True)


def _svg_open(width: float, height: float, title: str) -> str:
    """A plot's opening ``<svg>`` tag, labelled with its title for screen readers."""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="plot" viewBox="0 0 {width} {height}" width="{width}" height="{height}" {FONT} role="img" '
        f'aria-label="{_e(title)}">'
    )


def _nice_max(v: float) -> float:
    if v <= 0:
        return 1.0
    exp = 10 ** math.floor(math.log10(v))
    for m in (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10):
        if m * exp >= v:
            return m * exp
    return 10 * exp


def _legend(
    names: Sequence[str], colours: Sequence[str], x: float, y: float, width: float, styles: Sequence[SeriesStyle] | None = None
) -> tuple[list[str], float]:
    """Legend entries: a swatch (with the series' marker when ``styles`` are given) and the name."""
    out, cx, cy = [], x, y
    for i, (name, col) in enumerate(zip(names, colours)):
        w = 24 + 6.5 * len(name) + 14
        if cx + w > x + width and cx > x:
            cx, cy = x, cy + 17
        if styles is not None:
            st = styles[i]
            out.append(f'<g class="legend-entry" data-series="{_e(name)}" data-marker="{st.marker}" data-colour="{st.colour}">')
            out.append(f'<line x1="{cx:.1f}" x2="{cx + 18:.1f}" y1="{cy - 4:.1f}" y2="{cy - 4:.1f}" stroke="{col}" stroke-width="2"'
                       + (' stroke-dasharray="4 2"' if st.reference else "") + "/>")
            out.append(marker(st, cx + 9, cy - 4, 4.0))
            out.append(f'<text x="{cx + 22:.1f}" y="{cy:.1f}" font-size="11">{_e(name)}</text></g>')
        else:
            out.append(f'<rect x="{cx:.1f}" y="{cy - 9:.1f}" width="12" height="10" fill="{col}"/>')
            out.append(f'<text x="{cx + 16:.1f}" y="{cy:.1f}" font-size="11">{_e(name)}</text>')
        cx += w
    return out, cy + 14


def _fitted_text(text: str, x: float, y: float, max_width: float, font_size: float) -> str:
    """A bold title squeezed to ``max_width`` when its estimated width exceeds it: a long
    system name (``qwen3-vl-8b-transformers · spatial-cot: x``) stays whole instead of being
    cut at the plot's edge."""
    estimate = 0.6 * font_size * len(text)
    fit = f' textLength="{max_width - x:.0f}" lengthAdjust="spacingAndGlyphs"' if estimate > max_width - x else ""
    return f'<text x="{x}" y="{y}" font-size="{font_size}" font-weight="600"{fit}>{_e(text)}</text>'


def wrapped_lines(text: str, max_chars: int) -> list[str]:
    """``text`` in lines of at most ``max_chars`` characters, broken after a space, ``/`` or
    ``-`` where it can be (a system name such as ``qwen3-vl-8b-transformers · spatial-cot``),
    inside a word only when a word alone is longer than a line. Nothing is dropped."""
    import re

    pieces = re.findall(r"[^\s/-]*[\s/-]*", text)
    lines: list[str] = []
    line = ""
    for piece in (p for p in pieces if p):
        while len(piece) > max_chars:  # a word longer than a line: cut it
            if line:
                lines.append(line.rstrip())
                line = ""
            lines.append(piece[:max_chars])
            piece = piece[max_chars:]
        if len((line + piece).rstrip()) > max_chars and line:
            lines.append(line.rstrip())
            line = ""
        line += piece
    if line.strip():
        lines.append(line.rstrip())
    return lines or [""]


def _wrapped_text(text: str, x: float, y: float, max_width: float, font_size: float, line_height: float) -> tuple[str, int]:
    """A bold label wrapped onto lines that fit ``max_width`` (estimated at 0.6 em a
    character), never squeezed: ``(svg, number of lines)``."""
    chars = max(8, int(max_width / (0.6 * font_size)))
    lines = wrapped_lines(text, chars)
    spans = "".join(f'<tspan x="{x}" dy="{0 if i == 0 else line_height}">{_e(line)}</tspan>' for i, line in enumerate(lines))
    return f'<text x="{x}" y="{y}" font-size="{font_size}" font-weight="600">{spans}<title>{_e(text)}</title></text>', len(lines)


def _uid(title: str, names: Sequence[str]) -> str:
    """An id prefix for a plot's patterns: several plots share one page, so ids must differ."""
    return "p" + hashlib.sha256((title + "|" + "|".join(names)).encode()).hexdigest()[:8]


def grouped_bars(
    title: str,
    groups: Sequence[str],
    series: Sequence[tuple[str, Sequence[Estimate | None], bool]],
    y_label: str = "mean normalized L2",
    width: int = 820,
    height: int = 340,
    y_limit: float | None = None,
) -> str:
    """Bars per group and series, with CI whiskers; a series is ``(name, estimates, reference)``.
    ``y_limit``: the axis's top (a rate's is 1); ``None``: a round number above the tallest bar."""
    styles = series_styles(series)
    colours = [st.colour for st in styles]
    uid = _uid(title, [s[0] for s in series])
    legend, top = _legend([s[0] for s in series], colours, 60, 38, width - 80, styles)
    height += round(top - LEGEND_ROW_BOTTOM)  # each legend row past the first adds height: the plot keeps its own
    top += 6  # room for a marker on the tallest bar
    left, right, bottom = 60, 16, 46
    plot_h = height - top - bottom
    vals = [e.hi if e and e.hi is not None else (e.value if e and e.value is not None else 0.0) for _, ests, _ in series for e in ests]
    y_max = y_limit if y_limit is not None else _nice_max(max(vals, default=0.0) * 1.05)
    plot_w = width - left - right
    gw = plot_w / max(1, len(groups))
    bw = min(28.0, gw * 0.8 / max(1, len(series)))

    def y(v: float) -> float:
        return top + plot_h * (1 - v / y_max)

    out = [_svg_open(width, height, title)]
    out.append(_hatch_defs(styles, uid))
    out.append(f'<text x="{left}" y="18" font-size="14" font-weight="600">{_e(title)}</text>')
    out += legend
    for k in range(6):
        v = y_max * k / 5
        out.append(f'<line x1="{left}" x2="{width - right}" y1="{y(v):.1f}" y2="{y(v):.1f}" stroke="#e5e5e5"/>')
        out.append(f'<text x="{left - 6}" y="{y(v) + 4:.1f}" font-size="10" text-anchor="end">{v:.2f}</text>')
    out.append(f'<text transform="translate(14,{top + plot_h / 2:.0f}) rotate(-90)" font-size="11" text-anchor="middle">{_e(y_label)}</text>')
    for g, name in enumerate(groups):
        gx = left + g * gw + (gw - bw * len(series)) / 2
        for s, (sname, ests, _) in enumerate(series):
            e = ests[g] if g < len(ests) else None
            if e is None or e.value is None:
                continue
            x = gx + s * bw
            out.append(
                f'<rect x="{x:.1f}" y="{y(e.value):.1f}" width="{bw - 2:.1f}" height="{max(0.0, y(0) - y(e.value)):.1f}" {_bar_fill(styles[s], s, uid)}>'
                f"<title>{_e(sname)} / {_e(name)}: {e.value:.3f}"
                + (f" [{e.lo:.3f}, {e.hi:.3f}]" if e.lo is not None and e.hi is not None else "")
                + "</title></rect>"
            )
            cx = x + (bw - 2) / 2
            if e.lo is not None and e.hi is not None:
                out.append(
                    f'<path d="M{cx:.1f} {y(e.lo):.1f}V{y(e.hi):.1f}M{cx - 3:.1f} {y(e.lo):.1f}h6M{cx - 3:.1f} {y(e.hi):.1f}h6" stroke="#222" stroke-width="1" '
                    'fill="none"/>'
                )
            # the marker sits on the bar's top: a bar of height 0 (the oracle) is still seen
            out.append(marker(styles[s], cx, y(e.value), min(4.5, max(2.5, (bw - 2) / 2.4))))
        out.append(f'<text x="{left + g * gw + gw / 2:.1f}" y="{height - bottom + 16}" font-size="11" text-anchor="middle">{_e(name)}</text>')
    out.append(f'<line x1="{left}" x2="{width - right}" y1="{y(0):.1f}" y2="{y(0):.1f}" stroke="#444"/>')
    out.append("</svg>")
    return "".join(out)


def scatter(
    title: str,
    points: Sequence[tuple[float, float, int]],
    category_names: Sequence[str],
    x_label: str,
    y_label: str,
    size: int = 300,
) -> str:
    """Predicted (y axis) against GT (x axis) on [0, 1], with the diagonal; points are
    ``(gt, predicted, category index)``."""
    pad_l, pad_b, pad_t = 44, 40, 44
    plot = size - pad_l - 12
    height = plot + pad_t + pad_b
    names = list(category_names)
    legend, _ = _legend(names, [colour(i) for i in range(len(names))], pad_l, 34, plot)

    def px(v: float) -> float:
        return pad_l + plot * min(1.0, max(0.0, v))

    def py(v: float) -> float:
        return pad_t + plot * (1 - min(1.0, max(0.0, v)))

    out = [_svg_open(size, height, title)]
    out.append(_fitted_text(title, 8, 18, size - 12, 13))
    out += legend
    out.append(f'<rect x="{pad_l}" y="{pad_t}" width="{plot}" height="{plot}" fill="none" stroke="#999"/>')
    out.append(f'<line x1="{px(0)}" y1="{py(0)}" x2="{px(1)}" y2="{py(1)}" stroke="#bbb" stroke-dasharray="4 3"/>')
    for k in (0, 0.5, 1):
        out.append(f'<text x="{px(k):.1f}" y="{pad_t + plot + 14}" font-size="10" text-anchor="middle">{k:g}</text>')
        out.append(f'<text x="{pad_l - 5}" y="{py(k) + 4:.1f}" font-size="10" text-anchor="end">{k:g}</text>')
    out.append(f'<text x="{pad_l + plot / 2:.0f}" y="{height - 8}" font-size="11" text-anchor="middle">{_e(x_label)}</text>')
    out.append(f'<text transform="translate(12,{pad_t + plot / 2:.0f}) rotate(-90)" font-size="11" text-anchor="middle">{_e(y_label)}</text>')
    # one <path> per category: thousands of points stay a few hundred kilobytes at most
    by_cat: dict[int, list[str]] = {}
    for g, p, cat in points:
        if not (math.isfinite(g) and math.isfinite(p)):
            continue
        by_cat.setdefault(cat, []).append(f"M{px(g):.1f} {py(p):.1f}h0")
    for cat, segs in by_cat.items():
        out.append(f'<path d="{"".join(segs)}" stroke="{colour(cat)}" stroke-opacity="0.55" stroke-width="3.2" stroke-linecap="round" fill="none"/>')
    out.append("</svg>")
    return "".join(out)


def histogram(
    title: str,
    series: Sequence[tuple[str, Sequence[float], bool]],
    lo: float = 0.0,
    hi: float = math.sqrt(2.0),
    bins: int = 28,
    width: int = 820,
    height: int = 300,
    x_label: str = "normalized L2",
) -> str:
    """Step outlines of each series' distribution (share of its values per bin)."""
    styles = series_styles(series)
    colours = [st.colour for st in styles]
    legend, top = _legend([s[0] for s in series], colours, 60, 38, width - 80, styles)
    height += round(top - LEGEND_ROW_BOTTOM)  # each legend row past the first adds height: the plot keeps its own
    top += 6
    left, right, bottom = 60, 16, 40
    plot_h, plot_w = height - top - bottom, width - left - right
    shares: list[list[float]] = []
    for _, values, _ in series:
        counts = [0] * bins
        vals = [v for v in values if v is not None and math.isfinite(v)]
        for v in vals:
            k = int((min(hi, max(lo, v)) - lo) / (hi - lo) * bins)
            counts[min(bins - 1, k)] += 1
        n = max(1, len(vals))
        shares.append([c / n for c in counts])
    # shares never exceed 100%: an axis up to 120% would only waste height
    y_max = min(1.0, _nice_max(max((s for row in shares for s in row), default=0.0) * 1.05))

    def x(v: float) -> float:
        return left + plot_w * (v - lo) / (hi - lo)

    def y(v: float) -> float:
        return top + plot_h * (1 - v / y_max)

    out = [_svg_open(width, height, title)]
    out.append(f'<text x="{left}" y="18" font-size="14" font-weight="600">{_e(title)}</text>')
    out += legend
    for k in range(6):
        v = y_max * k / 5
        out.append(f'<line x1="{left}" x2="{width - right}" y1="{y(v):.1f}" y2="{y(v):.1f}" stroke="#e5e5e5"/>')
        out.append(f'<text x="{left - 6}" y="{y(v) + 4:.1f}" font-size="10" text-anchor="end">{100 * v:.0f}%</text>')
    for t in (0, 0.25, 0.5, 0.75, 1.0, 1.25, hi):
        out.append(f'<text x="{x(t):.1f}" y="{height - bottom + 14}" font-size="10" text-anchor="middle">{t:.2f}</text>')
    out.append(f'<text x="{left + plot_w / 2:.0f}" y="{height - 6}" font-size="11" text-anchor="middle">{_e(x_label)}</text>')
    step = (hi - lo) / bins
    for s, row in enumerate(shares):
        d = f"M{x(lo):.1f} {y(0):.1f}"
        for k, share in enumerate(row):
            d += f"V{y(share):.1f}H{x(lo + (k + 1) * step):.1f}"
        d += f"V{y(0):.1f}"
        dash = ' stroke-dasharray="5 3"' if styles[s].reference else ""
        out.append(f'<path d="{d}" fill="none" stroke="{colours[s]}" stroke-width="1.8"{dash}><title>{_e(series[s][0])}</title></path>')
        # a marker on every third non-empty bin's top, staggered by series (and a little apart)
        # so that equal shares (baselines often pile into one bin) do not hide one another,
        # and a series' peak always carries one
        shift = (s - (len(shares) - 1) / 2) * min(3.0, step / (hi - lo) * plot_w / max(1, len(shares)))
        peak = max(range(bins), key=lambda k: row[k])
        for k, share in enumerate(row):
            if share > 0 and ((k + s) % 3 == 0 or k == peak):
                out.append(marker(styles[s], x(lo + (k + 0.5) * step) + shift, y(share), 3.2))
    out.append(f'<line x1="{left}" x2="{width - right}" y1="{y(0):.1f}" y2="{y(0):.1f}" stroke="#444"/>')
    out.append("</svg>")
    return "".join(out)


@dataclass(frozen=True)
class StackedBar:
    """One horizontal bar of :func:`stacked_bars`: its group (a system), its own label (a
    condition), each part's share, and where clicking each part leads (``None``: nowhere)."""

    group: str
    label: str
    shares: dict[str, float | None]
    links: dict[str, str | None]


def stacked_bars(title: str, bars: Sequence[StackedBar], parts: Sequence[str], colours: Sequence[str], width: int = 820) -> str:
    """Horizontal bars from 0 to 100%, each split into ``parts`` (in that order, each in its
    colour), grouped under their group's name; every part is a link (``<a href>``) and carries
    a tooltip with its share."""
    left, right, bar_h, gap, group_gap = 300, 20, 16, 4, 12
    legend, top = _legend(list(parts), list(colours), 8, 38, width - 16)
    top += 6
    plot_w = width - left - right
    y = top
    body: list[str] = []
    previous = None
    line_h = 14
    group_end = 0.0  # where the current group's wrapped name ends: the next group starts below it
    for bar in bars:
        if bar.group != previous:
            if previous is not None:
                y = max(y, group_end) + group_gap
            # a long system name wraps onto lines beside its bars (never squeezed); the bars leave
            # room below when its lines outnumber them
            label, n_lines = _wrapped_text(bar.group, 8, y + bar_h - 3, left - 58, 12, line_h)
            body.append(label)
            group_end = y + bar_h - 3 + (n_lines - 1) * line_h + 6
            previous = bar.group
        body.append(f'<text x="{left - 8}" y="{y + bar_h - 4}" font-size="11" text-anchor="end">{_e(bar.label)}</text>')
        x = float(left)
        for part, col in zip(parts, colours):
            share = bar.shares.get(part)
            if not share:
                continue
            w = plot_w * share
            tip = f"{bar.group} · {bar.label}: {part} {100 * share:.1f}%"
            rect = f'<rect x="{x:.1f}" y="{y}" width="{w:.1f}" height="{bar_h}" fill="{col}" data-part="{_e(part)}"><title>{_e(tip)}</title></rect>'
            if w >= 34:
                rect += (f'<text x="{x + w / 2:.1f}" y="{y + bar_h - 4}" font-size="10" text-anchor="middle" fill="#fff" '
                         f'pointer-events="none">{100 * share:.0f}%</text>')
            link = bar.links.get(part)
            body.append(f'<a href="{_e(link)}">{rect}</a>' if link else rect)
            x += w
        y += bar_h + gap
    y = max(y, group_end)
    height = y + 30
    out = [_svg_open(width, height, title)]
    out.append(_fitted_text(title, 8, 18, width - 12, 13))
    out += legend
    for k in range(0, 101, 25):
        gx = left + plot_w * k / 100
        out.append(f'<line x1="{gx:.1f}" x2="{gx:.1f}" y1="{top - 4}" y2="{y}" stroke="#e5e5e5"/>')
        out.append(f'<text x="{gx:.1f}" y="{y + 14}" font-size="10" text-anchor="middle">{k}%</text>')
    out += body
    out.append("</svg>")
    return "".join(out)
