"""Synthetic buildings with known geometry, made in code: the buildings the
tests, the simulator, the benchmarks and the inspector's screenshot share.

Real maps come from ``mapkit build``; these exist so that tests and
benchmarks have ground truth that does not hang on the map builder.

One recipe for every building (metres, z up):

- walls: shapely solids; the open space is what they leave of the interior;
- segments (:func:`outline_segments`): along every ring of an outline, the
  floor (z = 0) and ceiling (z = wall height) junctions of each edge and a
  vertical edge at each corner; door gaps add their lintels
  (:func:`lintels`);
- regions and their lists, when a map is wanted: by brute-force visibility
  (:func:`mapkit_harness.visibility_oracle.visible_lists`, exact but slow) or by room and distance
  (:func:`room_or_near_lists`, cheap enough for thousands of regions).

Buildings:

- for the region builder and the visibility tests (walls, free space and
  segments, no regions; :class:`SyntheticScene`): :func:`apartment`,
  :func:`single_room`, :func:`l_room`, :func:`two_rooms`, :func:`open_hall`,
  or any walls through :func:`scene_from_walls`;
- for the matcher (a :class:`~linemap.lmap.LineMap` with brute-force lists):
  :func:`make_flat_map` (12 m x 9 m, seven rooms; ``bench_paper.py
  --synthetic``, cached by :func:`cached_flat_map`), :func:`make_small_flat`
  (two rooms), :func:`make_box_map` (one room);
- for the inspector (a LineMap of any size, quick): :func:`grid_flat`, a
  grid of rooms with doorways and columns, regions a square grid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import box
from shapely.ops import unary_union

from linemap.lmap import LineMap, SegmentKind
from mapkit.assemble import assemble_map
from mapkit.shapes import polygon_parts, rings_of
from mapkit.tolerances import CORNER_DEG

from mapkit_harness.plans.grid_layout import RoomGridLayout, oriented
from mapkit_harness.visibility_oracle import visible_lists

WALL_HEIGHT = 2.5
ROBOT_RADIUS = 0.2

#: The provenance the maps below carry in their META: the generator's name
#: when these maps were first made, kept so that they stay byte for byte the
#: maps the tests and the cached benchmark flat were made with.
SOURCE = "tools/synthetic_building.py"

# --------------------------------------------------------------------------
# Segments


def outline_segments(outline, wall_height: float = WALL_HEIGHT, corner_deg: float | None = CORNER_DEG,
                     min_edge: float = 0.0, jambs=None, door_head: float | None = None,
                     corners_last: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Model segments (N, 2, 3) and kinds (N,) along every ring of ``outline``
    (a shapely (Multi)Polygon): for each edge at least ``min_edge`` long its
    floor and ceiling junctions, and at each vertex where the ring turns by
    more than ``corner_deg`` degrees (every vertex with ``None``) a vertical
    edge; a vertex inside the geometry ``jambs`` is a door jamb, up to
    ``door_head``.

    Order (segment ids), per ring: each vertex's vertical after the edge
    leaving it, or with ``corners_last`` all verticals after the ring's
    edges. Tests sample segments by id, so each building keeps the order
    its tests were written against."""
    segs, kinds = [], []
    for ring, _ in rings_of(outline):
        n = len(ring)
        corners, corner_kinds = [], []
        for i in range(n):
            a, b = ring[i], ring[(i + 1) % n]
            if np.hypot(*(b - a)) >= min_edge:
                segs.append([[a[0], a[1], 0.0], [b[0], b[1], 0.0]])
                kinds.append(SegmentKind.FLOOR)
                segs.append([[a[0], a[1], wall_height], [b[0], b[1], wall_height]])
                kinds.append(SegmentKind.CEILING)
            d1, d2 = a - ring[i - 1], b - a
            turn = np.degrees(abs(np.arctan2(d1[0] * d2[1] - d1[1] * d2[0], d1 @ d2)))
            if corner_deg is None or turn > corner_deg:
                jamb = jambs is not None and jambs.contains(shapely.Point(a))
                corners.append([[a[0], a[1], 0.0], [a[0], a[1], door_head if jamb else wall_height]])
                corner_kinds.append(SegmentKind.JAMB if jamb else SegmentKind.VERTICAL)
                if not corners_last:
                    segs.append(corners.pop())
                    kinds.append(corner_kinds.pop())
        segs += corners
        kinds += corner_kinds
    return np.array(segs, dtype=float).reshape(-1, 2, 3), np.array(kinds, dtype=np.uint8)


def lintels(gaps, door_head: float) -> tuple[np.ndarray, np.ndarray]:
    """The two lintels (z = ``door_head``) of every door gap: the gap's
    axis-aligned box, lintels along its longer side on both wall faces."""
    segs = []
    for gap in gaps:
        x0, y0, x1, y1 = gap.bounds
        if x1 - x0 > y1 - y0:  # gap across a wall along x: lintels along x
            segs += [[[x0, y, door_head], [x1, y, door_head]] for y in (y0, y1)]
        else:
            segs += [[[x, y0, door_head], [x, y1, door_head]] for x in (x0, x1)]
    return np.array(segs, dtype=float).reshape(-1, 2, 3), np.full(len(segs), SegmentKind.LINTEL, dtype=np.uint8)


def _joined(*parts: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


# --------------------------------------------------------------------------
# Region lists (exact ones: :func:`mapkit_harness.visibility_oracle.visible_lists`)


def room_or_near_lists(regions, segments, room_size: tuple[float, float], rooms_y: int,
                       near: float) -> list[np.ndarray]:
    """Per region, the segments of its own room (rooms a grid of ``room_size``
    cells, ``rooms_y`` rows) plus every segment within ``near`` metres of its
    centre: a simple rule, cheap for thousands of regions, that gives lists
    the right size and the right locality."""
    rw, rh = room_size
    centres = np.array([[p.centroid.x, p.centroid.y] for p in regions])
    mids = segments.mean(axis=1)[:, :2]

    def room_of(xy):
        return np.floor(xy[:, 0] / rw).astype(int) * rooms_y + np.floor(xy[:, 1] / rh).astype(int)

    # A segment on a shared wall belongs to both rooms: test both sides of it.
    seg_rooms = np.stack([room_of(mids + d) for d in ([0.1, 0], [-0.1, 0], [0, 0.1], [0, -0.1])], axis=1)
    same_room = (seg_rooms[None, :, :] == room_of(centres)[:, None, None]).any(axis=2)
    close = np.linalg.norm(centres[:, None, :] - mids[None, :, :], axis=2) < near
    return [np.nonzero(row)[0] for row in same_room | close]


# --------------------------------------------------------------------------
# Scenes for the region builder and the visibility tests


@dataclass
class SyntheticScene:
    """``segments`` (N, 2, 3), ``kinds`` (N,) uint8, ``walls`` and
    ``free_space`` shapely geometries, ``wall_height`` metres: the fields of
    a :class:`mapkit.scene.Scene` the region builder reads, with the same
    meaning (a building as the map builder sees it), made in code."""

    segments: np.ndarray
    kinds: np.ndarray
    walls: object
    free_space: object
    wall_height: float


def _wall(x0, y0, x1, y1, t):
    """Axis-aligned wall of thickness ``t`` centred on the line (x0,y0)-(x1,y1)."""
    return box(min(x0, x1) - t / 2, min(y0, y1) - t / 2, max(x0, x1) + t / 2, max(y0, y1) + t / 2)


def scene_from_walls(walls, interior, doors, wall_height=WALL_HEIGHT, door_head=2.1,
                     robot_radius=ROBOT_RADIUS) -> SyntheticScene:
    """Segments along the outline of ``interior - walls`` (collinear vertices
    dropped: one straight wall, one segment; a vertical at every corner
    turning more than ``CORNER_DEG``) and the lintels of every door gap
    polygon in ``doors``."""
    open_space = shapely.simplify(interior.difference(walls), 1e-9)
    segs, kinds = _joined(outline_segments(open_space, wall_height, corners_last=True), lintels(doors, door_head))
    free = shapely.buffer(open_space, -robot_radius, join_style="mitre")
    return SyntheticScene(segs, kinds, walls, free, wall_height)


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


# --------------------------------------------------------------------------
# Maps for the matcher: full-height door openings (no lintels), edges
# shorter than MIN_EDGE dropped, lists by brute-force visibility.

MIN_EDGE = 0.2

ROOMS = {
    "living": (0.0, 0.0, 6.0, 5.0),
    "kitchen": (6.1, 0.0, 10.0, 3.5),
    "bath": (10.1, 0.0, 12.0, 3.5),
    "corridor": (6.1, 3.6, 12.0, 5.0),
    "bedroom1": (0.0, 5.1, 5.0, 9.0),
    "bedroom2": (5.1, 5.1, 9.0, 9.0),
    "study": (9.1, 5.1, 12.0, 9.0),
}
DOORS = [
    (6.0, 3.9, 6.1, 4.8),  # living - corridor
    (6.0, 0.6, 6.1, 2.6),  # living - kitchen, wide opening
    (7.0, 3.5, 7.9, 3.6),  # kitchen - corridor
    (10.6, 3.5, 11.4, 3.6),  # bath - corridor
    (3.5, 5.0, 4.4, 5.1),  # living - bedroom1
    (7.5, 5.0, 8.4, 5.1),  # corridor - bedroom2
    (10.0, 5.0, 10.9, 5.1),  # corridor - study
]
PILLARS = [(2.4, 2.2, 2.8, 2.6)]


def flat_geometry():
    """(free space, walls, room polygons) of the seven-room flat."""
    rooms = [box(*r) for r in ROOMS.values()]
    free = unary_union(rooms + [box(*d) for d in DOORS])
    for p in PILLARS:
        free = free.difference(box(*p))
    outer = box(-0.15, -0.15, 12.15, 9.15)
    walls = outer.difference(free)
    room_polys = [r.difference(unary_union([box(*p) for p in PILLARS])) for r in rooms]
    return free, walls, room_polys


def flat_segments(free, wall_height: float = WALL_HEIGHT) -> tuple[np.ndarray, np.ndarray]:
    """Model segments (N, 2, 3) and kinds (N,) of the free space's outline."""
    return outline_segments(free.simplify(1e-6), wall_height, min_edge=MIN_EDGE)


def make_flat_map(cell: float | None = 1.0) -> LineMap:
    """The seven-room flat as a LineMap (about a minute: brute-force lists).

    Regions are the free space (shrunk by the robot radius) cut by a grid of
    ``cell`` metres, or one per room with ``cell=None``: finer regions give
    shorter lists, as the builder's view-invariant regions do."""
    free, walls, rooms = flat_geometry()
    segments, kinds = flat_segments(free)
    if cell is None:
        regions = [r.buffer(-ROBOT_RADIUS, join_style="mitre") for r in rooms]
    else:
        space = free.buffer(-ROBOT_RADIUS, join_style="mitre")
        x0, y0, x1, y1 = space.bounds
        regions = []
        for gx in np.arange(x0, x1, cell):
            for gy in np.arange(y0, y1, cell):
                piece = shapely.make_valid(space.intersection(box(gx, gy, gx + cell, gy + cell)))
                parts = [g for g in getattr(piece, "geoms", [piece]) if g.geom_type == "Polygon" and g.area > 1e-3]
                if parts:
                    regions.append(unary_union(parts))
    lists = visible_lists(regions, segments, walls)
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": SOURCE,
            "robot_radius": ROBOT_RADIUS, "region_cell": cell}
    return assemble_map(segments, kinds, regions, lists, walls, meta)


def make_small_flat() -> LineMap:
    """Two rooms joined by a door (a 6 x 5 m room with a pillar and a 4 x 4 m
    one), one region per room: a map for tests, built in a second or two."""
    rooms = [box(0.0, 0.0, 6.0, 5.0), box(6.1, 0.5, 10.1, 4.5)]
    free = unary_union(rooms + [box(6.0, 1.8, 6.1, 2.7)]).difference(box(2.4, 2.2, 2.8, 2.6))
    walls = box(-0.15, -0.15, 10.25, 5.15).difference(free)
    segments, kinds = flat_segments(free)
    regions = [r.difference(box(2.4, 2.2, 2.8, 2.6)).buffer(-ROBOT_RADIUS, join_style="mitre") for r in rooms]
    lists = visible_lists(regions, segments, walls, spacing=0.5, samples=8)
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": SOURCE}
    return assemble_map(segments, kinds, regions, lists, walls, meta)


def make_box_map(width: float = 6.0, depth: float = 5.0, robot_radius: float = ROBOT_RADIUS) -> LineMap:
    """One empty rectangular room, one region (the room shrunk by
    ``robot_radius``, metres): the smallest useful map (fast)."""
    free = box(0.0, 0.0, width, depth)
    walls = box(-0.15, -0.15, width + 0.15, depth + 0.15).difference(free)
    segments, kinds = flat_segments(free)
    region = free.buffer(-robot_radius, join_style="mitre")
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": SOURCE}
    return assemble_map(segments, kinds, [region], [np.arange(len(segments))], walls, meta)


def cached_flat_map(path=None) -> LineMap:
    """The seven-room flat, built once and kept as a .lmap file (default in the temp dir)."""
    import os
    import tempfile

    from linemap.lmap import load_map, save_map

    path = path or os.path.join(tempfile.gettempdir(), "matcher_synthetic_flat_v2.lmap")
    if os.path.exists(path):
        try:
            return load_map(path)
        except Exception:
            pass
    m = make_flat_map()
    save_map(path, m)
    return load_map(path)


# --------------------------------------------------------------------------
# The inspector's flat: any number of rooms, quick, thousands of regions.

#: The camera recorded in the grid flat's build parameters (camera.json shape).
DEMO_CAMERA = {"width": 640, "height": 480, "fx": 457.0, "fy": 457.0, "cx": 320.0, "cy": 240.0,
               "height_m": 1.2, "pitch_deg": 5.0}


def grid_flat(
    rooms: tuple[int, int] = (3, 2),
    room_size: tuple[float, float] = (4.0, 3.5),
    cell: float = 0.5,
    wall_height: float = WALL_HEIGHT,
    door_height: float = 2.1,
    wall_thickness: float = 0.12,
    door_width: float = 0.9,
    near: float = 2.0,
) -> LineMap:
    """A flat of ``rooms`` = (nx, ny) rectangular rooms of ``room_size``
    metres joined by doorways, a square column in every other room; regions
    a grid of ``cell`` metres clipped to the free space, lists by
    :func:`room_or_near_lists`. Its segments are what a real build gives a
    plan like it: the junctions along every wall face (outer faces too), a
    vertical at every wall vertex (a jamb where it bounds a doorway), the
    lintels of each doorway. The rooms, walls and doorways are laid out by
    :class:`~mapkit_harness.plans.grid_layout.RoomGridLayout`.

    Deterministic: the same arguments give the same map.
    """
    nx, ny = rooms
    rw, rh = room_size
    t = wall_thickness
    layout = RoomGridLayout(rooms, room_size, t, door_width)
    width, height = layout.outline[2:]
    inside = box(*layout.inside)
    walls = box(*layout.outline).difference(inside)
    cuts, gaps = [], []  # boxes cutting the doorways (wider than the wall), the doorways themselves
    # The interior walls one by one, their doorways cut at the end: the
    # order of the shapely operations fixes the vertex order of the rings.
    for wall in (w for w in layout.walls() if not w.outer):
        walls = walls.union(box(*wall.whole))
        for doorway in wall.doorways:
            cuts.append(box(*oriented(wall.between_columns, doorway.span, (wall.line - t, wall.line + t))))
            gaps.append(box(*doorway.rect))
    door_union = shapely.union_all(cuts)
    walls = walls.difference(door_union)
    # A column in every other room: holes in the regions, more vertical corners.
    columns = [box((i + 0.7) * rw - 0.15, (j + 0.6) * rh - 0.15, (i + 0.7) * rw + 0.15, (j + 0.6) * rh + 0.15)
               for i in range(nx) for j in range(ny) if (i + j) % 2 == 0]
    walls = shapely.union_all([walls, *columns]).normalize()

    segments, kinds = _joined(
        outline_segments(walls, wall_height, corner_deg=None, jambs=door_union.buffer(1e-6), door_head=door_height,
                         corners_last=True),
        lintels(gaps, door_height),
    )

    free = inside.difference(walls).buffer(-0.2, join_style="mitre")
    gx, gy = np.meshgrid(np.arange(0.0, width, cell), np.arange(0.0, height, cell))
    clipped = shapely.intersection(shapely.box(gx.ravel(), gy.ravel(), gx.ravel() + cell, gy.ravel() + cell), free)
    regions = [p for g in clipped for p in polygon_parts(g) if p.area > 1e-4]
    lists = room_or_near_lists(regions, segments, room_size, ny, near)
    meta = {
        "units": "m",
        "wall_height": wall_height,
        "source": {"name": "synthetic flat", "rooms": [nx, ny]},
        "build": {"camera": dict(DEMO_CAMERA), "wall_height": wall_height, "door_height": door_height,
                  "max_range": 10.0, "robot_radius": 0.2, "region_cell": cell},
    }
    return assemble_map(segments, kinds, regions, lists, walls, meta)


__all__ = [
    "DEMO_CAMERA", "SyntheticScene", "apartment", "cached_flat_map", "flat_geometry", "flat_segments", "grid_flat",
    "l_room", "lintels", "make_box_map", "make_flat_map", "make_small_flat", "open_hall", "outline_segments",
    "room_or_near_lists", "scene_from_walls", "single_room", "two_rooms",
]
