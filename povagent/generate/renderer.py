"""CPU ray-cast renderer: RGB, depth and instance mask of a house from an AI2-THOR camera.

What it is for: render the exploration frames and observer views (512x512, vertical fov 100)
with one primary ray per pixel through embree (``embreex``, the engine behind trimesh's
``ray_pyembree``, called directly for hit distances and occlusion queries), then shade every
pixel: a point light under each room's ceiling with hard shadows (a second
embree pass), a camera fill light, highlights on metal and gloss, procedural textures (wood
grain, planks, tiles, fabric) and glowing lamp shades. The depth map is the optical-axis depth
AI2-THOR reports, so ``Camera.point_at_depth`` inverts it. Which face a pixel shows and how far
it is are decided from embree's hits by :mod:`povagent.generate.visible_face`, the same on every
CPU, and the shading uses IEEE arithmetic only, so a frame is the same bytes on every machine
(``docs/explanation/reproducibility.md``). What it must not do: decide where cameras go or what
is visible (exploration and pairs read the mask).

Why embree: on a house of ~3-5k triangles it casts a 512x512 frame's primary rays in about
30 ms of CPU and the occlusion-only shadow rays in about 15 ms (in its fast, not robust, mode),
leaving ~30 ms for numpy shading: ~0.07 s a frame in all (``benchmarks/bench_generate.py``
measures it). embreex casts one ray per Embree call whatever the batch, so the primary pass
hands it the whole frame at once and the shadow pass blocks of 64k rays (as fast; 8x8 tiles or
8k-ray chunks cost ~20% more). The shading works block by block (``SHADE_BLOCK`` pixels, so its
arrays stay in the CPU's caches) on float32 arrays of shape (3, n), one contiguous row per
coordinate (numpy runs several times faster along a row than down the columns of an (n, 3)
array), changed in place where the order of operations allows; embree reads the rays through
their (n, 3) views. Where the install built it, the compiled loop ``shading.c`` does the same
operations pixel by pixel over the whole frame instead (its shadow rays in one batch: Embree's
answer for a ray does not depend on the others), for the same bytes in about a third of the
CPU; this numpy code is its reference and the path taken without it. trimesh's
pure-numpy engine needs ``rtree`` for its triangle candidates (not installed here); a z-buffer
rasterizer could match embree on primary visibility but would still need a ray caster for the
shadows, so one engine does both.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from povagent.errors import PovagentError

try:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh
except ImportError as _exc:  # embreex ships wheels for x86-64 only
    raise PovagentError(
        "the dataset renderer needs embreex (Embree ray tracing), which has wheels for x86-64 only: "
        "`pip install embreex` where it is available, or generate datasets on an x86-64 machine "
        f"({_exc})"
    ) from _exc

from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.floorplan import WALL_HEIGHT
from povagent.generate.mesh_parts import (
    CEILING,
    EMISSIVE,
    FABRIC,
    FLOOR_TILE,
    FLOOR_WOOD,
    GLOSS,
    METAL,
    WALL,
    WOOD,
    MeshParts,
)
from povagent.generate.scene import House
from povagent.generate.thread_buffers import kept_for
from povagent.generate.visible_face import VisibleFaces
from povagent.geometry.camera import Camera

BACKGROUND = np.array([0.55, 0.6, 0.65], dtype=np.float32)
#: Pixels shaded at a time. The shading makes dozens of passes over float32 arrays: over a
#: whole 512x512 frame each pass streams megabytes from memory, over 64k pixels the arrays
#: stay in the CPU's caches (the frame's shading and shadow rays then cost ~0.75x the CPU;
#: embree casts 64k shadow rays per call as fast as a whole frame's). Every pixel is shaded
#: on its own, so the values do not depend on the block size.
SHADE_BLOCK = 65536
#: A face code's bits (``Renderer._face_codes``): its material, then its texture's axes.
_MATERIAL_BITS, _A_IS_Z, _B_IS_Z = 0x0F, 0x10, 0x20
#: The compiled shading (``shading.c``: the rays, then every pixel's shading in one loop before
#: the shadow pass and one after it), or ``None``: the numpy passes below, the same bytes.
_LOOP = "_shading"
_COMPILED = compiled_loop(_LOOP)
_THREAD = threading.local()


@dataclass(frozen=True)
class Frame:
    """One rendered view: ``rgb`` (H, W, 3) uint8, ``depth`` (H, W) float32 metres along the
    optical axis (inf where no surface), ``instance`` (H, W) uint16: 0 for walls, floors,
    ceilings and decoration, k + 1 for ``house.objects[k]``."""

    camera: Camera
    rgb: np.ndarray
    depth: np.ndarray
    instance: np.ndarray

    def pixel_counts(self) -> dict[int, int]:
        """Pixels per object index (``house.objects`` index), for objects that show at all."""
        counts = np.bincount(self.instance.ravel().astype(np.int64))
        return {k - 1: int(n) for k, n in enumerate(counts) if k > 0 and n > 0}


def _embree_scene(vertices: np.ndarray, faces: np.ndarray) -> rtcore_scene.EmbreeScene:
    """An embree scene of the triangles (float32: millimetre-exact over a house).

    Not embree's robust mode (embreex turns it on by default): its slower arithmetic made
    ~20% of the ray cost, and over 30 frames of a house the fast mode changed no pixel's
    object and no hit distance by 1 mm; only a tie between two coincident faces of the same
    object (a wall and its trim) may go the other way.
    """
    scene = rtcore_scene.EmbreeScene(robust=False)
    TriangleMesh(scene=scene, vertices=vertices.astype(np.float32), indices=faces.astype(np.int32))
    return scene


_TWO_PI = 2.0 * np.pi
_SINE_TERMS = tuple((-1.0) ** k / np.prod(np.arange(1.0, 2 * k + 2)) for k in range(1, 9))  # -1/3!, 1/5!, ... -1/17!


def _sin(x: np.ndarray) -> np.ndarray:
    """``sin(x)`` as an array of ``x``'s dtype, the same bits on every CPU.

    numpy's own ``sin`` runs kernels chosen for the CPU (its float32 loop differs between
    x86-64-v2 and v3 machines in the last bit, which the texture hash multiplies by 43758):
    here the argument is reduced by 2 pi and folded into [-pi/2, pi/2] in float64, then the
    Taylor series to x^17 (error under 1e-12) is summed with IEEE products and sums only.
    """
    r = np.asarray(x, dtype=np.float64)
    r = r - np.rint(r * (1.0 / _TWO_PI)) * _TWO_PI
    r = np.where(r > np.pi / 2, np.pi - r, r)
    r = np.where(r < -np.pi / 2, -np.pi - r, r)
    r2 = r * r
    total = np.full_like(r, _SINE_TERMS[-1])
    for term in _SINE_TERMS[-2::-1]:
        total *= r2
        total += term
    total *= r2
    total *= r
    total += r
    return total.astype(np.asarray(x).dtype, copy=False)


def _hash2(a: np.ndarray, b: np.ndarray | float) -> np.ndarray:
    """A cheap deterministic pseudo-random value in [0, 1) per integer cell (a, b)."""
    v = a * 12.9898  # in place from here: the same operations in the same order
    v += b * 78.233
    v = _sin(v)
    v *= 43758.5453
    v -= np.floor(v)
    return v


def _power_40(x: np.ndarray) -> np.ndarray:
    """``x ** 40`` by squaring (numpy's ``power`` differs between CPUs in the last bit)."""
    x8 = x * x
    x8 *= x8
    x8 *= x8  # x^8
    x32 = x8 * x8
    x32 *= x32  # x^32
    x32 *= x8
    return x32


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of two (3, N) arrays: x, y, z summed in that order."""
    out = a[0] * b[0]
    term = a[1] * b[1]  # one temporary for both terms
    out += term
    out += np.multiply(a[2], b[2], out=term)
    return out


class Renderer:
    """Renders one house; build it once per house and call :meth:`render` per camera."""

    def __init__(self, house: House, mesh: MeshParts, shadows: bool = True) -> None:
        vertices, faces, colors, materials, owners, rooms = mesh.arrays()
        self.house = house
        self.shadows = shadows
        self.face_count = len(faces)
        self._scene = _embree_scene(vertices, faces)
        # lamp shades glow and let their light through: the shadow scene leaves them out
        opaque = materials != EMISSIVE
        self._shadow_scene = _embree_scene(vertices, faces[opaque])
        # faces that shade alike (colour, material, object, room) share a look: between two
        # coplanar faces of one look it does not matter which one embree reports
        look_rows = np.column_stack([np.asarray(colors, dtype=np.float32).view(np.int32), materials, owners, rooms]).astype(np.int64)
        looks = np.unique(look_rows, axis=0, return_inverse=True)[1].ravel()
        closed = mesh.closed_faces()
        self._visible = VisibleFaces.build(vertices, faces, looks, closed)
        # what an instance mask and a probe ray need: only which object a ray meets
        self._objects = VisibleFaces.build(vertices, faces, owners.astype(np.int64), closed, by_look=True)
        normals = self._visible.face_normals  # each face's coplanar group's normal
        lights = np.array([[r.rect.center[0], WALL_HEIGHT - 0.35, r.rect.center[1]] for r in house.plan.rooms])
        # per face, gathered per frame (each its own contiguous (3, F) array, so a gather gives
        # (3, N) rows that numpy's passes run over at full speed): normal, colour, its room's light
        self._normals = np.ascontiguousarray(normals.T, dtype=np.float32)
        self._colors = np.ascontiguousarray(colors.T, dtype=np.float32)
        self._lights = np.ascontiguousarray(lights[rooms].T, dtype=np.float32)
        self._materials = materials
        # one byte per face, gathered once per pixel: the material (low bits) and the texture's
        # in-plane axes (a is z on faces turned to x, b is z on floors and ceilings), worked out
        # once per face rather than per pixel (the same values: a normal turned to the viewer
        # keeps its absolute values)
        ax = np.abs(self._normals)
        up = ax[1] >= np.maximum(ax[0], ax[2])
        self._face_codes = materials.astype(np.uint8)
        self._face_codes[(ax[0] >= ax[2]) & ~up] |= _A_IS_Z
        self._face_codes[up] |= _B_IS_Z
        self._face_codes_32 = self._face_codes.astype(np.int32)  # the compiled shading gathers them in vectors
        self._owners = owners.astype(np.uint16)
        self._grids: dict[tuple[int, int, float], np.ndarray] = {}
        # each object's own triangles, for its unoccluded silhouette (scenes built on demand)
        self._vertices, self._object_faces = vertices, faces
        self._object_scenes: dict[int, rtcore_scene.EmbreeScene | None] = {}

    def _directions(self, camera: Camera) -> np.ndarray:
        """Unit world rays through the pixel centres, float32 (3, N): one row per coordinate
        (``Camera.ray``, precomputed). Embree reads them through the (N, 3) view ``.T``.

        The camera-space directions depend only on the image size and fov, so they are built
        once; turning them by the camera's axes is one small matrix product per frame.
        """
        key = (camera.width, camera.height, camera.fov)
        if key not in self._grids:
            u, v = np.meshgrid(np.arange(camera.width) + 0.5, np.arange(camera.height) + 0.5)
            pixels = np.stack([u.ravel(), v.ravel()], axis=1)
            at_origin = Camera((0.0, 0.0, 0.0), 0.0, 0.0, camera.fov, camera.width, camera.height)
            # with yaw 0 and horizon 0 the axes are the identity: world rays are camera rays
            self._grids[key] = np.ascontiguousarray(at_origin.ray(pixels).T, dtype=np.float32)
        g, ax = self._grids[key], camera.axes().astype(np.float32)
        if _COMPILED is not None:
            out = np.empty_like(g)
            _COMPILED.directions(g, ax, out)  # the same sums, in one pass per row
            return out
        # row k = sum_j g[j] * ax[j, k], summed in j order, on whole contiguous rows: several
        # times faster than an einsum over (N, 3), with the same sums (``g.T @ ax`` would hand
        # the product to BLAS, whose threads cost more than they save and may round otherwise)
        out, term = np.empty_like(g), np.empty_like(g[0])
        for k in range(3):
            row = out[k]
            np.multiply(g[0], ax[0, k], out=row)
            row += np.multiply(g[1], ax[1, k], out=term)
            row += np.multiply(g[2], ax[2, k], out=term)
        return out

    def cast(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A triangle of the object each (unit) ray, (N, 3) arrays, meets first and the float64
        distance to it (-1 and inf: no hit), the same on every CPU (:class:`VisibleFaces`)."""
        # float32 views are read as they are (embree's wrapper takes any strides): no copies
        o32, d32 = np.asarray(origins, dtype=np.float32), np.asarray(directions, dtype=np.float32)
        # only the triangle (output=0): the distance is decided below, not embree's
        tri = self._scene.run(o32, d32, output=0)
        return self._objects.decide(tri.astype(np.int64), o32.T, d32.T)

    def first_hit(self, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Instance id (0: structure or nothing) and distance of each ray's first hit."""
        tri, t = self.cast(origins, directions)
        return np.where(tri >= 0, self._owners[np.where(tri >= 0, tri, 0)], 0), t

    def render(self, camera: Camera) -> Frame:
        """Render RGB, depth and instance mask for ``camera``."""
        W, H = camera.width, camera.height
        tri, t, planes = self._cast_and_shade(camera)
        hit = tri >= 0
        # optical-axis depth: the ray length (float32) times the cosine to the forward axis (= zc)
        depth = t * self._grids[(W, H, camera.fov)][2]  # inf where nothing was hit
        if hit.all():  # the usual case indoors
            instance = self._owners[tri]
        else:
            instance = self._owners[np.where(hit, tri, 0)]
            instance[~hit] = 0
        rgb = np.empty((H, W, 3), dtype=np.uint8)
        rgb.reshape(-1, 3).T[...] = planes  # interleaved in one pass
        return Frame(camera, rgb, depth.reshape(H, W), instance.reshape(H, W))

    def render_planes(self, camera: Camera) -> np.ndarray:
        """Only the colours of ``camera``'s view, uint8 (3, H * W): one contiguous plane per
        channel, the same values as :meth:`render`'s ``rgb``.

        For a view that is only encoded (the active mode's): no depth, no instance mask, and
        no interleaving in numpy (Pillow merges the planes into its own pixel layout at once).
        """
        return self._cast_and_shade(camera)[2]

    def _cast_and_shade(self, camera: Camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The primary cast's (int32 triangle, float32 distance) per pixel and the shaded colour planes."""
        d, origin, tri, t = self._seen(camera)
        assert t is not None
        if _COMPILED is not None:
            return tri, t, self._shade_compiled(_COMPILED, tri, t, d, origin)
        planes = np.empty((3, len(tri)), dtype=np.uint8)
        for start in range(0, len(tri), SHADE_BLOCK):
            block = slice(start, start + SHADE_BLOCK)
            rgb = self._shade_block(tri[block], t[block], d[:, block], origin)
            np.copyto(planes[:, block], rgb, casting="unsafe")  # as ``astype(np.uint8)``
        return tri, t, planes

    def _seen(self, camera: Camera, objects_only: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """The camera's rays (3, N), its origin, and per pixel the face seen (int32) and the
        distance to it (float32, the float64 decided rounded), decided alike on every CPU
        (:meth:`VisibleFaces.decide_image`; with ``objects_only``, only the object a pixel shows
        is decided so)."""
        d = self._directions(camera)
        origin = np.asarray(camera.position, dtype=np.float32)
        # a broadcast view: embree reads the one origin for every ray, no (N, 3) copy; only the
        # triangle is asked for (output=0: no distances, barycentrics or normals filled in, about
        # 1.3 ms a frame less), the distance is decided by ``decide_image``
        primitive = self._scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=0)
        visible = self._objects if objects_only else self._visible
        # (an instance mask wants no distances: then they are left uncomputed, None)
        # (embree's int32 triangles read as they are; int32 faces and float32 distances back)
        tri, t = visible.decide_image(primitive, origin, d, camera.height, camera.width, want_distance=not objects_only, skip=True, narrow=True)
        return d, origin, tri, t

    def _shade_compiled(self, loop: ModuleType, tri: np.ndarray, t: np.ndarray, d: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """The colour planes (3, N) uint8 of :meth:`_shade_block`, by the compiled ``loop``: every
        pixel's colours lit and shadowed, then Embree's shadow pass, then the shadowed pixels."""
        n = len(tri)
        planes = np.empty((3, n), dtype=np.uint8)
        s = _scratch(n)
        faces = (self._normals, self._colors, self._lights, self._face_codes_32)
        pixels = (np.ascontiguousarray(tri, dtype=np.int32), np.ascontiguousarray(t, dtype=np.float32), d, origin)
        rays = loop.shade_lit(*pixels, *faces, self.shadows, planes, s.shadowed, s.probe, s.start, s.toward, s.length)
        if rays:  # one batch: Embree's answer for a ray does not depend on the others
            occluded = self._shadow_scene.run(s.start, s.toward, dists=s.length, query="OCCLUDED")
            loop.apply_shadows(np.ascontiguousarray(occluded, dtype=np.int32), s.probe, s.shadowed, planes)
        return planes

    def _shade_block(self, tri: np.ndarray, t: np.ndarray, d: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """Colours (3, n) of a block of pixels, scaled to 0.5-255 (truncated to bytes after)."""
        # shading works on one contiguous row per coordinate, (3, n): numpy's passes over
        # whole rows run several times faster than over the columns of an (n, 3) array
        if tri.min() >= 0:  # the usual case indoors: every ray hits, no gathers needed
            p = d * t
            p += origin[:, None]
            rgb = self._shade(tri, d, p)
        else:
            rgb = np.empty((3, len(tri)), dtype=np.float32)
            rgb[:] = BACKGROUND[:, None]
            idx = np.flatnonzero(tri >= 0)
            if len(idx):
                dh = d[:, idx]
                p = dh * t[idx]
                p += origin[:, None]
                rgb[:, idx] = self._shade(tri[idx], dh, p)
        rgb *= 255.0
        rgb += 0.5
        np.clip(rgb, 0, 255, out=rgb)
        return rgb

    def instance_mask(self, camera: Camera) -> np.ndarray:
        """Only the instance mask (no shading): a cheap probe of what a camera would see."""
        _, _, tri, _ = self._seen(camera, objects_only=True)
        owners = np.where(tri >= 0, self._owners[np.where(tri >= 0, tri, 0)], 0)
        return owners.reshape(camera.height, camera.width)

    def silhouette(self, camera: Camera, index: int) -> np.ndarray:
        """Where ``house.objects[index]`` would show if nothing else were in the house: a
        (H, W) bool mask, the object's unoccluded projected area within the frame.

        Compared with the instance mask it says how much of an object is hidden (by a wall, a
        door jamb, other furniture), whatever the object's shape.
        """
        if index not in self._object_scenes:
            mine = self._object_faces[self._owners == index + 1]
            self._object_scenes[index] = _embree_scene(self._vertices, mine) if len(mine) else None
        scene = self._object_scenes[index]
        if scene is None:
            return np.zeros((camera.height, camera.width), dtype=bool)
        dirs = self._directions(camera).T
        origins = np.broadcast_to(np.asarray(camera.position, dtype=np.float32), dirs.shape)
        tri = scene.run(origins, dirs)
        return (np.asarray(tri) >= 0).reshape(camera.height, camera.width)

    # -- shading ----------------------------------------------------------------------------
    def _shade(self, tri: np.ndarray, d: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Colours (3, N) of the hits ``p`` (3, N) of the unit rays ``d`` (3, N) on faces ``tri``."""
        # np.take makes fresh arrays, changed in place below
        n, base, L = (np.take(a, tri, axis=1) for a in (self._normals, self._colors, self._lights))
        facing = _dot(n, d)
        np.negative(n, out=n, where=facing > 0)  # face the viewer
        fill = np.abs(facing, out=facing)
        code = np.take(self._face_codes, tri)
        mat = code & _MATERIAL_BITS
        base *= self._texture(code, mat, p)

        L -= p  # the light's position, turned into the unit vector to it in place
        dist2 = _dot(L, L)
        dist = np.sqrt(dist2)
        L /= dist
        lambert = _dot(n, L)
        dist2 *= 0.06
        dist2 += 1.0
        diffuse = np.maximum(lambert, 0.0)
        diffuse /= dist2
        if self.shadows:
            # only points the light can reach at all need a shadow ray
            probe = (lambert > 0.02) & (mat != EMISSIVE) & (mat != CEILING)
            if probe.any():
                # every pixel's ray in one batch, no gathers: a pixel that needs no shadow ray
                # gets a negative length, which embree skips at once; embree reads the (3, N)
                # rows through their transposed (N, 3) views
                start = n * np.float32(2e-3)
                start += p
                length = dist - np.float32(0.05)
                length[~probe] = -1.0
                blocked = self._shadow_scene.run(start.T, L.T, dists=length, query="OCCLUDED") >= 0
                blocked &= probe
                np.multiply(diffuse, np.float32(0.15), out=diffuse, where=blocked)
        # 0.30 + 0.85 * diffuse + 0.22 * fill, in place (the same operations in the same order)
        shade = diffuse
        shade *= 0.85
        shade += 0.30
        shade += 0.22 * fill
        ceiling = mat == CEILING
        shade[ceiling] = 0.62 + 0.25 * fill[ceiling]
        glow = mat == EMISSIVE
        shade[glow] = 0.95 + 0.05 * fill[glow]
        color = base
        color *= shade

        shiny = np.flatnonzero((mat == METAL) | (mat == GLOSS))
        if len(shiny):
            # np.take and a gather per row: the same values as fancy indexing, several times faster
            half = np.take(L, shiny, axis=1)
            half -= np.take(d, shiny, axis=1)
            half /= np.sqrt(_dot(half, half))
            spec = np.clip(_dot(np.take(n, shiny, axis=1), half), 0, 1)
            spec = _power_40(spec)
            spec *= 0.45
            for row in color:
                row[shiny] = np.take(row, shiny) + spec
        return color

    def _texture(self, code: np.ndarray, mat: np.ndarray, p: np.ndarray) -> np.ndarray:
        """A brightness factor per pixel from the material's procedural pattern (``code``:
        the pixels' face codes, ``mat``: their materials)."""
        out = np.ones(len(mat), dtype=np.float32)
        px, py, pz = p
        # in-plane coordinates (a, b) of each hit, from its face's dominant normal axis
        a = np.where(code & _A_IS_Z, pz, px)
        b = np.where(code & _B_IS_Z, pz, py)

        m = mat == WOOD
        if m.any():
            am = a[m]
            out[m] = 0.94 + 0.06 * _sin(am * 30.0 + 2.0 * _sin(b[m] * 5.0 + am * 2.0))
        m = mat == FABRIC
        if m.any():
            out[m] = 0.93 + 0.07 * _hash2(np.floor(a[m] * 160), np.floor(b[m] * 160))
        m = mat == WALL
        if m.any():
            out[m] = 0.97 + 0.03 * _hash2(np.floor(a[m] * 90), np.floor(b[m] * 90))
        m = mat == FLOOR_WOOD
        if m.any():
            x, z = px[m], pz[m]
            across = x / 0.18
            plank = np.floor(across)
            tint = 0.84 + 0.22 * _hash2(plank, plank * 0.37 + 1.0)
            shift = _hash2(plank, 7.0) * 1.4
            along = (z + shift) / 1.4
            # v - floor(v) is v % 1.0 exactly (the same value, rounded once) at a fraction of the cost
            seam = (across - plank < 0.05) | (along - np.floor(along) < 0.012)
            grain = 0.97 + 0.03 * _sin(z * 25.0 + 1.5 * _sin(x * 20.0 + plank))
            out[m] = np.where(seam, 0.55, tint * grain)
        m = mat == FLOOR_TILE
        if m.any():
            x, z = px[m] / 0.4, pz[m] / 0.4
            cx, cz = np.floor(x), np.floor(z)
            grout = (x - cx < 0.035) | (z - cz < 0.035)
            out[m] = np.where(grout, 0.72, 0.95 + 0.08 * _hash2(cx, cz))
        return out


class _Scratch:
    """The compiled shading's per-frame buffers for frames of ``n`` pixels, reused frame after
    frame (fresh frame-sized arrays cost their page faults every time): the shadowed colours,
    which pixels cast a shadow ray, and the rays."""

    def __init__(self, n: int) -> None:
        self.shadowed = np.empty((3, n), dtype=np.uint8)
        self.probe = np.empty(n, dtype=np.uint8)
        self.start, self.toward = np.empty((n, 3), dtype=np.float32), np.empty((n, 3), dtype=np.float32)
        self.length = np.empty(n, dtype=np.float32)


def _scratch(n: int) -> _Scratch:
    """This thread's buffers for frames of ``n`` pixels (the last size kept)."""
    return kept_for(_THREAD, "scratch", n, lambda: _Scratch(n))
