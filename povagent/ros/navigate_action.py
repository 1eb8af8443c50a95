"""The goal sent to Nav2 as its ``navigate_to_pose`` action, the action's outcome back into ``~/result``.

``/goal_pose`` is fire-and-forget: ``bt_navigator`` turns it into a ``navigate_to_pose`` goal and
nobody hears how it ended. With the node's ``navigate_action`` parameter set (``navigate_to_pose``,
or a namespaced name), the node is that action's client instead: each goal is sent as a
``nav2_msgs/action/NavigateToPose`` goal (``pose`` = the ``/goal_pose`` it would have published,
``behavior_tree`` empty: the navigator's default), and ``/goal_pose`` is not published (Nav2 would
get the goal twice). The command's answer says ``navigation.status = sent`` (or ``unavailable``
when no server is up, never waiting for one); when the action ends, a second ``~/result`` for the
same command carries the outcome: ``succeeded``, ``aborted``, ``canceled`` or ``rejected``, with
the result's ``error_code`` and ``error_msg`` where the result has them (Iron and later; Humble's
result is ``std_msgs/Empty`` and they stay ``None`` and ``""``). A newer goal preempts the one
before (Nav2's rule), whose outcome then comes as ``canceled`` or ``aborted``.

``nav2_msgs`` has no PyPI wheel: it comes with Nav2 (``apt install ros-$ROS_DISTRO-nav2-msgs``)
and is imported only when the parameter is set; without it the node stops with one line. A
:class:`NavigationInterface` names the action type and how a goal pose becomes its goal: Nav2's by
default, another for a navigator that serves its own. Never blocks: the outcome arrives on the
executor through the action client's futures.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable

from povagent.errors import ConfigError
from povagent.ros.extras import ROS_EXTRA, prepare_ros_environment
from povagent.ros.result import CommandResult, NavigationOutcome, NavigationStatus

prepare_ros_environment()  # before rclpy's first import
try:
    from action_msgs.msg import GoalStatus
    from rclpy.action import ActionClient
except ImportError as _missing:
    raise ConfigError(f"ros-node needs ROS 2's Python packages ({_missing.name} is missing): {ROS_EXTRA}") from None

#: Where the action type lives when the parameter asks for it.
NAV2_ACTION = ("nav2_msgs.action", "NavigateToPose")
#: A finished goal's status (``action_msgs/GoalStatus``) to what ``~/result`` says.
TERMINAL = {
    GoalStatus.STATUS_SUCCEEDED: NavigationStatus.SUCCEEDED,
    GoalStatus.STATUS_ABORTED: NavigationStatus.ABORTED,
    GoalStatus.STATUS_CANCELED: NavigationStatus.CANCELED,
}


@dataclass(frozen=True)
class NavigationInterface:
    """An action type a navigator serves, and how a ``geometry_msgs/PoseStamped`` becomes its goal."""

    action_type: Any
    goal_for: Callable[[Any], Any]


def nav2_navigate_to_pose() -> NavigationInterface:
    """Nav2's ``NavigateToPose`` (goal: ``pose``, ``behavior_tree`` left empty); :class:`ConfigError`
    in one line when Nav2's interfaces are missing."""
    module, name = NAV2_ACTION
    try:
        action = getattr(importlib.import_module(module), name)
        return NavigationInterface(action, lambda pose: action.Goal(pose=pose))
    except ImportError:
        raise ConfigError(
            "ros-node parameters: navigate_action needs nav2_msgs (Nav2's interfaces; no PyPI wheel exists): "
            "install Nav2 with your ROS distribution (apt install ros-$ROS_DISTRO-nav2-msgs) or leave navigate_action unset "
            "and let bt_navigator take /goal_pose"
        ) from None


def outcome_of(action: str, status: int, result: Any) -> NavigationOutcome:
    """A finished goal's outcome from its ``GoalStatus`` code and its result message."""
    code = getattr(result, "error_code", None)
    return NavigationOutcome(
        action=action,
        status=TERMINAL.get(status, NavigationStatus.ABORTED),
        reason="" if status in TERMINAL else f"the action ended with goal status {status}",
        error_code=None if code is None else int(code),
        error_msg=str(getattr(result, "error_msg", "")),
    )


class NavigateToPose:
    """The node's client of the navigation action: :meth:`send` a goal, hear its outcome later."""

    def __init__(self, node: Any, action_name: str, on_outcome: Callable[[CommandResult], None], interface: NavigationInterface | None = None) -> None:
        self.action_name = action_name
        self.interface = interface if interface is not None else nav2_navigate_to_pose()
        self.client: ActionClient[Any, Any, Any] = ActionClient(node, self.interface.action_type, action_name)
        self._on_outcome = on_outcome
        self._destroyed = False

    def send(self, pose: Any, result: CommandResult) -> NavigationOutcome:
        """Send ``pose`` as a goal for the command ``result`` answers; the outcome follows through ``on_outcome``."""
        if not self.client.server_is_ready():
            return NavigationOutcome(action=self.action_name, status=NavigationStatus.UNAVAILABLE,
                                     reason=f"no {self.action_name} action server is up; the goal was not sent")
        goal = self.interface.goal_for(pose)
        sent = NavigationOutcome(action=self.action_name, status=NavigationStatus.SENT)
        self.client.send_goal_async(goal).add_done_callback(lambda future: self._accepted(future, result))
        return sent

    def _accepted(self, future: Any, result: CommandResult) -> None:
        handle = future.result() if future.exception() is None else None
        if handle is None or not handle.accepted:
            why = "the action server refused the goal" if handle is not None else f"sending the goal failed: {future.exception()}"
            self._report(result, NavigationOutcome(action=self.action_name, status=NavigationStatus.REJECTED, reason=why))
            return
        handle.get_result_async().add_done_callback(lambda done: self._finished(done, result))

    def _finished(self, future: Any, result: CommandResult) -> None:
        if future.exception() is not None:
            outcome = NavigationOutcome(action=self.action_name, status=NavigationStatus.ABORTED, reason=f"getting the result failed: {future.exception()}")
        else:
            response = future.result()
            outcome = outcome_of(self.action_name, int(response.status), response.result)
        self._report(result, outcome)

    def _report(self, result: CommandResult, outcome: NavigationOutcome) -> None:
        self._on_outcome(result.model_copy(update={"navigation": outcome}))

    def destroy(self) -> None:
        """Destroy the action client (before the node); a second call does nothing."""
        if not self._destroyed:
            self._destroyed = True
            self.client.destroy()


__all__ = ["NAV2_ACTION", "TERMINAL", "NavigateToPose", "NavigationInterface", "nav2_navigate_to_pose", "outcome_of"]
