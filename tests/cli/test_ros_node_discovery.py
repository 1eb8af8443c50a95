"""``povagent ros-node`` started with no discovery variable set: it says it discovers on this
machine only, and it does: no socket on the domain's multicast discovery port.

This is the one ROS test that does not set ``ROS_AUTOMATIC_DISCOVERY_RANGE`` itself, since the
default is what it checks; its domain (101) is used by no other test.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")

DOMAIN = 101
#: The RTPS well-known ports of the domain: discovery multicast at 7400 + 250 d, unicast above it.
MULTICAST_PORT = 7400 + 250 * DOMAIN
DOMAIN_PORTS = range(MULTICAST_PORT, MULTICAST_PORT + 250)


def udp_ports(pid: int) -> set[int]:
    """The local ports of the UDP sockets process ``pid`` holds."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    ports = set()
    for table in ("udp", "udp6"):
        for line in open(f"/proc/{pid}/net/{table}").read().splitlines()[1:]:
            fields = line.split()
            if fields[9] in inodes:
                ports.add(int(fields[1].rsplit(":", 1)[1], 16))
    return ports


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process's sockets from /proc")
def test_ros_node_with_no_discovery_variable_says_localhost_and_opens_no_multicast_discovery_port(tmp_path):
    (tmp_path / "center.yaml").write_text("backend: center\nstrategy: basic\nparser: json\n")
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY")}
    env.update(ROS_DOMAIN_ID=str(DOMAIN), ROS_LOG_DIR=str(tmp_path))
    proc = subprocess.Popen([sys.executable, "-m", "povagent.cli", "ros-node", "--pipeline", "center.yaml"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        said = proc.stderr.readline()
        end = time.monotonic() + 60
        while not udp_ports(proc.pid) & set(DOMAIN_PORTS):  # the participant's unicast ports: DDS is up
            assert proc.poll() is None and time.monotonic() < end, "the node never opened its DDS ports"
            time.sleep(0.05)
        ports = udp_ports(proc.pid)
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
    assert said.startswith(f"ROS 2 discovery: LOCALHOST, domain {DOMAIN} (this machine only; ")
    assert MULTICAST_PORT not in ports, sorted(ports & set(DOMAIN_PORTS))
