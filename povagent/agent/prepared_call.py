"""One ``locate`` call's inputs made ready: the robot's frames letterboxed, named in a fresh
image store, and a synthetic benchmark instance around them.

What it is for: a strategy expects a POVBench :class:`~povagent.dataset.instances.Instance`, so the
agent builds one: condition A when frames are given, C when an ``observer_view`` is; the frames
letterboxed to the benchmark's 512x512 (:mod:`povagent.geometry.letterbox`, as the paper does
for house-tour videos; once per frame, kept by a :class:`~povagent.agent.shown_frame.ShownFrame`
handed in or by the agent's :class:`~povagent.agent.frame_memory.FrameMemory`, and letterboxed
and PNG-encoded only when a backend asks for the bytes), each told the unposed
square camera; for a strategy that solves the
geometry itself, the robot's cameras brought into its world (:mod:`povagent.agent.solver_cameras`).

What it must not do: talk to a model or parse an answer (:mod:`povagent.agent.grounding_agent`,
:mod:`povagent.agent.localization`), or read a dataset: the instance is made from the call alone.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from PIL import Image

from povagent.agent.frame_inputs import FrameInput, aligned
from povagent.agent.frame_memory import FrameMemory
from povagent.agent.shown_frame import ShownFrame
from povagent.agent.solver_cameras import posed_cameras
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.realworld_set import unknown_object, unposed_square_camera
from povagent.dataset.release_models import Condition, Direction
from povagent.errors import BadInputError, DatasetError
from povagent.exchange.images import ImageStore
from povagent.geometry.camera import Camera, ViewCamera
from povagent.geometry.goals import GoalCamera, PinholeCamera, Plane, camera_problem
from povagent.geometry.letterbox import Letterbox
from povagent.geometry.solver_world import SolverWorld

#: The id parts of the synthetic instance (the prompts never show them).
AGENT_HOUSE_ID = "agent"
AGENT_PAIR_ID = "query"

#: The folder the names of a call's in-memory frames sit in: a name the call's image store
#: answers for, never a folder on disk (nothing is written).
AGENT_FRAMES = Path("povagent-agent-frames")


@dataclass
class PreparedCall:
    """One call's inputs, ready for the strategy (``solver_cameras`` and ``world`` only for a
    :class:`~povagent.agent.solver_cameras.PosedSolver`)."""

    instance: Instance
    images: ImageStore
    boxes: list[Letterbox]
    cameras: list[GoalCamera | None]
    depths: list[np.ndarray | None]
    solver_cameras: list[ViewCamera] | None = None
    world: SolverWorld | None = None


def prepare_call(
    sentence: Any,
    frames: Sequence[FrameInput | ShownFrame],
    observer_view: FrameInput | ShownFrame | None,
    cameras: Any,
    depths: Any,
    *,
    pad_color: tuple[int, int, int],
    plane: Plane,
    posed: bool,
    memory: FrameMemory | None = None,
) -> PreparedCall:
    """One call's inputs, checked and made ready for the strategy.

    The frames (or the observer view) are loaded and letterboxed to the benchmark's square
    with ``pad_color`` (a :class:`ShownFrame` handed in keeps what it computed before) and
    named in a fresh image store under the file names strategies read them by, without a file
    being written; a frame is PNG-encoded only if a backend asks for its bytes. Cameras and
    depth images are lined up with them and checked. ``posed``: the strategy is a
    :class:`~povagent.agent.solver_cameras.PosedSolver`, so the robot's cameras are brought
    into its world (the floor ``plane``). ``memory``: the agent's frames seen before, by
    content (a frame handed in bare again gets back what was made of it). Any problem is a
    :class:`~povagent.errors.BadInputError`.
    """
    if not isinstance(sentence, str) or not sentence.strip():
        raise BadInputError("sentence: give the user's sentence as a non-empty string")
    if observer_view is not None:
        condition = Condition.GIVEN
        shown = [_shown(observer_view, "observer_view", pad_color, memory)]
    else:
        if isinstance(frames, (str, os.PathLike, Image.Image, np.ndarray, ShownFrame)):
            frames = [frames]  # one frame given bare
        frames = list(frames or ())
        if not frames:
            raise BadInputError("no frames: give at least one frame, or an observer_view")
        condition = Condition.INFERRED
        shown = [_shown(f, f"frames[{i}]", pad_color, memory) for i, f in enumerate(frames)]
    cams = aligned(cameras, len(shown), "cameras", (Camera, PinholeCamera))
    deps = aligned(depths, len(shown), "depths", (np.ndarray,))
    for i, (frame, cam) in enumerate(zip(shown, cams)):
        if cam is None:
            continue
        problem = camera_problem(cam)
        if problem is not None:
            raise BadInputError(f"cameras[{i}]: {problem}")
        original = frame.box.original
        if (cam.width, cam.height) != original:
            raise BadInputError(
                f"cameras[{i}] describes a {cam.width}x{cam.height} image but the frame is "
                f"{original[0]}x{original[1]}: give the camera of the original frame"
            )

    images = ImageStore()
    boxes = [f.box for f in shown]
    instance_frames: list[Frame] = []
    # The model sees benchmark-like frames; the camera it is told about is the square one.
    square_camera = unposed_square_camera()
    for i, frame in enumerate(shown):
        what = "observer_view" if condition is Condition.GIVEN else f"frames[{i}]"
        if frame.file is not None:
            # a file that needs no letterbox is the image sent: read and checked by the store
            try:
                images.add_file(frame.file)
            except DatasetError as exc:
                raise BadInputError(f"{what}: {exc}") from None
            file = frame.file
        else:
            # strategies know frames by file name: the store answers for this name without a
            # file, and encodes the square only if a backend asks for its bytes
            file = AGENT_FRAMES / f"frame_{i:03d}.png"
            images.add_unencoded(frame.image_hash(), (frame.box.size, frame.box.size), frame.png_bytes, file)
        name = "observer_view.png" if condition is Condition.GIVEN else f"frame_{i:03d}.png"
        # the frame's own camera is the unposed square one: only a PosedSolver is
        # told the robot's cameras (below), in the world it reasons in
        instance_frames.append(Frame(i, name, file, square_camera))
    solver_cameras, world = None, None
    if posed:
        solver_cameras, world = posed_cameras(cams, boxes, plane, condition, square_camera)
    instance = Instance(
        house_id=AGENT_HOUSE_ID,
        pair_id=AGENT_PAIR_ID,
        direction=Direction("front"),  # not shown to the model; the sentence carries the relation
        condition=condition,
        sentence=sentence.strip(),
        frames=tuple(instance_frames),
        target=(float("nan"),) * 3,
        observer_object=unknown_object("Observer"),
        anchor_object=unknown_object("Anchor"),
        observer_camera=square_camera,
    )
    return PreparedCall(instance, images, boxes, cams, deps, solver_cameras, world)


def _shown(frame: FrameInput | ShownFrame, what: str, pad_color: tuple[int, int, int], memory: FrameMemory | None) -> ShownFrame:
    """``frame`` made ready to be shown: a :class:`ShownFrame` handed in keeps what it already
    computed (a keyframe asked about again), as does a frame ``memory`` has seen; anything else
    is made ready for this call only."""
    if isinstance(frame, ShownFrame):
        shown = frame.for_pad(pad_color)
    elif memory is not None:
        return memory.shown(frame, what, pad_color)
    else:
        shown = ShownFrame(frame, pad_color)
    shown.prepare(what)
    return shown
