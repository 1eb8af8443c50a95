"""O-Plot and O&A-Plot markers (plugins/strategies/markers.py), checked on hand-projected points.

Cameras (see conftest): at the origin, yaw 0, horizon 0, fov 90 -> f = 512/2 = 256 px, so
(x, y, z) lands at u = 256 + 256 x/z, v = 256 - 256 y/z.
* observer at (1, 0, 2): u = 256 + 256 * 1/2 = 384, v = 256.
* anchor box centre (0, 0, 4), size (2, 1, 2): corners x = +-1, y = +-0.5, z = 3 or 5;
  the widest corners are at z = 3: u = 256 -+ 256/3 = 170.67 .. 341.33,
  v = 256 -+ 256*0.5/3 = 213.33 .. 298.67.
"""

from __future__ import annotations

import math

import pytest

from povagent.exchange.images import ImageStore
from povagent_plugins.strategies.markers import (
    ObserverAnchorPlotStrategy,
    ObserverPlotStrategy,
    anchor_rectangle,
    frame_markers,
    observer_point,
)

RED, BLUE = (255, 0, 0), (0, 0, 255)
GREY = (128, 128, 128)  # the colour of every test frame (conftest)


def marked_image(strategy, inst, index=0):
    store = ImageStore()
    request = strategy.build(inst, store)
    return store, request, store.open(request.image_hashes()[index]).convert("RGB")


def test_observer_projects_to_the_hand_computed_pixel(facing_z):
    assert observer_point(facing_z(), (1.0, 0.0, 2.0)) == pytest.approx((384.0, 256.0))


def test_anchor_rectangle_spans_the_hand_computed_corners(facing_z):
    corners = [[x, y, z] for x in (-1, 1) for y in (-0.5, 0.5) for z in (3, 5)]
    assert anchor_rectangle(facing_z(), corners) == pytest.approx((256 - 256 / 3, 256 - 128 / 3, 256 + 256 / 3, 256 + 128 / 3))


def test_o_plot_draws_a_red_circle_at_the_observer(make_instance, facing_z):
    inst = make_instance([facing_z()])
    _, _, im = marked_image(ObserverPlotStrategy(radius=10, line_width=3), inst)
    assert im.getpixel((384 + 9, 256)) == RED  # on the ring (outline drawn inside the radius)
    assert im.getpixel((384 - 9, 256)) == RED
    assert im.getpixel((384, 256 - 9)) == RED
    assert im.getpixel((384, 256)) == GREY  # an outline: the object stays visible
    assert im.getpixel((384 + 20, 256)) == GREY


def test_a_filled_observer_marker_covers_the_point(make_instance, facing_z):
    _, _, im = marked_image(ObserverPlotStrategy(observer_filled=True), make_instance([facing_z()]))
    assert im.getpixel((384, 256)) == RED


def test_o_plot_draws_no_anchor_box(make_instance, facing_z):
    _, _, im = marked_image(ObserverPlotStrategy(), make_instance([facing_z()]))
    assert im.getpixel((171, 256)) == GREY


def test_oa_plot_adds_a_blue_box_around_the_anchor(make_instance, facing_z):
    _, _, im = marked_image(ObserverAnchorPlotStrategy(line_width=3), make_instance([facing_z()]))
    assert im.getpixel((172, 256)) == BLUE  # left edge at u = 170.67
    assert im.getpixel((340, 256)) == BLUE  # right edge at u = 341.33
    assert im.getpixel((256, 215)) == BLUE  # top edge at v = 213.33
    assert im.getpixel((256, 297)) == BLUE  # bottom edge at v = 298.67
    assert im.getpixel((256, 256)) == GREY  # inside stays untouched
    assert im.getpixel((384 + 9, 256)) == RED


def test_marker_colours_are_configurable(make_instance, facing_z):
    strategy = ObserverAnchorPlotStrategy(observer_color="#00ff00", anchor_color=[255, 255, 0])
    _, _, im = marked_image(strategy, make_instance([facing_z()]))
    assert im.getpixel((384 + 9, 256)) == (0, 255, 0)
    assert im.getpixel((172, 256)) == (255, 255, 0)


def test_nothing_is_drawn_behind_the_camera(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(180)])
    store, request, _ = marked_image(ObserverAnchorPlotStrategy(), inst)
    # the second camera looks along -z: observer and anchor are behind it -> the frame unchanged
    assert request.image_hashes()[1] == store.add_file(inst.frames[1].file).image_hash
    assert frame_markers(inst, inst.frames[1], with_anchor=True).empty


def test_an_observer_outside_the_frame_is_not_drawn(make_instance, facing_z):
    inst = make_instance([facing_z()], observer=(5.0, 0.0, 2.0))  # u = 256 + 256 * 2.5 = 896 > 512
    assert frame_markers(inst, inst.frames[0], with_anchor=False).observer is None


def test_an_anchor_reaching_out_of_the_frame_is_clipped_to_it(facing_z):
    corners = [[x, y, z] for x in (0, 10) for y in (-0.5, 0.5) for z in (2, 3)]
    x0, y0, x1, y1 = anchor_rectangle(facing_z(), corners)
    assert x0 == pytest.approx(256.0) and x1 == 511.0
    assert (y0, y1) == pytest.approx((256 - 64, 256 + 64))


def test_an_anchor_partly_behind_the_camera_uses_the_corners_in_front(facing_z):
    corners = [[x, y, z] for x in (-1, 1) for y in (-0.5, 0.5) for z in (-1, 2)]
    assert anchor_rectangle(facing_z(), corners) == pytest.approx((128.0, 192.0, 384.0, 320.0))


def test_marked_frames_are_derived_once_per_recipe(make_instance, facing_z):
    inst = make_instance([facing_z(), facing_z(30)])
    store = ImageStore()
    strategy = ObserverAnchorPlotStrategy()
    first = strategy.build(inst, store).image_hashes()
    encodes = store.stats.png_encodes
    assert strategy.build(inst, store).image_hashes() == first
    assert store.stats.png_encodes == encodes


def test_marker_parameters_are_part_of_the_recipe(make_instance, facing_z):
    inst = make_instance([facing_z()])
    store = ImageStore()
    small = ObserverPlotStrategy(radius=6).build(inst, store).image_hashes()
    large = ObserverPlotStrategy(radius=14).build(inst, store).image_hashes()
    assert small != large


def test_marked_frames_keep_the_frame_size(make_instance, facing_z):
    store, request, im = marked_image(ObserverPlotStrategy(), make_instance([facing_z()]))
    assert im.size == (512, 512)


@pytest.mark.parametrize("options", [{"radius": 0}, {"line_width": 0}, {"observer_color": "not-a-colour"}, {"anchor_color": [1, 2]}])
def test_bad_marker_options_are_rejected_with_the_option_named(options):
    with pytest.raises(ValueError, match=next(iter(options))):
        ObserverAnchorPlotStrategy(**options)


# -- on the shipped fixture (tests/fixtures/povbench_mini), projected by hand ------------------------
def test_fixture_anchor_box_in_a_level_frame_is_the_hand_projected_rectangle(mini_dataset):
    """House 0, pair 0, frame 0: camera at (0, 1.5, 0), yaw 0, horizon 0, fov 90 -> f = 256,
    u = 256 + 256 x/z, v = 256 - 256 (y - 1.5)/z. Bed corners x = +-1, y = 0 or 0.6, z = 2 or 4:
    u spans 256 -+ 128 (z = 2); v spans 256 + 256*0.9/4 = 313.6 (top far) .. 256 + 256*1.5/2 = 448.
    The floor lamp (observer) at z = -0.5 is behind the camera: no circle."""
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    markers = frame_markers(inst, inst.frames[0], with_anchor=True)
    assert markers.observer is None
    assert markers.anchor_box == pytest.approx((128.0, 313.6, 384.0, 448.0))


def test_fixture_frame_looking_away_gets_no_marker(mini_dataset):
    """Frame 1 looks along -z (yaw 180): the bed is behind it, and the lamp projects below the
    frame (v = 256 + 256*0.7/0.5 = 614.4 > 511)."""
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    assert frame_markers(inst, inst.frames[1], with_anchor=True).empty


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
    inst = mini_dataset.instance("train_house_00000/0/right/a")
    assert frame_markers(inst, inst.frames[2], with_anchor=True).anchor_box == pytest.approx((x0, y0, x1, y1))
    assert (x0, y0, x1, y1) == pytest.approx((141.86, 152.57, 370.14, 234.29), abs=0.01)


def test_fixture_observer_in_front_is_drawn_at_the_hand_projected_pixel(mini_dataset):
    """House 1, pair 7, frame 1: camera at (5, 0.9, 5), yaw 225, horizon 30, fov 100; the sofa
    (observer) at (-0.3, 1.0, -0.3): d = (-5.3, 0.1, -5.3) lies straight ahead in x (xc = 0,
    u = 256); zc = 5.3 sqrt2 cos30 - 0.1 sin30, yc = 5.3 sqrt2 sin30 + 0.1 cos30, v = 256 - f yc/zc."""
    f = 256 / math.tan(math.radians(50))
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    zc = 5.3 * math.sqrt(2) * c - 0.1 * s
    yc = 5.3 * math.sqrt(2) * s + 0.1 * c
    inst = mini_dataset.instance("train_house_00001/7/left/a")
    markers = frame_markers(inst, inst.frames[1], with_anchor=False)
    assert markers.observer == pytest.approx((256.0, 256 - f * yc / zc))
    assert markers.observer[1] == pytest.approx(128.13, abs=0.01)
    im = marked_image(ObserverPlotStrategy(radius=10, line_width=3), inst, index=1)[2]
    assert im.getpixel((256 + 9, 128)) == RED and im.getpixel((256, 128)) != RED
