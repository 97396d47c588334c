"""Visibility among opaque walls: visibility polygons of points, and the
region of the floor from which each model segment is visible.

Conventions (docs/visibility.md has the full definition):

- Floor points ``q`` and segment points ``s`` in metres, world frame, z up.
  The camera centre stands at ``(q, h)``; its heading is free.
- Occluders are wall solids seen from above (full height, opaque). For sight
  tests they are shrunk by ``OCCLUSION_SHRINK``, so that a sight line ending
  on the wall face its segment lies on is not blocked by float noise.
- Everything computed here is a *superset* of the exact set it stands for:
  circles become circumscribed polygons, disks removed become inscribed ones.
  The matcher may only ever lose speed, never a visible segment.

Public names: :class:`Occluders` (edge arrays ready for sweeps),
:func:`visibility_polygon`, :func:`distance_band`,
:func:`vertical_distance_band`, :func:`segment_regions` (and
:func:`segment_regions_within` of a :class:`Sight`, skipping what cannot
reach the free space; its time, predicted before it runs:
:mod:`mapkit.region_cost`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from mapkit.memory import release_memory
from mapkit.parallel import map_chunks
from mapkit.progress import step
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (
    CIRCLE_SIDES,
    OVERLAY_GRID,
    VIS_BLOCK,
    VIS_BUILD_SHRINK,
    VIS_COLLINEAR,
    VIS_FIRST_EDGES,
    VIS_HIDDEN_SLACK,
    VIS_RAY_OFFSET_DEG,
    VIS_VERTICAL_XY,
    VIS_WITHIN_MARGIN,
    ZERO,
)


# --------------------------------------------------------------------------
# Occluders as oriented edges


@dataclass(frozen=True)
class Occluders:
    """Edges of the shrunk occluders, oriented with the solid on their left.

    - ``edges`` (E, 2, 2) float: edge ``e`` runs from ``edges[e, 0]`` to
      ``edges[e, 1]``; exteriors counter-clockwise, holes clockwise.
    - ``lo``, ``hi`` (E, 2): per-edge bounding boxes (range culling).
    - ``geometry``: the shrunk occluders as one shapely geometry.
    """

    edges: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    geometry: object

    @classmethod
    def from_geometry(cls, occluders, shrink: float = VIS_BUILD_SHRINK) -> Occluders:
        """Shrink ``occluders`` (shapely (Multi)Polygon) by ``shrink`` metres and
        collect their edges; walls thinner than ``2 * shrink`` vanish (they are
        drawing noise at that scale)."""
        if occluders is None or occluders.is_empty:
            geom = shapely.MultiPolygon()
        else:
            if not occluders.is_valid:  # drawings self-intersect; shrinking needs a valid area
                occluders = shapely.MultiPolygon(polygon_parts(shapely.make_valid(occluders)))
            geom = shapely.buffer(occluders, -shrink, join_style="mitre")
            geom = shapely.orient_polygons(geom, exterior_cw=False)
        segs = []
        for poly in polygon_parts(geom):
            for ring in [poly.exterior, *poly.interiors]:
                pts = np.asarray(ring.coords)[:, :2]
                if len(pts) >= 4:  # closed ring: first point repeated
                    segs.append(np.stack([pts[:-1], pts[1:]], axis=1))
        edges = np.concatenate(segs) if segs else np.zeros((0, 2, 2))
        keep = np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1) > 0
        edges = edges[keep]
        return cls(edges, edges.min(axis=1), edges.max(axis=1), geom)


# --------------------------------------------------------------------------
# Visibility polygon of one point


def visibility_polygon(p: np.ndarray, occ: Occluders, radius: float) -> np.ndarray:
    """Star-shaped polygon of the floor points whose sight line to ``p`` is clear.

    ``p`` (2,) metres; returns the (K, 2) vertices, counter-clockwise around
    ``p``, within the square of half-side ``radius`` around ``p`` (callers
    intersect with disks of radius <= ``radius``). Exact up to the ray offset
    ``VIS_RAY_OFFSET_DEG``.

    Angular sweep, vectorised: rays just either side of every vertex of a
    front-facing edge (clipped to the square), nearest hit among those edges
    and the square's sides. Between two consecutive rays the nearest edge
    cannot change (the edges do not cross, and every endpoint is a ray), so
    joining the hits is exact. Edges
    facing away from ``p`` are never first hit (a ray enters a solid through
    a front face), which halves the work.
    """
    p = np.asarray(p, dtype=float)
    half = float(radius)
    lo, hi = p - half, p + half
    e = occ.edges
    near = (occ.hi[:, 0] >= lo[0]) & (occ.lo[:, 0] <= hi[0]) & (occ.hi[:, 1] >= lo[1]) & (occ.lo[:, 1] <= hi[1])
    a, b = e[near, 0], e[near, 1]
    ab = b - a
    # Solid on the left of a->b: the edge faces p iff p is strictly on its right.
    front = ab[:, 0] * (p[1] - a[:, 1]) - ab[:, 1] * (p[0] - a[:, 0]) < 0.0
    # Clip to the square: an edge crossing its side would switch the nearest
    # hit between two rays, and the chord joining them would cut the corner.
    a, b = clip_segments(a[front], b[front], lo, hi)
    sq = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    a = np.concatenate([a, sq])
    b = np.concatenate([b, np.roll(sq, -1, axis=0)])
    verts = np.concatenate([a, b]) - p
    theta = np.arctan2(verts[:, 1], verts[:, 0])
    off = math.radians(VIS_RAY_OFFSET_DEG)
    ang = np.mod(np.concatenate([theta - off, theta + off]) + math.pi, 2.0 * math.pi) - math.pi
    d = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    t = _nearest_hits(d, a - p, b - a)
    # A vertex both of whose rays stop short of it is hidden: the nearest
    # edge does not change at its angle, so its rays only add points along
    # an edge already in the polygon. Dropping them keeps the outline (up to
    # VIS_HIDDEN_SLACK next to grazed corners) with a fraction of the vertices.
    r = np.hypot(verts[:, 0], verts[:, 1])
    seen = np.tile((t[: len(r)] >= r - VIS_HIDDEN_SLACK) | (t[len(r) :] >= r - VIS_HIDDEN_SLACK), 2)
    ang, d, t = ang[seen], d[seen], t[seen]
    ang, first = np.unique(ang, return_index=True)
    return p + d[first] * t[first, None]


def clip_segments(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clip segments ``a -> b`` ((M, 2) each) to the box ``[lo, hi]`` (Liang-Barsky,
    vectorised); segments outside the box, or reduced to a point, are dropped."""
    a, b, _ = clip_box(a, b, lo, hi)
    return a, b


def clip_box(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`clip_segments`, also returning the (M,) bool mask of the segments
    kept; ``lo``, ``hi`` are (2,) for one box or (M, 2) for a box per segment."""
    lo, hi = np.broadcast_to(lo, a.shape), np.broadcast_to(hi, a.shape)
    d = b - a
    t0, t1 = np.zeros(len(a)), np.ones(len(a))
    keep = np.ones(len(a), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in (0, 1):
            flat = d[:, k] == 0
            keep &= ~flat | ((a[:, k] >= lo[:, k]) & (a[:, k] <= hi[:, k]))
            ta, tb = (lo[:, k] - a[:, k]) / d[:, k], (hi[:, k] - a[:, k]) / d[:, k]
            t0 = np.where(flat, t0, np.maximum(t0, np.minimum(ta, tb)))
            t1 = np.where(flat, t1, np.minimum(t1, np.maximum(ta, tb)))
    keep &= t1 > t0
    a, d, t0, t1 = a[keep], d[keep], t0[keep], t1[keep]
    return a + t0[:, None] * d, a + t1[:, None] * d, keep


def _nearest_hits(d: np.ndarray, a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Distance along unit rays ``d`` (K, 2) from the origin to the nearest of
    the edges ``a + u e``, u in [0, 1] (``a``, ``e`` (E, 2)); inf if none.

    Edges are tried nearest first, in batches that double in size: a ray
    whose hit so far is no farther than the next edge's distance from the
    origin cannot be cut shorter by that edge or any later one, so it stops
    there. In a room most rays end on its own walls after the first batch:
    the work grows with what each point sees, not with the whole plan."""
    out = np.full(len(d), np.inf)
    if len(a) == 0 or len(d) == 0:
        return out
    ee = np.einsum("ij,ij->i", e, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.clip(np.where(ee > 0, -np.einsum("ij,ij->i", a, e) / ee, 0.0), 0.0, 1.0)
    reach = np.hypot(a[:, 0] + u * e[:, 0], a[:, 1] + u * e[:, 1])
    order = np.argsort(reach, kind="stable")
    a, e, reach = a[order], e[order], reach[order]
    rays = np.arange(len(d))
    start, batch = 0, VIS_FIRST_EDGES
    while start < len(a) and len(rays):
        stop = min(len(a), start + batch)
        out[rays] = _hits_block(d[rays], a[start:stop], e[start:stop], out[rays])
        start, batch = stop, 2 * batch
        if start < len(a):
            rays = rays[out[rays] > reach[start]]
    return out


def _hits_block(d: np.ndarray, a: np.ndarray, e: np.ndarray, best: np.ndarray | None = None) -> np.ndarray:
    """Nearest hit of rays ``d`` (K, 2) on edges ``a + u e`` (E, 2), or ``best``
    (K,) where that is nearer (inf by default): the brute-force kernel of
    :func:`_nearest_hits`, in blocks of at most ``VIS_BLOCK`` ray-edge pairs."""
    out = np.empty(len(d))
    chunk = max(1, VIS_BLOCK // max(1, len(a)))
    for i in range(0, len(d), chunk):
        dd = d[i : i + chunk, None, :]
        denom = dd[..., 0] * e[None, :, 1] - dd[..., 1] * e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / denom
            u = (a[None, :, 0] * dd[..., 1] - a[None, :, 1] * dd[..., 0]) / denom
        # u within [0, 1] up to round-off: a ray through a shared vertex must
        # not slip between the two edges meeting there.
        ok = (t > 0.0) & (u >= -ZERO.edge_parameter) & (u <= 1.0 + ZERO.edge_parameter)
        out[i : i + chunk] = np.where(ok, t, np.inf).min(axis=1)
    return out if best is None else np.minimum(out, best)


# --------------------------------------------------------------------------
# Distance and elevation: which horizontal distances suit a point at height z


def distance_band(z: np.ndarray, h: float, e_min: float, e_max: float, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal distances ``d`` from which a point at height ``z`` is seen.

    Conditions (2) and (3) of the definition: the 3D distance from the camera
    centre (height ``h``) is <= ``max_range``, and the elevation
    ``atan2(z - h, d)`` lies in ``[e_min, e_max]`` (radians). For a fixed
    ``z`` both say ``dmin <= d <= dmax``. Returns ``(dmin, dmax)`` arrays shaped
    like ``z``; an empty band has ``dmax < 0`` (both are -1 then).
    """
    z = np.asarray(z, dtype=float)
    dz = z - h
    with np.errstate(invalid="ignore"):
        dmax = np.sqrt(max_range**2 - dz**2)
    dmax = np.where(np.abs(dz) <= max_range, dmax, -1.0)
    dmin = np.zeros_like(dz)
    tmin, tmax = math.tan(e_min), math.tan(e_max)
    up, down = dz > 0, dz < 0
    # Above the camera the elevation falls from 90 deg towards 0 as d grows.
    if e_max <= 0:
        dmax = np.where(up, -1.0, dmax)
    elif e_max < math.pi / 2:
        dmin = np.where(up, np.maximum(dmin, dz / tmax), dmin)
    if e_min > 0:
        dmax = np.where(up, np.minimum(dmax, dz / tmin), dmax)
    # Below it the elevation rises from -90 deg towards 0.
    if e_min >= 0:
        dmax = np.where(down, -1.0, dmax)
    elif e_min > -math.pi / 2:
        dmin = np.where(down, np.maximum(dmin, dz / tmin), dmin)
    if e_max < 0:
        dmax = np.where(down, np.minimum(dmax, dz / tmax), dmax)
    # Level with the camera: elevation 0 at every distance.
    if not e_min <= 0.0 <= e_max:
        dmax = np.where(dz == 0, -1.0, dmax)
    empty = dmax < dmin
    return np.where(empty, -1.0, dmin), np.where(empty, -1.0, dmax)


def vertical_extent(d: np.ndarray, z0: np.ndarray, z1: np.ndarray, h: float, e_min: float, e_max: float, max_range: float) -> np.ndarray:
    """Length of the part of vertical segments ``[z0, z1]`` seen from
    horizontal distance ``d`` (all arrays broadcast); negative if none.

    Concave in ``d`` (a min of concave bounds minus a max of convex ones), so
    the distances where it exceeds a threshold form one interval."""
    d = np.asarray(d, dtype=float)
    reach = np.sqrt(np.maximum(max_range**2 - d**2, 0.0))
    reach = np.where(d <= max_range, reach, -np.inf)
    top = np.minimum(np.minimum(z1, h + d * math.tan(min(e_max, 1.5707))), h + reach)
    bot = np.maximum(np.maximum(z0, h + d * math.tan(max(e_min, -1.5707))), h - reach)
    return top - bot


def vertical_distance_band(z0, z1, need, h, e_min, e_max, max_range) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal distances from which vertical segments ``[z0, z1]`` (arrays
    (M,)) show a visible extent >= ``need`` (M,). Returns ``(dmin, dmax)``,
    widened outwards by 1 um; ``dmax < 0`` (both -1) when never.

    The extent is concave in ``d``: a ternary search finds its maximum, then
    bisections find where it crosses ``need`` on either side."""
    z0, z1, need = (np.asarray(v, dtype=float) for v in (z0, z1, need))

    def f(d):
        return vertical_extent(d, z0, z1, h, e_min, e_max, max_range) - need

    lo, hi = np.zeros_like(z0), np.full_like(z0, max_range)
    for _ in range(80):  # ternary search: interval shrinks by 2/3 per step
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        left = f(m1) < f(m2)
        lo, hi = np.where(left, m1, lo), np.where(left, hi, m2)
    peak = (lo + hi) / 2
    ok = f(peak) >= 0
    # Bisect [0, peak] for the first distance that qualifies, [peak, R] for the last.
    a, b = np.zeros_like(peak), peak.copy()
    c, e = peak.copy(), np.full_like(peak, max_range)
    for _ in range(60):
        m = (a + b) / 2
        good = f(m) >= 0
        a, b = np.where(good, a, m), np.where(good, m, b)
        m = (c + e) / 2
        good = f(m) >= 0
        c, e = np.where(good, m, c), np.where(good, e, m)
    dmin = np.where(f(np.zeros_like(peak)) >= 0, 0.0, a)
    dmax = np.where(f(np.full_like(peak, max_range)) >= 0, max_range, e)
    dmin, dmax = np.maximum(dmin - ZERO.derived_length, 0.0), dmax + ZERO.derived_length
    return np.where(ok, dmin, -1.0), np.where(ok, dmax, -1.0)


def annuli(centres: np.ndarray, r_in: np.ndarray, r_out: np.ndarray, sides: int = CIRCLE_SIDES) -> np.ndarray:
    """Shapely polygons ``r_in <= |q - c| <= r_out`` as supersets: the outer
    circle circumscribed, the inner one inscribed (it is removed). ``centres``
    (M, 2), radii (M,); ``r_in <= 0`` gives a disk. Returns an (M,) object array."""
    phi = np.linspace(0.0, 2.0 * math.pi, sides, endpoint=False)
    ring = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    outer = centres[:, None, :] + (r_out / math.cos(math.pi / sides))[:, None, None] * ring[None]
    shells = shapely.linearrings(outer)
    out = np.empty(len(centres), dtype=object)
    disk = r_in <= 0
    out[disk] = shapely.polygons(shells[disk])
    if (~disk).any():
        inner = centres[~disk, None, :] + r_in[~disk, None, None] * ring[None, ::-1]
        holes = shapely.linearrings(inner)
        out[~disk] = shapely.polygons(shells[~disk], holes[:, None])
    return out


# --------------------------------------------------------------------------
# Per-segment visibility regions


def polygonal(geoms: np.ndarray) -> np.ndarray:
    """The areal part of each geometry of an (M,) object array: overlays of
    touching polygons may return collections with stray lines or points."""
    geoms = np.asarray(geoms, dtype=object)
    out = geoms.copy()
    for k in np.nonzero(shapely.get_type_id(geoms) == 7)[0]:  # GeometryCollection
        parts = [g for g in polygon_parts(geoms[k]) if g.area > 0]
        out[k] = shapely.MultiPolygon(parts) if parts else Polygon()
    return out


def _simplified(raw: np.ndarray) -> np.ndarray:
    """Visibility polygons without their collinear vertices (within
    ``VIS_COLLINEAR``), each kept as it was where dropping them would make it
    invalid."""
    vp = shapely.simplify(raw, VIS_COLLINEAR, preserve_topology=False)
    bad = ~shapely.is_valid(vp)
    vp[bad] = raw[bad]
    return vp


def _overlap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The areal part of ``a & b``, elementwise, on the overlay grid."""
    return polygonal(shapely.intersection(a, b, grid_size=OVERLAY_GRID))


@dataclass
class SegmentRegions:
    """What :func:`segment_regions` returns.

    - ``regions``: (N,) object array of shapely geometries, ``R_S`` for each
      segment (empty geometry when never visible); not clipped to free space.
    - ``stats``: counts and timings (JSON-able).
    """

    regions: np.ndarray
    stats: dict


def sample_segment(seg: np.ndarray, spacing: float) -> np.ndarray:
    """(n, 3) points along ``seg`` (2, 3), end points included, spaced <= ``spacing``."""
    length = float(np.linalg.norm(seg[1] - seg[0]))
    n = max(1, math.ceil(length / spacing - ZERO.whole_number))
    t = np.linspace(0.0, 1.0, n + 1)
    return seg[0] + t[:, None] * (seg[1] - seg[0])


@dataclass
class _Samples:
    """The sample points of :func:`segment_regions` and the pairs of
    consecutive samples whose visibility polygons are overlaid.

    - ``xy`` (P, 2): distinct sample points (floor and ceiling edges share
      theirs), rounded to 1e-7 m;
    - ``vert_ids`` (V,) ids of the vertical segments, ``vert_keys`` (V,)
      the row of ``xy`` each stands at;
    - per pair of consecutive samples of a non-vertical segment (K,):
      ``pair_seg`` its segment, ``pair_a``, ``pair_b`` the rows of ``xy`` of
      its two samples, ``pair_mid`` (K, 2) their midpoint, ``pair_rin``,
      ``pair_rout`` the radii of the annulus bounding both distance bands.
    """

    xy: np.ndarray
    vert_ids: np.ndarray
    vert_keys: np.ndarray
    pair_seg: np.ndarray
    pair_a: np.ndarray
    pair_b: np.ndarray
    pair_mid: np.ndarray
    pair_rin: np.ndarray
    pair_rout: np.ndarray


@dataclass(frozen=True)
class Sight:
    """What a segment's visibility depends on besides the walls: the camera
    height ``h`` (m), its (lowest, highest) ``elevation`` angles (radians),
    ``max_range`` and ``min_visible_length`` (m)."""

    h: float
    elevation: tuple[float, float]
    max_range: float
    min_visible_length: float


def _pair_annuli(pts: np.ndarray, dmin: np.ndarray, dmax: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(seen, r_in, r_out)`` (K,) each, for the pairs of samples ``j`` and
    ``j + 1`` of ``pts`` (n, 3) (``j`` (K,) rows, both of one segment): the
    annulus around their midpoint that bounds both their distance bands
    (:func:`segment_regions`), and ``seen`` False where the pair is never
    seen (its radii are then meaningless). Elementwise, one formula per pair."""
    d0, d1 = dmax[j], dmax[j + 1]
    step_xy = pts[j + 1, :2] - pts[j, :2]
    delta2 = step_xy[:, 0] ** 2 + step_xy[:, 1] ** 2
    r_out2 = (d0**2 + d1**2) / 2.0 - delta2 / 4.0
    r_in2 = np.minimum(dmin[j], dmin[j + 1]) ** 2 - delta2 / 4.0
    # One sample never seen: the pair never is; nor is it with an empty annulus.
    seen = ~((d0 < 0) | (d1 < 0)) & ~(r_out2 <= np.maximum(r_in2, 0.0))
    with np.errstate(invalid="ignore"):
        r_in = np.where(r_in2 > 0, np.sqrt(np.maximum(r_in2, 0.0)), 0.0)
        r_out = np.sqrt(np.where(seen, r_out2, 0.0))
    return seen, r_in, r_out


def _samples(segs: np.ndarray, vertical: np.ndarray, sight: Sight) -> _Samples:
    """Sample every segment of ``segs`` (N, 2, 3) (``vertical`` (N,) bool:
    one sample at its xy point; else spaced <= ``min_visible_length / 2``)
    and pair the consecutive samples seen from a common annulus.

    Points are keyed by their xy rounded to 1e-7 m, numbered in order of
    first appearance (the vertical segments' points, then each other
    segment's samples in order); pairs come in segment order, then along
    the segment."""
    e_min, e_max = sight.elevation
    vert_ids = np.nonzero(vertical)[0]
    slanted = np.nonzero(~vertical)[0]
    parts = [sample_segment(segs[i], sight.min_visible_length / 2.0) for i in slanted]
    counts = np.array([len(p) for p in parts], dtype=np.int64)
    pts = np.concatenate(parts) if parts else np.zeros((0, 3))
    dmin, dmax = distance_band(pts[:, 2], sight.h, e_min, e_max, sight.max_range)

    keys: dict[tuple[float, float], int] = {}
    all_xy = np.concatenate([segs[vert_ids, 0, :2].reshape(-1, 2), pts[:, :2]]).tolist()
    ids = [keys.setdefault((round(x, 7), round(y, 7)), len(keys)) for x, y in all_xy]
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    vert_keys, ks = ids[: len(vert_ids)], ids[len(vert_ids) :]

    # Consecutive samples of one segment: every row but each segment's last.
    last = np.cumsum(counts) - 1
    j = np.setdiff1d(np.arange(len(pts), dtype=np.int64), last, assume_unique=True)
    seen, r_in, r_out = _pair_annuli(pts, dmin, dmax, j)
    j = j[seen]
    xy = np.array(list(keys)).reshape(-1, 2)
    return _Samples(xy, vert_ids, vert_keys, np.repeat(slanted, counts)[j].astype(np.int64), ks[j], ks[j + 1],
                    ((pts[j, :2] + pts[j + 1, :2]) / 2.0).reshape(-1, 2), r_in[seen], r_out[seen])


def _sample_polygons(xy: np.ndarray, occ: Occluders, max_range: float, progress: bool, workers: int,
                     within=None, used=None) -> np.ndarray:
    """(P,) the visibility polygon of each point of ``xy`` (P, 2) within
    ``max_range``, collinear vertices dropped, empty for a point buried in a
    wall, and empty for a point that cannot see anything of ``within``
    (:func:`_cut_off`; None: every point is swept) or that no overlay uses
    (``used`` (P,) bool False; None: all are used)."""
    box = max_range / math.cos(math.pi / CIRCLE_SIDES) + 0.01
    from mapkit.visibility_batch import polygons_of, visibility_polygons

    swept = np.arange(len(xy)) if used is None else np.nonzero(used)[0]
    if within is not None:
        swept = swept[~_cut_off(xy[swept], occ, box, within)]
    with step("visibility polygons", progress):
        coords, owner = visibility_polygons(xy[swept], occ, box, workers)
        raw = polygons_of(coords, swept[owner], len(xy))
    # Rays hitting one edge give collinear points; each later overlay pays per
    # vertex, so drop them (the outline moves by at most VIS_COLLINEAR m).
    vp = map_chunks(_simplified, [raw], workers)
    del raw  # the largest arrays of the stage: free them before the overlays
    release_memory()
    # A point inside a (shrunk) wall is seen from nowhere: every sight line
    # from outside crosses the solid. The sweep, which skips edges facing
    # away, would instead see through that wall.
    if len(xy):
        buried = shapely.contains_xy(occ.geometry, xy[:, 0], xy[:, 1])
        vp[buried] = Polygon()
    return vp


def _cut_off(xy: np.ndarray, occ: Occluders, box: float, within) -> np.ndarray:
    """(P,) bool: the points of ``xy`` (P, 2) whose open space stays
    ``VIS_WITHIN_MARGIN`` away from ``within``: the part of the plane
    outside the (shrunk) occluders that holds them, within the squares of
    half-side ``box`` the sweep looks at (a shaft no door leads to, a room
    left out of the free space). A sight line leaves that part only through
    an occluder, so the point's visibility polygon lies in it and shows
    nothing of ``within``; its sweep is skipped. A point buried in an
    occluder lies in no part and is swept as before."""
    if not len(xy):
        return np.zeros(0, dtype=bool)
    (x0, y0), (x1, y1) = xy.min(axis=0) - box, xy.max(axis=0) + box
    parts = shapely.get_parts(shapely.difference(shapely.box(x0, y0, x1, y1), occ.geometry))
    near = shapely.buffer(within, VIS_WITHIN_MARGIN, join_style="mitre")
    shapely.prepare(near)
    apart = parts[~shapely.intersects(near, parts)]
    if not len(apart):
        return np.zeros(len(xy), dtype=bool)
    apart = shapely.multipolygons(apart)
    shapely.prepare(apart)
    return shapely.contains_xy(apart, xy[:, 0], xy[:, 1])


def _samples_reaching(samples: _Samples, sight: Sight, within) -> tuple[_Samples, np.ndarray]:
    """``samples`` without the pairs whose annulus (its outer circle
    circumscribed, as :func:`annuli` makes it) and the vertical segments
    whose sight range stays ``VIS_WITHIN_MARGIN`` away from ``within``: their
    pieces lie in those disks, so they cannot meet it (a tile's segments near
    its border, computed again by the next tile: their samples beyond the
    sight range of the tile are not swept). Also (P,) bool, the points of
    ``samples.xy`` the rest use."""
    grow = 1.0 / math.cos(math.pi / CIRCLE_SIDES)
    shapely.prepare(within)
    k = shapely.distance(within, shapely.points(samples.pair_mid)) <= samples.pair_rout * grow + VIS_WITHIN_MARGIN
    v = (shapely.distance(within, shapely.points(samples.xy[samples.vert_keys]))
         <= sight.max_range * grow + VIS_WITHIN_MARGIN)
    kept = _Samples(samples.xy, samples.vert_ids[v], samples.vert_keys[v], samples.pair_seg[k], samples.pair_a[k],
                    samples.pair_b[k], samples.pair_mid[k], samples.pair_rin[k], samples.pair_rout[k])
    used = np.zeros(len(samples.xy), dtype=bool)
    used[kept.vert_keys] = used[kept.pair_a] = used[kept.pair_b] = True
    return kept, used


def _samples_seeing(samples: _Samples, vp: np.ndarray, within) -> _Samples:
    """``samples`` without the vertical segments and the pairs that a
    sample's visibility polygon ``vp`` (P,) shows nothing of ``within``
    from: nothing of it lies within ``VIS_WITHIN_MARGIN`` of that polygon
    (far more than the overlay grid moves a piece)."""
    near = shapely.buffer(within, VIS_WITHIN_MARGIN, join_style="mitre")
    shapely.prepare(near)
    sees = shapely.intersects(near, vp)
    v = sees[samples.vert_keys]
    k = sees[samples.pair_a] & sees[samples.pair_b]
    return _Samples(samples.xy, samples.vert_ids[v], samples.vert_keys[v], samples.pair_seg[k], samples.pair_a[k],
                    samples.pair_b[k], samples.pair_mid[k], samples.pair_rin[k], samples.pair_rout[k])


def _vertical_regions(regions: np.ndarray, segs: np.ndarray, samples: _Samples, vp: np.ndarray, sight: Sight,
                      workers: int) -> None:
    """Fill ``regions`` at the vertical segments: the visibility polygon of
    each one's xy point within the distance band where its visible z-extent
    reaches min(L, its length)."""
    vert_ids, vert_keys = samples.vert_ids, samples.vert_keys
    if not len(vert_ids):
        return
    z = np.sort(segs[vert_ids, :, 2], axis=1)
    need = np.minimum(sight.min_visible_length, z[:, 1] - z[:, 0])
    e_min, e_max = sight.elevation
    dmin, dmax = vertical_distance_band(z[:, 0], z[:, 1], need, sight.h, e_min, e_max, sight.max_range)
    ok = dmax >= 0
    if ok.any():
        idx = np.nonzero(ok)[0]
        ann = annuli(samples.xy[vert_keys[idx]], dmin[idx], dmax[idx])
        regions[vert_ids[idx]] = map_chunks(_overlap, [vp[vert_keys[idx]], ann], workers)


def _pair_pieces(samples: _Samples, vp: np.ndarray, progress: bool, workers: int) -> np.ndarray:
    """(K,) ``V(s_i) & V(s_j)`` within each pair's annulus; the polygon
    overlay is made once for pairs of the same two points."""
    n_xy = len(samples.xy)
    pa, pb = samples.pair_a, samples.pair_b
    lo_k, hi_k = np.minimum(pa, pb), np.maximum(pa, pb)
    uniq, inv = np.unique(lo_k * n_xy + hi_k, return_inverse=True)
    ua, ub = uniq // n_xy, uniq % n_xy
    with step("visibility overlaps", progress):
        both = map_chunks(lambda a, b: _overlap(vp[a], vp[b]), [ua, ub], workers)
        return map_chunks(
            lambda k, mid, r_in, r_out: polygonal(shapely.intersection(both[k], annuli(mid, r_in, r_out))),
            [inv, samples.pair_mid, samples.pair_rin, samples.pair_rout],
            workers,
        )


def _unite_pieces(regions: np.ndarray, pieces: np.ndarray, pair_seg: np.ndarray, progress: bool,
                  workers: int) -> np.ndarray:
    """``regions`` with each segment's pair pieces (``pair_seg`` (K,) the
    segment of each) united in place of its entry where it has any."""
    n = len(regions)
    order = np.argsort(pair_seg, kind="stable")
    bounds = np.searchsorted(pair_seg[order], np.arange(n + 1))

    def unite(ids: np.ndarray) -> np.ndarray:
        return polygonal(np.array([shapely.union_all(pieces[order[bounds[i] : bounds[i + 1]]]) for i in ids] + [None])[:-1])

    # Only the segments with pieces are shared out among the threads (the
    # vertical ones, a block at the end, have none: even chunks of all ids
    # would leave some threads idle).
    united = np.nonzero(bounds[1:] > bounds[:-1])[0]
    out = regions.copy()
    with step("segment regions", progress):
        if len(united):
            out[united] = map_chunks(unite, [united], workers)
    return out


def segment_regions(
    segments: np.ndarray,
    occ: Occluders,
    h: float,
    elevation: tuple[float, float],
    *,
    max_range: float,
    min_visible_length: float,
    progress: bool = False,
    workers: int = 1,
) -> SegmentRegions:
    """For every segment S, a region R_S containing every floor point S is visible from.

    ``segments`` (N, 2, 3) metres; ``h`` camera height; ``elevation`` the
    camera's (lowest, highest) elevation angles, radians.

    Non-vertical S: samples ``s_i`` spaced <= L/2 (``L = min_visible_length``).
    A seen piece of length >= L holds two consecutive samples, so
    ``R_S = U_i V(s_i) & V(s_i+1)``, where ``V(s)`` is the visibility polygon
    of ``s_xy`` within its distance band. The two bands of a pair are bounded
    together by one annulus around the pair's midpoint ``m`` (``delta`` apart):
    ``|q-m|^2 <= (dmax_i^2 + dmax_j^2)/2 - delta^2/4`` holds in both outer disks,
    and the disk ``|q-m| <= sqrt(min dmin^2 - delta^2/4)`` lies in their union.
    Vertical S: visibility polygon of its xy point within the distance band
    where its visible z-extent reaches min(L, its length).

    The overlays run in ``workers`` threads (:mod:`mapkit.parallel`); the
    regions do not depend on it.
    """
    sight = Sight(h, elevation, max_range, float(min_visible_length))
    return segment_regions_within(segments, occ, sight, None, progress=progress, workers=workers)


def segment_regions_within(segments: np.ndarray, occ: Occluders, sight: Sight, within, *, progress: bool = False,
                           workers: int = 1) -> SegmentRegions:
    """:func:`segment_regions` for the regions' use ``within`` a shapely
    (Multi)Polygon, the free space (None: everywhere), ``sight`` saying
    what visible means.

    A piece can only meet ``within`` if both its samples see some of it, so
    sample points walled off from it are not swept, and pieces (and
    vertical segments) whose visibility polygon stays ``VIS_WITHIN_MARGIN``
    away from it are left out: ``R_S & within`` is unchanged, and a segment
    seen from nowhere in it gets an empty region.
    """
    import time

    t0 = time.perf_counter()
    segs = np.asarray(segments, dtype=float).reshape(-1, 2, 3)
    n = len(segs)
    vertical = np.linalg.norm(segs[:, 1, :2] - segs[:, 0, :2], axis=1) <= VIS_VERTICAL_XY
    samples = _samples(segs, vertical, sight)
    t_sample = time.perf_counter()

    sample_pairs = len(samples.pair_seg)  # all of them, whether overlaid or not
    used = None
    if within is not None:
        samples, used = _samples_reaching(samples, sight, within)
    vp = _sample_polygons(samples.xy, occ, sight.max_range, progress, workers, within, used)
    t_vis = time.perf_counter()

    if within is not None:
        samples = _samples_seeing(samples, vp, within)
    regions = np.array([Polygon()] * n, dtype=object)
    _vertical_regions(regions, segs, samples, vp, sight, workers)
    n_pairs = len(samples.pair_seg)
    if n_pairs:
        pieces = _pair_pieces(samples, vp, progress, workers)
        del vp  # the pieces hold what the union needs
        release_memory()
        regions = _unite_pieces(regions, pieces, samples.pair_seg, progress, workers)
    t_union = time.perf_counter()
    stats = {
        "segments": n,
        "vertical_segments": int(vertical.sum()),
        "visibility_polygons": len(samples.xy),
        "sample_pairs": int(sample_pairs),
        "time_sampling_s": t_sample - t0,
        "time_visibility_polygons_s": t_vis - t_sample,
        "time_segment_regions_s": t_union - t_vis,
    }
    return SegmentRegions(regions, stats)


__all__ = [
    "Occluders",
    "SegmentRegions",
    "Sight",
    "annuli",
    "distance_band",
    "polygonal",
    "sample_segment",
    "segment_regions",
    "segment_regions_within",
    "vertical_distance_band",
    "vertical_extent",
    "visibility_polygon",
]
