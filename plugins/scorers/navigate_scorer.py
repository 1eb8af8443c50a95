"""The ``navigate`` scorer: did the walk arrive, and how close to the shortest path was it.

Success (the navigate task's rule, :mod:`povagent.active.navigation`): the robot called
``arrived`` within 1.0 m of the target on the floor, with the target in view (inside the final
camera's image, in front of it, not occluded). SPL (Anderson et al. 2018) weighs each success by
``l / max(p, l)``: ``l`` the geodesic shortest path on the house's reachable floor from the
start to a place within 1.0 m from which the target can be seen, ``p`` the path walked (the
positions the row's episode record holds). An episode that ends without ``arrived`` is a
failure: SPL 0. Both metrics count every navigable episode: one whose target has a place to
arrive at that the start reaches; an instance without one (a target high on a wall, behind
furniture) is no navigation episode and is scored unanswered (``navigable`` false), for every
agent alike. Scores: ``answered`` (= ``navigable``), ``arrived``, ``success``, ``spl``,
``distance_m`` (floor distance from where the walk ended to the target), ``target_in_view``,
``walked_m`` (``p``) and ``shortest_m`` (``l``). Everything is recomputed from the row and the
generated house, so ``povagent rescore`` reproduces a run's scores.
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent.scoring.normalized_l2 import answered_in_camera

#: Decimals kept of the distances a row records.
_DECIMALS = 4


class NavigateScorer(Scorer):
    """Success and SPL of a walk (no options)."""

    metrics = (
        Metric(
            "success_rate",
            "higher",
            "rate",
            "success",
            "Success rate",
            "Arrivals within 1.0 m of the target with the target in view / navigable episodes; no arrival fails.",
        ),
        Metric(
            "spl",
            "higher",
            "mean",
            "spl",
            "SPL",
            "Success weighted by path length, S * l / max(p, l) (Anderson et al. 2018), over navigable episodes: "
            "l the geodesic shortest path, p the path walked; no arrival scores 0.",
        ),
    )

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """Success, SPL and what they were computed from (see the module docstring)."""
        # the generator and the renderer load with the first row scored, not with the plugin list
        from povagent.active.geodesic import path_length, spl
        from povagent.active.live_episode import ARRIVED
        from povagent.active.navigation import ARRIVAL_RADIUS, floor_distance, house_of, in_view, shortest_arrival

        if answer.path is None or answer.camera is None:
            raise ValueError(f"instance {instance.id}: the answer is no walk: score runs of the navigate strategy")
        house = house_of(instance)
        target = instance.target
        camera = answer.camera
        shortest = shortest_arrival(house, answer.path[0], target)
        distance = floor_distance(camera.x, camera.z, target)
        with house.lock:  # the renderer answers one thread at a time
            seen = in_view(house.built.renderer, answered_in_camera(camera).camera, target)
        arrived = answer.span == ARRIVED
        success = arrived and distance <= ARRIVAL_RADIUS and seen
        walked = path_length(answer.path)
        return {
            "answered": shortest is not None,
            "navigable": shortest is not None,
            "arrived": arrived,
            "success": success,
            "spl": None if shortest is None else round(spl(success, shortest.length, walked), 6),
            "distance_m": round(distance, _DECIMALS),
            "target_in_view": seen,
            "walked_m": round(walked, _DECIMALS),
            "shortest_m": None if shortest is None else round(shortest.length, _DECIMALS),
        }


@hookimpl
def register_scorers(register) -> None:
    """Contribute the navigate scorer."""
    register("navigate", NavigateScorer, description="Navigation: success (within 1 m, target in view) and SPL")
