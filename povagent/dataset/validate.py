"""``povagent validate``: check every file and every referenced image of a dataset.

Reports *every* problem (file, JSON path, a plain sentence); never stops at the first. Files
are checked against the shipped JSON Schemas with ``jsonschema``; then what a schema cannot
say: sentences for every direction with a placement, unique pair ids, numbers that are finite
(no NaN or Infinity anywhere), every named file inside the dataset folder (an absolute path, a
``../`` that climbs out or a symlink leading out is reported and never opened), images that
exist, are complete, decode and have the camera's size, visible-object keys that name real
frames.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Iterable

from jsonschema import ValidationError as SchemaError

from povagent.dataset.image_files import image_problem
from povagent.dataset.json_files import read_dataset_json
from povagent.dataset.loader import EXPLORATION_LOG, VISIBLE_OBJECTS, house_folders
from povagent.dataset.paths import OutsideDatasetError, confined, dataset_root, observer_view_path
from povagent.dataset.problems import Problem, folder_name_problem, json_path, non_finite_problems
from povagent.dataset.release_models import DIRECTIONS
from povagent.dataset.schema import validator
from povagent.generate.record import NO_DIGEST, RECORD, parse_record, record_problem

_DIRECTION_NAMES = ", ".join(str(d) for d in DIRECTIONS)
_JSON_NAMES = {"array": "list", "object": "object (a mapping of keys to values)"}


def describe_schema_error(err: SchemaError) -> str:
    """A plain sentence for one jsonschema error."""
    field = err.path[-1] if err.path else None
    kind = err.validator
    # the schema's own value for the failed keyword (typed loosely by jsonschema: any JSON)
    value: Any = err.validator_value
    instance: Any = err.instance
    if kind == "required":
        missing = err.message.split("'")[1] if "'" in err.message else err.message
        return f"required field '{missing}' is missing"
    if kind == "propertyNames" or "propertyNames" in err.schema_path:
        return f"unknown direction {instance!r} (allowed: {_DIRECTION_NAMES})"
    if kind == "type":
        want = value if isinstance(value, str) else "/".join(value)
        got = json.dumps(instance)[:60]
        if field is None:
            return f"the file must hold a JSON {_JSON_NAMES.get(want, want)} (got {got})"
        if isinstance(field, int):
            return f"item {field} must be a JSON {_JSON_NAMES.get(want, want)} (got {got})"
        return f"'{field}' must be of type {want} (got {got})"
    if kind in ("minItems", "maxItems"):
        return f"'{field}' has {len(instance)} items; expected {'at least' if kind == 'minItems' else 'at most'} {value}"
    if kind in ("exclusiveMinimum", "exclusiveMaximum", "minimum", "maximum", "minLength"):
        return f"'{field}' is out of range: {err.message}"
    if kind == "anyOf" and any("sentence" in (sub.get("properties") or {}) for sub in value):
        return f"'{field}' must be a non-empty sentence: a string or an object with 'sentence' (got {json.dumps(instance)[:60]})"
    if kind == "anyOf":
        return f"'{field}' has an unexpected form (got {json.dumps(instance)[:60]})"
    return err.message


def _schema_problems(file: str, name: str, data: Any) -> list[Problem]:
    out = []
    for err in validator(name).iter_errors(data):
        # propertyNames errors point at the object; name the bad key in the path too
        path = list(err.absolute_path)
        if "propertyNames" in err.schema_path or err.validator == "propertyNames":
            path.append(err.instance)
        out.append(Problem(file, json_path(path), describe_schema_error(err)))
    # errors from one anyOf branch come out once; keep a stable order for readers
    return sorted(out, key=lambda p: (p.json_path, p.message))


def _load_json(path: Path, rel: str, problems: list[Problem], real_root: Path) -> Any:
    data = read_dataset_json(path, rel, real_root, problems)
    if data is not None:
        problems.extend(non_finite_problems(rel, data))
    return data


def check_image(path: Path, name: str, rel: str, where: str, size: tuple[int, int] | None, problems: list[Problem]) -> None:
    """The image ``name`` at ``path`` exists, is complete, decodes fully, and (when known) has
    the camera's size; a problem is recorded against file ``rel`` at JSON path ``where``."""
    problem = image_problem(path, name, size, decode=True)
    if problem is not None:
        problems.append(Problem(rel, where, problem))


def validate_house(
    folder: Path, root: Path, frame_size: tuple[int, int] = (512, 512), warnings: list[Problem] | None = None
) -> list[Problem]:
    """Every problem of one house folder; what is worth saying but no problem goes to ``warnings``."""
    problems: list[Problem] = []
    real_root = dataset_root(root)
    house_id = folder.name
    rel_house = folder.relative_to(root)
    not_text = folder_name_problem(str(rel_house))
    if not_text is not None:
        return [not_text]
    pairs_rel = str(rel_house / f"{house_id}.json")
    log_rel = str(rel_house / EXPLORATION_LOG)
    vis_rel = str(rel_house / VISIBLE_OBJECTS)

    pairs = _load_json(folder / f"{house_id}.json", pairs_rel, problems, real_root)
    if pairs is not None:
        problems.extend(_schema_problems(pairs_rel, "pair_file", pairs))
        if isinstance(pairs, list):
            problems.extend(_pair_checks(pairs, folder, pairs_rel, real_root))

    log = _load_json(folder / EXPLORATION_LOG, log_rel, problems, real_root)
    frame_paths: set[str] = set()
    if log is not None:
        problems.extend(_schema_problems(log_rel, "exploration_log", log))
        if isinstance(log, list):
            first_at: dict[str, int] = {}
            for i, rec in enumerate(log):
                if isinstance(rec, dict) and isinstance(rec.get("image_path"), str):
                    where = f"$[{i}].image_path"
                    rel = rec["image_path"]
                    if rel in first_at:
                        problems.append(
                            Problem(
                                log_rel,
                                where,
                                f"image_path {rel!r} repeats the one at $[{first_at[rel]}]; scoring uses this last record's camera, as officially",
                            )
                        )
                    first_at.setdefault(rel, i)
                    frame_paths.add(rel)
                    try:
                        path = confined(real_root, folder, rel)
                    except OutsideDatasetError as exc:
                        problems.append(Problem(log_rel, where, str(exc)))
                        continue
                    check_image(path, rel, log_rel, where, frame_size, problems)

    vis = _load_json(folder / VISIBLE_OBJECTS, vis_rel, problems, real_root)
    if vis is not None:
        problems.extend(_schema_problems(vis_rel, "per_image_visible_objects", vis))
        if isinstance(vis, dict) and log is not None:
            for key in vis:
                if key not in frame_paths and not _exists_inside(real_root, folder, key):
                    problems.append(Problem(vis_rel, json_path([key]), f"names image {key!r}, which is neither in the exploration log nor on disk"))

    record = folder / RECORD
    if record.exists() or record.is_symlink():  # a house povagent generated: its record must describe it
        problems.extend(_record_problems(folder, str(rel_house / RECORD), real_root, [] if warnings is None else warnings))
    return problems


def _record_problems(folder: Path, rel: str, real_root: Path, warnings: list[Problem]) -> list[Problem]:
    """The problems of a generated house's record: readable, naming its folder, its digest matching."""
    problems: list[Problem] = []
    raw = _load_json(folder / RECORD, rel, problems, real_root)
    if raw is None:
        return problems
    record = parse_record(raw)
    if record is None:
        return [*problems, Problem(rel, "$", "is not a generation record (an object with index, options and summary)")]
    wrong = record_problem(record, folder.name)
    if wrong is not None:
        problems.append(Problem(rel, f"$.{wrong[0]}", wrong[1]))
    elif record.digest is None:
        warnings.append(Problem(rel, "$.digest", f"{NO_DIGEST}; `povagent render` and the active mode use it as it is"))
    return problems


def _exists_inside(real_root: Path, folder: Path, rel: str) -> bool:
    # A key naming a file outside the dataset is not probed, only reported as absent.
    try:
        return confined(real_root, folder, rel).exists()
    except OutsideDatasetError:
        return False


def _pair_checks(pairs: list[Any], folder: Path, rel: str, real_root: Path) -> Iterable[Problem]:
    seen: dict[str, int] = {}
    for i, pair in enumerate(pairs):
        if not isinstance(pair, dict):
            continue
        pid = pair.get("pair_id")
        if pid is not None:
            if str(pid) in seen:
                yield Problem(rel, f"$[{i}].pair_id", f"pair_id {pid!r} repeats the one at $[{seen[str(pid)]}]; scoring uses this last entry, as officially")
            seen.setdefault(str(pid), i)
        placements = pair.get("placements")
        if not isinstance(placements, dict):
            placements = {}
        for stage in ("stage5", "stage6"):
            sentences = pair.get(stage)
            if not isinstance(sentences, dict):
                sentences = {}
            for d in placements:
                if d in [str(x) for x in DIRECTIONS] and d not in sentences:
                    yield Problem(rel, f"$[{i}].{stage}", f"direction '{d}' has a placement but no sentence in {stage}")
        cam = pair.get("camera") if isinstance(pair.get("camera"), dict) else None
        rgb = pair.get("rgb_path")
        if isinstance(rgb, str):
            size = None
            if cam is not None:
                w, h = cam.get("screen_width", 512), cam.get("screen_height", 512)
                if isinstance(w, int) and isinstance(h, int):
                    size = (w, h)
            try:
                path = observer_view_path(real_root, folder, rgb)
            except OutsideDatasetError as exc:
                yield Problem(rel, f"$[{i}].rgb_path", str(exc))
                continue
            probs: list[Problem] = []
            check_image(path, rgb, rel, f"$[{i}].rgb_path", size, probs)
            yield from probs


def validate_dataset(
    root: str | Path, frame_size: tuple[int, int] = (512, 512), warnings: list[Problem] | None = None
) -> list[Problem]:
    """Every problem in a dataset folder (empty list: the dataset is valid); what is worth
    saying but leaves it valid (a generation record without a digest) goes to ``warnings``."""
    root = Path(root)
    if not root.is_dir():
        return [Problem(str(root), "$", "dataset folder not found")]
    problems: list[Problem] = []
    if (root / "meta.json").exists():
        meta = _load_json(root / "meta.json", "meta.json", problems, dataset_root(root))
        if meta is not None:
            problems.extend(_schema_problems("meta.json", "meta", meta))
    folders = house_folders(root)
    if not folders:
        problems.append(Problem("artifacts", "$", "no house folders (expected artifacts/<house_id>/)"))
    for folder in folders:
        problems.extend(validate_house(folder, root, frame_size, warnings))
    return problems
