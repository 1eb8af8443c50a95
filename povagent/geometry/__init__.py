"""Geometry of POVBench: the AI2-THOR camera and the ground-truth placement rules (pure numpy)."""

from povagent.geometry.camera import Camera, Projection
from povagent.geometry.ground_truth import FLAT_TOPPED_ANCHORS, target_point

__all__ = ["Camera", "Projection", "FLAT_TOPPED_ANCHORS", "target_point"]
