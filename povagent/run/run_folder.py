"""Which folders are ours to write: a run or sweep folder carries a marker; any other folder that
is not empty is refused before anything is written to it.

``output:`` may name a folder that already holds someone's files (a ``config.yaml``, a
``summary.json``): writing a run there would overwrite them. A folder is ours when it holds
the marker file :data:`MARKER` (``.povagent-run``), a small JSON object ``{"format": 1,
"kind": "run" | "sweep"}`` written when povagent creates the folder or first adopts it. File
names prove nothing, so they are not the test.

Folders made before the marker existed are recognised by their content and adopted (the marker
is written, then the run resumes):

* a run folder: its ``config.yaml`` validates as a pipeline (read only: no plugin is imported)
  and its ``results.jsonl`` is empty or starts with a row of ours;
* a sweep folder: its ``sweep.json`` is our cell index (``cells``, each with ``name`` and
  ``run_dir``).

A folder that cannot be created or written (a read-only mount, no permission) is refused the
same way, with one line, before the run starts. This module decides and writes the marker; it
runs nothing.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Literal

from povagent.config.models import PipelineConfig
from povagent.config.validation_messages import validation_message
from povagent.config.yaml_reader import read_yaml, yaml_source
from povagent.errors import ConfigError, ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, open_regular, read_regular
from povagent.files.confined_write import ConfinedFolder, write_inside

#: The marker file of a folder povagent made, and the format version it holds.
MARKER = ".povagent-run"
MARKER_FORMAT = 1

Kind = Literal["run", "sweep"]

#: Files of ours that leave a folder "empty" (a run killed before it wrote anything).
_OURS_WHEN_ALONE = frozenset({MARKER, ".lock"})


def claim_folder(folder: Path, kind: Kind) -> None:
    """Make sure ``folder`` is ours to write a ``kind`` folder into, creating it (with its
    marker) when it does not exist; :class:`ConfigError` (one line, nothing written) when it
    holds files that are not a povagent folder, or cannot be written."""
    try:
        _claim(folder, kind)
    except OSError as exc:
        raise ConfigError(
            f"{folder}: cannot write the {kind} folder ({exc.strerror or exc}); choose a folder you can "
            f"write to (output: in the YAML, or --output)"
        ) from None


def _claim(folder: Path, kind: Kind) -> None:
    if not folder.exists():
        folder.mkdir(parents=True)
        _write_marker(folder, kind)
        return
    marker = _read_marker(folder)
    if marker is not None:
        if marker.get("kind") not in (None, kind):
            raise ConfigError(
                f"{folder}: is a povagent {marker.get('kind')} folder, not a {kind} folder; choose another output folder"
            )
        _writable(folder)
        return
    entries = sorted(p.name for p in folder.iterdir())
    if not [e for e in entries if e not in _OURS_WHEN_ALONE] or _made_by_an_earlier_version(folder, kind):
        _writable(folder)
        _write_marker(folder, kind)
        return
    shown = ", ".join(entries[:3]) + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")
    raise ConfigError(
        f"{folder}: not empty and not a povagent {kind} folder (it holds {shown}, and no {MARKER} marker); "
        f"nothing was written: choose another output folder (output: in the YAML, or --output), or empty this one"
    )


def _writable(folder: Path) -> None:
    """An ``OSError`` now (no permission, a read-only mount) rather than a traceback at the first write."""
    with ConfinedFolder(folder, create=False) as confined:  # a link planted as the probe is replaced, not followed
        confined.write_replace(f"{MARKER}.probe", "")  # a read-only mount says so here
        confined.unlink(f"{MARKER}.probe")


#: A marker is a line of JSON.
MAX_MARKER_BYTES = 4096


def _write_marker(folder: Path, kind: Kind) -> None:
    write_inside(folder, MARKER, json.dumps({"format": MARKER_FORMAT, "kind": kind}) + "\n")


def _read_marker(folder: Path) -> dict[str, Any] | None:
    path = folder / MARKER
    if not path.is_file():
        return None
    try:
        data = json.loads(read_regular(path, MAX_MARKER_BYTES, what="run folder marker"))
    except (OSError, ValueError, ReadTargetError):
        data = None
    if not isinstance(data, dict) or not isinstance(data.get("format"), int):
        raise ConfigError(f"{path}: not a povagent marker (expected {{\"format\": {MARKER_FORMAT}, \"kind\": ...}}); choose another output folder")
    if data["format"] > MARKER_FORMAT:
        raise ConfigError(f"{path}: made by a newer povagent (marker format {data['format']}); upgrade povagent to write into it")
    return data


# -- folders of earlier versions ----------------------------------------------------------------
def _made_by_an_earlier_version(folder: Path, kind: Kind) -> bool:
    return _an_earlier_run_folder(folder) if kind == "run" else _an_earlier_sweep_folder(folder)


def _an_earlier_run_folder(folder: Path) -> bool:
    """``config.yaml`` validates as a pipeline and ``results.jsonl`` is empty or opens with a row."""
    from povagent.results.rows import ResultRow

    results = folder / "results.jsonl"
    if not (folder / "config.yaml").is_file() or not results.is_file():
        return False
    try:
        read_run_config(folder)
        with open_regular(results, what="results file") as fh:
            first = fh.readline(1024 * 1024)
        if first.strip():
            ResultRow.model_validate_json(first)
    except Exception:  # anything unreadable is simply not recognised: the folder is refused
        return False
    return True


def _an_earlier_sweep_folder(folder: Path) -> bool:
    """``sweep.json`` is our cell index: ``cells``, each with ``name`` and ``run_dir``."""
    index = folder / "sweep.json"
    try:
        if not index.is_file():
            return False
        data = json.loads(read_regular(index, MAX_DOCUMENT_BYTES, what="sweep index"))
    except (OSError, ValueError, ReadTargetError):
        return False
    cells = data.get("cells") if isinstance(data, dict) else None
    return isinstance(cells, list) and all(isinstance(c, dict) and "name" in c and "run_dir" in c for c in cells)


def read_run_config(run_dir: Path, raw: bytes | None = None) -> PipelineConfig:
    """The pipeline a run was made with (``RUN_DIR/config.yaml``), validated; nothing it names
    (plugins, datasets) is loaded. ``raw``: the file's bytes as the run folder's reader read
    them (:class:`~povagent.results.finished_run.FinishedRun`), not read again."""
    path = run_dir / "config.yaml"
    source = read_yaml(path) if raw is None else yaml_source(path, raw)
    if not isinstance(source.data, dict):
        raise ConfigError(f"{source.file}: a pipeline must be a YAML mapping (key: value)")
    data = dict(source.data)
    if data.get("model") is not None and data.get("backend") is not None:
        # a resolved config keeps the profile name beside the backend it resolved to
        data["model"] = None
    from pydantic import ValidationError

    try:
        return PipelineConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"invalid pipeline:\n{validation_message(exc, PipelineConfig, source)}") from None
