"""Triangle meshes of the house: composite furniture per category, placed on the rooms' shell
(walls, floors, ceilings: :mod:`povagent.generate.house_shell`).

What it is for: give every object a recognizable shape built from parts (a bed has legs, a
frame, a mattress, a duvet, pillows and a headboard; a chair has legs, a seat and a back) that
fills the object's real ProcTHOR box, with per-category colours and a material per part that
the renderer shades (wood grain, fabric, metal, gloss, glowing lamp shades, tiles). What it must
not do: cast rays, shade pixels, or place objects.

Every part is built in the object's local frame (x across, y up from the floor of the object,
z towards its front), then turned by the object's yaw and moved to its box. Parts flagged as
decoration (the towel on a holder) belong to no object in the instance mask.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from povagent.generate.furnishing import DOOR_FRAME_TRIM
from povagent.generate.house_shell import add_structure
from povagent.generate.mesh_parts import (
    EMISSIVE,
    FABRIC,
    GLOSS,
    METAL,
    PLAIN,
    WOOD,
    MeshParts,
    Parts,
    pick,
    rgb,
)
from povagent.generate.scene import House, PlacedObject

# -- palettes -----------------------------------------------------------------------------------
WOODS = [rgb(c) for c in ("#8b5a2b", "#a0703c", "#6b4423", "#c49a6c", "#3e2a1c", "#d2b48c")]
FABRICS = [rgb(c) for c in ("#7a8791", "#3b4d6b", "#b8a88a", "#5f7a55", "#8a3b3b", "#4a4a4a", "#c7b9a5", "#2f5d62")]
BEDDING = [rgb(c) for c in ("#e8e4da", "#9db4c8", "#d9b8a0", "#b5c7a3", "#c9c0d8", "#f0e6c8")]
WHITE, OFFWHITE, BLACK = rgb("#f2f2f0"), rgb("#e6e1d6"), rgb("#1b1b1d")
STEEL, DARK_STEEL, GLASS = rgb("#b8bcc0"), rgb("#54585c"), rgb("#18222c")
LAMP_LIGHT = rgb("#fff1c8")


#: How far the frame reaches into the opening, past the wall's cut face.
JAMB_OVERLAP = 0.015


# -- furniture builders: (parts, w, h, d, rng, obj) ---------------------------------------------
def _bed(P: Parts, w, h, d, rng, obj):
    wood, sheet = pick(rng, WOODS), pick(rng, BEDDING)
    top = min(0.58, h * 0.62)
    hb = 0.07
    for x in (-w / 2 + 0.03, w / 2 - 0.09):
        P.box(x, 0, d / 2 - 0.1, x + 0.06, 0.1, d / 2 - 0.04, wood, WOOD)
    P.box(-w / 2, 0.1, -d / 2 + hb, w / 2, top - 0.22, d / 2, wood, WOOD)
    P.box(-w / 2 + 0.03, top - 0.22, -d / 2 + hb + 0.02, w / 2 - 0.03, top - 0.04, d / 2 - 0.03, WHITE, FABRIC)
    P.box(-w / 2 + 0.01, top - 0.3, -d / 2 + hb + 0.55, w / 2 - 0.01, top, d / 2 - 0.01, sheet, FABRIC)
    n = 2 if w > 1.2 else 1
    pw = (w - 0.2) / n
    for i in range(n):
        x0 = -w / 2 + 0.1 + i * pw
        P.box(x0 + 0.03, top - 0.04, -d / 2 + hb + 0.08, x0 + pw - 0.03, top + 0.1, -d / 2 + hb + 0.45, OFFWHITE, FABRIC)
    P.box(-w / 2, 0, -d / 2, w / 2, h, -d / 2 + hb, wood, WOOD)


def _sofa(P: Parts, w, h, d, rng, obj, seats=None):
    cloth = pick(rng, FABRICS)
    dark = tuple(c * 0.8 for c in cloth)
    arm = min(0.18, w * 0.15)
    seat_h = min(0.45, h * 0.5)
    back = min(0.22, d * 0.25)
    for x in (-w / 2 + 0.05, w / 2 - 0.1):
        for z in (-d / 2 + 0.05, d / 2 - 0.1):
            P.box(x, 0, z, x + 0.05, 0.08, z + 0.05, pick(rng, WOODS), WOOD)
    P.box(-w / 2 + arm, 0.08, -d / 2 + back, w / 2 - arm, seat_h - 0.1, d / 2 - 0.01, dark, FABRIC)
    n = seats or (3 if w > 2.0 else 2 if w > 1.3 else 1)
    cw = (w - 2 * arm) / n
    for i in range(n):
        x0 = -w / 2 + arm + i * cw
        P.box(x0 + 0.01, seat_h - 0.1, -d / 2 + back, x0 + cw - 0.01, seat_h, d / 2, cloth, FABRIC)
        P.box(x0 + 0.02, seat_h, -d / 2 + back, x0 + cw - 0.02, h - 0.08, -d / 2 + back + 0.14, cloth, FABRIC)
    P.box(-w / 2, 0.08, -d / 2, w / 2, h, -d / 2 + back, dark, FABRIC)
    for x0 in (-w / 2, w / 2 - arm):
        P.box(x0, 0.08, -d / 2 + back, x0 + arm, min(h, seat_h + 0.2), d / 2, dark, FABRIC)


def _armchair(P, w, h, d, rng, obj):
    _sofa(P, w, h, d, rng, obj, seats=1)


def _legs(P: Parts, w, d, y1, color, material, inset=0.04, t=0.045):
    for x in (-w / 2 + inset, w / 2 - inset - t):
        for z in (-d / 2 + inset, d / 2 - inset - t):
            P.box(x, 0, z, x + t, y1, z + t, color, material)


def _chair(P, w, h, d, rng, obj):
    wood = pick(rng, WOODS)
    seat = min(0.47, h * 0.5)
    _legs(P, w, d, seat - 0.04, wood, WOOD, inset=0.03)
    cushion = pick(rng, FABRICS) if rng.random() < 0.5 else wood
    P.box(-w / 2, seat - 0.04, -d / 2, w / 2, seat, d / 2, cushion, FABRIC if cushion != wood else WOOD)
    for x in (-w / 2 + 0.03, w / 2 - 0.07):
        P.box(x, seat, -d / 2 + 0.02, x + 0.04, h, -d / 2 + 0.06, wood, WOOD)
    P.box(-w / 2 + 0.03, h - 0.25, -d / 2 + 0.02, w / 2 - 0.03, h - 0.02, -d / 2 + 0.06, wood, WOOD)
    P.box(-w / 2 + 0.03, seat + 0.12, -d / 2 + 0.025, w / 2 - 0.03, seat + 0.17, -d / 2 + 0.055, wood, WOOD)


def _stool(P, w, h, d, rng, obj):
    wood = pick(rng, WOODS)
    _legs(P, w * 0.8, d * 0.8, h - 0.04, pick(rng, [wood, BLACK, STEEL]), WOOD, inset=0.02, t=0.035)
    P.cyl(0, 0, min(w, d) / 2, h - 0.05, h, pick(rng, [wood] + FABRICS[:3]), FABRIC)
    P.box(-w * 0.35, 0.22, -0.015, w * 0.35, 0.25, 0.015, wood, WOOD)


def _table(P, w, h, d, rng, obj, shelf=False, color=None):
    wood = color or pick(rng, WOODS)
    P.box(-w / 2, h - 0.045, -d / 2, w / 2, h, d / 2, wood, WOOD)
    _legs(P, w, d, h - 0.045, tuple(c * 0.85 for c in wood), WOOD, inset=0.05, t=0.06)
    P.box(-w / 2 + 0.05, h - 0.12, -d / 2 + 0.05, w / 2 - 0.05, h - 0.045, -d / 2 + 0.07, wood, WOOD)
    P.box(-w / 2 + 0.05, h - 0.12, d / 2 - 0.07, w / 2 - 0.05, h - 0.045, d / 2 - 0.05, wood, WOOD)
    if shelf:
        P.box(-w / 2 + 0.05, 0.1, -d / 2 + 0.05, w / 2 - 0.05, 0.13, d / 2 - 0.05, wood, WOOD)


def _coffee_table(P, w, h, d, rng, obj):
    _table(P, w, h, d, rng, obj, shelf=rng.random() < 0.5)


def _dining_table(P, w, h, d, rng, obj):
    _table(P, w, h, d, rng, obj)


def _cabinet(P, w, h, d, rng, obj, rows: int, body=None, cols: int = 1, top=None):
    body = body or pick(rng, WOODS + [WHITE, OFFWHITE, rgb("#5d6d7e")])
    front = tuple(min(1.0, c * 1.08) for c in body)
    knob = pick(rng, [STEEL, BLACK, rgb("#b08d57")])
    P.box(-w / 2 + 0.01, 0.0, -d / 2, w / 2 - 0.01, h - 0.03, d / 2 - 0.02, tuple(c * 0.8 for c in body), WOOD)
    P.box(-w / 2, h - 0.03, -d / 2, w / 2, h, d / 2, top or body, WOOD)
    rh = (h - 0.1) / rows
    cw = (w - 0.04) / cols
    for r in range(rows):
        for c in range(cols):
            x0, y0 = -w / 2 + 0.02 + c * cw, 0.06 + r * rh
            P.box(x0 + 0.008, y0 + 0.008, d / 2 - 0.02, x0 + cw - 0.008, y0 + rh - 0.008, d / 2 - 0.006, front, WOOD)
            kx = x0 + cw / 2
            P.box(kx - 0.05, y0 + rh * 0.7, d / 2 - 0.006, kx + 0.05, y0 + rh * 0.7 + 0.02, d / 2, knob, METAL)


def _dresser(P, w, h, d, rng, obj):
    _cabinet(P, w, h, d, rng, obj, rows=max(2, min(4, int(h / 0.22))), cols=2 if w > 1.0 else 1)


def _side_table(P, w, h, d, rng, obj):
    if rng.random() < 0.5:
        _cabinet(P, w, h, d, rng, obj, rows=2)
    else:
        _table(P, w, h, d, rng, obj, shelf=True)


def _desk(P, w, h, d, rng, obj):
    wood = pick(rng, WOODS + [WHITE])
    P.box(-w / 2, h - 0.04, -d / 2, w / 2, h, d / 2, wood, WOOD)
    pw = min(0.4, w * 0.35)
    _cabinet_like = tuple(c * 0.9 for c in wood)
    P.box(w / 2 - pw, 0, -d / 2 + 0.02, w / 2 - 0.01, h - 0.04, d / 2 - 0.03, _cabinet_like, WOOD)
    for r in range(3):
        y0 = 0.05 + r * (h - 0.1) / 3
        P.box(w / 2 - pw + 0.02, y0 + 0.01, d / 2 - 0.03, w / 2 - 0.03, y0 + (h - 0.1) / 3 - 0.01, d / 2 - 0.012, wood, WOOD)
        P.box(w / 2 - pw / 2 - 0.04, y0 + 0.12, d / 2 - 0.012, w / 2 - pw / 2 + 0.04, y0 + 0.14, d / 2, STEEL, METAL)
    P.box(-w / 2 + 0.01, 0, -d / 2 + 0.02, -w / 2 + 0.05, h - 0.04, d / 2 - 0.03, _cabinet_like, WOOD)
    P.box(-w / 2 + 0.05, h * 0.4, -d / 2 + 0.02, w / 2 - pw, h - 0.04, -d / 2 + 0.04, _cabinet_like, WOOD)


def _shelving(P, w, h, d, rng, obj):
    wood = pick(rng, WOODS + [WHITE, BLACK])
    t = 0.03
    P.box(-w / 2, 0, -d / 2, -w / 2 + t, h, d / 2, wood, WOOD)
    P.box(w / 2 - t, 0, -d / 2, w / 2, h, d / 2, wood, WOOD)
    P.box(-w / 2 + t, 0, -d / 2, w / 2 - t, h, -d / 2 + 0.015, tuple(c * 0.75 for c in wood), WOOD)
    n = max(2, int(h / 0.38))
    for i in range(n + 1):
        y = i * (h - t) / n
        P.box(-w / 2 + t, y, -d / 2 + 0.015, w / 2 - t, y + t, d / 2, wood, WOOD)
        if i == n:
            break
        x = -w / 2 + t + 0.02
        while x < w / 2 - t - 0.1:
            bw = float(rng.uniform(0.025, 0.05))
            bh = float(rng.uniform(0.16, min(0.3, (h - t) / n - 0.04)))
            if rng.random() < 0.8:
                P.box(x, y + t, -d / 2 + 0.03, x + bw, y + t + bh, d / 2 - 0.04, pick(rng, FABRICS + BEDDING[:2]), PLAIN)
            x += bw + 0.004
            if rng.random() < 0.08:
                x += 0.15


def _counter(P, w, h, d, rng, obj):
    body = pick(rng, [WHITE, OFFWHITE, rgb("#5d6d7e"), rgb("#7a5c3e"), rgb("#3f5e4a")])
    stone = pick(rng, [rgb("#d9d6cf"), rgb("#2b2b2b"), rgb("#bfb5a3"), rgb("#eeeeea")])
    P.box(-w / 2, 0, -d / 2, w / 2, 0.1, d / 2 - 0.08, BLACK, PLAIN)
    P.box(-w / 2, 0.1, -d / 2, w / 2, h - 0.04, d / 2 - 0.04, tuple(c * 0.8 for c in body), WOOD)
    P.box(-w / 2, h - 0.04, -d / 2, w / 2, h, d / 2, stone, FABRIC)
    n = max(1, int(round(w / 0.6)))
    cw = w / n
    for i in range(n):
        x0 = -w / 2 + i * cw
        P.box(x0 + 0.006, 0.11, d / 2 - 0.04, x0 + cw - 0.006, h - 0.2, d / 2 - 0.025, body, WOOD)
        P.box(x0 + 0.006, h - 0.19, d / 2 - 0.04, x0 + cw - 0.006, h - 0.05, d / 2 - 0.025, body, WOOD)
        P.box(x0 + cw / 2 - 0.06, h - 0.13, d / 2 - 0.025, x0 + cw / 2 + 0.06, h - 0.11, d / 2 - 0.01, STEEL, METAL)


def _sink(P, w, h, d, rng, obj):
    if h < 0.5:  # a kitchen sink set into the counter: only its rim and basin show
        P.box(-w / 2, h - 0.05, -d / 2, w / 2, h - 0.02, d / 2, STEEL, METAL)
        P.box(-w / 2 + 0.05, h - 0.02, -d / 2 + 0.05, w / 2 - 0.05, h - 0.015, d / 2 - 0.05, DARK_STEEL, METAL)
        P.box(-w / 2 + 0.06, h - 0.015, -d / 2 + 0.06, w / 2 - 0.06, h - 0.012, d / 2 - 0.06, rgb("#3a3d40"), METAL)
        return
    body = pick(rng, [WHITE, rgb("#6b4f3a"), rgb("#5d6d7e"), OFFWHITE])
    top = 0.85
    P.box(-w / 2 + 0.02, 0.08, -d / 2, w / 2 - 0.02, top - 0.06, d / 2 - 0.02, body, WOOD)
    P.box(-w / 2 + 0.02, 0, -d / 2, w / 2 - 0.02, 0.08, d / 2 - 0.06, BLACK, PLAIN)
    for x0 in (-w / 2 + 0.03, 0.005):
        P.box(x0, 0.1, d / 2 - 0.02, x0 + w / 2 - 0.035, top - 0.08, d / 2 - 0.005, tuple(min(1, c * 1.08) for c in body), WOOD)
    P.box(-w / 2, top - 0.06, -d / 2, w / 2, top, d / 2, WHITE, GLOSS)
    P.box(-w / 2 + 0.08, top, -d / 2 + 0.12, w / 2 - 0.08, top + 0.004, d / 2 - 0.08, rgb("#c8ccd0"), GLOSS)
    P.box(-w / 2, top, -d / 2, w / 2, h, -d / 2 + 0.03, WHITE, GLOSS)


def _faucet(P, w, h, d, rng, obj):
    col = pick(rng, [STEEL, rgb("#d4d7da"), BLACK])
    r = min(w, d) * 0.18
    P.cyl(0, -d / 2 + r + 0.01, r * 1.4, 0, 0.02, col, METAL)
    P.cyl(0, -d / 2 + r + 0.01, r, 0, h, col, METAL)
    P.box(-r, h - 2 * r, -d / 2 + 0.01, r, h, d / 2, col, METAL)
    P.box(w / 2 - 0.05, 0.02, -d / 2 + 0.01, w / 2, 0.07, -d / 2 + 0.04, col, METAL)


def _fridge(P, w, h, d, rng, obj):
    col = pick(rng, [WHITE, STEEL, rgb("#2e2e30"), rgb("#d8d2c4")])
    P.box(-w / 2, 0.03, -d / 2, w / 2, h, d / 2 - 0.04, col, METAL)
    P.box(-w / 2 + 0.05, 0, -d / 2, w / 2 - 0.05, 0.03, d / 2 - 0.08, BLACK, PLAIN)
    split = h * 0.66
    P.box(-w / 2 + 0.005, 0.03, d / 2 - 0.04, w / 2 - 0.005, split - 0.008, d / 2 - 0.02, col, METAL)
    P.box(-w / 2 + 0.005, split + 0.008, d / 2 - 0.04, w / 2 - 0.005, h - 0.005, d / 2 - 0.02, col, METAL)
    hx = w / 2 - 0.08
    P.box(hx, split - 0.55, d / 2 - 0.02, hx + 0.03, split - 0.1, d / 2, DARK_STEEL, METAL)
    P.box(hx, split + 0.08, d / 2 - 0.02, hx + 0.03, split + 0.35, d / 2, DARK_STEEL, METAL)


def _microwave(P, w, h, d, rng, obj):
    col = pick(rng, [WHITE, STEEL, BLACK, DARK_STEEL])
    P.box(-w / 2, 0.01, -d / 2, w / 2, h, d / 2 - 0.01, col, METAL)
    P.box(-w / 2 + 0.03, 0.04, d / 2 - 0.01, w / 2 * 0.3, h - 0.04, d / 2, GLASS, GLOSS)
    P.box(w / 2 * 0.38, 0.04, d / 2 - 0.01, w / 2 - 0.03, h - 0.04, d / 2, BLACK, PLAIN)
    for i in range(3):
        y = h - 0.1 - i * 0.06
        P.box(w / 2 * 0.45, y, d / 2 - 0.005, w / 2 - 0.06, y + 0.03, d / 2 + 0.0, DARK_STEEL, METAL)
    P.box(-w / 2 + 0.04, 0, -d / 2 + 0.04, w / 2 - 0.04, 0.01, d / 2 - 0.05, BLACK, PLAIN)


def _toaster(P, w, h, d, rng, obj):
    col = pick(rng, [STEEL, rgb("#c0392b"), WHITE, BLACK, rgb("#e8d8b0")])
    P.box(-w / 2, 0.01, -d / 2, w / 2, h - 0.006, d / 2, col, METAL)
    for x in (-w / 4 - 0.015, w / 4 - 0.015):
        P.box(x, h - 0.006, -d / 2 + 0.05, x + 0.03, h, d / 2 - 0.05, BLACK, PLAIN)
    P.box(w / 2 - 0.005, h * 0.5, -0.02, w / 2 + 0.0, h * 0.6, 0.02, BLACK, PLAIN)
    P.box(-w / 2 + 0.02, 0, -d / 2 + 0.02, w / 2 - 0.02, 0.01, d / 2 - 0.02, BLACK, PLAIN)


def _coffee_machine(P, w, h, d, rng, obj):
    col = pick(rng, [BLACK, STEEL, rgb("#8b1e1e"), WHITE])
    P.box(-w / 2, 0, -d / 2, w / 2, 0.05, d / 2, col, METAL)
    P.box(-w / 2, 0.05, -d / 2, w / 2, h, -d / 2 + d * 0.45, col, METAL)
    P.box(-w / 2, h - 0.1, -d / 2 + d * 0.45, w / 2, h, d / 2, col, METAL)
    P.cyl(0, d * 0.2, min(w, d) * 0.2, 0.05, h * 0.5, GLASS, GLOSS)
    P.box(-w / 2 + 0.03, h - 0.08, d / 2 - 0.005, w / 2 - 0.03, h - 0.03, d / 2, DARK_STEEL, GLOSS)


def _screen(P, w, h, d, rng, stand_h: float, frame=BLACK):
    P.box(-w * 0.2, 0, -d / 2, w * 0.2, 0.025, d / 2, frame, METAL)
    P.box(-0.03, 0.025, -0.02, 0.03, stand_h + 0.05, 0.02, frame, METAL)
    P.box(-w / 2, stand_h, -0.03, w / 2, h, 0.02, frame, METAL)
    P.box(-w / 2 + 0.02, stand_h + 0.02, 0.02, w / 2 - 0.02, h - 0.02, 0.03, GLASS, GLOSS)


def _television(P, w, h, d, rng, obj):
    _screen(P, w, h, min(d, 0.3), rng, stand_h=min(0.1, h * 0.15))


def _desktop(P, w, h, d, rng, obj):
    mw = w * 0.7
    P.box(-mw * 0.2, 0, -d / 2, mw * 0.2, 0.02, -d / 2 + 0.12, BLACK, METAL)
    P.box(-0.025, 0.02, -d / 2 + 0.04, 0.025, 0.14, -d / 2 + 0.07, BLACK, METAL)
    P.box(-mw / 2, 0.12, -d / 2 + 0.07, mw / 2, h, -d / 2 + 0.1, BLACK, METAL)
    P.box(-mw / 2 + 0.015, 0.135, -d / 2 + 0.1, mw / 2 - 0.015, h - 0.015, -d / 2 + 0.105, rgb("#24425e"), GLOSS)
    P.box(-w / 2, 0, d / 2 - 0.12, w * 0.1, 0.02, d / 2 - 0.01, DARK_STEEL, PLAIN)
    P.box(w * 0.2, 0, d / 2 - 0.1, w * 0.3, 0.02, d / 2 - 0.03, DARK_STEEL, PLAIN)


def _lamp_shade(P, r, y0, y1, rng):
    P.cyl(0, 0, r, y0, y1, pick(rng, [LAMP_LIGHT, rgb("#f6e7d2"), rgb("#fbf5e6")]), EMISSIVE, sections=16)


def _desk_lamp(P, w, h, d, rng, obj):
    col = pick(rng, [BLACK, STEEL, rgb("#b08d57"), WHITE])
    r = min(w, d) / 2
    P.cyl(0, 0, r * 0.55, 0, 0.03, col, METAL)
    P.cyl(0, 0, 0.012, 0.03, h * 0.6, col, METAL)
    _lamp_shade(P, r, h * 0.55, h, rng)


def _floor_lamp(P, w, h, d, rng, obj):
    col = pick(rng, [BLACK, STEEL, rgb("#b08d57")])
    r = min(w, d) / 2
    P.cyl(0, 0, r * 0.6, 0, 0.03, col, METAL)
    P.cyl(0, 0, 0.015, 0.03, h - 0.3, col, METAL)
    _lamp_shade(P, r, h - 0.35, h, rng)


def _garbage_can(P, w, h, d, rng, obj):
    col = pick(rng, [STEEL, BLACK, WHITE, rgb("#4d7c4a"), rgb("#7a8791")])
    P.cyl(0, 0, w / 2 * 0.92, 0, h - 0.03, col, METAL, rb=d / 2 * 0.92)
    P.cyl(0, 0, w / 2, h - 0.03, h, tuple(c * 0.7 for c in col), METAL, rb=d / 2)


def _house_plant(P, w, h, d, rng, obj):
    pot = pick(rng, [rgb("#b5651d"), WHITE, rgb("#3d3d3d"), rgb("#9c8b76")])
    green = pick(rng, [rgb("#3f7d3a"), rgb("#2e6b30"), rgb("#5a8f3e"), rgb("#4b7f52")])
    ph = h * 0.35
    r = min(w, d) / 2
    P.cyl(0, 0, r * 0.55, 0, ph, pot, PLAIN)
    P.cyl(0, 0, r * 0.5, ph - 0.02, ph, rgb("#3b2a1d"), PLAIN)
    fh = h - ph
    P.blob((0, ph + fh * 0.5, 0), (r, fh / 2, r), green, FABRIC)
    P.blob((r * 0.3, ph + fh * 0.62, -r * 0.2), (r * 0.62, fh * 0.38, r * 0.62), tuple(min(1, c * 1.2) for c in green), FABRIC)


def _safe(P, w, h, d, rng, obj):
    col = pick(rng, [rgb("#3a3f44"), rgb("#2b2b2b"), rgb("#6b6e70")])
    P.box(-w / 2, 0, -d / 2, w / 2, h, d / 2 - 0.02, col, METAL)
    P.box(-w / 2 + 0.03, 0.03, d / 2 - 0.02, w / 2 - 0.03, h - 0.03, d / 2 - 0.01, tuple(c * 1.2 for c in col), METAL)
    P.disc_z(0, h / 2, min(w, h) * 0.12, d / 2 - 0.01, d / 2, STEEL, METAL)


def _toilet(P, w, h, d, rng, obj):
    P.box(-w * 0.22, 0, -d / 2 + 0.2, w * 0.22, 0.3, d / 2 - 0.2, WHITE, GLOSS)
    P.cyl(0, d * 0.08, w / 2 - 0.02, 0.22, 0.39, WHITE, GLOSS, rb=d * 0.3)
    P.cyl(0, d * 0.08, w / 2, 0.39, 0.42, OFFWHITE, GLOSS, rb=d * 0.32)
    P.box(-w / 2, 0.38, -d / 2, w / 2, h - 0.03, -d / 2 + 0.2, WHITE, GLOSS)
    P.box(-w / 2 - 0.0, h - 0.03, -d / 2, w / 2, h, -d / 2 + 0.21, OFFWHITE, GLOSS)


def _towel(P, w, rng, drop: float):
    towel = pick(rng, BEDDING + [rgb("#7fb3d5"), rgb("#f5b7b1")])
    P.box(-w / 2 + 0.05, -drop, 0.0, w / 2 - 0.05, 0.0, 0.03, towel, FABRIC, decor=True)


def _towel_holder(P, w, h, d, rng, obj):
    P.box(-w / 2, 0, -d / 2, -w / 2 + 0.03, h, d / 2, STEEL, METAL)
    P.box(w / 2 - 0.03, 0, -d / 2, w / 2, h, d / 2, STEEL, METAL)
    P.box(-w / 2, h * 0.3, d / 2 - 0.03, w / 2, h * 0.7, d / 2, STEEL, METAL)
    if rng.random() < 0.9:
        _towel(P, w, rng, 0.45)


def _hand_towel_holder(P, w, h, d, rng, obj):
    P.box(-0.02, h - 0.04, -d / 2, 0.02, h, d / 2, STEEL, METAL)
    P.box(-w / 2, h - 0.04, d / 2 - 0.02, w / 2, h, d / 2, STEEL, METAL)
    P.box(-w / 2, h * 0.2, d / 2 - 0.02, -w / 2 + 0.015, h, d / 2, STEEL, METAL)
    P.box(w / 2 - 0.015, h * 0.2, d / 2 - 0.02, w / 2, h, d / 2, STEEL, METAL)
    towel = pick(rng, BEDDING)
    P.box(-w / 2 + 0.02, h * 0.2 - 0.12, d / 2 - 0.035, w / 2 - 0.02, h - 0.04, d / 2 - 0.02, towel, FABRIC, decor=True)


def _washer(P, w, h, d, rng, obj, door=GLASS):
    col = pick(rng, [WHITE, OFFWHITE, rgb("#cfd3d6")])
    P.box(-w / 2, 0.02, -d / 2, w / 2, h, d / 2 - 0.01, col, METAL)
    P.box(-w / 2 + 0.04, 0, -d / 2 + 0.04, w / 2 - 0.04, 0.02, d / 2 - 0.05, BLACK, PLAIN)
    P.box(-w / 2 + 0.02, h - 0.15, d / 2 - 0.01, w / 2 - 0.02, h - 0.02, d / 2, rgb("#d5d8dc"), METAL)
    P.box(w / 2 - 0.15, h - 0.12, d / 2 - 0.005, w / 2 - 0.06, h - 0.05, d / 2 + 0.0, DARK_STEEL, METAL)
    r = min(w, h) * 0.3
    P.disc_z(0, (h - 0.15) * 0.52, r, d / 2 - 0.01, d / 2, DARK_STEEL, METAL)
    P.disc_z(0, (h - 0.15) * 0.52, r * 0.78, d / 2 - 0.008, d / 2 + 0.0, door, GLOSS)


def _dryer(P, w, h, d, rng, obj):
    _washer(P, w, h, d, rng, obj, door=rgb("#5b6770"))


def _doorway(P, w, h, d, rng, obj):
    # the jambs and the head reach JAMB_OVERLAP into the opening: flush with the wall's cut
    # faces they would z-fight with them (a speckled frame) and let the baseboard ends poke out
    trim = DOOR_FRAME_TRIM + JAMB_OVERLAP
    col = pick(rng, [WHITE, OFFWHITE, rgb("#7a5230")]) if "entrance" not in obj.flags else rgb("#f4f1ea")
    P.box(-w / 2, 0, -d / 2, -w / 2 + trim, h, d / 2, col, WOOD)
    P.box(w / 2 - trim, 0, -d / 2, w / 2, h, d / 2, col, WOOD)
    P.box(-w / 2 + trim, h - trim, -d / 2, w / 2 - trim, h, d / 2, col, WOOD)
    if "entrance" in obj.flags:
        door = pick(rng, WOODS[:3] + [rgb("#2c3e50"), rgb("#7b241c")])
        P.box(-w / 2 + trim, 0, -0.02, w / 2 - trim, h - trim, 0.02, door, WOOD)
        for z in (0.02, -0.045):
            P.box(w / 2 - trim - 0.12, 1.0, z, w / 2 - trim - 0.08, 1.05, z + 0.025, STEEL, METAL)


BUILDERS: dict[str, Callable] = {
    "ArmChair": _armchair,
    "Bed": _bed,
    "Chair": _chair,
    "ClothesDryer": _dryer,
    "CoffeeMachine": _coffee_machine,
    "CoffeeTable": _coffee_table,
    "CounterTop": _counter,
    "Desk": _desk,
    "DeskLamp": _desk_lamp,
    "Desktop": _desktop,
    "DiningTable": _dining_table,
    "Doorway": _doorway,
    "Dresser": _dresser,
    "Faucet": _faucet,
    "FloorLamp": _floor_lamp,
    "Fridge": _fridge,
    "GarbageCan": _garbage_can,
    "HandTowelHolder": _hand_towel_holder,
    "HousePlant": _house_plant,
    "Microwave": _microwave,
    "Safe": _safe,
    "ShelvingUnit": _shelving,
    "SideTable": _side_table,
    "Sink": _sink,
    "Sofa": _sofa,
    "Stool": _stool,
    "Television": _television,
    "Toaster": _toaster,
    "Toilet": _toilet,
    "TowelHolder": _towel_holder,
    "WashingMachine": _washer,
}


def object_parts(obj: PlacedObject) -> Parts:
    """The parts of one object in its local frame."""
    P = Parts()
    w, h, d = obj.local_size
    BUILDERS[obj.object_type](P, w, h, d, np.random.default_rng(obj.style), obj)
    return P


def add_object(mesh: MeshParts, obj: PlacedObject, instance: int) -> None:
    """Append an object's parts, turned by its yaw and moved to its box, owned by ``instance``."""
    y = np.radians(obj.yaw)
    # local +z turns into (sin y, 0, cos y), local +x into (cos y, 0, -sin y)
    rot = np.array([[np.cos(y), 0.0, np.sin(y)], [0.0, 1.0, 0.0], [-np.sin(y), 0.0, np.cos(y)]])
    base = np.array([obj.center[0], obj.bottom, obj.center[2]])
    for verts, faces, color, material, decor in object_parts(obj).items:
        mesh.add(verts @ rot.T + base, faces, color, material, 0 if decor else instance, obj.room_id)


def house_mesh(house: House, rng: np.random.Generator) -> MeshParts:
    """The whole house: structure (owner 0), then object k with owner k + 1."""
    mesh = MeshParts()
    add_structure(mesh, house.plan, rng)
    for k, obj in enumerate(house.objects):
        add_object(mesh, obj, k + 1)
    return mesh
