"""A plugin package is a contract, end to end: ``povagent_anchor_kit`` (in
``tests/plugins/third_party_pkg/``, outside ``povagent/`` and ``plugins/``) is installed by its
``povagent`` entry point and adds the ``anchor-point`` answer type, the ``anchor-check`` scorer
with two declared metrics and the ``about_face`` active-mode tool. A passive run shows the
metrics in ``summary.json``, on the console, after ``rescore`` and in the report; an active run
offers the tool and records its call.

The expected numbers are worked out by hand from the synthetic release (``write_release``):
the centre baseline answers (256, 256) of 512 x 512, in frame 0 (yaw 0, horizon 30, at 0.9 m)
for Inferred and Stated and in the observer view (yaw towards the anchor, horizon 20, at 1.55 m)
for Given; the anchor (a bed at 0.3 m) stands 3 m from the camera along the yaw of its pair's
angle (pair 0: 0 degrees, pair 1: 180). The fov (100 degrees) spans the width, so the focal
length is 256 / tan 50 degrees pixels.
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

import povagent
from povagent import plugins
from povagent.cli import app
from povagent.results.episode import read_record
from povagent.results.rows import read_rows
from povagent.testing.loopback_server import LoopbackServer, Reply
from povagent.testing.pytest_plugin import write_release

pytestmark = pytest.mark.timeout(120)

PACKAGE_ROOT = Path(__file__).parent / "third_party_pkg"
BUILT_IN_TOOLS = ["go_to_frame", "turn", "tilt", "move", "ask", "answer"]

FOCAL = 256 / math.tan(math.radians(50))
CENTRE = 256 / 512
#: Given: the anchor 1.25 m below a camera 3 m away, seen 20 degrees down.
GIVEN_V = 0.5 + FOCAL * math.tan(math.atan(1.25 / 3) - math.radians(20)) / 512
#: Inferred/Stated, pair 0: the anchor 0.6 m below a camera 3 m away, seen 30 degrees down
#: (pair 1's anchor is behind frame 0).
FRAME0_V = 0.5 + FOCAL * math.tan(math.atan(0.6 / 3) - math.radians(30)) / 512
GIVEN_OFFSET = math.hypot(0.5 - CENTRE, GIVEN_V - CENTRE)
FRAME0_OFFSET = math.hypot(0.5 - CENTRE, FRAME0_V - CENTRE)


@pytest.fixture
def anchor_kit(tmp_path, monkeypatch):
    """The package installed as a distribution would be (a ``*.dist-info`` with its entry point on
    ``sys.path``, nothing pip-installed), and a fresh plugin host discovering it by entry point."""
    site = tmp_path / "site-packages"
    info = site / "povagent_anchor_kit-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: povagent-anchor-kit\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[povagent]\nanchor-kit = povagent_anchor_kit\n")
    monkeypatch.syspath_prepend(str(PACKAGE_ROOT))
    monkeypatch.syspath_prepend(str(site))
    host = plugins.build_plugin_host()
    monkeypatch.setattr(plugins, "_OVERRIDE", host)
    yield host
    for name in [m for m in sys.modules if m == "povagent_anchor_kit" or m.startswith("povagent_anchor_kit.")]:
        del sys.modules[name]


@pytest.fixture
def passive_run(tmp_path, anchor_kit):
    """``povagent run`` of the centre baseline over a 12-instance release, scored by
    ``anchor-check`` only: ``(run folder, console output)``."""
    release = write_release(tmp_path / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)
    path = tmp_path / "anchor.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(release)}, "backend": {"name": "center"}, "strategy": "anchor-basic",
        "parser": "anchor-json", "scorers": ["anchor-check"], "output": str(tmp_path / "run"),
    }))  # fmt: skip
    result = CliRunner().invoke(app, ["run", str(path)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return tmp_path / "run", result.stdout


def anchor_metrics(summary_file: Path) -> dict:
    return json.loads(summary_file.read_text(encoding="utf-8"))["metrics"]["anchor-check"]


def test_the_package_is_installed_by_its_entry_point_from_outside_povagent(anchor_kit):
    import povagent_anchor_kit

    origin = "entry point anchor-kit = povagent_anchor_kit from povagent-anchor-kit 0.1"
    assert [anchor_kit.entry(kind, name).source for kind, name in
            [("answer_type", "anchor-point"), ("scorer", "anchor-check"), ("strategy", "anchor-basic")]] == [origin] * 3  # fmt: skip
    # every registered tool is listed, the navigate task's arrived too (a point episode offers the rest)
    assert [e.name for e in anchor_kit.tool_entries()] == [*BUILT_IN_TOOLS, "arrived", "about_face"]
    package = Path(povagent_anchor_kit.__file__).resolve().parent
    assert package.parent == PACKAGE_ROOT.resolve()
    assert Path(povagent.__file__).resolve().parent not in package.parents


def test_a_run_records_the_package_answer_type_on_each_row(passive_run):
    folder, _ = passive_run
    rows = read_rows(folder / "results.jsonl")
    assert len(rows) == 12
    assert {(r.prediction.answer_type, json.dumps(r.prediction.value)) for r in rows if r.condition == "c"} == {
        ("anchor-point", json.dumps({"selected_image": None, "x": 256.0, "y": 256.0}))
    }


def test_the_summary_holds_the_scorers_two_metrics_with_their_values(passive_run):
    folder, _ = passive_run
    metrics = anchor_metrics(folder / "summary.json")
    assert list(metrics["declared"]) == ["anchor_in_view", "anchor_offset"]
    overall = metrics["overall"]
    assert overall["anchor_in_view"]["value"] == pytest.approx(8 / 12) and overall["anchor_in_view"]["n"] == 12
    assert overall["anchor_offset"]["value"] == pytest.approx((GIVEN_OFFSET + FRAME0_OFFSET) / 2, abs=1e-6)
    assert overall["anchor_offset"]["n"] == 8
    per_condition = metrics["per_condition"]
    assert [per_condition[c]["anchor_in_view"]["value"] for c in "abc"] == [0.5, 0.5, 1.0]
    assert per_condition["c"]["anchor_offset"]["value"] == pytest.approx(GIVEN_OFFSET, abs=1e-6)
    assert per_condition["a"]["anchor_offset"]["value"] == pytest.approx(FRAME0_OFFSET, abs=1e-6)


def test_the_console_prints_the_scorers_table(passive_run):
    _, printed = passive_run
    assert "scorer anchor-check" in printed
    assert "Anchor in view ↑" in printed and "Anchor offset ↓" in printed and "66.7%" in printed


def test_rescore_reproduces_the_metrics_and_prints_them(passive_run):
    folder, _ = passive_run
    result = CliRunner().invoke(app, ["rescore", str(folder), "--parser", "anchor-json"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "scorer anchor-check" in result.stdout and "Anchor offset ↓" in result.stdout
    assert anchor_metrics(folder / "rescored-anchor-json" / "summary.json") == anchor_metrics(folder / "summary.json")


def test_the_report_has_a_table_for_the_scorer(passive_run, tmp_path):
    folder, _ = passive_run
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(folder), "--out", str(out), "--bootstrap", "50", "--no-gallery"])
    assert result.exit_code == 0, result.output
    tables = (out / "tables.md").read_text(encoding="utf-8")
    assert "Scorer anchor-check" in tables and "Anchor in view" in tables and "Anchor offset" in tables
    assert "66.7%" in tables and f"{(GIVEN_OFFSET + FRAME0_OFFSET) / 2:.3f}" in tables


def test_the_console_prints_no_error_table_for_a_run_without_a_pixel_scorer(passive_run):
    _, printed = passive_run
    assert "mean L2" not in printed and "strict L2" not in printed


def test_rescore_prints_no_error_table_for_a_run_without_a_pixel_scorer(passive_run):
    folder, _ = passive_run
    result = CliRunner().invoke(app, ["rescore", str(folder), "--parser", "anchor-json"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "scorer anchor-check" in result.stdout and "mean L2" not in result.stdout


@pytest.fixture
def passive_report(passive_run, tmp_path):
    """``povagent report`` of the passive run (the dataset found through its config): the report folder."""
    folder, _ = passive_run
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(folder), "--out", str(out), "--bootstrap", "50", "--no-gallery"])
    assert result.exit_code == 0, result.output
    return out


def test_the_report_has_a_table_per_declared_metric_per_condition(passive_report):
    in_view = (passive_report / "tables" / "metric_anchor_check_anchor_in_view.md").read_text(encoding="utf-8")
    offset = (passive_report / "tables" / "metric_anchor_check_anchor_offset.md").read_text(encoding="utf-8")
    assert "Anchor in view (anchor-check)" in in_view and "| Inferred | Stated | Given | Overall |" in in_view.replace("**", "")
    assert "50.0%" in in_view and "100.0%" in in_view and "66.7%" in in_view
    assert f"{GIVEN_OFFSET:.3f}" in offset and f"{(GIVEN_OFFSET + FRAME0_OFFSET) / 2:.3f}" in offset


def test_the_reports_summary_holds_each_declared_metric_per_system_and_slice(passive_report):
    summary = json.loads((passive_report / "summary.json").read_text(encoding="utf-8"))
    center = summary["metrics"]["anchor-check"]["center"]
    assert center["overall"]["anchor_in_view"]["value"] == pytest.approx(8 / 12) and center["overall"]["anchor_in_view"]["n"] == 12
    assert [center["per_condition"][c]["anchor_in_view"]["value"] for c in "abc"] == [0.5, 0.5, 1.0]
    assert center["per_condition"]["c"]["anchor_offset"]["value"] == pytest.approx(GIVEN_OFFSET, abs=1e-6)


def test_the_report_plots_each_declared_metric(passive_report):
    plots = sorted(p.name for p in (passive_report / "plots").iterdir())
    assert plots == ["metric_anchor_check_anchor_in_view.svg", "metric_anchor_check_anchor_offset.svg"]


def test_the_report_of_a_run_scored_only_by_a_third_party_has_no_pixel_table(passive_report):
    summary = json.loads((passive_report / "summary.json").read_text(encoding="utf-8"))
    tables = sorted(p.stem for p in (passive_report / "tables").glob("*.md"))
    assert tables == [
        "metric_anchor_check_anchor_in_view", "metric_anchor_check_anchor_in_view_by_direction",
        "metric_anchor_check_anchor_offset", "metric_anchor_check_anchor_offset_by_direction", "response_rates",
    ]
    assert summary["scorers"] == [] and [s["system"] for s in summary["systems"]] == ["center"]  # no computed centre baseline


def test_the_reports_response_rate_counts_the_rows_answered(passive_report):
    summary = json.loads((passive_report / "summary.json").read_text(encoding="utf-8"))
    (system,) = summary["systems"]
    assert system["overall"]["response_rate"]["value"] == 1.0
    assert system["overall"]["official_mean_l2"]["value"] is None
    assert "a response is a row whose status is answered" in (passive_report / "tables" / "response_rates.md").read_text(encoding="utf-8")


def test_the_report_gallery_shows_each_answer_as_its_type_shows_it(passive_run, tmp_path):
    folder, _ = passive_run
    out = tmp_path / "gallery-report"
    result = CliRunner().invoke(app, ["report", str(folder), "--out", str(out), "--bootstrap", "0"])
    assert result.exit_code == 0, result.output
    page = (out / "report.html").read_text(encoding="utf-8")
    shown = set(re.findall(r'"v": ?"([^"]*)"', page))
    assert shown == {"anchor at (256.0, 256.0) in image None", "anchor at (256.0, 256.0) in image 0"}


def calls(*pairs: tuple[str, object]) -> Reply:
    return Reply(None, tool_calls=tuple({"name": n, "arguments": a} for n, a in pairs))


def test_an_active_run_offers_the_packages_tool_and_records_its_call(generated_release, tmp_path, anchor_kit, monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-not-a-key")
    path = tmp_path / "active.yaml"
    with LoopbackServer(reply="I cannot tell.", max_lifetime_s=100, fetch_images=True) as server:
        path.write_text(yaml.safe_dump({
            "dataset": {"path": str(generated_release)},
            "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
            "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": server.url,
                                                       "api_key_env": "POVAGENT_TEST_KEY"}},
            "strategy": {"name": "active", "options": {"max_actions": 4}}, "parser": "active",
            "scorers": ["official"], "retry": {"attempts": 1}, "output": str(tmp_path / "active"),
        }))  # fmt: skip
        server.script(calls(("about_face", {})), calls(("answer", {"image": "view 1", "x": 100, "y": 200})))
        result = CliRunner().invoke(app, ["run", str(path)])
        assert result.exit_code == 0, result.output
        first = server.requests[0]
    assert [t["function"]["name"] for t in first.body["tools"]] == [*BUILT_IN_TOOLS, "about_face"]
    assert "about_face() turns round to look behind" in first.body["messages"][0]["content"][-1]["text"]
    (row,) = read_rows(tmp_path / "active" / "results.jsonl")
    record = read_record(row.exchanges[-1].raw)
    step, _ = record.steps
    assert (row.status, step.action, step.valid, step.view) == ("answered", "about_face", True, 1)
    assert record.views[0].camera.yaw == pytest.approx((record.start.yaw + 180.0) % 360.0)
