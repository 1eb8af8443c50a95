"""Counterfactual targets: where the target would be under a wrong reading of the sentence.

Each is the official placement rule (:func:`povagent.geometry.ground_truth.target_point`, never a
second copy of it) applied to the same record (:class:`PlacementCase`) with one input changed:

* **egocentric**: the directions are taken from the *viewing camera* instead of the observer.
  The official rule sets ``fwd = normalize(anchor - observer)`` (y zeroed), ``right = up x fwd``,
  ``left = -right``, ``front = -fwd``. Here ``fwd`` becomes the camera's horizontal forward axis,
  ``(sin yaw, 0, cos yaw)`` (its optical axis with the tilt dropped), so ``right`` becomes the
  camera's right axis ``(cos yaw, 0, -sin yaw)``: "left" means the image's left, and "front"
  the anchor's side facing the camera. The viewing camera is the frame the model answered in:
  the selected exploration frame in A/B, the observer view in C (where the egocentric target is
  the ground truth itself, up to the small angle between the observer camera's yaw and the line
  to the anchor's position). It is computed by handing the rule a stand-in observer one metre
  behind the anchor along the camera's forward axis. ``up`` does not depend on a viewpoint: its
  egocentric target is the ground truth.
* **mirrored**: left and right swapped (the rule's ``right`` negated), which is the rule's
  target for the opposite side. A left-right mirror leaves front and up where they are, so for
  ``front`` and ``up`` the mirrored target is the ground truth (a "front"/"behind" confusion is
  not a mirror image and is not planted or diagnosed here).
* **anchor centre**: the anchor's AABB centre, what a model that finds the anchor and stops
  there would point at.

A direction whose verdict is not ``appropriate`` keeps its raw placement under every reading, as
officially. Everything here is pure 3D geometry; projecting into a frame (with the official
clamping and behind-camera rules) is :func:`povagent.scoring.normalized_l2.project_ground_truth`'s job.
"""

from __future__ import annotations

import math

import numpy as np

from povagent.geometry.camera import Camera
from povagent.geometry.directions import DIRECTION_REGISTRY, direction_spec
from povagent.geometry.ground_truth import PlacementCase

#: The side each lateral direction is swapped with by a mirror (the registry's ``mirror``).
MIRRORED_DIRECTION = {spec.name: spec.mirror for spec in DIRECTION_REGISTRY if spec.mirror != spec.name}


def camera_forward_xz(camera: Camera) -> np.ndarray:
    """The camera's forward axis with its tilt dropped: ``(sin yaw, 0, cos yaw)``."""
    yaw = math.radians(camera.yaw)
    return np.array([math.sin(yaw), 0.0, math.cos(yaw)])


def egocentric_target(case: PlacementCase, camera: Camera) -> np.ndarray:
    """The rule's target with the directions of ``camera`` (see the module docstring)."""
    spec = direction_spec(case.direction)
    if not case.rules_apply or (spec is not None and spec.vertical):
        return case.target()
    stand_in = np.asarray(case.anchor_position, dtype=float) - camera_forward_xz(camera)
    return case.target(observer_position=stand_in)


def mirrored_target(case: PlacementCase) -> np.ndarray:
    """The rule's target with left and right swapped; front and up are their own mirror images."""
    other = MIRRORED_DIRECTION.get(case.direction)
    if other is None or not case.rules_apply:
        return case.target()
    return case.target(direction=other)


def anchor_centre(case: PlacementCase) -> np.ndarray:
    """The anchor's AABB centre."""
    return np.asarray(case.anchor_centre, dtype=float)

