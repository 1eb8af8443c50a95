"""What the agent returns, and how the model's answer becomes it.

What it is for: :class:`Localization`, the typed result of a ``locate`` call (the frame, the
pixel in the *original* frame, the normalized point, how the answer parsed, the raw answer,
latency and tokens, and with a camera a 3D goal in the robot's world), and :func:`localize`,
which makes it from the final answer: parsed, mapped back through the exact letterbox
transform, and back-projected (:mod:`povagent.geometry.goals`) or taken from a strategy that
solved the geometry itself. What it must not do: call a model or retry (an answer that names no
usable point or frame is an :class:`~povagent.errors.UnparseableAnswerError` carrying the raw
answer, for the robot app to log or re-ask).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict

from povagent.agent.prepared_call import PreparedCall
from povagent.agent.solver_cameras import solved_goal
from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.release_models import Condition
from povagent.errors import UnparseableAnswerError
from povagent.exchange.messages import Request, Response
from povagent.exchange.usage_totals import UsageTotals
from povagent.geometry.goals import Goal3D, GoalUnavailable, Plane, back_project
from povagent.geometry.letterbox import pixel_index
from povagent.interfaces import Parser


class Localization(BaseModel):
    """Where the model put the target, in the robot's own frame (and world, given a camera).

    ``frame_index`` is the index of the chosen frame in ``frames`` (A/B), or 0 for the observer
    view (C). ``pixel`` is a continuous coordinate in that original frame (``(0, 0)`` its
    top-left corner, ``(W, H)`` its bottom-right; see :mod:`povagent.geometry.letterbox`) and
    ``pixel_index`` the ``(column, row)`` of the pixel containing it; ``normalized`` is
    ``pixel / (W, H)``. ``square_point`` is the answer as the model gave it in the letterboxed
    512x512 image, and ``on_padding`` says it fell on the letterbox border (it was moved to the
    nearest image edge). ``latency_s`` is the whole call's wall time; ``model_latency_s`` the
    sum of the model calls'. ``goal`` is the 3D point when a camera was given for the frame.
    """

    model_config = ConfigDict(frozen=True)

    condition: Condition
    frame_index: int
    pixel: tuple[float, float]
    pixel_index: tuple[int, int]
    normalized: tuple[float, float]
    frame_size: tuple[int, int]
    square_point: tuple[float, float]
    on_padding: bool
    status: ParseStatus
    reason: str = ""
    repair: str | None = None
    raw_answer: str
    latency_s: float
    model_latency_s: float
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cost_usd: float | None = None
    retries: int = 0
    exchanges: int = 1
    goal: Goal3D | None = None
    goal_error: str | None = None

    @property
    def point_3d(self) -> tuple[float, float, float] | None:
        """The 3D goal's coordinates, or ``None`` when none was computed."""
        return self.goal.point if self.goal is not None else None


def localize(
    prepared: PreparedCall,
    exchanges: list[tuple[Request, Response]],
    elapsed: float,
    parser: Parser,
    plane: Plane,
    depth_kind: Literal["z", "range"],
) -> Localization:
    """The final answer of ``exchanges`` as a :class:`Localization` in the robot's frame.

    ``parser`` reads the last answer; the pixel is mapped back through the exact letterbox
    transform and, with a camera, to a 3D goal (the solver's own, else back-projected onto
    ``plane`` or at the depth image's ``depth_kind`` depth). An answer with no usable point or
    frame is an :class:`~povagent.errors.UnparseableAnswerError`; a goal that cannot be computed
    is not an error (``goal_error`` says why). ``elapsed`` is the whole call's wall time.
    """
    request, response = exchanges[-1]
    text = response.text or ""
    parsed: ParsedAnswer = parser.parse(text, request.answer)
    instance = prepared.instance
    point = parsed.point
    if point is None:
        raise _unparseable(
            f"no point could be read from the model's answer ({parsed.reason or parsed.status}): {_clip(text)}",
            text,
            parsed,
        )
    if instance.povbench_condition.uses_exploration_frames:
        k = parsed.selected_image
        if k is None or instance.selected_frame(k) is None:
            named = "no frame" if k is None else f"frame {k}"
            raise _unparseable(
                f"the answer names {named}, but there are frames 0..{len(instance.frames) - 1}: {_clip(text)}",
                text,
                parsed,
            )
    else:
        k = 0
    box = prepared.boxes[k]
    square = (float(point[0]), float(point[1]))
    pixel_arr = box.to_original(np.array(square))
    pixel = (float(pixel_arr[0]), float(pixel_arr[1]))
    width, height = box.original
    goal, goal_error = None, None
    camera = prepared.cameras[k]
    solved = solved_goal(response, camera, prepared.world, pixel)
    if solved is not None:  # a strategy that solved the geometry gives the goal itself
        goal = solved
    elif camera is not None:
        try:
            goal = back_project(camera, pixel, depth=prepared.depths[k], plane=plane, depth_kind=depth_kind)
        except GoalUnavailable as exc:
            goal_error = str(exc)
    spent = UsageTotals.of(r.usage for _, r in exchanges)
    return Localization(
        condition=instance.condition,
        frame_index=k,
        pixel=pixel,
        pixel_index=pixel_index(pixel, width, height),
        normalized=(pixel[0] / width, pixel[1] / height),
        frame_size=(width, height),
        square_point=square,
        on_padding=box.on_padding(square),
        status=parsed.status,
        reason=parsed.reason,
        repair=parsed.repair,
        raw_answer=text,
        latency_s=elapsed,
        model_latency_s=sum(r.latency_s for _, r in exchanges),
        prompt_tokens=spent.prompt_tokens,
        completion_tokens=spent.completion_tokens,
        cost_usd=spent.cost_usd,
        retries=sum(r.retries for _, r in exchanges),
        exchanges=len(exchanges),
        goal=goal,
        goal_error=goal_error,
    )


def _unparseable(message: str, raw_answer: str, parsed: ParsedAnswer) -> UnparseableAnswerError:
    """The error with the raw answer and its parse attached (a robot app may log or re-ask)."""
    return UnparseableAnswerError(message, raw_answer, parsed)


def _clip(text: str, limit: int = 200) -> str:
    one_line = " ".join(text.split())
    return repr(one_line if len(one_line) <= limit else one_line[:limit] + "...")
