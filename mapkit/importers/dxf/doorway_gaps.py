"""Doorway widths measured in the gaps of a plan's wall lines, whatever its
units: what tells the units of a plan that draws no door symbols.

A doorway without a door drawing is where a wall stops short: its free
width is the distance from the wall's end to the next wall end in line
with it, facing it (two collinear wall ends), or to the wall the end runs
into (a wall end facing a wall across a passage). A wall end is the free
end of a single wall line, or the cap of a double-line wall (a short line
whose ends each meet one of the wall's two sides). Measured on the strokes
as read, before the units are known, so nothing here is in metres: every
bound is a share of the plan's extent (``GAP_UNITS_*`` in
:mod:`mapkit.tolerances`).

A plan of closed outlines with no openings (rooms traced as rectangles)
gives no gaps, and says nothing of its units here.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from mapkit.tolerances import (BRIDGE_ANGLE_DEG, GAP_UNITS_FACING_DEG, GAP_UNITS_NEIGHBOURS, GAP_UNITS_REACH_SHARE,
                               GAP_UNITS_TOUCH_SHARE)


def doorway_gaps(strokes: list, extent: float) -> np.ndarray:
    """The free width of each doorway the wall ``strokes`` leave open, in
    their own units (``extent``: the plan's largest side in those units),
    one per doorway, shape ``(K,)``. Wall ends inside another wall's closed
    outline (walls drawn overlapping at a junction) are no wall ends.

    Each wall end is paired with the nearest end in line with it and facing
    it (within ``BRIDGE_ANGLE_DEG``), the nearest pairs first; an end left
    unpaired gives its distance to the wall line it runs into, when that
    line stands within ``GAP_UNITS_FACING_DEG`` of square to it. Ends
    farther apart than ``GAP_UNITS_REACH_SHARE`` of the extent are no
    doorway."""
    if extent <= 0:
        return np.zeros(0)
    touch = GAP_UNITS_TOUCH_SHARE * extent
    reach = GAP_UNITS_REACH_SHARE * extent
    a, b, stroke_of = stroke_pieces(strokes, touch)
    if not len(a):
        return np.zeros(0)
    tree = shapely.STRtree(shapely.linestrings(np.stack([a, b], axis=1)))
    tips, outs, own = _wall_ends(a, b, tree, touch)
    open_end = ~_buried(tips, stroke_of[own], strokes)
    tips, outs, own = tips[open_end], outs[open_end], own[open_end]
    if not len(tips):
        return np.zeros(0)
    widths, paired = _paired(tips, outs, reach)
    lone = np.setdiff1d(np.arange(len(tips)), paired)
    widths += _to_facing_walls(tips[lone], outs[lone], own[lone], a, b, tree, touch, reach)
    return np.asarray(widths, dtype=float)


def wall_doorway_gaps(walls: list) -> np.ndarray:
    """:func:`doorway_gaps` of the wall strokes ``walls``, measured against
    their own extent (the largest side of their bounding box)."""
    if not walls:
        return np.zeros(0)
    points = np.concatenate([np.asarray(s.coords, dtype=float)[:, :2] for s in walls])
    return doorway_gaps(walls, float((points.max(axis=0) - points.min(axis=0)).max()))


def stroke_pieces(strokes: list, touch: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The straight pieces ``a -> b`` (each (N, 2)) of the ``strokes``,
    those no longer than ``touch`` left out, and the index of the stroke
    each belongs to (N,)."""
    starts, ends, owner = [], [], []
    for k, s in enumerate(strokes):
        xy = np.asarray(s.coords, dtype=float)[:, :2]
        if len(xy) < 2:
            continue
        ring = np.vstack([xy, xy[:1]]) if s.closed else xy
        starts.append(ring[:-1])
        ends.append(ring[1:])
        owner.append(np.full(len(ring) - 1, k))
    if not starts:
        z = np.zeros((0, 2))
        return z, z, np.zeros(0, dtype=int)
    a, b, owner = np.concatenate(starts), np.concatenate(ends), np.concatenate(owner)
    long = np.hypot(*(b - a).T) > touch  # (False for a non-finite piece)
    return a[long], b[long], owner[long]


def _wall_ends(a: np.ndarray, b: np.ndarray, tree, touch: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The wall ends among the segments ``a -> b`` (``tree`` their index):
    their points (K, 2), the unit directions out of the wall (K, 2) and the
    segment each belongs to (K,): a free end's own segment, a cap."""
    n = len(a)
    points = np.concatenate([a, b])  # point k is an end of segment k % n
    hit_point, hit_seg = tree.query(shapely.points(points), predicate="dwithin", distance=touch)
    other = hit_seg != hit_point % n
    hit_point, hit_seg = hit_point[other], hit_seg[other]
    count = np.bincount(hit_point, minlength=2 * n)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    unit = d / length[:, None]
    tips, outs, own = [], [], []
    for k in np.flatnonzero(count == 0):  # free ends: nothing else within touch
        seg = k % n
        tips.append(points[k])
        outs.append(-unit[seg] if k < n else unit[seg])
        own.append(seg)
    # Caps: each end meets exactly one other segment; the two run back side
    # by side, square to the cap, each longer than it (a wall is longer
    # than it is thick).
    cos_par = math.cos(math.radians(BRIDGE_ANGLE_DEG))
    sin_par = math.sin(math.radians(BRIDGE_ANGLE_DEG))
    only = np.full(2 * n, -1)
    single = count[hit_point] == 1
    only[hit_point[single]] = hit_seg[single]
    for seg in np.flatnonzero((only[:n] >= 0) & (only[n:] >= 0) & (only[:n] != only[n:])):
        j, k = only[seg], only[n + seg]
        if not (length[j] > length[seg] and length[k] > length[seg]):
            continue
        away_j, away_k = _away(a[j], b[j], a[seg]), _away(a[k], b[k], b[seg])
        if away_j @ away_k < cos_par or abs(away_j @ unit[seg]) > sin_par:
            continue
        out = -(away_j + away_k)
        tips.append((a[seg] + b[seg]) / 2.0)
        outs.append(out / np.hypot(*out))
        own.append(seg)
    if not tips:
        z = np.zeros((0, 2))
        return z, z, np.zeros(0, dtype=int)
    return np.asarray(tips), np.asarray(outs), np.asarray(own, dtype=int)


def _buried(tips: np.ndarray, tip_stroke: np.ndarray, strokes: list) -> np.ndarray:
    """Which ``tips`` (of the strokes ``tip_stroke``) lie in or on another
    closed outline of the ``strokes`` (a wall drawn running into another,
    their outlines overlapping: a junction, not a wall end), shape ``(K,)``
    bool."""
    closed = [k for k, s in enumerate(strokes) if s.closed and len(s.coords) >= 3]
    outlines = [shapely.Polygon(np.asarray(strokes[k].coords, dtype=float)[:, :2]) for k in closed]
    buried = np.zeros(len(tips), dtype=bool)
    if outlines and len(tips):
        tip, outline = shapely.STRtree(outlines).query(shapely.points(tips), predicate="intersects")
        other = np.asarray(closed, dtype=int)[outline] != tip_stroke[tip]
        buried[tip[other]] = True
    return buried


def _away(p: np.ndarray, q: np.ndarray, joint: np.ndarray) -> np.ndarray:
    """The unit direction of segment ``p``-``q`` away from ``joint`` (where
    it meets a cap)."""
    near, far = (p, q) if np.hypot(*(p - joint)) <= np.hypot(*(q - joint)) else (q, p)
    v = far - near
    return v / np.hypot(*v)


def _paired(tips: np.ndarray, outs: np.ndarray, reach: float) -> tuple[list[float], np.ndarray]:
    """The widths of the gaps between wall ends in line and facing each
    other (within ``BRIDGE_ANGLE_DEG``), at most ``reach`` apart, each end
    used once, the nearest pairs first; and the indices of the ends used.
    An end's partner is sought among its ``GAP_UNITS_NEIGHBOURS`` nearest
    ends (a doorway's other jamb is near it; the work stays linear in the
    ends of a plan of thousands)."""
    from scipy.spatial import cKDTree

    k = min(GAP_UNITS_NEIGHBOURS + 1, len(tips))
    if k < 2:
        return [], np.zeros(0, dtype=int)
    dist, j = cKDTree(tips).query(tips, k=k, distance_upper_bound=reach)
    i = np.repeat(np.arange(len(tips)), k).reshape(dist.shape)
    found = np.isfinite(dist) & (j != i) & (dist > 0)
    i, j, dist = i[found], j[found], dist[found]
    keep = i < j  # each pair once (a pair found from one side only is kept too)
    i, j, dist = np.concatenate([i[keep], j[~keep]]), np.concatenate([j[keep], i[~keep]]), \
        np.concatenate([dist[keep], dist[~keep]])
    u = (tips[j] - tips[i]) / dist[:, None]
    cos_par = math.cos(math.radians(BRIDGE_ANGLE_DEG))
    facing = (((outs[i] * outs[j]).sum(axis=1) < -cos_par) & ((outs[i] * u).sum(axis=1) > cos_par)
              & (-(outs[j] * u).sum(axis=1) > cos_par))
    used: set[int] = set()
    widths = []
    for n in np.flatnonzero(facing)[np.argsort(dist[facing], kind="stable")]:
        a, b = int(i[n]), int(j[n])
        if a in used or b in used:
            continue
        used |= {a, b}
        widths.append(float(dist[n]))
    return widths, np.asarray(sorted(used), dtype=int)


def _to_facing_walls(tips, outs, own, a, b, tree, touch: float, reach: float) -> list[float]:
    """For each wall end (``tips``, its direction out of the wall ``outs``,
    its segment ``own``), the distance to the first segment (``a -> b``) it
    runs into within ``reach``, when that segment stands within
    ``GAP_UNITS_FACING_DEG`` of square to it; ends facing nothing, or
    first meeting a line at a slant, give none. Rays are cast a sixteenth,
    then a quarter of ``reach``, then all of it, each time for the ends that
    met nothing yet: a long slanted ray's box holds much of a dense plan."""
    nearest = np.full(len(tips), np.inf)
    first_facing = np.full(len(tips), np.inf)
    todo = np.arange(len(tips))
    for length in (reach / 16, reach / 4, reach):
        if not len(todo):
            break
        near, facing = _first_met(tips[todo], outs[todo], own[todo], a, b, tree, touch, length)
        nearest[todo], first_facing[todo] = near, facing
        todo = todo[~np.isfinite(near)]
    return [float(t) for t, n in zip(first_facing, nearest) if np.isfinite(t) and t <= n]


def _first_met(tips, outs, own, a, b, tree, touch: float, length: float) -> tuple[np.ndarray, np.ndarray]:
    """For rays from ``tips`` along ``outs`` (from ``touch`` to ``length``
    out), the distance to the first segment each meets other than its
    ``own`` and to the first standing within ``GAP_UNITS_FACING_DEG`` of
    square to it (inf: none), each shape (K,)."""
    nearest = np.full(len(tips), np.inf)
    first_facing = np.full(len(tips), np.inf)
    rays = shapely.linestrings(np.stack([tips + outs * touch, tips + outs * length], axis=1))
    hit_ray, hit_seg = tree.query(rays, predicate="intersects")
    keep = hit_seg != own[hit_ray]
    hit_ray, hit_seg = hit_ray[keep], hit_seg[keep]
    if not len(hit_ray):
        return nearest, first_facing
    # The ray p + t u meets the segment a + s d where t = (w x d) / (u x d), w = a - p.
    p, u = tips[hit_ray], outs[hit_ray]
    d = b[hit_seg] - a[hit_seg]
    cross_ud = u[:, 0] * d[:, 1] - u[:, 1] * d[:, 0]
    w = a[hit_seg] - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / cross_ud
        square = np.abs(cross_ud) / np.hypot(d[:, 0], d[:, 1])  # sine of the angle between ray and segment
    met = np.isfinite(t)
    facing = met & (square >= math.cos(math.radians(GAP_UNITS_FACING_DEG)))
    np.minimum.at(nearest, hit_ray[met], t[met])
    np.minimum.at(first_facing, hit_ray[facing], t[facing])
    return nearest, first_facing


__all__ = ["doorway_gaps", "wall_doorway_gaps"]
