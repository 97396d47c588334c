"""Small synthetic buildings with known geometry, for visibility tests and
benchmarks: walls, door gaps, free space and the 3D model segments an edge
extractor would produce (floor and ceiling junctions along the wall outlines,
vertical corners, door lintels). Metres, z up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import box

from mapkit.shapes import polygon_parts
from linemap.lmap import SegmentKind
from mapkit.tolerances import CORNER_DEG


@dataclass
class SyntheticScene:
    """``segments`` (N, 2, 3), ``kinds`` (N,) uint8, ``walls`` and
    ``free_space`` shapely geometries, ``wall_height`` metres."""

    segments: np.ndarray
    kinds: np.ndarray
    walls: object
    free_space: object
    wall_height: float


def _wall(x0, y0, x1, y1, t):
    """Axis-aligned wall of thickness ``t`` centred on the line (x0,y0)-(x1,y1)."""
    return box(min(x0, x1) - t / 2, min(y0, y1) - t / 2, max(x0, x1) + t / 2, max(y0, y1) + t / 2)


def scene_from_walls(walls, interior, doors, wall_height=2.5, door_head=2.1, robot_radius=0.2) -> SyntheticScene:
    """Segments along the outline of ``interior - walls``: floor (z=0) and
    ceiling (z=wall_height) junctions on every edge, a vertical at every
    corner turning more than ``CORNER_DEG``, and for every door gap polygon
    in ``doors`` the two lintels (z=door_head) across it."""
    # Drop collinear outline vertices: one straight wall, one segment.
    open_space = shapely.simplify(interior.difference(walls), 1e-9)
    segs, kinds = [], []
    for poly in polygon_parts(open_space):
        for ring in [poly.exterior, *poly.interiors]:
            pts = np.asarray(ring.coords)[:-1, :2]
            nxt = np.roll(pts, -1, axis=0)
            prv = np.roll(pts, 1, axis=0)
            for a, b in zip(pts, nxt):
                segs.append([[*a, 0.0], [*b, 0.0]])
                kinds.append(SegmentKind.FLOOR)
                segs.append([[*a, wall_height], [*b, wall_height]])
                kinds.append(SegmentKind.CEILING)
            d0, d1 = pts - prv, nxt - pts
            turn = np.degrees(np.abs(np.arctan2(d0[:, 0] * d1[:, 1] - d0[:, 1] * d1[:, 0], (d0 * d1).sum(1))))
            for p in pts[turn > CORNER_DEG]:
                segs.append([[*p, 0.0], [*p, wall_height]])
                kinds.append(SegmentKind.VERTICAL)
    for gap in doors:
        x0, y0, x1, y1 = gap.bounds
        if x1 - x0 > y1 - y0:  # gap across a horizontal wall: lintels along x
            for y in (y0, y1):
                segs.append([[x0, y, door_head], [x1, y, door_head]])
                kinds.append(SegmentKind.LINTEL)
        else:
            for x in (x0, x1):
                segs.append([[x, y0, door_head], [x, y1, door_head]])
                kinds.append(SegmentKind.LINTEL)
    free = shapely.buffer(open_space, -robot_radius, join_style="mitre")
    return SyntheticScene(np.array(segs, dtype=float), np.array(kinds, dtype=np.uint8), walls, free, wall_height)


def apartment() -> SyntheticScene:
    """An 11 x 8.5 m flat: five rooms, five doors, a free-standing column."""
    t_out, t_in = 0.2, 0.1
    outer = box(-t_out, -t_out, 11 + t_out, 8.5 + t_out).difference(box(0, 0, 11, 8.5))
    inner = [
        _wall(4.5, 0, 4.5, 8.5, t_in),
        _wall(4.5, 4.0, 11, 4.0, t_in),
        _wall(8.0, 4.0, 8.0, 8.5, t_in),
        _wall(0, 5.5, 4.5, 5.5, t_in),
    ]
    doors = [
        box(4.5 - t_in / 2, 2.0, 4.5 + t_in / 2, 2.9),
        box(4.5 - t_in / 2, 6.0, 4.5 + t_in / 2, 6.9),
        box(6.0, 4.0 - t_in / 2, 6.9, 4.0 + t_in / 2),
        box(8.0 - t_in / 2, 6.5, 8.0 + t_in / 2, 7.4),
        box(1.5, 5.5 - t_in / 2, 2.4, 5.5 + t_in / 2),
    ]
    column = box(7.3, 1.8, 7.7, 2.2)
    walls = shapely.union_all([outer, *inner, column]).difference(shapely.union_all(doors))
    return scene_from_walls(walls, box(0, 0, 11, 8.5), doors)


def single_room(width=6.0, depth=4.0, thickness=0.2) -> SyntheticScene:
    """One rectangular room, walls all round, no door."""
    walls = box(-thickness, -thickness, width + thickness, depth + thickness).difference(box(0, 0, width, depth))
    return scene_from_walls(walls, box(0, 0, width, depth), [])


def l_room(thickness=0.2) -> SyntheticScene:
    """An L-shaped room: 8 x 3 m along x, plus a 3 x 5 m wing up from x in [0, 3]."""
    interior = shapely.union_all([box(0, 0, 8, 3), box(0, 0, 3, 8)])
    walls = interior.buffer(thickness, join_style="mitre").difference(interior)
    return scene_from_walls(walls, interior, [])


def two_rooms(thickness=0.2) -> SyntheticScene:
    """Two 5 x 4 m rooms side by side (x in [0, 5] and [5.2, 10.2]), joined by a
    0.9 m door at y in [1.5, 2.4] in the 0.2 m wall between them."""
    interior = box(0, 0, 10.2, 4)
    outer = interior.buffer(thickness, join_style="mitre").difference(interior)
    door = box(5.0, 1.5, 5.2, 2.4)
    walls = shapely.union_all([outer, box(5.0, 0, 5.2, 4)]).difference(door)
    return scene_from_walls(walls, interior, [door])


def open_hall(seed: int = 0) -> SyntheticScene:
    """A 52 x 22 m open plan (the scale of the Barcelona pavilion, denser):
    16 cruciform columns and 30 free-standing wall pieces 1-6 m long at
    seeded random places; about 1400 segments."""
    rng = np.random.default_rng(seed)
    width, depth = 52.0, 22.0
    interior = box(0, 0, width, depth)
    blocks = []
    for i in range(4):
        for j in range(4):
            cx, cy = 8 + i * 12, 4 + j * 4.7
            blocks += [
                box(cx - 0.15, cy - 0.02, cx + 0.15, cy + 0.02),
                box(cx - 0.02, cy - 0.15, cx + 0.02, cy + 0.15),
                box(cx - 0.08, cy - 0.08, cx + 0.08, cy + 0.08),
            ]
    for _ in range(30):
        cx, cy = rng.uniform([2, 2], [width - 2, depth - 2])
        half = rng.uniform(1, 6) / 2
        vertical = rng.random() < 0.5
        blocks.append(box(cx - 0.1, cy - half, cx + 0.1, cy + half) if vertical else box(cx - half, cy - 0.1, cx + half, cy + 0.1))
    walls = shapely.union_all([interior.buffer(0.3, join_style="mitre").difference(interior), *blocks])
    return scene_from_walls(walls, interior, [])


__all__ = ["SyntheticScene", "apartment", "l_room", "open_hall", "scene_from_walls", "single_room", "two_rooms"]
