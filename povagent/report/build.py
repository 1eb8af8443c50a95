"""Writing a report folder for a run or a sweep: tables, plots, summary and the HTML page.

Layout of ``--out``::

    report.html            the page (tables, plots, gallery); open it from disk
    images/<sha256>.jpg    gallery drawings (+ ``.t.jpg`` thumbnails), named by hash
    answers/<sha256>.js    raw answers, loaded by the page when a card is opened
    tables/<name>.md|.csv|.tex, tables.md, tables.tex
    plots/<name>.svg
    summary.json           every number of the report, with CIs

This module wires the steps together; each step lives in its own module.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from povagent.files.confined_write import ConfinedFolder, write_inside
from povagent.report.active_section import active_section
from povagent.report.analysis import Analysis, analyze, what_was_compared
from povagent.report.baseline import CENTER_SYSTEM
from povagent.report.choice_gold import SetQuestions
from povagent.report.choice_tables import choice_answers, choice_tables
from povagent.report.collect import collect, find_runs
from povagent.report.figures import report_figures
from povagent.report.gallery import ANSWERS_DIR, IMAGES_DIR, GalleryStats, build_gallery, write_answer_chunks
from povagent.report.gallery_runs import run_shown_note
from povagent.report.html import (
    DIAGNOSIS_LEGEND,
    OFFICIAL_LEGEND,
    OFFICIAL_STRIP_TICK,
    SUCCESS_LEGEND,
    SUCCESS_STRIP_TICK,
    figures_section,
    notes_section,
    render_page,
    tables_section,
)
from povagent.report.leaderboard import leaderboard_tables
from povagent.report.manual import manual_tables
from povagent.report.official_beside import official_beside_table
from povagent.report.paper_tables import paper_tables
from povagent.report.run_sets import load_collection_dataset
from povagent.report.statistics import DEFAULT_BOOT
from povagent.report.systems import Pooling
from povagent.report.tables import Table, to_csv, to_latex, to_markdown
from povagent.report.why import FIGURE as WHY_FIGURE
from povagent.report.why import failure_steps_figure, why_section
from povagent.results.summary_json import summary_json_text

REPORT_PAGE = "report.html"


@dataclass
class ReportResult:
    """What a report wrote and how long each step took."""

    out: Path
    page: Path
    tables: list[Table]
    analysis: Analysis
    gallery: GalleryStats | None
    dataset_note: str | None = None
    timings: dict[str, float] = field(default_factory=dict)
    #: Runs pooled into one system (``pool`` or a shared ``label:``); empty: every run its own system.
    poolings: list[Pooling] = field(default_factory=list)


def write_tables(tables: list[Table], out: Path) -> dict[str, list[tuple[str, str]]]:
    """Each table as Markdown, CSV and LaTeX under ``out/tables``, plus combined files;
    returns the per-table download links relative to ``out``."""
    links: dict[str, list[tuple[str, str]]] = {}
    for t in tables:
        for ext, text in (("md", to_markdown(t)), ("csv", to_csv(t)), ("tex", to_latex(t))):
            write_inside(out, f"tables/{t.key}.{ext}", text)
        links[t.key] = [(name, f"tables/{t.key}.{ext}") for name, ext in (("Markdown", "md"), ("CSV", "csv"), ("LaTeX", "tex"))]
    write_inside(out, "tables.md", "\n".join(to_markdown(t) for t in tables))
    write_inside(out, "tables.tex", "\n".join(to_latex(t) for t in tables))
    return links


def report_folder(source: Path, out: Path | None) -> Path:
    """The report's folder, made with its subfolders, none of them a link planted there.

    The default ``<source>/report`` lies in a run folder, which is untrusted: ``report`` and
    everything below it are opened without following links (see
    :mod:`povagent.files.confined_write`), a link is one line naming it. An ``--out`` the user
    typed is theirs to place (followed), its subfolders are not.
    """
    root, rel = (source, "report") if out is None else (out, "")
    with ConfinedFolder(root, rel) as folder:
        for name in ("tables", "plots", IMAGES_DIR, ANSWERS_DIR):
            folder.sub(name).close()
        return folder.path


def _frame_size_lookup(dataset: Any):
    if dataset is None:
        return None

    def size(instance_id: str) -> tuple[int, int]:
        inst = dataset.instance(instance_id)
        return inst.frame_size if inst is not None else (512, 512)

    return size


def write_report(
    source: str | Path,
    out: str | Path | None = None,
    dataset_path: str | Path | None = None,
    n_boot: int = DEFAULT_BOOT,
    gallery_limit: int | None = None,
    gallery: bool = True,
    workers: int | None = None,
    seed: int = 0,
    pool: bool = False,
) -> ReportResult:
    """Write the full report of a run or sweep folder (default ``out``: ``<source>/report``).

    Every run is its own system; ``pool`` pools runs of the same name (the notes say so)."""
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    source = Path(source)
    out = report_folder(source, Path(out) if out is not None else None)
    # the set first: the transient memory of reading its files does not stack on the rows' observations
    runs = find_runs(source)
    sets = SetQuestions()  # each set the runs asked, opened once for the gallery and the choice tables
    dataset, note = load_collection_dataset(runs, dataset_path, sets)
    collection = collect(source, pool=pool, runs=runs)
    timings["load"] = time.perf_counter() - t0

    t = time.perf_counter()
    analysis = analyze(collection, dataset, note, n_boot=n_boot, seed=seed)
    analysis.notes.extend(p.note() for p in collection.poolings)
    tables = paper_tables(analysis)
    beside = official_beside_table(collection)
    if beside is not None:  # repaired numbers never stand alone: the official parse beside them
        tables.append(beside)
    choices = choice_answers(collection, sets)
    # multiple-choice runs: the systems x sets leaderboard, then per set accuracy, pairs, confusion
    added = leaderboard_tables(collection, analysis, list(choices), dataset, n_boot=n_boot, seed=seed)
    added += choice_tables(collection, n_boot=n_boot, seed=seed, sets=sets, read=choices)
    added += manual_tables(source, collection.runs)  # judgements by hand of these runs (povagent annotate, judge mode)
    tables += added
    timings["statistics"] = time.perf_counter() - t

    t = time.perf_counter()
    links = write_tables(tables, out)
    figures = report_figures(analysis, _frame_size_lookup(dataset))
    why_figure = failure_steps_figure(analysis)
    for name, (_, svg) in (figures | ({WHY_FIGURE: why_figure} if why_figure else {})).items():
        write_inside(out, f"plots/{name}.svg", svg)
    timings["tables_plots"] = time.perf_counter() - t

    t = time.perf_counter()
    gallery_data = None
    gstats = None
    if gallery:
        shown = [s.system for s in analysis.systems if s.system != CENTER_SYSTEM]
        folders = {r.name: r.folder for r in collection.runs}  # active rows show their rendered views
        entries, gstats = build_gallery(analysis.observations, shown, dataset, out, gallery_limit, workers, folders)
        answers = write_answer_chunks(entries, out, keys=("a", "tr"))
        gallery_data = {
            "systems": shown, "entries": entries, "images_dir": "images", "answers_dir": ANSWERS_DIR, "answers": answers,
            "strips": gstats.strips,
            "views": gstats.views,
            "strip_tick": OFFICIAL_STRIP_TICK if analysis.has_official else SUCCESS_STRIP_TICK,
            "run_note": run_shown_note(analysis.observations, shown),
        }
        if dataset is None:
            analysis.notes.append("Gallery images need the dataset's frames: " + (note or "dataset not available") + ".")
    timings["gallery"] = time.perf_counter() - t

    t = time.perf_counter()
    why = why_section(analysis, why_figure)  # an addition: only when rows carry diagnose/relation scores
    # an addition too: only when a run used the active strategy
    active, active_numbers = active_section(collection, dataset, out, n_boot=n_boot, seed=seed)
    body = notes_section(analysis.notes) + tables_section(tables, links) + figures_section(figures) + why + active
    n_rows = sum(len(r.rows) for r in collection.runs)
    legend = "<br>".join(
        text for text, shown in ((OFFICIAL_LEGEND, analysis.has_official), (SUCCESS_LEGEND, analysis.has_success),
                                 (DIAGNOSIS_LEGEND, analysis.has_diagnostics)) if shown
    )
    subtitle = (
        f"{source} · {len(collection.runs)} run folder{'s' if len(collection.runs) != 1 else ''} · "
        f"{what_was_compared(analysis)} · {n_rows} rows"
    )
    if analysis.dataset_path:
        subtitle += f" · {'real-world set' if analysis.has_success and not analysis.has_official else 'dataset'} {analysis.dataset_path}"
    page_html = render_page(
        f"povagent report: {source.name}",
        subtitle,
        body,
        gallery_data,
        nav=[("#notes", "Notes"), ("#tables", "Tables"), ("#plots", "Plots")] + ([("#why", "Why it fails")] if why else [])
        + ([("#active", "Active")] if active else []),
        legend=legend,
    )
    page = out / REPORT_PAGE
    write_inside(out, REPORT_PAGE, page_html)
    timings["html"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    summary = analysis.as_dict() | {
        "gallery": None if gstats is None else gstats.__dict__,
        **({"active": active_numbers} if active_numbers else {}),
        **({"tables": {t.key: t.numbers() for t in added}} if added else {}),
        "timings_s": {k: round(v, 3) for k, v in timings.items()},
    }
    write_inside(out, "summary.json", summary_json_text(summary))
    return ReportResult(out, page, tables, analysis, gstats, note, timings, collection.poolings)
