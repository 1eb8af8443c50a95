"""Reference systems are shown once only when they are one baseline crossed with axes it ignores
and answered identically: two offline explorers whose walks scored differently (no pixel answer
tells them apart) stay two rows, and so do two different baselines that answered alike."""

from __future__ import annotations

from dataclasses import replace

from povagent.report.analysis import merge_identical_baselines
from povagent.report.collect import Observation

ROW = Observation(system="explorer-oracle", run_name="r", run=0, instance_id="h/p/front/a", house_id="h", pair_id="p",
                  direction="front", condition="a", status="answered", parse_status="ok", answered=True, l2=None,
                  l2_strict=None, gt_in_frame=None, gt_behind=None, gt_u=None, gt_v=None, selected_image=None,
                  image_path=None, x=None, y=None, sentence="", raw=None, scorer="")  # fmt: skip
AXES = {"explorer-oracle": {"backend": "explorer-oracle"}, "explorer-random": {"backend": "explorer-random"}}


def merged(oracle: Observation, random: Observation) -> list[str]:
    by_system = {"explorer-oracle": [oracle], "explorer-random": [random]}
    order, _ = merge_identical_baselines(list(by_system), by_system, {k: dict(v) for k, v in AXES.items()}, set(by_system))
    return order


def test_walks_that_scored_differently_are_two_systems():
    oracle = replace(ROW, metric_values={"navigate": {"success_rate": 1.0, "spl": 0.97}})
    random = replace(ROW, system="explorer-random", metric_values={"navigate": {"success_rate": 0.0, "spl": 0.0}})
    assert merged(oracle, random) == ["explorer-oracle", "explorer-random"]


def test_one_baseline_crossed_with_axes_it_ignores_is_shown_once():
    values = {"navigate": {"success_rate": 1.0, "spl": 1.0}}
    cells = {"center · basic": [replace(ROW, system="center · basic", metric_values=values)],
             "center · cot": [replace(ROW, system="center · cot", metric_values=values)]}  # fmt: skip
    axes = {"center · basic": {"backend": "center", "strategy": "basic"}, "center · cot": {"backend": "center", "strategy": "cot"}}
    order, notes = merge_identical_baselines(list(cells), cells, axes, set(cells))
    assert order == ["center"] and "shown once as 'center'" in notes[0]


def test_two_different_baselines_that_answered_alike_are_both_shown():
    values = {"navigate": {"success_rate": 1.0, "spl": 1.0}}
    assert merged(replace(ROW, metric_values=values), replace(ROW, system="explorer-random", metric_values=values)) == [
        "explorer-oracle", "explorer-random"]


def test_a_system_its_config_labels_is_never_merged():
    values = {"navigate": {"success_rate": 1.0, "spl": 1.0}}
    cells = {"center · basic": [replace(ROW, system="center · basic", metric_values=values)],
             "mine": [replace(ROW, system="mine", metric_values=values)]}  # fmt: skip
    axes = {"center · basic": {"backend": "center", "strategy": "basic"}, "mine": {"backend": "center", "strategy": "cot"}}
    order, _ = merge_identical_baselines(list(cells), cells, axes, set(cells), labelled=frozenset({"mine"}))
    assert order == ["center · basic", "mine"]
