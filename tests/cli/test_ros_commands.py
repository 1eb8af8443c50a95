"""``povagent ros-replay``: a bag in, the ~/result JSON or a short table out; ``ros-node`` and
``ros-replay`` without a model say what to give (each command run as the console script shows it, in this process)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the bags extra is not installed (pip install 'povagent[bags]')")

from typer.testing import CliRunner

from povagent.agent import GroundingAgent
from povagent.cli import app
from povagent.dataset.loader import load_dataset
from povagent.errors import ConfigError
from povagent.geometry.goals import Plane
from povagent.ros.house_tour import house_tour, well_seen_instance
from povagent.ros.tour_bag import write_tour_bag

CENTER = "backend: center\nstrategy: basic\nparser: json\n"


@pytest.fixture(scope="module")
def tour_bag(generated_release, tmp_path_factory):
    tour = house_tour(*well_seen_instance(load_dataset(generated_release)))
    return tour, write_tour_bag(tour, tmp_path_factory.mktemp("bag") / "tour")


def test_ros_replay_prints_the_result_json_with_the_agents_goal_and_saves_the_memory(tour_bag, tmp_path, console_here):
    tour, bag = tour_bag
    (tmp_path / "center.yaml").write_text(CENTER)
    proc = console_here(["ros-replay", str(bag), "--command", "the mug", "--pipeline", "center.yaml", "--json", "--save-memory", "memory"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    with GroundingAgent(plane=Plane.horizontal(0.0, up_axis="z")) as agent:
        direct = agent.locate("the mug", [f.rgb for f in tour.frames], cameras=tour.cameras())
    assert result["status"] == "ok" and result["keyframes"] == len(tour.frames)
    assert np.allclose(result["goal"], direct.goal.point, atol=1e-6, rtol=0)
    assert (tmp_path / "memory" / "memory.json").is_file()


def test_ros_replay_prints_a_short_table_by_default(tour_bag, tmp_path, console_here):
    _, bag = tour_bag
    (tmp_path / "center.yaml").write_text(CENTER)
    proc = console_here(["ros-replay", str(bag), "--command", "the mug", "--pipeline", "center.yaml"], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    keys = [line.split()[0] for line in proc.stdout.splitlines()]
    assert keys == ["bag", "status", "keyframe", "pixel", "goal"]
    assert " m in map (plane)" in proc.stdout


def test_ros_replay_without_a_model_says_what_to_give(tour_bag):
    _, bag = tour_bag
    result = CliRunner().invoke(app, ["ros-replay", str(bag), "--command", "the mug"])
    assert isinstance(result.exception, ConfigError) and str(result.exception) == "give --pipeline P.yaml or --model M (one of them)"


def test_ros_replay_of_a_missing_bag_is_one_line(tmp_path):
    (tmp_path / "center.yaml").write_text(CENTER)
    result = CliRunner().invoke(app, ["ros-replay", str(tmp_path / "nowhere"), "--command", "x", "--pipeline", str(tmp_path / "center.yaml")])
    assert isinstance(result.exception, ConfigError) and str(result.exception) == f"{tmp_path / 'nowhere'}: no such bag"


def test_ros_replay_refuses_to_save_a_memory_among_someone_elses_files_in_one_line_before_reading_the_bag(tmp_path, console_here):
    (tmp_path / "center.yaml").write_text(CENTER)
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "todo.txt").write_text("mine")
    # the bag does not exist: the folder is refused before the bag is even looked at
    proc = console_here(["ros-replay", "nowhere", "--command", "x", "--pipeline", "center.yaml", "--save-memory", "notes"], cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "error: notes: not empty and not a saved keyframe memory (it holds todo.txt, and no readable memory.json); "
        "nothing was written: choose another --save-memory folder, or empty this one"
    ]
    assert [p.name for p in (tmp_path / "notes").iterdir()] == ["todo.txt"]
