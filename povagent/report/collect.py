"""Loading run and sweep folders into one tidy table of observations (one per result row).

A run folder holds ``config.yaml`` and ``results.jsonl``; a sweep folder holds one run folder
per cell and ``sweep.json`` (the cell index, with each cell's axis values). Every row becomes an
:class:`Observation` labelled with its *system*: its run, named as
:mod:`povagent.report.systems` names runs (a config's ``label:``, else the axes that vary across
the collected runs; two runs are never pooled unless the user asks).

A run's rows carry the fields of the scorer that follows a scoring protocol
(``Scorer.protocol``, :mod:`povagent.scoring.score_protocols`): POVBench's normalized L2 on a
release-layout set, a hit against hand-marked ground truth on a real-world set
(:mod:`povagent.dataset.realworld_set`); each observation says which scorer and protocol (``scorer``,
``protocol``) and carries those numbers: an error, or a hit or miss. A run scored only by scorers
without a protocol carries their declared metrics alone, answered when its row's status says so.

This module only reads: it never rescores a row (the numbers are the row's ``scores`` as the
scorers wrote them) and never writes.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from povagent.errors import PredictionsError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular
from povagent.report.baseline_systems import is_baseline_system
from povagent.report.choice_fields import chosen_label
from povagent.report.diagnosed_observation import diagnosis_of
from povagent.report.shared_values import label_table, number_table
from povagent.report.systems import Pooling, assign_systems, planted_label, set_name, simulation_label
from povagent.results.finished_run import RESULTS_FILE, FinishedRun, is_run_folder
from povagent.results.rows import ResultRow, StoredRows
from povagent.results.transcript import RunTurns, transcripts
from povagent.scoring.metrics import Declared, MetricValues, row_category, row_metric_flat, row_metric_groups
from povagent.scoring.score_protocols import PROTOCOLS, registered_protocols, shown_answer

#: Raw answers and requests longer than this are cut in the report's answers files (the full
#: text stays in results.jsonl).
MAX_RAW_CHARS = 8000

SWEEP_INDEX = "sweep.json"


@dataclass(frozen=True, slots=True)
class Observation:
    """One result row as the report sees it (slotted: a report holds one per row)."""

    system: str
    run_name: str
    run: int
    instance_id: str
    house_id: str
    pair_id: str
    direction: str
    condition: str
    status: str
    parse_status: str | None
    answered: bool
    l2: float | None
    l2_strict: float | None
    gt_in_frame: bool | None
    gt_behind: bool | None
    gt_u: float | None
    gt_v: float | None
    selected_image: int | None
    image_path: str | None
    x: float | None
    y: float | None
    sentence: str
    raw: str | None
    parse_reason: str = ""
    #: The scorer whose protocol fields the row carries (``""``: none).
    scorer: str = ""
    #: That scorer's protocol (:data:`~povagent.interfaces.ScoreProtocol`; ``None``: no scorer of
    #: the run follows one, and only declared metrics describe the row).
    protocol: str | None = "normalized_l2"
    #: ``marked_hit`` rows: the answer is within a mark (a failure when unanswered); else ``None``.
    success: bool | None = None
    #: ``marked_hit`` rows: distance to the nearest point mark, in frame diagonals (``None``: no point mark).
    distance_norm: float | None = None
    #: ``marked_hit`` rows: the hit radius of point marks without their own, in original pixels.
    hit_radius_px: float | None = None
    #: Every exchange of the row, in order: ``(request as sent or None, raw answer or None)``
    #: (the transcript, each request rebuilt and cut to one character over
    #: :data:`MAX_RAW_CHARS`; a request not kept, as in early rows of format 0, is ``None``).
    #: :func:`collect` leaves them in the results file until they are looked at (:func:`row_turns`):
    #: every row of a run holds its run's :class:`~povagent.results.transcript.RunTurns`.
    turns: Sequence[tuple[str | None, str | None]] | RunTurns = ()
    #: The ``diagnose`` scorer's first failing step (``frame`` ... ``correct``; ``None``: not diagnosed).
    fail_step: str | None = None
    #: ``diagnose``: the egocentric and mirrored targets in the scored frame (clamped fractions).
    egocentric_uv: tuple[float, float] | None = None
    mirrored_uv: tuple[float, float] | None = None
    #: ``diagnose``: the egocentric-bias vote (``None``: no vote).
    nearer_egocentric: bool | None = None
    #: ``relation``: the point lies in the relation region (``None``: not scored).
    relation: bool | None = None
    #: Each scorer's declared metrics for this row (:func:`povagent.scoring.metrics.row_metric_values`).
    metric_values: Mapping[str, Mapping[str, float | None]] = field(default_factory=dict)
    #: The row's groups of grouped metrics (:func:`povagent.scoring.metrics.row_metric_groups`;
    #: ``None``: no grouped metric declared), so the report groups a set's copies of a question as
    #: the run's summary does.
    metric_groups: Mapping[str, Mapping[str, str]] | None = None
    #: The question's category slices as the run's summary counts them (:func:`~povagent.scoring.metrics.row_category`).
    category: str | tuple[str, ...] | None = None
    #: The prediction as its answer type shows it (``AnswerType.show``; ``None``: an untyped row).
    answer: str | None = None
    #: The option label a choice scorer recorded (``None``: none scored the row, or no option was read).
    chosen: str | None = None


@dataclass
class RunInfo:
    """One run folder as the report names it: the folder opened once (:attr:`opened`), its
    config, rows and axis values."""

    #: The run folder's one reader: its rows, config, summary's declarations and transcripts.
    opened: FinishedRun
    folder: Path
    name: str
    config: dict[str, Any]
    axes: dict[str, str]
    #: read from the results file as they are iterated (:class:`~povagent.results.rows.StoredRows`):
    #: a report holds no row objects, whatever the run's length
    rows: Sequence[ResultRow]
    system: str = ""
    #: The system's name without the set it was asked (a leaderboard's row); :attr:`system` adds
    #: the set when runs of one name were asked different sets.
    entrant: str = ""
    #: The sweep folder whose index listed this run (``None``: a run folder of its own).
    sweep: Path | None = None
    #: The axis values the sweep's index gives this cell (``{}`` for a run of its own).
    cell_axes: dict[str, str] = field(default_factory=dict)

    @property
    def scorer(self) -> str:
        """The scorer whose protocol fields the report reads for this run (see :func:`run_scorer`)."""
        return run_scorer(self.config, self.rows)

    @property
    def protocol(self) -> str | None:
        """That scorer's protocol (``None``: the run has no protocol scorer)."""
        return registered_protocols().get(self.scorer)

    @property
    def benchmark(self) -> str:
        """The set the run was asked, by name (:func:`~povagent.report.systems.set_name`)."""
        return set_name(self.config, self.dataset_path)

    @property
    def dataset_path(self) -> Path | None:
        """The dataset the run was evaluated on, as its config names it (``None`` if unknown)."""
        ds = self.config.get("dataset")
        raw = ds.get("path") or ds.get("root") if isinstance(ds, dict) else ds
        if not raw:
            return None
        p = Path(str(raw)).expanduser()
        if not p.is_absolute() and not p.exists():
            p = (self.folder / p).resolve()
        return p


@dataclass
class Collection:
    """Everything a report reads: the runs, their observations, and the systems in order."""

    source: Path
    runs: list[RunInfo]
    observations: list[Observation] = field(default_factory=list)
    #: Rows left out as outside the paper's protocol (see :func:`collect`).
    outside_protocol_rows: int = 0
    #: Runs pooled into one system (by a shared ``label:`` or ``--pool``); empty: every run is its own.
    poolings: list[Pooling] = field(default_factory=list)

    @property
    def systems(self) -> list[str]:
        """System labels in the order their first run appears."""
        seen: dict[str, None] = {}
        for r in self.runs:
            seen.setdefault(r.system, None)
        return list(seen)

    def dataset_paths(self) -> list[Path]:
        """Distinct dataset folders named by the runs' configs."""
        return dataset_paths(self.runs)

    def system_axes(self, system: str) -> dict[str, str]:
        """The axis values of a system (from its first run)."""
        for r in self.runs:
            if r.system == system:
                return r.axes
        return {}


def run_scorer(config: dict[str, Any], rows: Sequence[ResultRow]) -> str:
    """The scorer whose protocol fields the report reads for a run: the first protocol's
    (:data:`~povagent.scoring.score_protocols.PROTOCOLS` order) among the scorers the config names,
    else among those its rows carry, else, for a config naming none, the pipeline's default
    scorers'; ``""`` when no scorer of the run follows a protocol.

    Read from the config first because a row that failed before scoring (an infra error) has
    no scores, yet still counts: as a non-response, and for a hit protocol as a failure.
    """
    from povagent.config.pipeline import default_scorers  # the plugin checks: only when asked

    known = registered_protocols()
    named = [_name_of(s) for s in config.get("scorers") or [] if _name_of(s)]
    carried = list(rows.carried_scores) if isinstance(rows, StoredRows) else list(dict.fromkeys(name for row in rows for name in row.scores))
    default = [] if named else default_scorers()
    for candidates in (named, carried, default):
        for protocol in PROTOCOLS:
            found = next((n for n in candidates if known.get(n) == protocol), None)
            if found is not None:
                return found
    return ""


def _name_of(section: Any) -> str:
    if isinstance(section, str):
        return section
    if isinstance(section, dict):
        return str(section.get("name") or "")
    return ""


def config_axes(config: dict[str, Any], rows: Sequence[ResultRow]) -> dict[str, str]:
    """Model, backend, strategy and parser of a run, from its config (falling back to its rows).

    The model is the one the rows name when they do (its profile's name, else the model
    string: what answered); rows that name none (early rows of format 0) take it from the config."""
    backend = config.get("backend")
    first = rows[0] if rows else None
    # a pipeline names either a model profile (top-level ``model:``) or a backend with options
    model = (first.profile or first.model) if first is not None else ""
    if not model:
        model = str(config["model"]) if isinstance(config.get("model"), str) else ""
    if not model and isinstance(backend, dict):
        opts = backend.get("options") or {}
        model = str(opts.get("model") or backend.get("model") or "") if isinstance(opts, dict) else ""
    axes = {
        "backend": _name_of(backend) or (first.backend if first else ""),
        "model": model,
        "strategy": _name_of(config.get("strategy")) or (first.strategy if first else ""),
        "parser": _name_of(config.get("parser")) or (first.parser if first else ""),
    }
    if axes["backend"] == "simulated":  # a perception simulation is never labelled as a model
        axes["model"] = simulation_label(backend.get("options") if isinstance(backend, dict) else None)
    if axes["backend"] == "planted":  # nor is a behaviour simulation
        axes["model"] = planted_label(backend.get("options") if isinstance(backend, dict) else None)
    if not axes["model"]:
        axes["model"] = axes["backend"]
    return {k: v for k, v in axes.items() if v}


def _cells_of_index(index: Any) -> list[dict[str, Any]]:
    cells = index.get("cells") if isinstance(index, dict) else index
    return [c for c in cells if isinstance(c, dict)] if isinstance(cells, list) else []


def _cell_folders(cell: dict[str, Any]) -> list[str]:
    """Where a cell's run folder may be, most specific first (a name under the sweep folder,
    then a recorded path, which may be relative to wherever the sweep was started)."""
    return [cell[k] for k in ("folder", "dir", "directory", "name", "path", "run_dir") if isinstance(cell.get(k), str)]


def _cell_axes(cell: dict[str, Any]) -> dict[str, str]:
    for key in ("axes", "values", "params", "axis_values"):
        if isinstance(cell.get(key), dict):
            return {str(k): _axis_text(v) for k, v in cell[key].items()}
    skip = {"folder", "dir", "directory", "path", "name", "run_dir", "status", "summary"}
    return {str(k): _axis_text(v) for k, v in cell.items() if k not in skip and not isinstance(v, (dict, list))}


def _axis_text(value: Any) -> str:
    if isinstance(value, dict):
        return str(value.get("name") or value.get("model") or json.dumps(value, sort_keys=True))
    if isinstance(value, (list, tuple)):
        return "+".join(str(v) for v in value)
    return str(value)


def _load_run(folder: Path, name: str, extra_axes: dict[str, str] | None = None, sweep: Path | None = None) -> RunInfo:
    opened = FinishedRun.open(folder)
    axes = config_axes(opened.config, opened.rows)
    # the run's own config names model, strategy and parser best (sweep labels are slugs);
    # the index adds the axes a config cannot say, such as a named override
    for k, v in (extra_axes or {}).items():
        axes.setdefault(k, v)
    return RunInfo(opened, folder, name, opened.config, axes, opened.rows, sweep=sweep, cell_axes=dict(extra_axes or {}))


def dataset_paths(runs: Iterable[RunInfo]) -> list[Path]:
    """Distinct dataset folders named by ``runs``' configs, in order."""
    return list(dict.fromkeys(r.dataset_path for r in runs if r.dataset_path is not None))


def find_runs(path: str | Path) -> list[RunInfo]:
    """The runs under ``path``: a run folder, or a sweep folder (by its index, or by scanning)."""
    root = Path(path)
    if not root.exists():
        raise PredictionsError(f"{root}: no such run or sweep folder")
    if is_run_folder(root):
        return [_load_run(root, root.name)]
    runs: list[RunInfo] = []
    index_path = root / SWEEP_INDEX
    if index_path.exists():
        try:
            index = json.loads(read_regular(index_path, MAX_DOCUMENT_BYTES, what="sweep index"))
        except json.JSONDecodeError as exc:
            raise PredictionsError(f"{index_path}: not valid JSON ({exc.msg} at line {exc.lineno})") from exc
        for i, cell in enumerate(_cells_of_index(index)):
            names = _cell_folders(cell)
            if not names:
                raise PredictionsError(f"{index_path}: cells[{i}] names no folder (expected 'name' or 'run_dir')")
            found = [root / n for n in names if (root / n / RESULTS_FILE).exists()]
            found += [Path(n) for n in names if Path(n).is_absolute() and (Path(n) / RESULTS_FILE).exists()]
            if found:  # a cell not run yet has no results: nothing to report for it
                runs.append(_load_run(found[0], found[0].name, _cell_axes(cell), sweep=root))
    if not runs:
        for folder in sorted(p for p in root.iterdir() if p.is_dir()):
            if (folder / RESULTS_FILE).exists():
                runs.append(_load_run(folder, folder.name))
    if not runs:
        raise PredictionsError(f"{root}: neither a run folder ({RESULTS_FILE}) nor a sweep folder with run folders")
    return runs


def observation_of(
    row: ResultRow, system: str, run_name: str, scorer: str, declared: Declared | None = None, protocol: str | None = None,
    turns: Sequence[tuple[str | None, str | None]] | RunTurns | None = None, share: Callable[[str], str] = sys.intern,
    same: Callable[[Any], Any] = lambda value: value,
) -> Observation:
    """The report's view of one row, read from ``scores[scorer]`` as stored (never recomputed).

    ``protocol`` is ``scorer``'s. ``normalized_l2``: answered when the scorer answered it, with
    its error. ``marked_hit``: answered when the scorer answered it, and a hit only when it said
    so (a row it did not score, such as an infra error, is a failure, as the paper counts it).
    No protocol: answered when the row's status says so (its declared metrics say the rest).
    ``turns``: the row's turns as stored elsewhere (default: taken from ``row``), such as its
    run's :class:`~povagent.results.transcript.RunTurns`. ``share`` and ``same``: what make equal
    labels and equal floats one object (default: :func:`sys.intern`, and each float its own;
    :func:`collect` passes tables of its own, :mod:`povagent.report.shared_values`).
    """
    fields = (row.scores.get(scorer) or {}) if scorer else {}
    hit_fields = fields if protocol == "marked_hit" else {}
    off = fields if protocol == "normalized_l2" else {}
    if protocol == "marked_hit":
        answered = row.status == "answered" and bool(hit_fields.get("answered"))
        success: bool | None = answered and hit_fields.get("success") is True
        in_frame = hit_fields.get("frame_has_gt") if answered else None
    elif protocol == "normalized_l2":
        answered = bool(off.get("answered")) and off.get("l2") is not None
        success = None
        in_frame = off.get("gt_in_frame")
    else:
        answered, success, in_frame = row.status == "answered", None, None
    with_l2 = protocol == "normalized_l2" and answered
    answer = shown_answer(row.prediction.answer_type, row.prediction.value)  # a baseline's, a choice's: a few texts over all rows
    return Observation(
        system=system,
        run_name=run_name,
        run=row.run,
        # labels and texts repeat over rows (runs, houses, conditions): one string each, not one a row
        instance_id=share(row.instance_id),
        house_id=share(row.house_id),
        pair_id=share(row.pair_id),
        direction=share(str(row.direction)),
        condition=share(str(row.condition)),
        status=share(str(row.status)),
        parse_status=share(str(row.parse.status)) if row.parse is not None else None,
        answered=answered,
        # numbers repeat too: a point's ground truth in every run, a strict error equal to the
        # official one, an answer given again (one float object each, not one a row)
        l2=same(float(off["l2"])) if with_l2 else None,
        l2_strict=same(float(off["l2_strict"])) if with_l2 and off.get("l2_strict") is not None else None,
        gt_in_frame=in_frame,
        gt_behind=off.get("gt_behind"),
        gt_u=same(off.get("gt_u")),
        gt_v=same(off.get("gt_v")),
        selected_image=row.prediction.selected_image,
        image_path=share(row.prediction.image_path) if row.prediction.image_path is not None else None,
        x=same(row.prediction.x),
        y=same(row.prediction.y),
        sentence=share(row.sentence),
        raw=share(row.raw_response) if row.raw_response is not None else None,  # a baseline's, a choice's: a few texts
        parse_reason=(row.parse.reason if row.parse is not None else (row.error_message or "")),
        scorer=scorer,
        protocol=protocol,
        success=success,
        distance_norm=same(hit_fields.get("distance_norm")) if answered else None,
        hit_radius_px=same(hit_fields.get("hit_radius_px")),
        turns=tuple(zip(transcripts(row.exchanges, keep=MAX_RAW_CHARS + 1), (e.raw for e in row.exchanges))) if turns is None else turns,
        metric_values=MetricValues(tuple(map(same, row_metric_flat(row, declared))), declared) if declared else {},  # one tuple a row, not two dicts
        metric_groups=_groups_of(row, run_name, declared) if declared else None,
        category=row_category(row),
        answer=share(answer) if answer is not None else None,
        chosen=chosen_label(row),
        **diagnosis_of(row, scorer if protocol == "normalized_l2" else None),
    )


def row_turns(o: Observation) -> Sequence[tuple[str | None, str | None]]:
    """An observation's turns: its own (a row built whole, a baseline's none), or a collected
    row's, read from its run's results file now (:class:`~povagent.results.transcript.RunTurns`)."""
    return o.turns.of(o.instance_id, o.run) if isinstance(o.turns, RunTurns) else o.turns


def _groups_of(row: ResultRow, run_name: str, declared: Declared) -> dict[str, dict[str, str]] | None:
    """The row's groups of grouped metrics, apart from another run folder's (a system pooling
    folders must not join one folder's copy of a question with another's)."""
    groups = row_metric_groups(row, declared)
    return {s: {m: f"{run_name}/{g}" for m, g in by.items()} for s, by in groups.items()} or None


def collect(
    paths: str | Path | Iterable[str | Path], *, outside_protocol: bool = False, pool: bool = False, runs: list[RunInfo] | None = None
) -> Collection:
    """Load one or more run/sweep folders into a :class:`Collection`.

    Each run is one system; runs of the same name are pooled only with ``pool`` or a shared
    ``label:`` (:func:`povagent.report.systems.assign_systems`), and the collection lists each
    pooling.

    Rows the paper's protocol does not cover (a model under an intervention on Given:
    :mod:`povagent.report.paper_protocol`) are left out unless ``outside_protocol``; the collection
    counts them in ``outside_protocol_rows``. Baselines never read the prompt: theirs stay.
    ``runs``: the runs :func:`find_runs` found under ``paths`` already (found again when not given).
    """
    from povagent.report.paper_protocol import outside_paper_protocol

    paths = [Path(p) for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
    runs = list(runs) if runs is not None else [r for p in paths for r in find_runs(p)]
    poolings = assign_systems(runs, pool=pool)
    obs: list[Observation] = []
    left_out = 0
    # one string per distinct label, one float per distinct number, from tables of this
    # collection's own (interning would grow the interpreter's table, which never shrinks)
    share, same = label_table(), number_table()
    for r in runs:
        screened = not outside_protocol and not is_baseline_system(r.axes, r.system)
        known = _known_keys(r.config)
        declared = r.opened.declared  # none in a summary without metrics
        scorer, protocol = r.scorer, r.protocol  # once: the rows are read again each time they are looked at
        # one object for the run's turns, not one a row: found by instance and run when shown
        turns = RunTurns(r.rows, MAX_RAW_CHARS + 1, known)
        for row in r.rows:
            turns.add(row.instance_id, row.run)
            if screened and outside_paper_protocol(row.strategy, str(row.condition)):
                left_out += 1
                continue
            o = observation_of(row, r.system, r.name, scorer, declared, protocol, turns, share, same)
            obs.append(_scrubbed(o, known) if known is not None else o)
    return Collection(Path(paths[0]), runs, obs, outside_protocol_rows=left_out, poolings=poolings)


def _known_keys(config: dict[str, Any]) -> Callable[[str], str] | None:
    """What removes the keys povagent knows (the run config's ``api_key_env`` values, key-like
    environment values) from a text, or ``None`` when none is known.

    A run made before answers were redacted as they arrived may hold a key a server echoed:
    the report never copies it onto its pages (see :meth:`povagent.files.redaction.Redactor.known`).
    """
    from povagent.files.redaction import Redactor, secrets_named_by

    redactor = Redactor(secrets_named_by(config))
    return redactor.known if redactor.knows_secrets else None


def _scrubbed(o: Observation, known: Callable[[str], str]) -> Observation:
    """``o`` with its answer texts passed through ``known`` (a run's turns redact as they are read)."""
    return dataclasses.replace(
        o, raw=known(o.raw) if o.raw is not None else None, parse_reason=known(o.parse_reason),
        turns=o.turns if isinstance(o.turns, RunTurns) else
        tuple((known(p) if isinstance(p, str) else p, known(a) if isinstance(a, str) else a) for p, a in o.turns),
    )


def run_success_breakdown(run_dir: str | Path) -> dict[str, Any] | None:
    """:func:`success_breakdown` of a run folder's rows, with response rates, read as
    ``povagent report`` reads them (the ``marked_hit`` scorer's ``answered`` and ``success`` per
    row; a row it did not score, such as a parse or infra error, is an unanswered failure).
    ``None`` when no scorer of the run follows that protocol.
    """
    from povagent.dataset.realworld_set import success_breakdown

    collection = collect(run_dir)
    if not any(r.protocol == "marked_hit" for r in collection.runs):
        return None
    return success_breakdown(
        {"condition": o.condition, "direction": o.direction, "success": o.success, "answered": o.answered}
        for o in collection.observations
        if o.protocol == "marked_hit"
    )
