"""Occlusion by the map's walls, seen from above (numpy only).

Walls are extruded to the full height of the map and the camera is below
their top, so a sight line is blocked exactly when its floor projection
crosses a wall outline. Wall outlines come as edges ``(a (E, 2), b (E, 2))``.
"""

from __future__ import annotations

import numpy as np

from matcher.tolerances import DEFAULT, MapIndexConstants, SharedConstants


class WallEdges(tuple):
    """Wall edges ``(a (E, 2), b (E, 2))``, a plain pair to unpack, that also
    carries the homogeneous forms :func:`sight_clear` multiplies with, made
    once per map: ``ends`` (3, 2E) the end points ``(x, y, 1)``, a then b,
    and ``lines`` (3, E) each edge's line ``(n_x, n_y, -n . a)``, normal
    ``(-s_y, s_x)`` for ``s = b - a``."""

    def __new__(cls, a: np.ndarray, b: np.ndarray):
        self = super().__new__(cls, (a, b))
        self.ends, self.lines = _homogeneous(a, b)
        return self


def _homogeneous(ea: np.ndarray, eb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:class:`WallEdges`' ``ends`` and ``lines`` of edges ``ea, eb`` (E, 2)."""
    E = len(ea)
    ends = np.ones((3, 2 * E))
    ends[:2, :E] = ea.T
    ends[:2, E:] = eb.T
    s = eb - ea
    lines = np.empty((3, E))
    lines[0] = -s[:, 1]
    lines[1] = s[:, 0]
    lines[2] = s[:, 1] * ea[:, 0] - s[:, 0] * ea[:, 1]
    return ends, lines


def wall_edges(linemap) -> WallEdges | None:
    """The map's wall outlines as edges ``(a (E, 2), b (E, 2))``, or None."""
    rings = linemap.wall_rings()
    if not rings:
        return None
    return WallEdges(np.concatenate(rings), np.concatenate([np.roll(r, -1, axis=0) for r in rings]))


def inside_walls(points: np.ndarray, walls) -> np.ndarray:
    """(Q,) bool: floor points (Q, 2) inside the wall outlines (even-odd)."""
    if walls is None or len(walls[0]) == 0 or len(points) == 0:
        return np.zeros(len(points), dtype=bool)
    a, b = walls
    x, y = points[:, 0:1], points[:, 1:2]
    straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (y - a[None, :, 1]) / (b[None, :, 1] - a[None, :, 1])
        xc = a[None, :, 0] + t * (b[None, :, 0] - a[None, :, 0])
    return ((straddle & (xc > x)).sum(axis=1) % 2) == 1


def face_normals(segments: np.ndarray, walls, work: MapIndexConstants = DEFAULT.map_index) -> np.ndarray:
    """(N, 2) unit normal of the wall face each non-vertical segment (N, 2, 3)
    lies on, pointing into the room; zeros where there is no single face (a
    vertical segment, a line in a doorway or away from the walls). Probed
    ``face_probe_m`` metres to either side at a quarter, half and three quarters
    of the segment: the face is where one side is wall all three times and
    the other side never. Such a segment is seen only from the room side."""
    probe = work.face_probe_m
    n = len(segments)
    out = np.zeros((n, 2))
    d = segments[:, 1, :2] - segments[:, 0, :2]
    length = np.linalg.norm(d, axis=1)
    ok = length > 1e-6
    if walls is None or not ok.any():
        return out
    idx = np.nonzero(ok)[0]
    perp = np.stack([-d[idx, 1], d[idx, 0]], axis=1) / length[idx, None]
    t = np.array([0.25, 0.5, 0.75])
    pts = segments[idx, None, 0, :2] + t[None, :, None] * d[idx, None, :]  # (M, 3, 2)
    left = inside_walls((pts + probe * perp[:, None]).reshape(-1, 2), walls).reshape(-1, 3)
    right = inside_walls((pts - probe * perp[:, None]).reshape(-1, 2), walls).reshape(-1, 3)
    to_left = right.all(axis=1) & ~left.any(axis=1)  # wall on the right: the room is left
    to_right = left.all(axis=1) & ~right.any(axis=1)
    out[idx[to_left]] = perp[to_left]
    out[idx[to_right]] = -perp[to_right]
    return out


def fan_cast(origins: np.ndarray, dirs: np.ndarray, walls, skip: float, chunk: int) -> np.ndarray:
    """(U, B) distance along each of the rays from each of ``origins`` (U, 2)
    in each of the unit directions ``dirs`` (B, 2) to the first wall edge
    crossed beyond ``skip`` metres; inf if none. At most about ``chunk``
    (ray, wall edge) pairs are handled at once.

    A ray o + t d meets the edge a + u s at t = (w x s) / (d x s) and
    u = (w x d) / (d x s), w = a - o: the denominators are the fan's, the
    same from every origin, and w x s is one number per (origin, edge), so
    only u is worked out per ray."""
    U, B = len(origins), len(dirs)
    if walls is None or len(walls[0]) == 0:
        return np.full((U, B), np.inf)
    ea, eb = walls
    s = eb - ea  # (E, 2)
    den = dirs[:, None, 0] * s[None, :, 1] - dirs[:, None, 1] * s[None, :, 0]  # (B, E)
    crosses = np.abs(den) > 1e-12
    out = np.empty((U, B))
    block = max(1, chunk // (len(s) * B))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in range(0, U, block):
            w = ea[None] - origins[i:i + block, None]  # (u, E, 2)
            t = (w[..., 0] * s[None, :, 1] - w[..., 1] * s[None, :, 0])[:, None] / den  # (u, B, E)
            u = (w[:, None, :, 0] * dirs[None, :, None, 1] - w[:, None, :, 1] * dirs[None, :, None, 0]) / den
            hit = crosses & (t > skip) & (u >= 0) & (u <= 1)
            out[i:i + block] = np.where(hit, t, np.inf).min(axis=2)
    return out


class SightRays:
    """How far one sees back from floor points, per bearing: the distance
    along the ray from the point at each of ``bins`` bearings to the first
    wall it crosses (beyond ``skip`` metres: the point stands on a wall face).
    A vertical edge seen at bearing b stands on the ray back from it at
    b + pi, up to that distance. Rays are cast once per point and kept, so
    a map's table fills up over the frames."""

    def __init__(self, walls, work: MapIndexConstants = DEFAULT.map_index) -> None:
        self.walls = walls
        self.bins = int(work.sight_bins)
        self.step = 2 * np.pi / self.bins
        self.skip = float(work.sight_skip_m)
        self.chunk = int(work.ray_chunk)
        self._rows: dict[tuple[float, float], np.ndarray] = {}
        self._wide: dict[tuple[float, float], np.ndarray] = {}
        bear = np.arange(self.bins) * self.step - np.pi
        self._dirs = np.stack([np.cos(bear), np.sin(bear)], axis=1)

    def bin_of(self, bearing: np.ndarray) -> np.ndarray:
        """Bin index of world bearings (radians, any range)."""
        return np.rint((bearing + np.pi) / self.step).astype(np.int64) % self.bins

    def reach(self, points: np.ndarray) -> np.ndarray:
        """(U, bins) distances from ``points`` (U, 2) along each bearing."""
        return self._table(points, self._rows)

    def reach_along(self, points: np.ndarray, rows: np.ndarray, bearings: np.ndarray) -> np.ndarray:
        """(...) how far one sees from ``points[rows]`` (points (U, 2), rows
        (...) int) along world ``bearings`` (...): the longest reach among the
        bearing's bin and its two neighbours (a ray that just grazes a door
        jamb is blocked in one bin and clear in the next)."""
        return self._table(points, self._wide)[rows, self.bin_of(bearings)]

    def _table(self, points: np.ndarray, table: dict) -> np.ndarray:
        """(U, bins) rows of ``table`` (raw or widened reaches) for ``points``
        (U, 2), casting the rays of points not seen before."""
        keys = [(round(float(x), 6), round(float(y), 6)) for x, y in points]
        todo = [i for i, k in enumerate(keys) if k not in self._rows]
        if todo:
            got = fan_cast(points[todo], self._dirs, self.walls, self.skip, self.chunk)
            for i, row in zip(todo, got):
                self._rows[keys[i]] = row
                # The widened row: each bin the longest of itself and its neighbours.
                self._wide[keys[i]] = np.maximum(np.maximum(row, np.roll(row, 1)), np.roll(row, -1))
        if len(keys) == 1:
            return table[keys[0]][None]
        return np.stack([table[k] for k in keys]) if keys else np.zeros((0, self.bins))


def sight_clear(cam: np.ndarray, points: np.ndarray, walls, end_margin: float,
                shared: SharedConstants = DEFAULT.shared) -> np.ndarray:
    """(Q,) bool: the floor sight line from ``cam`` (2,) or (Q, 2) to each of
    ``points`` (Q, 2) crosses no wall edge farther than ``end_margin`` metres
    from both its ends (the points lie on wall faces; the camera may be a
    little off).

    A sight line, trimmed by the margin at both ends, crosses an edge when
    the edge's ends lie strictly on either side of the sight line and the
    trimmed line's ends strictly on either side of the edge. Each side test
    is a signed distance ``n . x - n . p`` for all pairs at once, as one
    matrix product of homogeneous points ``(x, y, 1)`` and lines
    ``(n_x, n_y, -n . p)``: a handful of numpy calls, this runs at every
    leaf of the tree. Above ``box_filter_edges`` wall edges the sight lines
    are first tested against the edges' bounding boxes."""
    if walls is None or len(walls[0]) == 0 or len(points) == 0:
        return np.ones(len(points), dtype=bool)
    ea, eb = walls
    cam = np.asarray(cam, dtype=float)  # (2,) or (Q, 2): broadcast in every use below
    ends, lines = (walls.ends, walls.lines) if isinstance(walls, WallEdges) else _homogeneous(ea, eb)
    if len(ea) > shared.box_filter_edges:
        lo = np.minimum(points.min(axis=0), cam.reshape(-1, 2).min(axis=0))
        hi = np.maximum(points.max(axis=0), cam.reshape(-1, 2).max(axis=0))
        near = (np.maximum(ea, eb) >= lo).all(axis=1) & (np.minimum(ea, eb) <= hi).all(axis=1)
        if not near.any():
            return np.ones(len(points), dtype=bool)
        ends, lines = ends[:, np.concatenate([near, near])], lines[:, near]
    Q, E = len(points), lines.shape[1]
    r = points - cam
    length = np.hypot(r[:, 0], r[:, 1])
    trim = r * (end_margin / np.maximum(length, 1e-12))[:, None]
    sight = np.empty((Q, 3))  # the sight lines, normal (-r_y, r_x)
    sight[:, 0] = -r[:, 1]
    sight[:, 1] = r[:, 0]
    sight[:, 2] = r[:, 1] * cam[..., 0] - r[:, 0] * cam[..., 1]
    side = sight @ ends  # (Q, 2E)
    tips = np.ones((2 * Q, 3))  # the trimmed sight lines' ends, near then far
    tips[:Q, :2] = cam + trim
    tips[Q:, :2] = points - trim
    across = tips @ lines  # (2Q, E)
    hit = (side[:, :E] * side[:, E:] < 0) & (across[:Q] * across[Q:] < 0)
    # A sight line shorter than both margins has nothing left to cross.
    return ~hit.any(axis=1) | (length <= 2 * end_margin)
