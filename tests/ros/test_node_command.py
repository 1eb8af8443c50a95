"""``povagent ros-node`` as its own process on the graph: ROS arguments set its parameters (the
camera mount written as the docs show it), it answers a player's tour and command, says which
frame its goals are in, and Ctrl-C ends it cleanly."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")


def test_the_node_command_answers_a_played_tour_with_the_pipelines_goal(ros_graph, tour, tmp_path, wait_until):
    import rclpy
    from std_msgs.msg import String

    from povagent.agent import GroundingAgent
    from povagent.geometry.goals import Plane
    from povagent.ros.extras import tf2_messages
    from povagent.ros.tour_player import TourPlayer, camera_info, mount_parameters

    (tmp_path / "center.yaml").write_text("backend: center\nstrategy: basic\nparser: json\n")
    mount = mount_parameters(tour)
    ros_args = ["--ros-args", "-r", "__node:=povagent_cli", "-p", "odom_topic:=/odom", "-p", "reliable_images:=true",
                "-p", f"mount_parent:={mount['mount_parent']}", "-p", f"mount_child:={mount['mount_child']}",
                "-p", "mount_transform:=" + " ".join(f"{v:.17g}" for v in mount["mount_transform"])]  # the docs' string form
    # -X faulthandler: a node that does not end after Ctrl-C is sent SIGABRT, which prints every
    # thread's stack into the failure's message (where it waits) before the process ends
    proc = subprocess.Popen([sys.executable, "-X", "faulthandler", "-m", "povagent.cli", "ros-node", "--pipeline", "center.yaml", *ros_args],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    player_node = ros_graph.add(rclpy.create_node("cli_player", context=ros_graph.context))
    try:
        player = TourPlayer(player_node, command_topic="/povagent_cli/command")
        results: list[dict] = []
        lock = threading.Lock()

        def take(msg):
            with lock:
                results.append(json.loads(msg.data))

        player_node.create_subscription(String, "/povagent_cli/result", take, 10)
        publishers = (player.info, player.image, player.odom, player.command)
        wait_until(lambda: all(p.get_subscription_count() for p in publishers) and player_node.count_publishers("/povagent_cli/result"),
                   timeout=60, what="the node process on the graph")
        player.info.publish(camera_info(tour, tour.frames[0].stamp_ns))
        player.say("a probe before any image")  # answered after the camera_info, which came first on its own topic
        probe = wait_until(lambda: list(results), timeout=60, what="the probe's answer")[0]
        assert probe["status"] == "no_keyframes"
        player.play(tour, after_each=lambda i: threading.Event().wait(0.05))

        def memory_full(k=[0]):  # noqa: B006  a counter across polls: each probe has its own sentence
            k[0] += 1
            player.say(f"probe {k[0]}")
            answer = wait_until(lambda: [r for r in results if r["command"] == f"probe {k[0]}"], timeout=30, what="a probe's answer")[0]
            return answer["keyframes"] == len(tour.frames)

        # the node takes the last transforms a moment after the last image: ask until it says all are kept
        wait_until(memory_full, timeout=60, what="the node to keep every frame")
        player.say("the mug")
        reply = wait_until(lambda: [r for r in results if r["command"] == "the mug"], timeout=60, what="the node's answer")[0]
        assert reply["status"] == "ok" and reply["keyframes"] == len(tour.frames), {k: reply[k] for k in ("keyframes", "images", "malformed")}
        with GroundingAgent(plane=Plane.horizontal(0.0, up_axis="z")) as agent:
            direct = agent.locate("the mug", [f.rgb for f in tour.frames], cameras=tour.cameras())
        assert np.allclose(reply["goal"], direct.goal.point, atol=1e-6, rtol=0)
    finally:
        ros_graph.remove(player_node)
        player_node.destroy_node()
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGABRT)
            try:
                _, err = proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                _, err = proc.communicate()
            err = f"the node did not end within 30 s of SIGINT; its threads' stacks at SIGABRT:\n{err}"
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    if tf2_messages() is None:  # the PyPI packages alone: the odometry's frame, decided by its first message
        assert "goals will be in the frame of the first odometry message on /odom" in err
        assert "goals are in the 'map' frame: the frame of the odometry on /odom" in err


def test_ros_arguments_rcl_cannot_read_are_one_error_line_not_a_traceback(ros_graph, tmp_path):
    (tmp_path / "center.yaml").write_text("backend: center\nstrategy: basic\nparser: json\n")
    mixed = "mount_transform:=[0.1, 0, 0.9, -0.5, 0.5, -0.5, 0.5]"  # YAML reads 0 as an integer among decimals
    proc = subprocess.run([sys.executable, "-m", "povagent.cli", "ros-node", "--pipeline", "center.yaml", "--ros-args", "-p", mixed],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    [line] = [x for x in proc.stderr.splitlines() if x.startswith("error:")]
    assert line.startswith("error: ros-node: the ROS arguments could not be read: Couldn't parse parameter override rule")
    assert "0.0 not 0" in line
