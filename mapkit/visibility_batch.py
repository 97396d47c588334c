"""Visibility polygons of many points at once.

:func:`visibility_polygons` computes, for an array of points, exactly what
:func:`mapkit.visibility.visibility_polygon` computes for each one, bit for
bit, but with every step done for a whole chunk of points by a few numpy
calls. The per-point sweep spends most of its time in the fixed cost of its
numpy calls (a point of a room sees a few dozen edges); here that cost is
paid once per chunk.

Ragged arrays: the edges, rays and output vertices of all the points of a
chunk sit in flat arrays, grouped by point, in the order the per-point sweep
uses; ``owner`` arrays say which point each row belongs to. Every number is
computed by the same elementwise formula as in the per-point sweep, and the
only reductions are minima (exact in any order), so the results are equal.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from mapkit.parallel import map_chunks
from mapkit.tolerances import (
    VIS_BLOCK,
    VIS_FIRST_EDGES,
    VIS_HIDDEN_SLACK,
    VIS_NEAR_BLOCK,
    VIS_RAY_OFFSET_DEG,
    VIS_SWEEP_EDGES,
    ZERO,
)
from mapkit.visibility import Occluders, clip_box


def visibility_polygons(points: np.ndarray, occ: Occluders, radius: float, workers: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Visibility polygons of ``points`` (P, 2) metres, each within the square
    of half-side ``radius`` around its point.

    Returns ``(coords, owner)``: (V, 2) vertices and (V,) int64 point index,
    grouped by point in point order, each point's vertices counter-clockwise
    as :func:`mapkit.visibility.visibility_polygon` returns them. Chunks of
    points are swept in ``workers`` threads (numpy releases the GIL in its
    array loops); each point's polygon does not depend on its chunk."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if workers > 1:

        def sweep(idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            coords, owner = visibility_polygons(points[idx], occ, radius)
            return coords, idx[owner]

        return map_chunks(sweep, [np.arange(len(points))], workers)
    coords, owners = [np.zeros((0, 2))], [np.zeros(0, dtype=np.int64)]
    n_edges = max(1, len(occ.edges))
    step = max(1, VIS_NEAR_BLOCK // n_edges)
    for i in range(0, len(points), step):
        pts = points[i : i + step]
        half = float(radius)
        lo, hi = pts - half, pts + half
        near = (
            (occ.hi[None, :, 0] >= lo[:, None, 0])
            & (occ.lo[None, :, 0] <= hi[:, None, 0])
            & (occ.hi[None, :, 1] >= lo[:, None, 1])
            & (occ.lo[None, :, 1] <= hi[:, None, 1])
        )
        # Sub-chunks of about VIS_SWEEP_EDGES near edges: bounds the rays.
        count = np.cumsum(near.sum(axis=1))
        start = 0
        while start < len(pts):
            stop = max(start + 1, int(np.searchsorted(count, (count[start - 1] if start else 0) + VIS_SWEEP_EDGES, side="right")))
            pi, ei = np.nonzero(near[start:stop])
            c, o = _sweep(pts[start:stop], pi, ei, occ, half)
            coords.append(c)
            owners.append(o + i + start)
            start = stop
    return np.concatenate(coords), np.concatenate(owners)


def polygons_of(coords: np.ndarray, owner: np.ndarray, n: int) -> np.ndarray:
    """(n,) shapely Polygons from :func:`visibility_polygons`' ragged output;
    an empty polygon for a point without vertices."""
    out = np.empty(n, dtype=object)
    out[:] = [shapely.Polygon()] * n
    present = np.unique(owner)
    if len(present):
        rings = shapely.linearrings(coords, indices=np.searchsorted(present, owner))
        out[present] = list(shapely.polygons(rings))
    return out


def _sweep(pts: np.ndarray, pi: np.ndarray, ei: np.ndarray, occ: Occluders, half: float) -> tuple[np.ndarray, np.ndarray]:
    """The sweep of :func:`mapkit.visibility.visibility_polygon` for the points
    ``pts`` (P, 2), given their near edges as pairs (``pi`` point, ``ei`` edge,
    grouped by point, edges in index order)."""
    n_pts = len(pts)
    lo, hi = pts - half, pts + half
    a, b = occ.edges[ei, 0], occ.edges[ei, 1]
    p = pts[pi]
    ab = b - a
    front = ab[:, 0] * (p[:, 1] - a[:, 1]) - ab[:, 1] * (p[:, 0] - a[:, 0]) < 0.0
    pi, a, b = pi[front], a[front], b[front]
    a, b, kept = clip_box(a, b, lo[pi], hi[pi])
    pi = pi[kept]
    # Each point's edges: its clipped edges in order, then its square's sides.
    sq = np.stack([lo, np.stack([hi[:, 0], lo[:, 1]], 1), hi, np.stack([lo[:, 0], hi[:, 1]], 1)], axis=1)
    sq_next = np.roll(sq, -1, axis=1)
    sq_owner = np.repeat(np.arange(n_pts), 4)
    order = np.argsort(np.concatenate([pi, sq_owner]), kind="stable")
    e_pt = np.concatenate([pi, sq_owner])[order]
    a = np.concatenate([a, sq.reshape(-1, 2)])[order]
    b = np.concatenate([b, sq_next.reshape(-1, 2)])[order]
    m = np.bincount(e_pt, minlength=n_pts)  # edges per point
    e0 = np.concatenate([[0], np.cumsum(m)[:-1]])  # first edge of each point
    # Rays: per point, its 2m vertices (all a's, then all b's) turned by
    # -off, then the same vertices turned by +off: 4m rays.
    r_pt = np.repeat(np.arange(n_pts), 4 * m)
    r0 = np.repeat(4 * e0, 4 * m)
    m_r = m[r_pt]  # each ray's point's edge count
    local = np.arange(len(r_pt)) - r0
    vert = local % (2 * m_r)
    plus = local >= 2 * m_r
    on_a = vert < m_r
    edge_of = e0[r_pt] + np.where(on_a, vert, vert - m_r)
    # One gather from the a's followed by the b's, not two and a choice.
    vx = np.concatenate([a, b])[np.where(on_a, edge_of, edge_of + len(a))] - pts[r_pt]
    theta = np.arctan2(vx[:, 1], vx[:, 0])
    off = math.radians(VIS_RAY_OFFSET_DEG)
    ang = np.mod(np.where(plus, theta + off, theta - off) + math.pi, 2.0 * math.pi) - math.pi
    d = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    # Rays sorted by point, then angle (stable). A vertex shared by two edges
    # casts the same rays twice: cast each distinct (point, angle) once.
    order = _by_group(ang, r_pt)
    new = np.ones(len(order), dtype=bool)
    new[1:] = (r_pt[order][1:] != r_pt[order][:-1]) | (ang[order][1:] != ang[order][:-1])
    cast = order[new]
    t = _nearest_hits(d[cast], r_pt[cast], a - pts[e_pt], b - a, e_pt, m, e0)
    back = np.empty_like(order)  # the inverse permutation of order (its argsort)
    back[order] = np.arange(len(order))
    t = t[np.cumsum(new) - 1][back]
    # Hidden vertices: both rays stop short (see visibility_polygon).
    r = np.hypot(vx[:, 0], vx[:, 1])
    short = t < r - VIS_HIDDEN_SLACK
    twin = np.where(plus, np.arange(len(t)) - 2 * m_r, np.arange(len(t)) + 2 * m_r)
    seen = ~(short & short[twin])
    # Per point, by angle, the first seen ray of each angle (as np.unique).
    order = order[seen[order]]
    pt_s, ang_s = r_pt[order], ang[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = (pt_s[1:] != pt_s[:-1]) | (ang_s[1:] != ang_s[:-1])
    keep = order[first]
    return pts[r_pt[keep]] + d[keep] * t[keep, None], r_pt[keep]


def _by_group(key: np.ndarray, group: np.ndarray) -> np.ndarray:
    """``np.lexsort((key, group))`` for (K,) ``group`` ids of this chunk's
    points (below ``2**31``): rows by group, then key, ties in row order.
    Two stable sorts, the second on ``group`` as small ints (numpy sorts
    16-bit ints by radix), cost less than the lexsort."""
    first = np.argsort(key, kind="stable")
    small = np.int16 if len(group) == 0 or int(group.max()) < 2**15 else np.int32
    return first[np.argsort(group[first].astype(small), kind="stable")]


def _nearest_hits(d, r_pt, a, e, e_pt, m, e0) -> np.ndarray:
    """:func:`mapkit.visibility._nearest_hits` for the rays of many points:
    ``d`` (K, 2) unit rays of points ``r_pt`` (K,); edges ``a + u e`` relative
    to their point, grouped by point ``e_pt`` (``m`` edges per point from
    ``e0``). Each point's edges are tried nearest first in doubling batches,
    and a ray stops as in the per-point sweep."""
    out = np.full(len(d), np.inf)
    ee = np.einsum("ij,ij->i", e, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.clip(np.where(ee > 0, -np.einsum("ij,ij->i", a, e) / ee, 0.0), 0.0, 1.0)
    reach = np.hypot(a[:, 0] + u * e[:, 0], a[:, 1] + u * e[:, 1])
    order = _by_group(reach, e_pt)  # stable: ties keep the edges' order
    a, e, reach = a[order], e[order], reach[order]
    cross = a[:, 0] * e[:, 1] - a[:, 1] * e[:, 0]
    rays = np.arange(len(d))
    start, batch = 0, VIS_FIRST_EDGES
    while len(rays):
        pt = r_pt[rays]
        count = np.minimum(m[pt], start + batch) - start
        out[rays] = np.minimum(_hits(d[rays], e0[pt] + start, count, a, e, cross), out[rays])
        start, batch = start + batch, 2 * batch
        more = m[pt] > start
        rays, pt = rays[more], pt[more]
        rays = rays[out[rays] > reach[e0[pt] + start]]
    return out


def _hits(d: np.ndarray, first: np.ndarray, count: np.ndarray, a, e, cross) -> np.ndarray:
    """Nearest hit of each ray ``d`` (K, 2) on its edges ``first[k] ..
    first[k] + count[k] - 1`` (rows of ``a``, ``e``, ``cross = a x e``); inf
    if none. The formulas of :func:`mapkit.visibility._hits_block`, on a
    (width, rays) grid: row j holds each ray's j-th edge (masked past its
    count), so every numpy loop runs along the rays. Blocks of about
    ``VIS_BLOCK`` ray-edge pairs."""
    out = np.full(len(d), np.inf)
    width = int(count.max(initial=0))
    if width == 0:
        return out
    fields = [np.concatenate([f, np.zeros(width)]) for f in (e[:, 0], e[:, 1], a[:, 0], a[:, 1], cross)]
    cols = np.arange(width)[:, None]
    step = max(1, VIS_BLOCK // width)
    for i in range(0, len(d), step):
        idx = first[i : i + step] + cols
        e0, e1, a0, a1, cr = (f[idx] for f in fields)
        d0, d1 = d[i : i + step, 0], d[i : i + step, 1]
        denom = d0 * e1 - d1 * e0
        with np.errstate(divide="ignore", invalid="ignore"):
            t = cr / denom
            u = (a0 * d1 - a1 * d0) / denom
        ok = (t > 0.0) & (u >= -ZERO.edge_parameter) & (u <= 1.0 + ZERO.edge_parameter) & (cols < count[i : i + step])
        out[i : i + step] = np.where(ok, t, np.inf).min(axis=0)
    return out


__all__ = ["polygons_of", "visibility_polygons"]
