"""Procedural POVBench-format datasets: houses, renderer, exploration, queries.

What it is for: ``generate_dataset`` writes a dataset in the release layout (the one
``povagent validate``, ``run``, ``sweep`` and ``score`` read) following the paper's protocol
(its section 4 and appendix) on ProcTHOR-like single-story houses rendered on the CPU. What it
must not do: import ``procthor`` or ``ai2thor`` (their JSON databases are read as files), or
reach the network.

Rooms: ``assets`` (ProcTHOR sizes), ``floorplan`` (rooms, walls, doorways), ``furnishing``
(placement rules), ``scene`` (the shared house model), ``meshes`` (composite furniture),
``renderer`` (ray casting: RGB, depth, instance mask), ``exploration`` (reachable grid, tour),
``judge`` (pluggable surface judge), ``sentences`` (A/B/C templates), ``pairs`` (pairs, observer
views, targets), ``writer`` (deterministic files), ``pipeline`` (one house), ``house_task`` (one
house as a task any engine runs), ``dataset`` (many).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from povagent.generate.dataset import GenerationReport, generate_dataset
    from povagent.generate.judge import JudgeRequest, PhysicalRulesJudge, SurfaceJudge, SurfaceVerdict

#: Where each name is defined: imported when first asked for, so that importing one room (the
#: report's floor plans read ``floorplan``) does not load the renderer and the mesh library.
_DEFINED_IN = {
    "GenerationReport": "povagent.generate.dataset",
    "generate_dataset": "povagent.generate.dataset",
    "JudgeRequest": "povagent.generate.judge",
    "PhysicalRulesJudge": "povagent.generate.judge",
    "SurfaceJudge": "povagent.generate.judge",
    "SurfaceVerdict": "povagent.generate.judge",
}


def __getattr__(name: str) -> Any:
    module = _DEFINED_IN.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


__all__ = [
    "GenerationReport",
    "JudgeRequest",
    "PhysicalRulesJudge",
    "SurfaceJudge",
    "SurfaceVerdict",
    "generate_dataset",
]
