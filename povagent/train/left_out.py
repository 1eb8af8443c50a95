"""What loading left out of an export, and why: whole houses and single pairs.

The loader skips a house it cannot use (a truncated or non-image frame, a path leading out of
the dataset, a malformed file) and a pair whose observer view is unusable (a bomb-sized or
wrongly sized image), recording a problem that names file and field. An export says every one
of them, on the console and in its card's "Left out" list: a training set silently smaller than
its dataset hides what went wrong.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path

from povagent.dataset.loader import House
from povagent.dataset.problems import Problem
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular

_PAIR_ENTRY = re.compile(r"^\$\[(\d+)\]")


def _raw_pair_ids(pair_file: Path) -> list[str | None]:
    try:
        raw = json.loads(read_regular(pair_file, MAX_DOCUMENT_BYTES, what="pair file"))
    except (OSError, ValueError, RecursionError, ReadTargetError):
        return []
    if not isinstance(raw, list):
        return []
    return [str(e["pair_id"]) if isinstance(e, dict) and "pair_id" in e else None for e in raw]


def left_out(folder: Path, house: House | None, problems: Sequence[Problem]) -> dict[str, str]:
    """``{where: why}`` for what loading the house at ``folder`` dropped: ``house`` is what it
    loaded (``None``: the whole house), ``problems`` what it reported meanwhile.

    ``where`` is the house id, ``"<house> pair <id>"`` for a pair of a house that loaded, or
    ``"<house> <file>"`` for another file of it that was not used;
    ``why`` is the loader's sentences (file, field and reason).
    """
    if house is None:
        return {folder.name: "; ".join(str(p) for p in problems[:3]) or "the house could not be loaded"}
    out: dict[str, str] = {}
    pair_file = f"{folder.name}.json"
    ids: list[str | None] | None = None
    for problem in problems:
        match = _PAIR_ENTRY.match(problem.json_path)
        where = f"{folder.name} {Path(problem.file).name}"  # a loaded house's other file (visible objects)
        if match and Path(problem.file).name == pair_file:
            ids = _raw_pair_ids(folder / pair_file) if ids is None else ids
            index = int(match.group(1))
            pair_id = ids[index] if index < len(ids) else None
            if pair_id is not None and pair_id in house.pairs:
                continue  # a note about a pair that loaded (a repeated id: the last entry is used)
            where = f"{folder.name} pair {pair_id if pair_id is not None else f'entry {index}'}"
        out[where] = f"{out[where]}; {problem}" if where in out else str(problem)
    return out
