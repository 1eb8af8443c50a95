"""One ``locate`` call's inputs made ready: the robot's frames letterboxed into a fresh image
store and a synthetic benchmark instance around them.

What it is for: a strategy expects a POVBench :class:`~povagent.dataset.instances.Instance`, so the
agent builds one: condition A when frames are given, C when an ``observer_view`` is; the frames
letterboxed to the benchmark's 512x512 (:mod:`povagent.geometry.letterbox`, as the paper does
for house-tour videos), each told the unposed square camera; for a strategy that solves the
geometry itself, the robot's cameras brought into its world (:mod:`povagent.agent.solver_cameras`).

What it must not do: talk to a model or parse an answer (:mod:`povagent.agent.grounding_agent`,
:mod:`povagent.agent.localization`), or read a dataset: the instance is made from the call alone.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from PIL import Image

from povagent.agent.frame_inputs import FrameInput, aligned, load_frame
from povagent.agent.solver_cameras import posed_cameras
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.models import Condition, Direction
from povagent.dataset.realworld import unknown_object, unposed_square_camera
from povagent.errors import BadInputError
from povagent.exchange.images import ImageStore
from povagent.geometry.camera import Camera, ViewCamera
from povagent.geometry.goals import GoalCamera, PinholeCamera, Plane, camera_problem
from povagent.geometry.letterbox import Letterbox
from povagent.geometry.solver_world import SolverWorld

#: The id parts of the synthetic instance (the prompts never show them).
AGENT_HOUSE_ID = "agent"
AGENT_PAIR_ID = "query"


@dataclass
class PreparedCall:
    """One call's inputs, ready for the strategy (``solver_cameras`` and ``world`` only for a
    :class:`~povagent.agent.solver_cameras.PosedSolver`)."""

    instance: Instance
    images: ImageStore
    boxes: list[Letterbox]
    cameras: list[GoalCamera | None]
    depths: list[np.ndarray | None]
    folder: tempfile.TemporaryDirectory
    solver_cameras: list[ViewCamera] | None = None
    world: SolverWorld | None = None


def prepare_call(
    sentence: Any,
    frames: Sequence[FrameInput],
    observer_view: FrameInput | None,
    cameras: Any,
    depths: Any,
    *,
    pad_color: tuple[int, int, int],
    plane: Plane,
    posed: bool,
) -> PreparedCall:
    """One call's inputs, checked and made ready for the strategy.

    The frames (or the observer view) are loaded, letterboxed to the benchmark's square with
    ``pad_color`` and put into a fresh image store, each also written once to a temporary
    folder (strategies read frames by file); cameras and depth images are lined up with them
    and checked. ``posed``: the strategy is a :class:`~povagent.agent.solver_cameras.PosedSolver`,
    so the robot's cameras are brought into its world (the floor ``plane``). Any problem is a
    :class:`~povagent.errors.BadInputError`; the temporary folder is the caller's to clean up.
    """
    if not isinstance(sentence, str) or not sentence.strip():
        raise BadInputError("sentence: give the user's sentence as a non-empty string")
    if observer_view is not None:
        condition = Condition.GIVEN
        shown = [load_frame(observer_view, "observer_view")]
    else:
        if isinstance(frames, (str, os.PathLike, Image.Image, np.ndarray)):
            frames = [frames]  # one frame given bare
        frames = list(frames or ())
        if not frames:
            raise BadInputError("no frames: give at least one frame, or an observer_view")
        condition = Condition.INFERRED
        shown = [load_frame(f, f"frames[{i}]") for i, f in enumerate(frames)]
    cams = aligned(cameras, len(shown), "cameras", (Camera, PinholeCamera))
    deps = aligned(depths, len(shown), "depths", (np.ndarray,))
    for i, (im, cam) in enumerate(zip(shown, cams)):
        if cam is None:
            continue
        problem = camera_problem(cam)
        if problem is not None:
            raise BadInputError(f"cameras[{i}]: {problem}")
        if (cam.width, cam.height) != im.size:
            raise BadInputError(
                f"cameras[{i}] describes a {cam.width}x{cam.height} image but the frame is "
                f"{im.size[0]}x{im.size[1]}: give the camera of the original frame"
            )

    images = ImageStore()
    folder = tempfile.TemporaryDirectory(prefix="povagent-agent-")
    boxes: list[Letterbox] = []
    instance_frames: list[Frame] = []
    # The model sees benchmark-like frames; the camera it is told about is the square one.
    square_camera = unposed_square_camera()
    try:
        for i, im in enumerate(shown):
            box = Letterbox.for_size(im.size[0], im.size[1])
            stored = images.add_pil(box.apply(im, pad_color))
            # strategies read frames by file: write the encoded bytes once, so the file
            # hashes to the image already stored (no second encode)
            file = Path(folder.name) / f"frame_{i:03d}.png"
            file.write_bytes(images.encoded_bytes(stored.image_hash))
            boxes.append(box)
            name = "observer_view.png" if condition is Condition.GIVEN else file.name
            # the frame's own camera is the unposed square one: only a PosedSolver is
            # told the robot's cameras (below), in the world it reasons in
            instance_frames.append(Frame(i, name, file, square_camera))
    except BaseException:
        folder.cleanup()
        raise
    solver_cameras, world = None, None
    if posed:
        try:
            solver_cameras, world = posed_cameras(cams, boxes, plane, condition, square_camera)
        except BaseException:
            folder.cleanup()
            raise
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
    return PreparedCall(instance, images, boxes, cams, deps, folder, solver_cameras, world)
