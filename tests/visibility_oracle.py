"""Brute-force reference for segment visibility, independent of mapkit.visibility.

Straight from the definition in docs/visibility.md, point by point: every
segment is sampled every ``step`` metres; a sample is seen from the floor
point q if its distance and elevation suit the camera and the open 2D sight
line from q to it crosses no occluder edge; a segment is visible if a run of
consecutive seen samples spans at least ``min_visible_length`` (a segment
shorter than that: every sample). Occluders are shrunk by twice the
builder's ``OCCLUSION_SHRINK``, so the reference sees slightly more than the
builder assumes: a stricter check of the builder's superset guarantee.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from mapkit.tolerances import OCCLUSION_SHRINK


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
        xy, inv = np.unique(self.points[cand, :2], axis=0, return_inverse=True)
        clear = self._clear(q, xy)
        ok[cand] = clear[inv.ravel()]
        return ok

    def _clear(self, q, targets) -> np.ndarray:
        """(M,) bool: the open segment q -> target crosses no occluder edge."""
        a, b = self.edges[:, 0], self.edges[:, 1]
        out = np.empty(len(targets), dtype=bool)
        for i in range(0, len(targets), 2000):
            s = targets[i : i + 2000, None, :]

            def cross(u, v):
                return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

            o1 = cross(s - q, a - q)
            o2 = cross(s - q, b - q)
            o3 = cross(b - a, q - a)
            o4 = cross(b - a, s - a)
            blocked = (o1 * o2 < 0) & (o3 * o4 < 0)
            out[i : i + 2000] = ~blocked.any(axis=1)
        return out

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
            padded = np.concatenate([[0], run.astype(np.int8), [0]])
            edges = np.diff(padded)
            longest = (np.nonzero(edges == -1)[0] - np.nonzero(edges == 1)[0]).max()
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
