"""O-Plot and O&A-Plot markers (plugins/strategies/markers.py), checked on hand-projected points.

Cameras (see conftest): at the origin, yaw 0, horizon 0, fov 90 -> f = 512/2 = 256 px, so
(x, y, z) lands at u = 256 + 256 x/z, v = 256 - 256 y/z.
* observer at (1, 0, 2): u = 256 + 256 * 1/2 = 384, v = 256.
* anchor box centre (0, 0, 4), size (2, 1, 2): corners x = +-1, y = +-0.5, z = 3 or 5;
  the widest corners are at z = 3: u = 256 -+ 256/3 = 170.67 .. 341.33,
  v = 256 -+ 256*0.5/3 = 213.33 .. 298.67.
"""

from __future__ import annotations

import pytest

from povagent.images import ImageStore
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
