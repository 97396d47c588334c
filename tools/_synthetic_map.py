"""A synthetic flat as a LineMap, for the matcher's tests, simulator and benchmark.

Maps made without the map builder, so that the matcher's results do not
hang on it: ``bench_paper.py --synthetic`` runs the paper's protocol on
:func:`make_flat_map`, a 12 m x 9 m flat of seven rooms (living room with
a pillar and an open kitchen, kitchen, bathroom, corridor, two bedrooms, a
study), walls 0.1 m thick and ``WALL_HEIGHT`` high, full-height door openings.

Segments: the floor and ceiling junctions along every wall face (edges
shorter than 0.2 m dropped) and a vertical edge at every corner of the free
space. Regions: the free space (shrunk by the robot radius) cut by a 1 m
grid; each region's list holds every segment seen from a sample of its
points (a grid plus its outline) with at least ``MIN_SEEN`` of the segment
unoccluded, by brute force with shapely (about a minute; cached).
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import box
from shapely.ops import unary_union

from mapkit.assemble import assemble_map
from linemap.lmap import LineMap, SegmentKind

WALL_HEIGHT = 2.5
ROBOT_RADIUS = 0.2
MIN_EDGE = 0.2
MIN_SEEN = 0.1  # metres of a segment that must be unoccluded to list it
CORNER_DEG = 20.0

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
    """(free space, walls, room polygons) as shapely geometries."""
    rooms = [box(*r) for r in ROOMS.values()]
    free = unary_union(rooms + [box(*d) for d in DOORS])
    for p in PILLARS:
        free = free.difference(box(*p))
    outer = box(-0.15, -0.15, 12.15, 9.15)
    walls = outer.difference(free)
    room_polys = [r.difference(unary_union([box(*p) for p in PILLARS])) for r in rooms]
    return free, walls, room_polys


def _rings(geom):
    polys = [geom] if geom.geom_type == "Polygon" else list(geom.geoms)
    out = []
    for p in polys:
        out.append(np.asarray(p.exterior.coords)[:-1])
        out += [np.asarray(r.coords)[:-1] for r in p.interiors]
    return out


def flat_segments(free, wall_height: float = WALL_HEIGHT) -> tuple[np.ndarray, np.ndarray]:
    """Model segments (N, 2, 3) and kinds (N,) of the free space's outline."""
    segs, kinds = [], []
    for ring in _rings(free.simplify(1e-6)):
        n = len(ring)
        for i in range(n):
            a, b = ring[i], ring[(i + 1) % n]
            if np.hypot(*(b - a)) >= MIN_EDGE:
                segs.append([[a[0], a[1], 0.0], [b[0], b[1], 0.0]])
                kinds.append(SegmentKind.FLOOR)
                segs.append([[a[0], a[1], wall_height], [b[0], b[1], wall_height]])
                kinds.append(SegmentKind.CEILING)
            prev = ring[i - 1]
            d1, d2 = a - prev, b - a
            turn = np.degrees(abs(np.arctan2(d1[0] * d2[1] - d1[1] * d2[0], d1 @ d2)))
            if turn > CORNER_DEG:
                segs.append([[a[0], a[1], 0.0], [a[0], a[1], wall_height]])
                kinds.append(SegmentKind.VERTICAL)
    return np.array(segs, dtype=float), np.array(kinds, dtype=np.uint8)


def _sample_points(reg, spacing: float) -> np.ndarray:
    """Points of a region: a grid inside plus points along its outline."""
    x0, y0, x1, y1 = reg.bounds
    gx, gy = np.meshgrid(np.arange(x0 + spacing / 2, x1, spacing), np.arange(y0 + spacing / 2, y1, spacing))
    pts = np.stack([gx.ravel(), gy.ravel()], 1)
    pts = pts[shapely.contains_xy(reg, pts[:, 0], pts[:, 1])]
    outline = []
    for ring in _rings(reg):
        closed = np.vstack([ring, ring[:1]])
        for a, b in zip(closed[:-1], closed[1:]):
            n = max(1, int(np.ceil(np.hypot(*(b - a)) / spacing)))
            outline.append(a + np.linspace(0, 1, n, endpoint=False)[:, None] * (b - a))
    return np.concatenate([pts] + outline)


def _visible_lists(regions, segments, walls, spacing: float = 0.25, samples: int = 10):
    """Per region, the segments with ``MIN_SEEN`` metres unoccluded from some
    sample point of the region (brute force, shapely)."""
    occ = walls.buffer(-2e-3)
    shapely.prepare(occ)
    t = (np.arange(samples) + 0.5) / samples
    seg_pts = segments[:, 0, None, :2] + t[None, :, None] * (segments[:, 1, None, :2] - segments[:, 0, None, :2])
    seg_len = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    flat = seg_pts.reshape(-1, 2)
    lists = []
    for reg in regions:
        pts = _sample_points(reg, spacing)
        starts = np.repeat(pts, len(flat), axis=0)
        ends = np.tile(flat, (len(pts), 1))
        lines = shapely.linestrings(np.stack([starts, ends], axis=1))
        blocked = shapely.intersects(lines, occ).reshape(len(pts), len(segments), samples)
        seen = ((~blocked).sum(axis=2) * seg_len / samples >= MIN_SEEN).any(axis=0)
        lists.append(np.nonzero(seen)[0])
    return lists


def make_flat_map(cell: float | None = 1.0) -> LineMap:
    """The synthetic flat as a LineMap (seconds: brute-force lists).

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
                piece = space.intersection(box(gx, gy, gx + cell, gy + cell))
                piece = shapely.make_valid(piece)
                parts = [g for g in getattr(piece, "geoms", [piece]) if g.geom_type == "Polygon" and g.area > 1e-3]
                if parts:
                    regions.append(unary_union(parts))
    lists = _visible_lists(regions, segments, walls)
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": "tools/_synthetic_map.py",
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
    lists = _visible_lists(regions, segments, walls, spacing=0.5, samples=8)
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": "tools/_synthetic_map.py"}
    return assemble_map(segments, kinds, regions, lists, walls, meta)


def make_box_map(width: float = 6.0, depth: float = 5.0) -> LineMap:
    """One empty rectangular room, one region: the smallest useful map (fast)."""
    free = box(0.0, 0.0, width, depth)
    walls = box(-0.15, -0.15, width + 0.15, depth + 0.15).difference(free)
    segments, kinds = flat_segments(free)
    region = free.buffer(-ROBOT_RADIUS, join_style="mitre")
    meta = {"units": "m", "wall_height": WALL_HEIGHT, "source": "tools/_synthetic_map.py"}
    return assemble_map(segments, kinds, [region], [np.arange(len(segments))], walls, meta)


def cached_flat_map(path=None) -> LineMap:
    """The flat map, built once and kept as a .lmap file (default in the temp dir)."""
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


__all__ = ["cached_flat_map", "flat_geometry", "flat_segments", "make_box_map", "make_flat_map", "make_small_flat"]
