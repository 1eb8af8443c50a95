"""The camera mount given as the node's ``mount_transform`` parameter: seven numbers, two spellings.

``mount_transform`` is the camera frame's pose in its parent, ``x y z qx qy qz qw`` (metres, a
unit quaternion). ROS arguments can carry it two ways, and both are taken:

* a string, as the docs and a shell write it: ``-p mount_transform:="0.1 0 0.9 -0.5 0.5 -0.5 0.5"``
  (spaces or commas between the numbers);
* an array: ``-p mount_transform:=[0.1,0.0,0.9,-0.5,0.5,-0.5,0.5]`` (YAML gives a whole-number
  array as integers, so integer arrays are taken too).

Anything else (another count of numbers, a word, a boolean, a non-unit quaternion) is a
:class:`~povagent.ros.transforms.TransformProblem` whose one line says what was given and what is
expected; the node turns it into its one-line parameter error. Pure: no rclpy.
"""

from __future__ import annotations

import math
from array import array
from typing import Any

from povagent.ros.transforms import RigidTransform, TransformProblem

#: What the parameter holds, in the words the error repeats.
EXPECTED = 'seven numbers "x y z qx qy qz qw" (a string or an array)'


def mount_from_parameter(value: Any, what: str = "parameter mount_transform") -> RigidTransform:
    """The mount a ``mount_transform`` value describes; :class:`TransformProblem` naming ``what`` otherwise."""
    numbers = _numbers(value, what)
    if len(numbers) != 7:
        raise TransformProblem(f"{what}: expected {EXPECTED}, got {len(numbers)} number(s): {value!r}")
    return RigidTransform.checked(numbers[:3], numbers[3:], what)


def _numbers(value: Any, what: str) -> list[float]:
    if isinstance(value, str):
        words = value.replace(",", " ").strip().strip("[]").split()
        try:
            numbers = [float(w) for w in words]
        except ValueError:
            raise TransformProblem(f"{what}: expected {EXPECTED}, got {value!r}") from None
    # rclpy hands an array parameter over as a list or an array.array
    elif isinstance(value, (list, tuple, array)) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        numbers = [float(v) for v in value]
    else:
        raise TransformProblem(f"{what}: expected {EXPECTED}, got {type(value).__name__} {value!r}")
    if not all(math.isfinite(v) for v in numbers):
        raise TransformProblem(f"{what}: the numbers must be finite, got {value!r}")
    return numbers


__all__ = ["EXPECTED", "mount_from_parameter"]
