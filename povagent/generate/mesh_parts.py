"""The primitives meshes are built from: a growing set of coloured triangles (:class:`MeshParts`),
one object's parts in its local frame (:class:`Parts`), boxes, prisms and squashed spheres,
the materials the renderer shades, and the draw of a colour from a palette.

What it must not do: know any furniture category (that is :mod:`povagent.generate.meshes`) or
a room's walls and floors (:mod:`povagent.generate.house_shell`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh.creation

# Materials the renderer knows how to shade.
PLAIN, WOOD, FABRIC, METAL, GLOSS, EMISSIVE, FLOOR_WOOD, FLOOR_TILE, WALL, CEILING = range(10)


def rgb(hex_color: str) -> tuple[float, float, float]:
    """An ``#rrggbb`` colour as floats in [0, 1]."""
    h = hex_color.lstrip("#")
    return (int(h[0:2], 16) / 255.0, int(h[2:4], 16) / 255.0, int(h[4:6], 16) / 255.0)


def pick(rng: np.random.Generator, palette):
    """One colour of ``palette``, drawn with the house's generator (one draw per call)."""
    return palette[int(rng.integers(len(palette)))]


@dataclass
class MeshParts:
    """Triangles with a colour, a material, an owner and a room per face."""

    vertices: list[np.ndarray] = field(default_factory=list)
    faces: list[np.ndarray] = field(default_factory=list)
    colors: list[np.ndarray] = field(default_factory=list)
    materials: list[np.ndarray] = field(default_factory=list)
    owners: list[np.ndarray] = field(default_factory=list)
    rooms: list[np.ndarray] = field(default_factory=list)
    closed: list[np.ndarray] = field(default_factory=list)
    count: int = 0

    def add(self, vertices: np.ndarray, faces: np.ndarray, color, material: int, owner: int, room: int, closed: bool = True) -> None:
        """Append a triangle set; ``owner`` is the instance id (0: structure or decoration),
        ``room`` the room whose light falls on it; ``closed``: the set bounds a solid, its
        triangles turned outward (seen from outside only), as every box, prism and sphere is;
        a floor or a ceiling is a lone quad, seen from either side."""
        self.vertices.append(np.asarray(vertices, dtype=float))
        self.faces.append(np.asarray(faces, dtype=np.int64) + self.count)
        n = len(faces)
        self.colors.append(np.tile(np.asarray(color, dtype=np.float32), (n, 1)))
        self.materials.append(np.full(n, material, dtype=np.int8))
        self.owners.append(np.full(n, owner, dtype=np.int32))
        self.rooms.append(np.full(n, room, dtype=np.int32))
        self.closed.append(np.full(n, closed, dtype=bool))
        self.count += len(vertices)

    def closed_faces(self) -> np.ndarray:
        """Per face, whether it bounds a closed solid (see :meth:`add`)."""
        return np.concatenate(self.closed)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(vertices, faces, face colours, materials, owners, rooms) as flat arrays."""
        return (
            np.concatenate(self.vertices),
            np.concatenate(self.faces),
            np.concatenate(self.colors),
            np.concatenate(self.materials),
            np.concatenate(self.owners),
            np.concatenate(self.rooms),
        )


def box_mesh(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """The axis-aligned box [lo, hi]: 8 vertices and 12 outward-facing triangles."""
    box = trimesh.creation.box(bounds=np.array([lo, hi], dtype=float))
    return np.asarray(box.vertices), np.asarray(box.faces)


def _cylinder(center, radius_a: float, radius_b: float, y0: float, y1: float, axis: str = "y", sections: int = 14):
    """A closed prism approximating a cylinder (elliptic when the radii differ), its axis along
    y (from ``y0`` to ``y1``) or, with ``axis="z"``, along z (``y0``/``y1`` are then z extents)."""
    prism = trimesh.creation.cylinder(radius=1.0, height=y1 - y0, sections=sections)
    verts = np.asarray(prism.vertices) * (radius_a, radius_b, 1.0)  # trimesh's axis is z
    verts[:, 2] += (y0 + y1) / 2.0
    faces = np.asarray(prism.faces)
    if axis == "y":
        # our y is trimesh's z: swapping two axes mirrors the mesh, so the faces turn to stay outward
        verts, faces = verts[:, [0, 2, 1]], faces[:, ::-1]
    return verts + np.asarray(center, dtype=float), faces


def _blob(center, radii, subdivisions: int = 1):
    """A squashed icosphere (foliage, cushions seen from far)."""
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return np.asarray(sphere.vertices) * np.asarray(radii) + np.asarray(center), np.asarray(sphere.faces)


class Parts:
    """Collects one object's parts in its local frame."""

    def __init__(self) -> None:
        self.items: list[tuple[np.ndarray, np.ndarray, tuple, int, bool]] = []

    def box(self, x0, y0, z0, x1, y1, z1, color, material=PLAIN, decor=False) -> None:
        """An axis-aligned box part."""
        self.items.append((*box_mesh((x0, y0, z0), (x1, y1, z1)), color, material, decor))

    def cyl(self, x, z, r, y0, y1, color, material=PLAIN, rb=None, sections=14) -> None:
        """A vertical cylinder part centred at (x, z)."""
        v, f = _cylinder((x, 0, z), r, r if rb is None else rb, y0, y1, "y", sections)
        self.items.append((v, f, color, material, False))

    def disc_z(self, x, y, r, z0, z1, color, material=PLAIN) -> None:
        """A cylinder whose axis runs front to back (round doors, dials)."""
        v, f = _cylinder((x, y, 0), r, r, z0, z1, "z", 16)
        self.items.append((v, f, color, material, False))

    def blob(self, center, radii, color, material=FABRIC) -> None:
        """A squashed sphere part."""
        v, f = _blob(center, radii)
        self.items.append((v, f, color, material, False))
