"""The renderer shades a frame block by block, and the active mode encodes its colour planes:
neither changes a pixel (on the compiled shading's path and on numpy's)."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate import renderer as renderer_module
from povagent.generate.exploration import plan_tour
from povagent.geometry.camera import Camera
from tests.generate.compiled_paths import each_path

path = pytest.fixture(each_path(renderer_module))


def _outside_camera(tiny_dataset) -> Camera:
    """A camera outside the house looking at its wall: part of the frame shows nothing at all."""
    rooms = tiny_dataset.built.house.plan.rooms
    x0 = min(r.rect.center[0] for r in rooms) - 6.0
    z = rooms[0].rect.center[1]
    return Camera.from_pose((x0, 1.4, z), 90.0, -30.0, 100.0)


def test_a_frame_shaded_in_small_blocks_has_the_pixels_of_one_shaded_whole(tiny_dataset, monkeypatch):
    monkeypatch.setattr(renderer_module, "_COMPILED", None)  # numpy's passes shade by blocks (the C loop by tiles)
    renderer = tiny_dataset.built.renderer
    cameras = [*plan_tour(tiny_dataset.built.house, renderer, 2), _outside_camera(tiny_dataset)]
    whole = [renderer.render(c) for c in cameras]
    assert any(np.isinf(f.depth).any() and np.isfinite(f.depth).any() for f in whole)  # hits and misses
    monkeypatch.setattr(renderer_module, "SHADE_BLOCK", 10_007)  # blocks of all hits, all misses and both
    for camera, frame in zip(cameras, whole):
        blocks = renderer.render(camera)
        assert np.array_equal(blocks.rgb, frame.rgb)
        assert np.array_equal(blocks.depth, frame.depth)
        assert np.array_equal(blocks.instance, frame.instance)


@pytest.mark.parametrize("outside", [False, True])
@pytest.mark.parametrize("path", ["compiled", "numpy"], indirect=True)
def test_the_colour_planes_of_a_view_are_its_frame_rgb_channels(tiny_dataset, outside, path):
    renderer = tiny_dataset.built.renderer
    camera = _outside_camera(tiny_dataset) if outside else plan_tour(tiny_dataset.built.house, renderer, 1)[0]
    frame = renderer.render(camera)
    planes = renderer.render_planes(camera)
    assert planes.dtype == np.uint8
    assert np.array_equal(planes, frame.rgb.reshape(-1, 3).T)
