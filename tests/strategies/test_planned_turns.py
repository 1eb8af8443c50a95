"""Every turn a strategy takes is known before it runs (``Strategy.plan_turns``): ``show-prompt``
prints each planned request, with a placeholder where the model's earlier answer will stand,
and ``sweep --dry-run`` counts each turn's requests, which the loopback server then receives."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.dataset import load_dataset
from povagent.exchange.images import ImageStore
from povagent.interfaces import PlannedTurn, Strategy, declares_turns, earlier_answer, whole_answer_placeholders
from povagent.run.sweep import expand_sweep, run_sweep
from povagent.run.sweep_estimate import dry_run
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.geometric import GeometricStrategy

TWO_TURNS = Path(__file__).with_name("two_turn_strategy.py")
KEY_VARIABLE = "POVAGENT_TWO_TURN_KEY"
runner = CliRunner()


@pytest.fixture
def release(tiny_dataset) -> Path:
    """One house, one pair, two directions, three frames: 6 instances (2 per condition)."""
    return tiny_dataset(houses=1, pairs=1, pair_directions=2, frames=3)


def write_pipeline(folder: Path, release: Path, backend, **keys) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(TWO_TURNS, folder / TWO_TURNS.name)  # a config loads .py plugins only from its own folder
    data = {"plugins": [TWO_TURNS.name], "dataset": {"path": str(release)}, "backend": backend, "strategy": "check-twice",
            "parser": "official", "output": str(folder / "run"), **keys}
    path = folder / "pipeline.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_the_placeholder_names_the_turn_and_dry_runs_find_whole_answers():
    assert earlier_answer(2) == "<<the model's answer to turn 2>>"
    assert earlier_answer(1, "anchor") == "<<anchor, read from the model's answer to turn 1>>"
    text = f"a {earlier_answer(1)} b {earlier_answer(3, 'anchor')} c {earlier_answer(2)}"
    assert whole_answer_placeholders(text) == [1, 2]
    with pytest.raises(ValueError, match="positive integer"):
        earlier_answer(0)


def test_show_prompt_prints_both_turns_with_the_earlier_answer_as_a_placeholder(tmp_path, release):
    pipeline = write_pipeline(tmp_path / "p", release, "center")
    instance = load_dataset(release).instances()[0].id
    result = runner.invoke(app, ["show-prompt", str(pipeline), "--instance", instance, "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    shown = result.stdout
    assert [line for line in shown.splitlines() if line.startswith("=== ")] == ["=== turn 1 of 2 ===", "=== turn 2 of 2 ==="]
    first, second = shown.split("=== turn 2 of 2 ===")
    # turn 2 repeats turn 1's message, then the model's answer (a placeholder), then the check
    assert second.count("--- message") == 3
    after_answer = second.split("--- message 2 (assistant) ---\n", 1)[1]
    assert after_answer.startswith("<<the model's answer to turn 1>>\n--- message 3 (user) ---\nCheck that point")
    unsaved = lambda text: re.sub(r" -> [^\]]+\]", "]", text)  # noqa: E731 - where each turn's images were saved
    assert unsaved(first.split("--- message 1 (user) ---", 1)[1].split("--- generation")[0]) in unsaved(second)
    # each turn's images saved in its own folder
    assert sorted(p.name for p in (tmp_path / "shown").iterdir()) == ["turn-1", "turn-2"]


def test_a_single_turn_strategy_prints_as_before_without_turn_headings(tmp_path, release):
    pipeline = write_pipeline(tmp_path / "p", release, "center", strategy="basic")
    instance = load_dataset(release).instances()[0].id
    result = runner.invoke(app, ["show-prompt", str(pipeline), "--instance", instance, "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("--- message 1 (user) ---") and "=== turn" not in result.stdout
    assert "note:" not in result.stderr


def test_the_dry_run_counts_each_turn_and_the_server_receives_exactly_that(tmp_path, release, loopback_server, monkeypatch):
    monkeypatch.setenv(KEY_VARIABLE, "sk-test")
    backend = {"name": "litellm", "options": {"model": "openai/loopback-model", "api_base": loopback_server.url, "api_key_env": KEY_VARIABLE}}
    write_pipeline(tmp_path, release, backend, retry={"attempts": 1}, timeout=20)
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sweep"), "axes": {"conditions": ["a", "c"]}}))
    result = runner.invoke(app, ["sweep", str(sweep), "--dry-run"], env={"COLUMNS": "100"})
    assert result.exit_code == 0, result.output
    rows = {cells[0]: cells[1:] for cells in ([c.strip() for c in line.split("│")[1:-1]] for line in result.stdout.splitlines() if line.startswith("│"))}
    # 2 keys per cell, 2 turns each: 4 requests a cell, each turn's 2 under it
    assert rows["a"][:3] == ["2", "0", "4"] and rows["c"][:3] == ["2", "0", "4"]
    assert rows["turn 1"][2] == "2" and rows["turn 2"][2] == "2"
    assert rows["total"][2] == "8"
    # the second turn carries the first's prompt and an answer of up to max_tokens: more tokens
    _, cells = expand_sweep(sweep)
    (plan_a, plan_c) = dry_run(cells)
    assert [t.requests for t in plan_a.turns] == [t.requests for t in plan_c.turns] == [2, 2] and plan_a.requests == 4
    assert plan_a.turns[1].prompt_tokens > plan_a.turns[0].prompt_tokens + 2 * 256
    assert plan_a.turns[1].max_completion_tokens == plan_a.turns[0].max_completion_tokens == 2 * 256

    run_sweep(sweep, quiet=True)
    assert len(loopback_server.requests) == int(rows["total"][2]) == 8
    # the requests the server saw alternate: turn 1 (one user message), turn 2 (user, assistant, user)
    shapes = sorted(len(r.body["messages"]) for r in loopback_server.requests)
    assert shapes == [1, 1, 1, 1, 3, 3, 3, 3]
    again = runner.invoke(app, ["sweep", str(sweep), "--dry-run"], env={"COLUMNS": "100"})
    total = next(line for line in again.stdout.splitlines() if "total" in line)
    assert [c.strip() for c in total.split("│")[1:-1]][1:4] == ["4", "4", "0"]


def test_the_geometric_strategy_plans_its_sub_questions_and_its_solved_answer(mini_dataset):
    by_condition = {}
    for inst in mini_dataset.instances():
        by_condition.setdefault(str(inst.condition), inst)
    images = ImageStore()
    strategy = GeometricStrategy()
    plan_a = strategy.plan_turns(by_condition["a"], images)
    plan_c = strategy.plan_turns(by_condition["c"], images)
    kinds = lambda plan: [(t.request.question or {}).get("kind") for t in plan]  # noqa: E731
    assert kinds(plan_a) == ["read", "surface", "locate", "locate", "final"]
    assert kinds(plan_c) == ["read", "surface", "locate", "final"]
    assert [t.sent for t in plan_a] == [True, True, True, True, False]
    locate_text = "".join(p.text for p in plan_a[2].request.messages[0].parts if hasattr(p, "text"))
    assert earlier_answer(1, "anchor") in locate_text and len(plan_a[2].request.image_hashes()) == len(by_condition["a"].frames)
    assert earlier_answer(1, "observer") in "".join(p.text for p in plan_a[3].request.messages[0].parts if hasattr(p, "text"))
    assert all(t.note for t in plan_a[1:])


def test_a_strategy_overriding_solve_without_plan_turns_is_reported_as_undeclared(tmp_path, release):
    class Undeclared(BasicStrategy):
        async def solve(self, instance, ask, images):
            return await super().solve(instance, ask, images)

    assert declares_turns(BasicStrategy()) and not declares_turns(Undeclared())
    inst = load_dataset(release).instances()[0]
    (only,) = Undeclared().plan_turns(inst, ImageStore())
    assert isinstance(only, PlannedTurn) and only.sent and isinstance(Undeclared(), Strategy)
    from two_turn_strategy import TwoTurnStrategy  # the plugin file beside this test

    assert declares_turns(TwoTurnStrategy())


def test_request_text_names_roles_text_and_image_labels(release):
    inst = load_dataset(release).instances()[0]
    request = BasicStrategy().build(inst, ImageStore())
    text = request.as_text()
    assert text.startswith("--- user ---\n")
    assert re.findall(r"\[image: ([^\]]+)\]", text) == [p.label for p in request.messages[0].parts if hasattr(p, "label")]
