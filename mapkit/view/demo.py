"""A synthetic flat as a :class:`~linemap.lmap.LineMap`, for the inspector's
tests, its screenshot and demos when no built map is at hand.

The flat is a grid of rectangular rooms joined by doorways, with a few square
columns. Its model segments are what a real build gives a plan like it: the
wall/floor and wall/ceiling junctions along every wall face, a vertical
corner at every wall vertex (a jamb where the vertex bounds a doorway) and a
lintel across each doorway. Its regions are a square grid clipped to the free
space. A region's list holds the segments of its own room plus everything
within a couple of metres: a simple rule, cheap enough for thousands of
regions, that gives lists the right size and the right locality.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import box

from mapkit.assemble import assemble_map
from mapkit.shapes import polygon_parts
from linemap.lmap import LineMap, SegmentKind

#: The camera recorded in the synthetic map's build parameters (camera.json shape).
DEMO_CAMERA = {"width": 640, "height": 480, "fx": 457.0, "fy": 457.0, "cx": 320.0, "cy": 240.0,
               "height_m": 1.2, "pitch_deg": 5.0}


def synthetic_flat(
    rooms: tuple[int, int] = (3, 2),
    room_size: tuple[float, float] = (4.0, 3.5),
    cell: float = 0.5,
    wall_height: float = 2.5,
    door_height: float = 2.1,
    wall_thickness: float = 0.12,
    door_width: float = 0.9,
    near: float = 2.0,
) -> LineMap:
    """A flat of ``rooms`` = (nx, ny) rooms of ``room_size`` metres, regions of ``cell`` metres.

    Deterministic: the same arguments give the same map.
    """
    nx, ny = rooms
    rw, rh = room_size
    t = wall_thickness
    width, height = nx * rw, ny * rh
    inside = box(t, t, width - t, height - t)
    walls = box(0, 0, width, height).difference(inside)
    doors = []
    for i in range(1, nx):  # walls between columns of rooms, one doorway per room
        x = i * rw
        walls = walls.union(box(x - t / 2, 0, x + t / 2, height))
        mids = [(j + 0.5) * rh for j in range(ny)]
        doors += [box(x - t, c - door_width / 2, x + t, c + door_width / 2) for c in mids]
    for j in range(1, ny):
        y = j * rh
        walls = walls.union(box(0, y - t / 2, width, y + t / 2))
        mids = [(i + 0.3) * rw for i in range(nx)]
        doors += [box(c - door_width / 2, y - t, c + door_width / 2, y + t) for c in mids]
    door_union = shapely.union_all(doors)
    walls = walls.difference(door_union)
    # A column in every other room: holes in the regions, more vertical corners.
    columns = [box((i + 0.7) * rw - 0.15, (j + 0.6) * rh - 0.15, (i + 0.7) * rw + 0.15, (j + 0.6) * rh + 0.15)
               for i in range(nx) for j in range(ny) if (i + j) % 2 == 0]
    walls = shapely.union_all([walls, *columns]).normalize()

    segments, kinds = _wall_segments(walls, door_union, doors, wall_height, door_height, t)

    free = inside.difference(walls).buffer(-0.2, join_style="mitre")
    xs = np.arange(0.0, width, cell)
    ys = np.arange(0.0, height, cell)
    gx, gy = np.meshgrid(xs, ys)
    cells = shapely.box(gx.ravel(), gy.ravel(), gx.ravel() + cell, gy.ravel() + cell)
    clipped = shapely.intersection(cells, free)
    regions = [p for g in clipped for p in polygon_parts(g) if p.area > 1e-4]

    centres = np.array([[p.centroid.x, p.centroid.y] for p in regions])
    mids = segments.mean(axis=1)[:, :2]
    room_of = lambda xy: np.floor(xy[:, 0] / rw).astype(int) * ny + np.floor(xy[:, 1] / rh).astype(int)  # noqa: E731
    # A segment on a shared wall belongs to both rooms: test both sides of it.
    seg_rooms = np.stack([room_of(mids + d) for d in ([0.1, 0], [-0.1, 0], [0, 0.1], [0, -0.1])], axis=1)
    reg_room = room_of(centres)
    same_room = (seg_rooms[None, :, :] == reg_room[:, None, None]).any(axis=2)
    close = np.linalg.norm(centres[:, None, :] - mids[None, :, :], axis=2) < near
    visible = same_room | close
    lists = [np.nonzero(row)[0] for row in visible]
    meta = {
        "units": "m",
        "wall_height": wall_height,
        "source": {"name": "synthetic flat", "rooms": [nx, ny]},
        "build": {"camera": dict(DEMO_CAMERA), "wall_height": wall_height, "door_height": door_height,
                  "max_range": 10.0, "robot_radius": 0.2, "region_cell": cell},
    }
    return assemble_map(segments, kinds, regions, lists, walls, meta)


def _wall_segments(walls, door_union, doors, wall_height, door_height, t) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2, 3) segments and (N,) kinds of the wall solids ``walls``."""
    segs, kinds = [], []
    near_door = door_union.buffer(1e-6)
    for poly in polygon_parts(walls):
        for ring in [poly.exterior, *poly.interiors]:
            pts = np.asarray(ring.coords)[:-1]
            for a, b in zip(pts, np.roll(pts, -1, axis=0)):
                segs.append([[a[0], a[1], 0.0], [b[0], b[1], 0.0]])
                kinds.append(SegmentKind.FLOOR)
                segs.append([[a[0], a[1], wall_height], [b[0], b[1], wall_height]])
                kinds.append(SegmentKind.CEILING)
            for p in pts:
                jamb = near_door.contains(shapely.Point(p))
                segs.append([[p[0], p[1], 0.0], [p[0], p[1], door_height if jamb else wall_height]])
                kinds.append(SegmentKind.JAMB if jamb else SegmentKind.VERTICAL)
    for d in doors:
        x0, y0, x1, y1 = d.bounds
        if x1 - x0 < y1 - y0:  # doorway in a wall along y: lintels on both faces
            xc = (x0 + x1) / 2
            for x in (xc - t / 2, xc + t / 2):
                segs.append([[x, y0, door_height], [x, y1, door_height]])
                kinds.append(SegmentKind.LINTEL)
        else:
            yc = (y0 + y1) / 2
            for y in (yc - t / 2, yc + t / 2):
                segs.append([[x0, y, door_height], [x1, y, door_height]])
                kinds.append(SegmentKind.LINTEL)
    return np.asarray(segs, dtype=np.float64), np.asarray(kinds, dtype=np.uint8)
