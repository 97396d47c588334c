"""Brute-force visibility, independent of mapkit.visibility: the ground truth
the harness makes frames and synthetic maps from and checks the builder
against.

Three questions, two sight tests. :func:`crosses_an_edge` (a proper
crossing of an occluder edge: touching an edge or a corner, or running
along one, does not block) is the one test of the simulator and of the
region builder's reference; they differ in their occluders, each for a
reason below. The synthetic buildings' region lists keep shapely's test:

- :func:`sight_blocked`, the reference for **what a camera sees** in the
  simulator (:func:`mapkit_harness.simulate.visible_lines`, hence every
  frame of ``simulate.make_frame`` and ``runs.simulate_run``, the tests'
  and benchmarks' seeded frames). Occluders are the map's wall outlines
  exactly (``simulate.wall_edges``), unshrunk: a camera must not see
  through a wall by a tolerance. The targets lie on wall faces, so each
  sight line is shortened by 2 mm at its far end instead.
- :class:`VisibilityOracle`, the reference for **the region builder**
  (``tests/test_visibility.py``, ``tests/test_vir.py``,
  ``tools/bench_vir.py``): the segments visible from a floor point under
  the builder's own definition (docs/visibility.md), below. Occluders are
  shrunk by twice the builder's ``OCCLUSION_SHRINK`` with mitred corners
  (``occluder_edges``), so the reference sees slightly more than the
  builder assumes: a stricter check of the builder's superset guarantee;
  nothing is shortened, since the shrink already leaves targets on wall
  faces clear.
- :func:`visible_lists`, the reference for **the synthetic buildings'
  region lists** (``plans.buildings``: ``make_flat_map``,
  ``make_small_flat``), written into their maps: the bytes of those maps
  depend on it, so it stays as written. Per region, a segment is listed if
  ``min_seen`` metres of its ``samples`` mid-sample points are unoccluded
  from some sample point of the region (a grid inside and points along its
  outline). Occluders are the wall polygons shrunk by 2 mm with round
  corners (shapely's default buffer), and a sight line is blocked if it
  meets them at all (``shapely.intersects``: touching counts). It is not
  :func:`crosses_an_edge` on the edges of those shrunk walls because that
  changes a map: measured, ``make_small_flat``'s bytes stayed the same but
  ``make_flat_map``'s changed (round corners, touching lines; a list is
  asked of every sample point of a region against every sample of every
  segment, so a grazing case does turn up), and it was no faster (262 s
  against shapely's 202 s for ``make_flat_map``).

:class:`VisibilityOracle`, straight from the definition in
docs/visibility.md, point by point: every segment is sampled every ``step``
metres; a sample is seen from the floor point q if its distance and
elevation suit the camera and the open 2D sight line from q to it crosses
no occluder edge; a segment is visible if a run of
consecutive seen samples spans at least ``min_visible_length`` (a segment
shorter than that: every sample).
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from mapkit.shapes import rings_of
from mapkit.tolerances import OCCLUSION_SHRINK


def crosses_an_edge(origin: np.ndarray, targets: np.ndarray, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """(M,) bool: the open segment from ``origin`` (2,) to each of ``targets``
    (M, 2) properly crosses one of the edges ``ea`` -> ``eb`` (E, 2): both
    orientation tests strict, so touching an edge or a corner, or running
    along an edge, does not count. The one sight test of the simulator and
    of :class:`VisibilityOracle` (their occluders differ, not the test)."""
    q = np.asarray(origin, dtype=float)
    targets = np.asarray(targets, dtype=float)
    ea, eb = np.asarray(ea, dtype=float), np.asarray(eb, dtype=float)
    # The orientation tests cross(u, v) = u.x v.y - u.y v.x, written out on
    # x and y arrays of their own: the same differences and products as on
    # stacked (..., 2) vectors, so the same floating-point values, without
    # the (targets, edges, 2) temporaries. o3 depends on the edges alone.
    ax, ay = ea[:, 0] - q[0], ea[:, 1] - q[1]  # ea - q
    bx, by = eb[:, 0] - q[0], eb[:, 1] - q[1]  # eb - q
    dx, dy = eb[:, 0] - ea[:, 0], eb[:, 1] - ea[:, 1]  # eb - ea
    o3 = dx * (q[1] - ea[:, 1]) - dy * (q[0] - ea[:, 0])  # cross(eb - ea, q - ea)
    lo_e, hi_e = np.minimum(ea, eb), np.maximum(ea, eb)
    out = np.zeros(len(targets), dtype=bool)
    for i in range(0, len(targets), 2000):
        chunk = targets[i : i + 2000]
        # Only the edges whose bounding boxes meet that of this chunk's sight
        # lines can cross one (a millimetre of margin keeps the cut clear of
        # rounding): the same test against far fewer edges.
        lo, hi = np.minimum(q, chunk.min(axis=0)) - 1e-3, np.maximum(q, chunk.max(axis=0)) + 1e-3
        e = np.flatnonzero((lo_e <= hi).all(axis=1) & (hi_e >= lo).all(axis=1))
        if not len(e):
            continue
        sx, sy = chunk[:, 0, None], chunk[:, 1, None]
        ux, uy = sx - q[0], sy - q[1]  # s - q
        o1 = ux * ay[e] - uy * ax[e]  # cross(s - q, ea - q)
        o2 = ux * by[e] - uy * bx[e]  # cross(s - q, eb - q)
        o4 = dx[e] * (sy - ea[e, 1]) - dy[e] * (sx - ea[e, 0])  # cross(eb - ea, s - ea)
        out[i : i + 2000] = ((o1 * o2 < 0) & (o3[e] * o4 < 0)).any(axis=1)
    return out


def longest_run(flags: np.ndarray) -> tuple[int, int]:
    """First and last index of the first longest run of True in ``flags`` (S,) (one True at least)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flags.astype(np.int8), [0]])))
    starts, ends = edges[0::2], edges[1::2]
    k = int(np.argmax(ends - starts))
    return int(starts[k]), int(ends[k]) - 1


def sight_blocked(c: np.ndarray, q: np.ndarray, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """(S,) bool: sight lines from c (2,) to points q (S, 2) cross a wall edge.

    Sight lines are shortened by 2 mm at q, which lies on a wall face."""
    d = q - c
    ln = np.linalg.norm(d, axis=1, keepdims=True)
    return crosses_an_edge(c, c + d * np.maximum(ln - 2e-3, 0) / np.maximum(ln, 1e-12), ea, eb)


def _sample_points(reg, spacing: float) -> np.ndarray:
    """Points of a region: a grid inside plus points along its outline."""
    x0, y0, x1, y1 = reg.bounds
    gx, gy = np.meshgrid(np.arange(x0 + spacing / 2, x1, spacing), np.arange(y0 + spacing / 2, y1, spacing))
    pts = np.stack([gx.ravel(), gy.ravel()], 1)
    pts = pts[shapely.contains_xy(reg, pts[:, 0], pts[:, 1])]
    outline = []
    for ring, _ in rings_of(reg):
        closed = np.vstack([ring, ring[:1]])
        for a, b in zip(closed[:-1], closed[1:]):
            n = max(1, int(np.ceil(np.hypot(*(b - a)) / spacing)))
            outline.append(a + np.linspace(0, 1, n, endpoint=False)[:, None] * (b - a))
    return np.concatenate([pts] + outline)


def visible_lists(regions, segments, walls, spacing: float = 0.25, samples: int = 10,
                  min_seen: float = 0.1) -> list[np.ndarray]:
    """Per region, the segments with ``min_seen`` metres unoccluded from some
    sample point of the region (a grid plus its outline; brute force, shapely)."""
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
        seen = ((~blocked).sum(axis=2) * seg_len / samples >= min_seen).any(axis=0)
        lists.append(np.nonzero(seen)[0])
    return lists


def occluder_edges(occluders, shrink: float) -> np.ndarray:
    """(E, 2, 2) edges of every ring of ``occluders`` shrunk by ``shrink``."""
    geom = shapely.buffer(occluders, -shrink, join_style="mitre")
    edges = []
    for ring in shapely.get_rings(shapely.get_parts(geom)):
        pts = shapely.get_coordinates(ring)
        edges.append(np.stack([pts[:-1], pts[1:]], axis=1))
    return np.concatenate(edges) if edges else np.zeros((0, 2, 2))


class VisibilityOracle:
    """``visible(q)``: sorted ids of the segments visible from floor point q.

    ``segments`` (N, 2, 3) metres; ``height`` camera height; ``elevation``
    (lowest, highest) elevation angles, radians.
    """

    def __init__(self, segments, occluders, height, elevation, max_range, min_visible_length, step=0.01):
        self.h = float(height)
        self.e_min, self.e_max = elevation
        self.max_range = float(max_range)
        self.L = float(min_visible_length)
        self.edges = occluder_edges(occluders, 2 * OCCLUSION_SHRINK)
        segs = np.asarray(segments, dtype=float)
        pts, owner, spacing, counts = [], [], [], []
        for i, (a, b) in enumerate(segs):
            length = float(np.linalg.norm(b - a))
            k = max(1, math.ceil(length / step))
            t = np.linspace(0.0, 1.0, k + 1)
            pts.append(a + t[:, None] * (b - a))
            owner.append(np.full(k + 1, i))
            spacing.append(length / k)
            counts.append(k + 1)
        self.points = np.concatenate(pts)
        self.owner = np.concatenate(owner)
        self.spacing = np.array(spacing)
        self.lengths = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
        self.start = np.concatenate([[0], np.cumsum(counts)])
        # Samples above one another (a vertical segment, segments over one
        # wall line) share one sight line: each floor point is tested once.
        self.floor_points, self.floor_point_of = np.unique(self.points[:, :2], axis=0, return_inverse=True)
        self.floor_point_of = self.floor_point_of.ravel()

    def seen_samples(self, q) -> np.ndarray:
        """(P,) bool: which samples are seen from q."""
        q = np.asarray(q, dtype=float)
        rel = self.points[:, :2] - q
        d = np.hypot(rel[:, 0], rel[:, 1])
        dz = self.points[:, 2] - self.h
        elev = np.arctan2(dz, d)
        ok = (np.hypot(d, dz) <= self.max_range) & (elev >= self.e_min) & (elev <= self.e_max)
        cand = np.nonzero(ok)[0]
        if len(cand) == 0:
            return ok
        wanted = np.zeros(len(self.floor_points), dtype=bool)
        wanted[self.floor_point_of[cand]] = True
        tested = np.nonzero(wanted)[0]
        clear = np.zeros(len(self.floor_points), dtype=bool)
        clear[tested] = self._clear(q, self.floor_points[tested])
        ok[cand] = clear[self.floor_point_of[cand]]
        return ok

    def _clear(self, q, targets) -> np.ndarray:
        """(M,) bool: the open segment q -> target crosses no occluder edge."""
        return ~crosses_an_edge(q, targets, self.edges[:, 0], self.edges[:, 1])

    def visible(self, q) -> np.ndarray:
        """Sorted int64 ids of the segments visible from q."""
        seen = self.seen_samples(q)
        ids = []
        for i in range(len(self.lengths)):
            run = seen[self.start[i] : self.start[i + 1]]
            if not run.any():
                continue
            if self.lengths[i] < self.L:
                if run.all():
                    ids.append(i)
                continue
            # Longest run of consecutive seen samples, as a length.
            first, last = longest_run(run)
            longest = last - first + 1
            if (longest - 1) * self.spacing[i] >= self.L - 1e-9:
                ids.append(i)
        return np.array(ids, dtype=np.int64)


def random_points(geom, n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, 2) points drawn uniformly in the shapely area ``geom``."""
    x0, y0, x1, y1 = geom.bounds
    out = []
    while sum(len(o) for o in out) < n:
        p = rng.uniform([x0, y0], [x1, y1], size=(4 * n, 2))
        out.append(p[shapely.contains_xy(geom, p[:, 0], p[:, 1])])
    return np.concatenate(out)[:n]
