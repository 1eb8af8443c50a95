"""The report's Active section: active beside passive on the same instances (paired), the
actions used, L2 against the budget, trajectories with the views each rendered."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def report(generated_release, tmp_path_factory):
    root = tmp_path_factory.mktemp("active-report")
    for name, backend, strategy, parser in (("center", "center", "basic", "json"),
                                            ("oracle", "explorer-oracle", "active", "active")):  # fmt: skip
        (root / f"{name}.yaml").write_text(yaml.safe_dump({
            "dataset": {"path": str(generated_release)}, "instances": {"houses": ["train_house_00000"], "sample": 3, "seed": 2},
            "backend": backend, "strategy": strategy, "parser": parser, "scorers": ["official"],
            "output": str(root / "runs" / name)}))  # fmt: skip
        run_pipeline(load_pipeline(root / f"{name}.yaml"))
    return write_report(root / "runs", root / "report", n_boot=200)


def test_each_active_system_is_compared_with_the_passive_run_on_the_same_instances(report):
    overall = [c for c in _active(report)["comparisons"] if c["condition"] == "all"]
    assert len(overall) == 1 and overall[0]["n_pairs"] == 3
    assert overall[0]["mean_b"] < 0.01 and overall[0]["passive"].startswith("center")


def test_the_actions_used_and_the_budget_are_tabled(report):
    numbers = _active(report)
    assert numbers["actions"][0]["episodes"] == 3 and sum(numbers["actions"][0]["actions"].values()) == 3
    assert [b["budget"] for b in numbers["budgets"]] == [8]


def test_trajectories_are_drawn_with_the_views_they_rendered(report):
    page = report.page.read_text()
    assert 'id="active"' in page and page.count('class="active-episode"') == 3
    thumbs = list((report.out / "images" / "active").glob("*.jpg"))
    assert thumbs and all(f"images/active/{t.name}" in page for t in thumbs)


def test_the_gallery_card_shows_the_rendered_view_answered_in_and_the_trajectory_from_above(report):
    svgs = [p.read_text() for p in (report.out / "images").glob("*.svg")]
    assert sum('id="trajectory"' in s for s in svgs) == 3  # one bird's-eye card per active row
    assert report.gallery.without_image == 0  # every active row answered in a view has its drawing


def _active(report) -> dict:
    import json

    return json.loads((report.out / "summary.json").read_text())["active"]
