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

from povagent.generate.dataset import GenerationReport, generate_dataset
from povagent.generate.judge import JudgeRequest, PhysicalRulesJudge, SurfaceJudge, SurfaceVerdict

__all__ = [
    "GenerationReport",
    "JudgeRequest",
    "PhysicalRulesJudge",
    "SurfaceJudge",
    "SurfaceVerdict",
    "generate_dataset",
]
