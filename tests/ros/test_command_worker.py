"""The node's answering without a graph: every command one final result, whatever raises."""

from __future__ import annotations

import threading

import pytest

from povagent.ros.command_worker import CommandWorker
from povagent.ros.result import CommandResult, CommandStatus


class Published:
    """Collects what the worker publishes; ``fail_on`` names commands whose first publish raises."""

    def __init__(self, fail_on: tuple[str, ...] = ()) -> None:
        self.results: list[CommandResult] = []
        self.fail_on = set(fail_on)
        self.lock = threading.Lock()

    def __call__(self, result: CommandResult) -> None:
        with self.lock:
            if result.command in self.fail_on:
                self.fail_on.discard(result.command)
                raise ValueError("nanoseconds value must be nonnegative")  # what rclpy's Time says of a negative stamp
            self.results.append(result)

    def final(self, command: str) -> list[CommandStatus]:
        with self.lock:
            return [r.status for r in self.results if r.command == command and r.status != CommandStatus.QUEUED]


def answered(command: str) -> CommandResult:
    if command == "raise":
        raise KeyError("a bug")
    return CommandResult(command=command, status=CommandStatus.NO_KEYFRAMES)


@pytest.fixture
def logged():
    return []


def test_an_answer_that_raises_is_an_internal_error_result_and_the_next_command_is_answered(wait_until, logged):
    published = Published()
    worker = CommandWorker(answered, published, map_frame="map", max_queue=4, log_bug=logged.append)
    try:
        worker.submit("raise")
        worker.submit("after")
        wait_until(lambda: published.final("after"), what="the next command's answer")
    finally:
        worker.close()
    assert published.final("raise") == [CommandStatus.INTERNAL_ERROR] and published.final("after") == [CommandStatus.NO_KEYFRAMES]
    [internal] = [r for r in published.results if r.command == "raise"]
    assert internal.reason == "answering raised KeyError: 'a bug'"
    assert "Traceback" in logged[0] and "KeyError" in logged[0]


def test_a_result_that_cannot_be_published_is_replaced_by_its_internal_error_and_the_worker_goes_on(wait_until, logged):
    published = Published(fail_on=("negative stamp",))
    worker = CommandWorker(answered, published, map_frame="map", max_queue=4, log_bug=logged.append)
    try:
        worker.submit("negative stamp")
        worker.submit("after")
        wait_until(lambda: published.final("after"), what="the next command's answer")
    finally:
        worker.close()
    assert published.final("negative stamp") == [CommandStatus.INTERNAL_ERROR]
    [internal] = [r for r in published.results if r.command == "negative stamp"]
    assert internal.reason.startswith("the no_keyframes result could not be published: ValueError")


def test_a_command_finding_the_queue_full_is_told_it_is_dropped(wait_until):
    gate = threading.Event()
    published = Published()

    def held(command: str) -> CommandResult:
        gate.wait(30)
        return answered(command)

    worker = CommandWorker(held, published, map_frame="map", max_queue=1)
    try:
        worker.submit("first")
        wait_until(lambda: worker.answering, what="the worker to start answering")
        worker.submit("second")
        worker.submit("third")
        [full] = [r for r in published.results if r.command == "third"]
        gate.set()
        wait_until(lambda: published.final("second"), what="the queued command's answer")
    finally:
        gate.set()
        worker.close()
    assert full.status == CommandStatus.QUEUE_FULL and full.reason.startswith("dropped: 2 command(s) ahead and the queue holds 1")
    assert [published.final(c) for c in ("first", "second", "third")] == [[CommandStatus.NO_KEYFRAMES]] * 2 + [[CommandStatus.QUEUE_FULL]]
