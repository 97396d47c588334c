"""Region lookup on a loaded map with numpy only (no shapely at run time).

A query goes: lookup-grid cells under the disk's bounding box -> candidate
regions -> exact test on those regions' ring edges (the disk's centre is
inside the region under the even-odd rule, or within ``radius`` of one of
its edges). Everything per query is a few array operations.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.errors import InputError


def concat_ranges(starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """``np.concatenate([np.arange(s, s + n) for s, n in zip(starts, lengths)])``
    without the Python loop: the index runs of a few regions' edges or lists."""
    lengths = np.asarray(lengths, dtype=np.int64)
    firsts = np.cumsum(lengths) - lengths  # where each run starts in the output
    return np.arange(int(lengths.sum()), dtype=np.int64) + np.repeat(np.asarray(starts, dtype=np.int64) - firsts,
                                                                     lengths)


class RegionLookup:
    """Precomputed ring edges of a :class:`~linemap.lmap.LineMap` for fast queries."""

    def __init__(self, m) -> None:
        self.m = m
        pts, offs = m.ring_points, m.ring_offsets
        k = len(m.ring_region)
        # Edge e goes from a[e] to b[e]; b is the next point of the same ring.
        idx = np.arange(len(pts))
        ring_of_point = np.repeat(np.arange(k), np.diff(offs))
        nxt = idx + 1
        if k:
            last = offs[1:] - 1
            nxt[last] = offs[:-1]
        self.a = pts
        self.b = pts[nxt] if len(pts) else pts
        self.edge_region = m.ring_region[ring_of_point] if k else np.zeros(0, dtype=np.int64)
        # Rings are sorted by region, so a region's edges are one contiguous run.
        r = m.n_regions
        self.region_edge_start = np.searchsorted(self.edge_region, np.arange(r + 1))
        self.centres, self.radii, self.areas = self._centres_radii_areas(ring_of_point)

    def _centres_radii_areas(self, ring_of_point: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = self.m.n_regions
        a, b = self.a, self.b
        cross = a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]  # shoelace terms, signed
        # Holes are oriented either way in files; make each ring's sign follow its role.
        ring_area2 = np.bincount(ring_of_point, weights=cross, minlength=len(self.m.ring_region))
        sign = np.where(self.m.ring_is_hole, -1.0, 1.0) * np.sign(ring_area2)
        s = sign[ring_of_point] if len(ring_of_point) else np.zeros(0)
        w = cross * s
        area2 = np.bincount(self.edge_region, weights=w, minlength=r)
        cx = np.bincount(self.edge_region, weights=w * (a[:, 0] + b[:, 0]), minlength=r)
        cy = np.bincount(self.edge_region, weights=w * (a[:, 1] + b[:, 1]), minlength=r)
        with np.errstate(invalid="ignore", divide="ignore"):
            centres = np.stack([cx, cy], axis=1) / (3.0 * area2[:, None])
        # Degenerate (zero-area) regions fall back to the vertex mean.
        bad = ~np.isfinite(centres).all(axis=1)
        if bad.any():
            cnt = np.maximum(np.bincount(self.edge_region, minlength=r), 1)
            mean = np.stack(
                [np.bincount(self.edge_region, weights=a[:, i], minlength=r) / cnt for i in (0, 1)], axis=1
            )
            centres[bad] = mean[bad]
        d = np.linalg.norm(a - centres[self.edge_region], axis=1) if len(a) else np.zeros(0)
        radii = np.zeros(r)
        if len(d):
            np.maximum.at(radii, self.edge_region, d)
        return centres, radii, 0.5 * np.abs(area2)

    def candidate_regions(self, x: float, y: float, radius: float) -> np.ndarray:
        """Regions listed by the grid cells under the disk's bounding box (a superset)."""
        m = self.m
        ny, nx = m.grid_shape
        ox, oy = m.grid_origin
        c = m.grid_cell
        # Cell indices clipped while still floats: a huge radius or point
        # (1e308) would overflow an int.
        with np.errstate(over="ignore"):
            ix0, ix1 = (int(np.clip(np.floor((v - ox) / c), -1, nx)) for v in (x - radius, x + radius))
            iy0, iy1 = (int(np.clip(np.floor((v - oy) / c), -1, ny)) for v in (y - radius, y + radius))
        ix0, iy0 = max(ix0, 0), max(iy0, 0)
        ix1, iy1 = min(ix1, nx - 1), min(iy1, ny - 1)
        if ix0 > ix1 or iy0 > iy1:
            return np.zeros(0, dtype=np.int64)
        cells = (np.arange(iy0, iy1 + 1)[:, None] * nx + np.arange(ix0, ix1 + 1)[None, :]).ravel()
        starts, ends = m.grid_offsets[cells], m.grid_offsets[cells + 1]
        if (ends - starts).sum() == 0:
            return np.zeros(0, dtype=np.int64)
        return np.unique(m.grid_regions[concat_ranges(starts, ends - starts)])

    def regions_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Sorted ids of regions meeting the closed disk (radius 0: containing the point)."""
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(radius)) or radius < 0:
            raise InputError(f"query needs finite x, y and radius >= 0, got ({x}, {y}, {radius})")
        cand = self.candidate_regions(x, y, radius)
        starts = self.region_edge_start[cand]
        lengths = self.region_edge_start[cand + 1] - starts
        cand, starts, lengths = cand[lengths > 0], starts[lengths > 0], lengths[lengths > 0]  # no edges: never met
        if cand.size == 0:
            return cand
        edges = concat_ranges(starts, lengths)
        runs = np.cumsum(lengths) - lengths  # each candidate's first edge in ``edges``
        a, b = self.a[edges], self.b[edges]
        # Even-odd crossing test of a ray towards +x.
        straddle = (a[:, 1] > y) != (b[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # horizontal edges never straddle
            t = (y - a[:, 1]) / (b[:, 1] - a[:, 1])
            xcross = a[:, 0] + t * (b[:, 0] - a[:, 0])
        inside = np.add.reduceat((straddle & (xcross > x)).astype(np.int64), runs) % 2 == 1
        # Distance from the centre to each edge.
        ab = b - a
        denom = ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            u = np.clip(((x - a[:, 0]) * ab[:, 0] + (y - a[:, 1]) * ab[:, 1]) / denom, 0.0, 1.0)
        u = np.where(denom > 0, u, 0.0)
        d = np.hypot(a[:, 0] + u * ab[:, 0] - x, a[:, 1] + u * ab[:, 1] - y)
        near = np.minimum.reduceat(d, runs) <= radius
        return cand[inside | near]
