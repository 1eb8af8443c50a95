"""The ``mount_transform`` parameter: the string the docs show and the array YAML gives are the
same mount; anything else is one line saying what is expected."""

from __future__ import annotations

from array import array

import pytest

from povagent.ros.camera_mount import mount_from_parameter
from povagent.ros.transforms import TransformProblem

MOUNT = (0.1, 0.0, 0.9, -0.5, 0.5, -0.5, 0.5)


def test_the_string_the_docs_show_is_the_mount():
    mount = mount_from_parameter("0.1 0 0.9 -0.5 0.5 -0.5 0.5")
    assert mount.translation == MOUNT[:3] and mount.rotation == pytest.approx(MOUNT[3:])


@pytest.mark.parametrize("value", [list(MOUNT), array("d", MOUNT), "0.1, 0, 0.9, -0.5, 0.5, -0.5, 0.5", "[0.1, 0, 0.9, -0.5, 0.5, -0.5, 0.5]"])
def test_an_array_or_a_comma_separated_string_is_the_same_mount(value):
    assert mount_from_parameter(value) == mount_from_parameter("0.1 0 0.9 -0.5 0.5 -0.5 0.5")


def test_a_whole_number_array_is_taken():
    assert mount_from_parameter([0, 0, 1, 0, 0, 0, 1]).translation == (0.0, 0.0, 1.0)


@pytest.mark.parametrize(("value", "says"), [
    ("0 0 0 0 0 1", "got 6 number"),
    ([0.0] * 8, "got 8 number"),
    ("x y z qx qy qz qw", "got 'x y z qx qy qz qw'"),
    (True, "got bool True"),
    ("0 0 nan 0 0 0 1", "must be finite"),
    ("0 0 0 0 0 0 0", "norm 0"),
])
def test_anything_else_is_one_line_saying_what_is_expected(value, says):
    with pytest.raises(TransformProblem, match=r"^parameter mount_transform: ") as caught:
        mount_from_parameter(value)
    assert says in str(caught.value) and "\n" not in str(caught.value)
