"""A small table model and its renderings: Markdown, CSV, LaTeX (booktabs) and HTML.

A :class:`Table` holds numbers, not strings: each column knows its kind (an error, a rate, a
p-value, a count) and which direction is better, so every rendering bolds the same best value
per column. Reference rows (the center baseline) are shown under a rule and never bolded: the
bold marks the best *model*, as in the paper. Ties at the displayed precision are all bolded.

Rendering only: which tables a report has is :mod:`povagent.report.paper_tables`' job.
"""

from __future__ import annotations

import csv
import html
import io
from dataclasses import dataclass, field
from typing import Literal

from povagent.report.csv_formulas import inert

Kind = Literal["l2", "rate", "p", "count", "signed"]
Better = Literal["lower", "higher", None]


@dataclass(frozen=True)
class Column:
    """A column: header, kind of number, and which way is better (``None``: no bold)."""

    name: str
    kind: Kind = "l2"
    better: Better = "lower"


@dataclass(frozen=True)
class Cell:
    """A number with an optional 95% CI."""

    value: float | None
    lo: float | None = None
    hi: float | None = None


@dataclass
class Row:
    """A labelled row; ``reference`` rows (baselines) are set apart and never bolded."""

    label: str
    cells: list[Cell]
    reference: bool = False


@dataclass
class Table:
    """One table of a report."""

    key: str
    title: str
    caption: str
    row_header: str
    columns: list[Column]
    rows: list[Row] = field(default_factory=list)
    show_ci: bool = True
    #: The key of the table this one is folded under on the report's page (one click opens it
    #: there); ``None``: shown in its own place. Exports list it as any other table.
    folded_under: str | None = None

    def numbers(self) -> dict[str, object]:
        """The table's numbers for a ``summary.json``: its title, columns and, per row, each
        cell's value with its CI (``None`` where it has none)."""
        return {
            "title": self.title,
            "columns": [c.name for c in self.columns],
            "rows": {r.label: [{"value": c.value, "ci_lo": c.lo, "ci_hi": c.hi} for c in r.cells] for r in self.rows},
        }


def format_value(value: float | None, kind: Kind) -> str:
    """The displayed text of a number of a given kind (``--`` for missing)."""
    if value is None:
        return "--"
    if kind == "rate":
        return f"{100.0 * value:.1f}%"
    if kind == "count":
        return f"{int(round(value))}"
    if kind == "p":
        return "<0.001" if value < 0.001 else f"{value:.3f}"
    if kind == "signed":
        return f"{value:+.3f}"
    return f"{value:.3f}"


def _format_ci(cell: Cell, kind: Kind) -> str:
    if cell.lo is None or cell.hi is None:
        return ""
    if kind == "rate":
        return f"[{100 * cell.lo:.1f}, {100 * cell.hi:.1f}]"
    if kind == "signed":
        return f"[{cell.lo:+.3f}, {cell.hi:+.3f}]"
    return f"[{cell.lo:.3f}, {cell.hi:.3f}]"


def best_rows(table: Table) -> list[set[int]]:
    """Per column, the indices of the rows holding the best displayed value (models only)."""
    out: list[set[int]] = []
    for j, col in enumerate(table.columns):
        if col.better is None:
            out.append(set())
            continue
        shown: dict[int, float] = {}
        for i, row in enumerate(table.rows):
            v = row.cells[j].value if j < len(row.cells) else None
            if row.reference or v is None:
                continue
            # compare what the reader sees, so equal printed values are bolded together
            shown[i] = float(format_value(v, col.kind).rstrip("%").lstrip("<"))
        if len(shown) < 2:
            out.append(set())
            continue
        target = min(shown.values()) if col.better == "lower" else max(shown.values())
        out.append({i for i, v in shown.items() if v == target})
    return out


def _ordered_rows(table: Table) -> list[tuple[int, Row]]:
    """Model rows first, reference rows after (a rule separates them)."""
    models = [(i, r) for i, r in enumerate(table.rows) if not r.reference]
    refs = [(i, r) for i, r in enumerate(table.rows) if r.reference]
    return models + refs


def to_markdown(table: Table) -> str:
    """GitHub Markdown; best values in ``**bold**``, CIs in brackets, reference rows in italics."""
    best = best_rows(table)
    head = [table.row_header] + [c.name for c in table.columns]
    lines = [f"**{table.title}**", "", "| " + " | ".join(head) + " |", "|" + "|".join(["---"] + [":---:"] * len(table.columns)) + "|"]
    for i, row in _ordered_rows(table):
        cells = []
        for j, col in enumerate(table.columns):
            c = row.cells[j]
            text = format_value(c.value, col.kind)
            if i in best[j]:
                text = f"**{text}**"
            ci = _format_ci(c, col.kind) if table.show_ci else ""
            cells.append(f"{text} {ci}".strip())
        label = f"*{row.label}*" if row.reference else row.label
        lines.append("| " + " | ".join([_md_escape(label)] + cells) + " |")
    lines += ["", table.caption]
    return "\n".join(lines) + "\n"


def _md_escape(text: str) -> str:
    return text.replace("|", "\\|")


def to_csv(table: Table) -> str:
    """CSV with full precision: per column its value, CI bounds, and a ``best`` flag; a label a
    spreadsheet would run as a formula is written inert (:mod:`povagent.report.csv_formulas`)."""
    best = best_rows(table)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    header = [table.row_header, "reference"]
    for c in table.columns:
        header += [c.name, f"{c.name} ci_lo", f"{c.name} ci_hi", f"{c.name} best"]
    w.writerow([inert(h) for h in header])
    for i, row in _ordered_rows(table):
        out: list[object] = [inert(row.label), int(row.reference)]
        for j, _ in enumerate(table.columns):
            cell = row.cells[j]
            out += [_num(cell.value), _num(cell.lo), _num(cell.hi), int(i in best[j])]
        w.writerow(out)  # the numbers are written as numbers (repr), never guarded
    return buf.getvalue()


def _num(v: float | None) -> str:
    return "" if v is None else repr(float(v))


_LATEX_SPECIAL = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
    "·": r"$\cdot$",
}


def latex_escape(text: str) -> str:
    """Escape LaTeX's special characters in plain text."""
    return "".join(_LATEX_SPECIAL.get(ch, ch) for ch in text)


def to_latex(table: Table) -> str:
    """A ``table`` environment with a booktabs ``tabular``; best values ``\\textbf``, CIs in
    ``\\scriptsize`` below-precision brackets, reference rows under a ``\\midrule``."""
    best = best_rows(table)
    spec = "l" + "c" * len(table.columns)
    lines = [
        "% requires \\usepackage{booktabs}",
        "\\begin{table}[t]",
        "\\centering",
        "\\small",
        f"\\begin{{tabular}}{{{spec}}}",
        "\\toprule",
        " & ".join([f"\\textbf{{{latex_escape(table.row_header)}}}"] + [f"\\textbf{{{latex_escape(c.name)}}}" for c in table.columns]) + " \\\\",
        "\\midrule",
    ]
    ordered = _ordered_rows(table)
    seen_ref = False
    for i, row in ordered:
        if row.reference and not seen_ref and any(not r.reference for _, r in ordered):
            lines.append("\\midrule")
        seen_ref = seen_ref or row.reference
        cells = []
        for j, col in enumerate(table.columns):
            c = row.cells[j]
            text = latex_escape(format_value(c.value, col.kind))
            if i in best[j]:
                text = f"\\textbf{{{text}}}"
            ci = _format_ci(c, col.kind) if table.show_ci else ""
            if ci:
                text += f"\\,{{\\scriptsize {latex_escape(ci)}}}"
            cells.append(text)
        label = latex_escape(row.label)
        if row.reference:
            label = f"\\textit{{{label}}}"
        lines.append(" & ".join([label] + cells) + " \\\\")
    lines += [
        "\\bottomrule",
        "\\end{tabular}",
        f"\\caption{{{latex_escape(table.caption)}}}",
        f"\\label{{tab:{table.key}}}",
        "\\end{table}",
    ]
    return "\n".join(lines) + "\n"


def to_html(table: Table) -> str:
    """An HTML ``<table>`` (no styles inline; the report's stylesheet styles ``.best``, ``.ci``)."""
    best = best_rows(table)
    e = html.escape
    parts = [f'<table class="results" id="table-{e(table.key)}" data-table="{e(table.key)}">']
    parts.append(f"<caption><b>{e(table.title)}.</b> {e(table.caption)}</caption>")
    parts.append("<thead><tr><th>" + e(table.row_header) + "</th>" + "".join(f"<th>{e(c.name)}</th>" for c in table.columns) + "</tr></thead><tbody>")
    for i, row in _ordered_rows(table):
        cls = ' class="reference"' if row.reference else ""
        tds = []
        for j, col in enumerate(table.columns):
            c = row.cells[j]
            text = e(format_value(c.value, col.kind))
            if i in best[j]:
                text = f'<span class="best">{text}</span>'
            ci = _format_ci(c, col.kind) if table.show_ci else ""
            if ci:
                text += f' <span class="ci">{e(ci)}</span>'
            tds.append(f"<td>{text}</td>")
        parts.append(f"<tr{cls}><th scope=\"row\">{e(row.label)}</th>{''.join(tds)}</tr>")
    parts.append("</tbody></table>")
    return "".join(parts)
