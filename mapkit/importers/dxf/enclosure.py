"""Gaps a drawing leaves open between wall ends: window openings whose glass
is not drawn, doorways without a door symbol.

A plan tells inside from outside by what its walls enclose. Where a wall
stops and the same wall goes on a little farther (two wall ends facing each
other across a gap, their end faces parallel), the gap is an opening: for
finding the rooms it is shut like a door. :func:`end_bridges` finds those
gaps; :func:`passable` tells which of them join two rooms (an open doorway:
the robot passes) from those between a room and the outside (an opening in
the facade: the robot stays in).
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import Point, Polygon

from mapkit.shapes import polygon_parts
from mapkit.tolerances import BRIDGE_ANGLE_DEG, BRIDGE_MAX_GAP, MERGE, ZERO


def wall_ends(walls, max_wall_thickness: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The end faces of the walls: ``(a, b, out)``, each (K, 2).

    An end face is an edge ``a -> b`` at most ``max_wall_thickness`` long
    whose neighbouring edges run back side by side (a U-turn of the
    outline), ``out`` the unit direction the wall ends in (out of the wall)."""
    ends_a, ends_b, outs = [], [], []
    cos_par = math.cos(math.radians(BRIDGE_ANGLE_DEG))
    sin_par = math.sin(math.radians(BRIDGE_ANGLE_DEG))
    # Noding leaves vertices along straight wall faces where other pieces
    # touched them: drop them, so that a wall's side is one edge.
    geom = shapely.orient_polygons(shapely.simplify(walls, MERGE / 10), exterior_cw=False) if not walls.is_empty else walls
    for poly in polygon_parts(geom):
        for ring in [poly.exterior, *poly.interiors]:
            pts = np.asarray(ring.coords)[:-1, :2]
            n = len(pts)
            if n < 4:
                continue
            d = np.roll(pts, -1, axis=0) - pts  # edge i: pts[i] -> pts[i + 1]
            length = np.hypot(d[:, 0], d[:, 1])
            unit = d / np.maximum(length, ZERO.divisor)[:, None]
            prev, nxt = np.roll(unit, 1, axis=0), np.roll(unit, -1, axis=0)
            cap = (
                (length > MERGE)
                & (length <= max_wall_thickness)
                & ((prev * nxt).sum(axis=1) < -cos_par)  # the sides run back side by side
                & (np.abs((unit * prev).sum(axis=1)) < sin_par)  # the end is square to them
                # A wall is longer than it is thick, along one side at least
                # (a pier may stand on the other, close to the end).
                & (np.maximum(np.roll(length, 1), np.roll(length, -1)) > length)
            )
            for i in np.flatnonzero(cap):
                ends_a.append(pts[i])
                ends_b.append(pts[(i + 1) % n])
                outs.append(prev[i])
    if not outs:
        z = np.zeros((0, 2))
        return z, z, z
    return np.array(ends_a), np.array(ends_b), np.array(outs)


def end_bridges(walls, max_wall_thickness: float) -> list[Polygon]:
    """Quadrilaterals shutting the gaps between pairs of wall ends that face
    each other at most ``BRIDGE_MAX_GAP`` apart, in line (within
    ``BRIDGE_ANGLE_DEG``), with no wall in between. Each end is used once,
    the nearest pairs first."""
    a, b, out = wall_ends(walls, max_wall_thickness)
    if len(a) < 2:
        return []
    centre = (a + b) / 2.0
    cos_par = math.cos(math.radians(BRIDGE_ANGLE_DEG))
    from scipy.spatial import cKDTree

    pairs = []
    for i, j in cKDTree(centre).query_pairs(BRIDGE_MAX_GAP):
        v = centre[j] - centre[i]
        dist = float(np.hypot(*v))
        if dist <= MERGE:
            continue
        u = v / dist
        if out[i] @ out[j] < -cos_par and out[i] @ u > cos_par and -(out[j] @ u) > cos_par:
            pairs.append((dist, i, j))
    used: set[int] = set()
    bridges = []
    shapely.prepare(walls)
    for dist, i, j in sorted(pairs):
        if i in used or j in used:
            continue
        quad = shapely.convex_hull(shapely.MultiPoint([a[i], b[i], a[j], b[j]]))
        if not isinstance(quad, Polygon) or quad.area <= 0:
            continue
        # Nothing of the walls inside it but the two end faces it joins.
        if quad.buffer(-2 * MERGE).intersects(walls):
            continue
        used |= {i, j}
        bridges.append(quad)
    return bridges


def passable(bridge: Polygon, rooms) -> bool:
    """Whether rooms lie on both sides of ``bridge`` (a doorway between two
    rooms) rather than on one (an opening to the outside).

    The sides are probed just beyond the bridge's two long edges, at their
    middles."""
    rect = np.asarray(bridge.minimum_rotated_rectangle.exterior.coords)[:4]
    sides = [(rect[k], rect[(k + 1) % 4]) for k in range(4)]
    lengths = [float(np.hypot(*(q - p))) for p, q in sides]
    k = int(np.argmax(lengths))
    c = np.asarray(bridge.centroid.coords[0])
    probes = []
    for p, q in (sides[k], sides[(k + 2) % 4]):
        mid = (p + q) / 2.0
        away = mid - c
        norm = float(np.hypot(*away)) or 1.0
        probes.append(Point(mid + away / norm * 10 * MERGE))
    return all(rooms.covers(pt) for pt in probes)


__all__ = ["end_bridges", "passable", "wall_ends"]
