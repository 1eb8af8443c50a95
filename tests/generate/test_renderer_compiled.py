"""The renderer's compiled shading (``shading.c``) gives numpy's frames, bit for bit: real views of
three houses that show every material, and a camera outside a house whose rays partly hit nothing."""

from __future__ import annotations

import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from types import ModuleType

import numpy as np
import pytest

from povagent.generate import mesh_parts
from povagent.generate import renderer as renderer_module
from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.exploration import plan_tour
from povagent.generate.house_pipeline import build_house
from povagent.geometry.camera import Camera
from tests.generate.compiled_paths import OTHER_BUILDS, other_build

LOOP = compiled_loop(renderer_module._LOOP)
pytestmark = pytest.mark.skipif(LOOP is None, reason="the compiled shading is not built here, or POVAGENT_PURE_NUMPY is set")
MATERIALS = ("PLAIN", "WOOD", "FABRIC", "METAL", "GLOSS", "EMISSIVE", "FLOOR_WOOD", "FLOOR_TILE", "WALL", "CEILING")
#: (seed, index) of the houses whose views are compared (with the session's tiny dataset's house)
HOUSES = ((0, 0), (1, 0))


def _outside(house) -> Camera:
    """A camera outside the house looking at its wall: part of the frame shows nothing at all."""
    rooms = house.plan.rooms
    x0 = min(r.rect.center[0] for r in rooms) - 6.0
    return Camera.from_pose((x0, 1.4, rooms[0].rect.center[1]), 90.0, -30.0, 100.0)


@pytest.fixture(scope="module")
def views(tiny_dataset) -> list[tuple[str, renderer_module.Renderer, Camera]]:
    """Two exploration views of each house and one from outside it: (name, renderer, camera)."""
    built = [tiny_dataset.built, *(build_house(seed, index) for seed, index in HOUSES)]
    found = []
    for b in built:
        cameras = [*plan_tour(b.house, b.renderer, 2), _outside(b.house)]
        found += [(f"{b.house.house_id}-{k}", b.renderer, c) for k, c in enumerate(cameras)]
    return found


@pytest.fixture(scope="module")
def compiled_planes(views):
    """``compiled_planes(k)``: the colour planes the compiled loop shades for view ``k``. Made on
    first use and kept for the module: the threads' and the other builds' tests compare the same
    planes as the loop-against-numpy test."""
    made: dict[int, np.ndarray] = {}

    def planes(k: int) -> np.ndarray:
        if k not in made:
            _, renderer, camera = views[k]
            with pytest.MonkeyPatch.context() as patch:
                patch.setattr(renderer_module, "_COMPILED", LOOP)
                made[k] = renderer.render_planes(camera)
        return made[k]

    return planes


def _use(monkeypatch: pytest.MonkeyPatch, compiled: bool) -> None:
    monkeypatch.setattr(renderer_module, "_COMPILED", LOOP if compiled else None)


def _both(monkeypatch, fn):
    _use(monkeypatch, True)
    compiled = fn()
    _use(monkeypatch, False)
    return compiled, fn()


def test_the_views_compared_show_every_material_and_rays_that_hit_nothing(views):
    seen: set[int] = set()
    misses = 0
    for _, renderer, camera in views:
        tri = renderer._seen(camera)[2]
        seen |= set(np.unique(renderer._materials[tri[tri >= 0]]).tolist())
        misses += int((tri < 0).sum())
    assert seen == {getattr(mesh_parts, name) for name in MATERIALS}
    assert misses > 0


@pytest.mark.parametrize("k", range(9))
def test_a_view_shaded_by_the_compiled_loop_is_numpys_frame(views, compiled_planes, monkeypatch, k):
    _, renderer, camera = views[k]
    compiled, numpy = _both(monkeypatch, lambda: renderer.render(camera))
    assert np.array_equal(compiled.rgb, numpy.rgb)
    assert np.array_equal(compiled.depth, numpy.depth, equal_nan=True)
    assert np.array_equal(compiled.instance, numpy.instance)
    planes, numpy_planes = compiled_planes(k), renderer.render_planes(camera)  # (numpy's path still set)
    assert np.array_equal(planes, numpy_planes)
    assert np.array_equal(planes, numpy.rgb.reshape(-1, 3).T)


def test_a_frame_whose_pixels_fill_no_whole_tile_is_numpys_too(views, monkeypatch):
    _, renderer, camera = views[0]
    odd = Camera.from_pose(camera.position, camera.yaw, camera.horizon, camera.fov, width=97, height=61)  # 5917 pixels: 23 tiles and 29
    compiled, numpy = _both(monkeypatch, lambda: renderer.render(odd))
    assert np.array_equal(compiled.rgb, numpy.rgb)
    assert compiled.rgb.shape == (61, 97, 3)


def test_without_shadows_the_compiled_loop_gives_numpys_colours(views, monkeypatch):
    _, renderer, camera = views[0]
    monkeypatch.setattr(renderer, "shadows", False)
    compiled, numpy = _both(monkeypatch, lambda: renderer.render_planes(camera))
    assert np.array_equal(compiled, numpy)
    monkeypatch.setattr(renderer, "shadows", True)
    assert not np.array_equal(renderer.render_planes(camera), numpy)  # the shadows do darken this view


@pytest.mark.parametrize("pose", [(0.0, 0.0), (37.5, -30.0), (-123.25, 17.0), (270.0, 60.0)])
def test_the_compiled_rays_are_numpys_to_the_bit(views, monkeypatch, pose):
    _, renderer, _ = views[0]
    camera = Camera.from_pose((1.25, 1.5, -2.0), pose[0], pose[1], 100.0)
    compiled, numpy = _both(monkeypatch, lambda: renderer._directions(camera))
    assert compiled.dtype == numpy.dtype == np.float32 and compiled.shape == numpy.shape
    assert np.array_equal(compiled.view(np.uint32), numpy.view(np.uint32))


def test_threads_shading_at_once_each_get_their_own_colours(views, compiled_planes, monkeypatch):
    _use(monkeypatch, True)
    _, renderer, _ = views[0]
    shown = [k for k, (_, r, _) in enumerate(views) if r is renderer]
    cameras = [views[k][2] for k in shown]
    alone = [compiled_planes(k) for k in shown]
    with ThreadPoolExecutor(2) as pool:
        together = list(pool.map(renderer.render_planes, cameras * 2))
    assert all(np.array_equal(a, b) for a, b in zip(alone * 2, together))


def test_the_loop_knows_the_renderers_materials_and_face_code_bits():
    assert tuple(getattr(mesh_parts, name) for name in MATERIALS) == LOOP.MATERIALS
    assert LOOP.CODE_BITS == (renderer_module._MATERIAL_BITS, renderer_module._A_IS_Z, renderer_module._B_IS_Z)


def test_a_face_index_past_the_faces_is_refused(views, monkeypatch):
    _use(monkeypatch, True)
    _, renderer, camera = views[0]
    d, origin, tri, t64 = renderer._seen(camera)
    tri = tri.copy()
    tri[5] = renderer.face_count
    with pytest.raises(ValueError, match="past the faces"):
        renderer._shade_compiled(LOOP, tri, t64, d, origin)


def test_apply_shadows_darkens_exactly_the_probing_pixels_whose_ray_is_blocked():
    n = 600  # two whole tiles of 256 and part of a third
    rng = np.random.default_rng(7)
    probe = rng.integers(0, 2, n).astype(np.uint8)
    occluded = np.where(rng.integers(0, 2, n) == 1, 0, -1).astype(np.int32)
    occluded[::7] = rng.integers(1, 5000, len(occluded[::7]))  # any face index counts as blocked
    ends = [0, 255, 256, n - 1]  # each tile's first and last pixels darkened
    probe[ends], occluded[ends] = 1, 0
    shadowed = rng.integers(0, 256, (3, n)).astype(np.uint8)
    planes = rng.integers(0, 256, (3, n)).astype(np.uint8)
    expected = np.where((probe == 1) & (occluded >= 0), shadowed, planes)
    LOOP.apply_shadows(occluded, probe, shadowed, planes)
    assert np.array_equal(planes, expected)
    assert 0 < int(((probe == 1) & (occluded >= 0)).sum()) < n  # both kinds of pixel were there


def test_buffers_of_the_wrong_sizes_are_refused():
    n, faces = 4, 2
    f32, u8 = np.zeros(3 * n, np.float32), np.zeros(3 * n, np.uint8)
    table = np.zeros(3 * faces, np.float32)
    pixels = [np.zeros(n, np.int32), np.zeros(n, np.float32), f32, np.zeros(3, np.float32)]  # int32 faces, float32 distances
    outputs = [u8, u8.copy(), np.zeros(n, np.uint8), f32.copy(), f32.copy(), np.zeros(n, np.float32)]
    args = [*pixels, table, table, table, np.zeros(faces, np.int32), True, *outputs]
    # all zeros: each pixel shows face 0 at the light itself, its direction NaN: no shadow ray
    assert LOOP.shade_lit(*args) == 0
    short = list(args)
    short[2] = np.zeros(3 * n - 1, np.float32)
    with pytest.raises(ValueError, match="sizes"):
        LOOP.shade_lit(*short)
    with pytest.raises(ValueError, match="sizes"):
        LOOP.apply_shadows(np.zeros(n - 1, np.int32), np.zeros(n, np.uint8), u8, u8.copy())
    with pytest.raises(ValueError, match="sizes"):
        LOOP.directions(np.zeros((3, n), np.float32), np.zeros(8, np.float32), np.zeros((3, n), np.float32))


@pytest.mark.skipif((shutil.which("cc") is None and shutil.which("gcc") is None) or sys.platform == "win32", reason="no C compiler to build the generic loops")
@OTHER_BUILDS
def test_the_loops_built_for_another_cpu_give_the_installed_loops_bytes(views, compiled_planes, tmp_path, monkeypatch, extra):
    generic = other_build(tmp_path, "shading", extra)
    # two views inside a house and one from outside it; the AVX2 clone's code, one inside, one outside
    for k in (1, 2) if extra else (0, 1, 2):
        _, renderer, camera = views[k]
        monkeypatch.setattr(renderer_module, "_COMPILED", generic)
        assert np.array_equal(compiled_planes(k), renderer.render_planes(camera))
        rays, rays_again = _both_loops(monkeypatch, generic, lambda: renderer._directions(camera))  # noqa: B023
        assert np.array_equal(rays.view(np.uint32), rays_again.view(np.uint32))


def _both_loops(monkeypatch, other: ModuleType, fn):
    monkeypatch.setattr(renderer_module, "_COMPILED", LOOP)
    first = fn()
    monkeypatch.setattr(renderer_module, "_COMPILED", other)
    return first, fn()
