"""O-Plot and O&A-Plot markers (plugins/strategies/markers.py) against the drawing rules of the
authors' ablation scripts (run_vlm_eval_ab1.py, ab2.py), on hand-projected points.

Cameras (see conftest): at the origin, yaw 0, horizon 0, fov 90 -> f = 512/2 = 256 px, so
(x, y, z) lands at u = 256 + 256 x/z, v = 256 - 256 y/z, truncated with int().
* observer at (1, 0, 2): u = 256 + 256 * 1/2 = 384, v = 256; disc radius
  max(8, int(512 * 0.022)) = 11, so pixels up to 11 px away are drawn: 10-11 the white rim.
* anchor box centre (0, 0, 4), size (2, 1, 2): corners x = +-1, y = +-0.5, z = 3 or 5;
  the widest corners are at z = 3: u = 256 -+ 256/3 = 170.67 .. 341.33 -> 170 .. 341,
  v = 256 -+ 256*0.5/3 = 213.33 .. 298.67 -> 213 .. 298; the 3 px line is drawn inward.
In floats f = 256 / tan(45 deg) is 256.00000000000006, so a point that lands on a whole pixel by
hand may truncate one lower (128 -> 127.99999999999997 -> 127), exactly as in the runner:
:func:`px` does the runner's arithmetic where that matters.
"""

from __future__ import annotations

import math

import pytest

from povagent.dataset.release_models import AxisAlignedBoundingBox, RawMetadata, SceneObject, Vec3
from povagent.exchange.images import ImageStore
from povagent_plugins.strategies.markers import (
    ObserverAnchorPlotStrategy,
    ObserverPlotStrategy,
    anchor_box,
    anchor_circle_radius,
    disc_radius,
    frame_markers,
)

RED, WHITE, BLUE = (255, 0, 0), (255, 255, 255), (0, 0, 255)
#: The ids of conftest's observer (a sofa) and anchor (a desk).
OBSERVER_ID, ANCHOR_ID = "Sofa|1", "Desk|1"
GREY = (128, 128, 128)  # the colour of every test frame (conftest)


def px(x: float, y: float, z: float, f: float = 256 / math.tan(math.radians(90 / 2))) -> tuple[int, int]:
    """A camera-frame point of the conftest cameras in truncated pixels, the runner's arithmetic."""
    return int(f * x / z + 256.0), int(256.0 - f * y / z)


def marked_image(strategy, inst, index=0):
    store = ImageStore()
    request = strategy.build(inst, store)
    return store, request, store.open(request.image_hashes()[index]).convert("RGB")


def unchanged(strategy, inst, index=0) -> bool:
    store, request, _ = marked_image(strategy, inst, index)
    return request.image_hashes()[index] == store.add_file(inst.frames[index].file).image_hash


# -- sizes ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("size, radius", [((512, 512), 11), ((300, 300), 8), ((1000, 800), 17), ((64, 2000), 8)])
def test_disc_radius_is_max_8_and_2_2_percent_of_the_short_side_truncated(size, radius):
    assert disc_radius(*size) == radius


@pytest.mark.parametrize("size, radius", [((512, 512), 20), ((300, 300), 15), ((1000, 800), 32)])
def test_fallback_anchor_circle_radius_is_max_15_and_4_percent_of_the_short_side(size, radius):
    assert anchor_circle_radius(*size) == radius


# -- the observer disc --------------------------------------------------------------------------------
def test_o_plot_draws_a_filled_red_disc_with_a_white_rim_at_the_observer(make_instance, facing_z):
    _, _, im = marked_image(ObserverPlotStrategy(), make_instance([facing_z()]))
    assert im.getpixel((384, 256)) == RED  # filled: the centre is red
    for dx, dy in ((9, 0), (-9, 0), (0, 9), (0, -9)):
        assert im.getpixel((384 + dx, 256 + dy)) == RED
    for dx, dy in ((10, 0), (11, 0), (-11, 0), (0, 11), (0, -10)):
        assert im.getpixel((384 + dx, 256 + dy)) == WHITE  # the 2 px outline at radius 11
    assert im.getpixel((384 + 12, 256)) == GREY and im.getpixel((384, 256 - 12)) == GREY


def test_the_disc_needs_the_observer_in_the_frames_hits(make_instance, facing_z):
    inst = make_instance([facing_z()], hits=(ANCHOR_ID,))
    assert frame_markers(inst, inst.frames[0], with_anchor=False).empty
    assert unchanged(ObserverPlotStrategy(), inst)


def test_the_disc_needs_the_observer_in_front_of_the_camera(make_instance, facing_z):
    inst = make_instance([facing_z(180)])  # looks along -z: the observer at z = 2 is behind it
    assert frame_markers(inst, inst.frames[0], with_anchor=True).empty
    assert unchanged(ObserverAnchorPlotStrategy(), inst)


def test_a_disc_centred_just_outside_the_frame_is_still_drawn(make_instance, facing_z):
    """In front and in the hits is enough (the runner ignores in-frame): u = 256 + 256 * 259/256 = 515."""
    inst = make_instance([facing_z()], observer=(2 * 259 / 256, 0.0, 2.0))
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer == (515, 256)
    im = marked_image(ObserverPlotStrategy(), inst)[2]
    assert im.getpixel((508, 256)) == RED and im.getpixel((505, 256)) == WHITE


def test_the_disc_centre_is_truncated_toward_zero(make_instance, facing_z):
    """(1, 0.5, 3) -> (341.33, 213.33) -> (341, 213); u = -3.7 -> -3 (int(), not floor)."""
    inst = make_instance([facing_z()], observer=(1.0, 0.5, 3.0))
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer == (341, 213)
    x = -2 * (259.7 / 256)  # u = 256 - 259.7 = -3.7
    inst = make_instance([facing_z()], observer=(x, 0.0, 2.0))
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer == (-3, 256)


def test_the_disc_marks_raw_metadata_position_before_the_box_centre(make_instance, facing_z, make_object):
    observer = make_object("Sofa", (0.0, 0.0, 9.0), (-1.0, 0.0, 2.0), (0.5, 0.5, 0.5), raw_position=(1.0, 0.0, 2.0))
    inst = make_instance([facing_z()], observer=observer)
    # raw position (1, 0, 2) -> 384; not the box centre (-1, 0, 2) -> 128, nor the top-level position
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer == (384, 256)


def test_without_raw_position_the_disc_marks_the_box_centre(make_instance, facing_z, make_object):
    observer = make_object("Sofa", (0.0, 0.0, 9.0), (-1.0, 0.0, 2.0), (0.5, 0.5, 0.5))
    inst = make_instance([facing_z()], observer=observer)
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer == px(-1.0, 0.0, 2.0) == (127, 256)


# -- the anchor box -----------------------------------------------------------------------------------
def test_o_plot_draws_no_anchor_box(make_instance, facing_z):
    _, _, im = marked_image(ObserverPlotStrategy(), make_instance([facing_z()]))
    assert im.getpixel((171, 256)) == GREY


def test_oa_plot_adds_a_3px_blue_box_over_the_truncated_corners(make_instance, facing_z):
    inst = make_instance([facing_z()], observer=(-1.0, 0.0, 1.0))  # u = 0: the disc keeps off the box
    assert frame_markers(inst, inst.frames[0], with_anchor=True).anchor_box == (170, 213, 341, 298)
    _, _, im = marked_image(ObserverAnchorPlotStrategy(), inst)
    assert [im.getpixel((x, 256)) for x in (169, 170, 172, 173)] == [GREY, BLUE, BLUE, GREY]
    assert [im.getpixel((x, 256)) for x in (338, 339, 341, 342)] == [GREY, BLUE, BLUE, GREY]
    assert im.getpixel((256, 213)) == BLUE and im.getpixel((256, 298)) == BLUE
    assert im.getpixel((256, 256)) == GREY  # an outline: the anchor stays visible


def test_the_anchor_box_is_drawn_over_the_observer_disc(make_instance, facing_z):
    """The observer at (1, 0, 3) lands on the box's right edge (u = 341): the edge stays blue."""
    inst = make_instance([facing_z()], observer=(1.0, 0.0, 3.0))
    _, _, im = marked_image(ObserverAnchorPlotStrategy(), inst)
    assert im.getpixel((341, 256)) == BLUE and im.getpixel((339, 256)) == BLUE
    assert im.getpixel((336, 256)) == RED and im.getpixel((345, 256)) == RED


def test_the_box_needs_the_anchor_in_the_frames_hits(make_instance, facing_z):
    inst = make_instance([facing_z()], hits=(OBSERVER_ID,))
    markers = frame_markers(inst, inst.frames[0], with_anchor=True)
    assert markers.anchor_box is None and markers.observer == (384, 256)


def test_a_box_reaching_out_of_the_frame_is_clipped_to_it(facing_z):
    corners = [[x, y, z] for x in (0, 10) for y in (-0.5, 0.5) for z in (2, 3)]
    assert anchor_box(facing_z(), corners) == (256, 192, 511, 320)


def test_a_box_left_without_width_is_not_drawn(facing_z):
    corners = [[x, y, z] for x in (3, 4) for y in (-0.5, 0.5) for z in (2, 3)]  # all right of the frame
    assert anchor_box(facing_z(), corners) is None


def test_a_box_partly_behind_the_camera_spans_the_corners_in_front(facing_z):
    corners = [[x, y, z] for x in (-1, 1) for y in (-0.5, 0.5) for z in (-1, 2)]
    (x0, y0), (x1, y1) = px(-1, 0.5, 2), px(1, -0.5, 2)  # the z = -1 corners are left out
    assert anchor_box(facing_z(), corners) == (x0, y0, x1, y1) == (127, 192, 384, 320)


def _anchor_without_corners(position) -> SceneObject:
    box = AxisAlignedBoundingBox.model_construct(center=Vec3(x=0.0, y=0.0, z=9.0), size=Vec3(x=1.0, y=1.0, z=1.0), cornerPoints=[])
    raw = RawMetadata.model_construct(objectType="Desk", position=Vec3(x=position[0], y=position[1], z=position[2]), axisAlignedBoundingBox=box)
    return SceneObject.model_construct(objectId=ANCHOR_ID, position=Vec3(x=0.0, y=0.0, z=0.0), raw_metadata=raw)


def test_an_anchor_without_corners_gets_a_blue_circle_of_radius_20(make_instance, facing_z):
    inst = make_instance([facing_z()], observer=(-1.0, 0.0, 1.0), anchor=_anchor_without_corners((0.0, 0.0, 4.0)))
    markers = frame_markers(inst, inst.frames[0], with_anchor=True)
    assert markers.anchor_box is None and markers.anchor_circle == (256, 256)
    _, _, im = marked_image(ObserverAnchorPlotStrategy(), inst)
    assert im.getpixel((256 + 19, 256)) == BLUE and im.getpixel((256, 256 - 19)) == BLUE
    assert im.getpixel((256, 256)) == GREY and im.getpixel((256 + 22, 256)) == GREY


def test_the_fallback_circle_needs_the_anchor_inside_the_frame(make_instance, facing_z):
    inst = make_instance([facing_z()], anchor=_anchor_without_corners((5.0, 0.0, 2.0)))  # u = 896
    assert frame_markers(inst, inst.frames[0], with_anchor=True).anchor_circle is None


# -- images in the store --------------------------------------------------------------------------
def test_marked_frames_are_derived_once_per_recipe(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(30)])
    store = ImageStore()
    strategy = ObserverAnchorPlotStrategy()
    first = strategy.build(inst, store).image_hashes()
    encodes = store.stats.png_encodes
    assert strategy.build(inst, store).image_hashes() == first
    assert store.stats.png_encodes == encodes


def test_o_plot_and_oa_plot_frames_differ(make_instance, facing_z):
    inst = make_instance([facing_z()])
    store = ImageStore()
    assert ObserverPlotStrategy().build(inst, store).image_hashes() != ObserverAnchorPlotStrategy().build(inst, store).image_hashes()


def test_marked_frames_keep_the_frame_size(make_instance, facing_z):
    _, _, im = marked_image(ObserverPlotStrategy(), make_instance([facing_z()]))
    assert im.size == (512, 512)


def test_given_is_sent_unmarked(make_instance, facing_z):
    from povagent.dataset.release_models import Condition

    inst = make_instance([facing_z()], condition=Condition.GIVEN, hits=())
    assert unchanged(ObserverAnchorPlotStrategy(), inst)


# -- on the shipped fixture (tests/fixtures/povbench_mini), projected by hand ------------------------
def test_fixture_anchor_box_in_a_level_frame_is_the_hand_projected_rectangle(mini_dataset):
    """House 0, pair 0, frame 0 (hits: the bed): camera at (0, 1.5, 0), yaw 0, horizon 0, fov 90
    -> f = 256, u = 256 + 256 x/z, v = 256 - 256 (y - 1.5)/z. Bed corners x = +-1, y = 0 or 0.6,
    z = 2 or 4: u spans 256 -+ 128 (z = 2); v spans 256 + 256*0.9/4 = 313.6 (top far) ..
    256 + 256*1.5/2 = 448. The floor lamp (observer) is not in the frame's hits: no disc."""
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    markers = frame_markers(inst, inst.frames[0], with_anchor=True)
    assert markers.observer is None
    (x0, _), (x1, _), (_, y0), (_, y1) = px(-1, 0, 2), px(1, 0, 2), px(0, 0.6 - 1.5, 4), px(0, 0.0 - 1.5, 2)
    assert markers.anchor_box == (x0, y0, x1, y1) == (127, 313, 384, 448)


def test_fixture_frame_without_hits_gets_no_marker(mini_dataset):
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    assert inst.frames[1].in_frame_hits == frozenset()
    assert frame_markers(inst, inst.frames[1], with_anchor=True).empty


def test_fixture_observer_in_the_hits_but_behind_the_camera_gets_no_disc(mini_dataset):
    """Frame 2 lists the floor lamp, but at z = -0.5 it is behind the camera (looking along +z)."""
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    assert inst.observer_object.objectId in inst.frames[2].in_frame_hits
    assert frame_markers(inst, inst.frames[2], with_anchor=False).observer is None


def test_fixture_anchor_box_in_a_tilted_frame_is_the_hand_projected_rectangle(mini_dataset):
    """Frame 2: camera at (0, 0.9, 0), yaw 0, horizon 30 (looking down), fov 100. With
    d = corner - camera: zc = 0.866 dz - 0.5 dy, yc = 0.866 dy + 0.5 dz, f = 256 / tan 50deg.
    The nearest corners, (+-1, 0.6, 2), are the widest: u = 256 -+ f/zc; the top edge is at
    (y 0.6, z 4), the bottom edge at (y 0, z 2)."""
    f = 256 / math.tan(math.radians(50))
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))

    def uv(x, y, z):
        dy = y - 0.9
        zc, yc = c * z - s * dy, c * dy + s * z
        return 256 + f * x / zc, 256 - f * yc / zc

    (x0, _), (x1, _), (_, y0), (_, y1) = uv(-1, 0.6, 2), uv(1, 0.6, 2), uv(0, 0.6, 4), uv(0, 0.0, 2)
    assert (x0, y0, x1, y1) == pytest.approx((141.86, 152.57, 370.14, 234.29), abs=0.01)
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    assert frame_markers(inst, inst.frames[2], with_anchor=True).anchor_box == (int(x0), int(y0), int(x1), int(y1))


def test_fixture_observer_in_front_is_drawn_at_the_hand_projected_pixel(mini_dataset):
    """House 1, pair 7, frame 1 (hits: sofa and television): camera at (5, 0.9, 5), yaw 225,
    horizon 30, fov 100; the television (observer) at (-0.3, 1.0, -0.3): d = (-5.3, 0.1, -5.3)
    lies straight ahead in x (xc = 0, u = 256); zc = 5.3 sqrt2 cos30 - 0.1 sin30,
    yc = 5.3 sqrt2 sin30 + 0.1 cos30, v = 256 - f yc/zc = 128.13 -> 128."""
    f = 256 / math.tan(math.radians(50))
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    zc = 5.3 * math.sqrt(2) * c - 0.1 * s
    yc = 5.3 * math.sqrt(2) * s + 0.1 * c
    assert 256 - f * yc / zc == pytest.approx(128.13, abs=0.01)
    inst = mini_dataset.instance("train_house_00001/7/left/a")
    assert frame_markers(inst, inst.frames[1], with_anchor=False).observer == (256, 128)
    im = marked_image(ObserverPlotStrategy(), inst, index=1)[2]
    assert im.getpixel((256, 128)) == RED and im.getpixel((256 + 11, 128)) == WHITE
