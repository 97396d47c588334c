"""What the structure search uses from the map: per floor point and world
bearing, where the walls' junctions and the vertical edges in sight are.

Derived per map (:func:`grid_profiles`, kept with the map like the
:class:`~matcher.map_index.MapIndex` parts) for a lattice of floor points
covering the map's regions, each point's the first time a search asks for
it (:class:`ProfileTable`), and for any other points (the refinement's,
:func:`profiles_at`). Bearings are binned: ``bins`` bins round
the turn, bin ``k`` covering world bearings ``[k, k + 1) * 2 pi / bins``
(counter-clockwise from the x axis), each bin's profile taken along its
middle ray.

Per point and bin:

- ``floor_m``: the distance to the first wall/floor junction (the map's
  FLOOR segments) the ray meets (inf: none): what a floor line at that
  bearing in the image says, through the camera's height;
- ``ceiling_m``, ``ceiling_z``: the same for the wall/ceiling junctions
  (CEILING segments) and the junction's height;
- ``edge_cum``: the vertical edges (corners, jambs) in plain sight, as a
  running count over the bins (twice round, so that any arc of bins is one
  difference): a bin holds an edge when the edge's bearing from somewhere
  within ``slack_m`` of the point falls in it. In sight: the point lies on
  the ray back from the edge before the first wall
  (:class:`~matcher.map_geometry.occlusion.SightRays`, the map's sight table).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from linemap.lmap import LineMap, SegmentKind
from matcher.map_index import index_of
from matcher.search.structure.yaw import map_directions
from matcher.tolerances import Tolerances


@dataclass(frozen=True)
class MapStructure:
    """The map's parts the profiles are made of: ``floor`` (F, 2, 2) and
    ``ceiling`` (G, 2, 2) junctions seen from above, ``ceiling_z`` (G,)
    their heights, metres; ``edges`` (E, 2) the vertical edges' floor
    points (one per place); ``sight`` the map's sight table (None: no
    walls, every edge in sight)."""

    floor: np.ndarray
    ceiling: np.ndarray
    ceiling_z: np.ndarray
    edges: np.ndarray
    sight: object | None


@dataclass(frozen=True)
class Profiles:
    """The profiles of ``points`` (P, 2) (module docstring), bin first (a
    yaw's columns are then whole rows): ``floor_inv`` and ``ceiling_inv``
    (bins, P) float32 one over the junction's distance (NaN: none),
    ``ceiling_z`` (bins, P) float32 its height, ``edge_cum`` (2 bins + 1,
    P) int32; ``slack_m`` the position slack the edges' bearings were
    widened by."""

    points: np.ndarray
    floor_inv: np.ndarray
    ceiling_inv: np.ndarray
    ceiling_z: np.ndarray
    edge_cum: np.ndarray
    slack_m: float

    @property
    def bins(self) -> int:
        return int(self.floor_inv.shape[0])

    def take(self, rows: np.ndarray) -> Profiles:
        """The profiles of ``points[rows]``."""
        return Profiles(self.points[rows], self.floor_inv[:, rows], self.ceiling_inv[:, rows],
                        self.ceiling_z[:, rows], self.edge_cum[:, rows], self.slack_m)

    def typical_m(self, rows) -> np.ndarray:
        """(R,) the median distance of the junctions seen from
        ``points[rows]`` (over the bearings holding one), metres."""
        inv = np.fmax(np.nan_to_num(self.floor_inv[:, rows], nan=0.0), np.nan_to_num(self.ceiling_inv[:, rows], nan=0.0))
        inv = np.where(inv > 0, inv, np.nan)
        with np.errstate(divide="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a point that sees no junction: NaN, inf below
            return np.nan_to_num(1.0 / np.nanmedian(inv.astype(float), axis=0), nan=np.inf)


def bins_of(tol: Tolerances) -> int:
    """Bearing bins round the turn: one per yaw step of the pose grid
    (``Tolerances.yaw_step_deg``), so that the grid's yaws are whole shifts
    of a profile."""
    return 2 * max(4, int(round(180.0 / tol.yaw_step_deg)))


def structure_of(linemap: LineMap, tol: Tolerances) -> MapStructure:
    """The :class:`MapStructure` of ``linemap``."""
    seg, kinds = linemap.segments, linemap.kinds
    floor = seg[kinds == SegmentKind.FLOOR][:, :, :2]
    ceil = seg[kinds == SegmentKind.CEILING]
    vert = seg[np.isin(kinds, (SegmentKind.VERTICAL, SegmentKind.JAMB))]
    edges = vert[:, :, :2].mean(axis=1)
    if len(edges):  # one per place: a jamb's pieces above and below a window are one edge
        edges = np.unique(np.round(edges, 3), axis=0)
    return MapStructure(floor, ceil[:, :, :2], ceil[:, :, 2].mean(axis=1), edges.reshape(-1, 2),
                        index_of(linemap).sight(tol.map_index))


class GridProfiles:
    """The lattice of floor points the search scores, ``step`` metres apart
    inside the map's regions, their :class:`Profiles` and the map's wall
    ``directions`` (:func:`~.yaw.map_directions`); made once per
    map and per its arguments (:meth:`linemap.lmap.LineMap.derived`)."""

    def __init__(self, linemap: LineMap, tol: Tolerances) -> None:
        self.structure = structure_of(linemap, tol)
        self.bins = bins_of(tol)
        self.step, points = lattice(linemap, tol, self.bins)
        slack = self.step / math.sqrt(2.0)
        points = points[clear_of_walls(points, self.structure.floor, slack + tol.model_m, tol.map_index.ray_chunk)]
        self.profiles = ProfileTable(self.structure, points, self.bins, slack, tol)
        self.directions = map_directions(linemap, self.bins // 2)
        self._cell = np.round((points - points.min(axis=0, initial=0.0)) / self.step).astype(np.int64) \
            if len(points) else np.zeros((0, 2), np.int64)
        shape = self._cell.max(axis=0) + 1 if len(points) else np.zeros(2, np.int64)
        self._row = np.full(tuple(int(n) for n in shape), -1, np.int64)
        self._row[self._cell[:, 0], self._cell[:, 1]] = np.arange(len(points))

    def make_all(self) -> None:
        """Make every lattice point's profiles now (a lost search's first
        call would; a robot may rather pay it when it loads its map)."""
        self.profiles.take(np.arange(len(self.profiles.points)))

    def shifted(self, rows: np.ndarray, offset: np.ndarray) -> tuple[np.ndarray, float]:
        """``(rows (R,), residual)``: the lattice points nearest to
        ``points[rows] + offset`` ((2,) metres: a camera's place on a robot
        at those points), and how far that is from the offset, metres.
        Where the nearest lattice point is off the lattice (out of the map's
        regions) the point itself."""
        shift = np.round(np.asarray(offset, dtype=float) / self.step).astype(np.int64)
        residual = float(np.hypot(*(np.asarray(offset, dtype=float) - shift * self.step)))
        cell = self._cell[rows] + shift
        fits = np.all((cell >= 0) & (cell < np.array(self._row.shape)), axis=1)
        out = np.array(rows, dtype=np.int64)
        found = self._row[cell[fits, 0], cell[fits, 1]]
        out[np.flatnonzero(fits)[found >= 0]] = found[found >= 0]
        return out, residual


class ProfileTable:
    """The :class:`Profiles` of a fixed set of ``points`` (P, 2), each
    point's made the first time it is asked for and kept: a search from a
    prior asks for the few lattice points within its reach, and only a lost
    search for the whole floor. A point's profiles do not depend on which
    others are made with it, so the table holds what one :func:`profiles_at`
    call over all points gives."""

    def __init__(self, structure: MapStructure, points: np.ndarray, bins: int, slack_m: float,
                 tol: Tolerances) -> None:
        self.structure, self.points, self.slack_m, self._tol = structure, points, slack_m, tol
        self.bins = bins
        self._made = np.zeros(len(points), dtype=bool)
        self._table: Profiles | None = None  # allocated at the first call

    def take(self, rows: np.ndarray) -> Profiles:
        """The profiles of ``points[rows]``, making those not made yet."""
        rows = np.asarray(rows, dtype=np.int64)
        todo = np.unique(rows[~self._made[rows]])
        if len(todo):
            part = profiles_at(self.structure, self.points[todo], self.bins, self.slack_m, self._tol)
            if self._table is None:
                P = len(self.points)
                self._table = Profiles(self.points, np.empty((self.bins, P), np.float32),
                                       np.empty((self.bins, P), np.float32), np.empty((self.bins, P), np.float32),
                                       np.empty((2 * self.bins + 1, P), np.int32), self.slack_m)
            for name in ("floor_inv", "ceiling_inv", "ceiling_z", "edge_cum"):
                getattr(self._table, name)[:, todo] = getattr(part, name)
            self._made[todo] = True
        if self._table is None:  # no points asked for
            return profiles_at(self.structure, self.points[rows], self.bins, self.slack_m, self._tol)
        return self._table.take(rows)


class _Kept:
    """The map's :class:`GridProfiles`, one per values of the constants
    they are made with (:func:`grid_profiles`)."""

    def __init__(self, linemap: LineMap) -> None:
        self.linemap = linemap
        self.made: dict[tuple, GridProfiles] = {}


def grid_profiles(linemap: LineMap, tol: Tolerances) -> GridProfiles:
    """The map's :class:`GridProfiles` for ``tol``, made on the first call
    with these values of the constants they read (the lattice's step, the
    bins, ``model_m``, the sight table's and the raster's constants) and
    kept with the map."""
    kept = linemap.derived(_Kept)
    key = (tol.stage1.region_step_m, tol.yaw_step_deg, tol.model_m, tol.map_index)
    if key not in kept.made:
        kept.made[key] = GridProfiles(linemap, tol)
    return kept.made[key]


def lattice(linemap: LineMap, tol: Tolerances, bins: int) -> tuple[float, np.ndarray]:
    """``(step, points (P, 2))``: the floor points of a square lattice inside
    the map's regions, ``Stage1Constants.region_step_m`` apart (the spacing
    at which stage 1 samples a loose set's camera positions), wider on a
    plan so large that its profiles would pass the free-space raster's
    memory bound (``MapIndexConstants.free_max_cells`` values, over the
    four arrays of ``bins`` a point keeps)."""
    pts = linemap.ring_points
    if not len(pts):
        return tol.stage1.region_step_m, np.zeros((0, 2))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    step = tol.stage1.region_step_m
    cap = tol.map_index.free_max_cells / (4.0 * bins)
    area = float(np.prod(hi - lo))
    if area / step**2 > cap:
        step = math.sqrt(area / cap)
    xs = np.arange(lo[0] + step / 2, hi[0], step)
    ys = np.arange(lo[1] + step / 2, hi[1], step)
    grid = np.stack(np.meshgrid(xs, ys, indexing="xy"), axis=-1).reshape(-1, 2)
    inside = index_of(linemap).free(tol.map_index).distance(grid) <= 0.0
    return step, grid[inside]


def clear_of_walls(points: np.ndarray, walls: np.ndarray, clearance_m: float, chunk: int) -> np.ndarray:
    """(P,) bool: the ``points`` (P, 2) farther than ``clearance_m`` from
    every wall face ``walls`` (W, 2, 2), the floor junctions, metres;
    ``chunk`` bounds the point-and-wall pairs worked at once.

    A lattice point stands for every place within its slack (half the
    lattice's diagonal) and the map's error. A point that near a wall
    cannot be scored: the wall's corners and jambs fall within the widened
    bearings of every bin (:func:`edge_counts`) and its face may lie on
    either side of the true place, so the point agrees with any frame and
    outranks the rooms' middles. A map built for a small footprint (a
    tripod's, a few centimetres) has regions that reach that near; one
    built for a robot's does not."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    keep = np.ones(len(points), dtype=bool)
    if not len(walls) or not len(points):
        return keep
    a, d = walls[:, 0], walls[:, 1] - walls[:, 0]  # (W, 2)
    dd = np.maximum(np.einsum("wi,wi->w", d, d), 1e-18)
    block = max(1, chunk // len(walls))
    for s in range(0, len(points), block):
        rel = points[s:s + block, None, :] - a[None]  # (B, W, 2)
        t = np.clip(np.einsum("bwi,wi->bw", rel, d) / dd, 0.0, 1.0)
        gap = rel - t[..., None] * d[None]
        keep[s:s + block] = np.einsum("bwi,bwi->bw", gap, gap).min(axis=1) > clearance_m ** 2
    return keep


def profiles_at(structure: MapStructure, points: np.ndarray, bins: int, slack_m: float, tol: Tolerances) -> Profiles:
    """The :class:`Profiles` of ``points`` (P, 2), the edges' bearings
    widened by ``slack_m`` (how far the true place may be from a point)
    and the map's own error ``model_m``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    middle = (np.arange(bins) + 0.5) * (2.0 * math.pi / bins)
    block = max(1, tol.map_index.ray_chunk // (32 * max(len(structure.floor), len(structure.ceiling), 1)))
    floor_m, _ = _in_blocks(points, bins, structure.floor, block)
    ceiling_m, hit = _in_blocks(points, bins, structure.ceiling, block)
    z = structure.ceiling_z[np.maximum(hit, 0)] if len(structure.ceiling_z) else np.zeros(hit.shape)
    ceiling_z = np.where(hit >= 0, z, np.nan).astype(np.float32)
    cum = edge_counts(structure, points, bins, slack_m + tol.model_m)
    with np.errstate(divide="ignore"):
        floor_inv = np.where(np.isfinite(floor_m), 1.0 / floor_m, np.nan).astype(np.float32)
        ceiling_inv = np.where(np.isfinite(ceiling_m), 1.0 / ceiling_m, np.nan).astype(np.float32)
    return Profiles(points, np.ascontiguousarray(floor_inv.T), np.ascontiguousarray(ceiling_inv.T),
                    np.ascontiguousarray(ceiling_z.T), np.ascontiguousarray(cum.T), slack_m)


def _in_blocks(points: np.ndarray, bins: int, segments: np.ndarray, block: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`first_hits` ``block`` points at a time (a (point, segment)
    pair casts a few tens of bins: about ``MapIndexConstants.ray_chunk``
    rays at once)."""
    parts = [first_hits(points[i:i + block], bins, segments) for i in range(0, max(len(points), 1), block)]
    return np.concatenate([d for d, _ in parts]), np.concatenate([k for _, k in parts])


def first_hits(points: np.ndarray, bins: int, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(distance (P, bins), index (P, bins))``: along the middle ray of each
    bearing bin from each point (P, 2), the first of ``segments`` (S, 2, 2)
    it meets and how far (inf and -1: none). Each (point, segment) pair
    casts only the rays of the bins between its end points' bearings."""
    P, S = len(points), len(segments)
    dist = np.full(P * bins, np.inf)
    index = np.full(P * bins, -1, dtype=np.int64)
    if not S or not P:
        return dist.reshape(P, bins), index.reshape(P, bins)
    width = 2 * np.pi / bins
    a = segments[None, :, 0] - points[:, None]  # (P, S, 2)
    b = segments[None, :, 1] - points[:, None]
    a0 = np.arctan2(a[..., 1], a[..., 0])
    turn = np.remainder(np.arctan2(b[..., 1], b[..., 0]) - a0 + np.pi, 2 * np.pi) - np.pi  # a to b, signed
    lo = np.minimum(a0, a0 + turn)
    first = np.ceil(lo / width - 0.5).astype(np.int64)  # the first bin whose middle ray lies in the span
    count = np.floor((lo + np.abs(turn)) / width - 0.5).astype(np.int64) - first + 1
    p, s = np.nonzero(count > 0)
    n = count[p, s]
    pair = np.repeat(np.arange(len(p)), n)
    k = np.repeat(first[p, s] - (np.cumsum(n) - n), n) + np.arange(len(pair))
    kb = np.mod(k, bins)
    middle = (np.arange(bins) + 0.5) * width
    # What a ray needs of its pair, taken once a pair: the segment's
    # direction e and the cross product a x e (a ray hits the segment's
    # line at t = (a x e) / (u x e), u the ray's direction).
    ap, e = a[p, s], b[p, s] - a[p, s]
    a_cross_e = ap[:, 0] * e[:, 1] - ap[:, 1] * e[:, 0]
    denom = np.cos(middle)[kb] * e[pair, 1] - np.sin(middle)[kb] * e[pair, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = a_cross_e[pair] / denom
    t = np.where(np.isfinite(t) & (t > 0), t, np.inf)
    key = p[pair] * bins + kb
    np.minimum.at(dist, key, t)
    first = np.isfinite(t) & (t == dist[key])  # the pairs that give their ray's distance
    index[key[first]] = s[pair][first]
    return dist.reshape(P, bins), index.reshape(P, bins)


def edge_counts(structure: MapStructure, points: np.ndarray, bins: int, slack_m: float) -> np.ndarray:
    """(P, 2 bins + 1) int32 running count, twice round, of the bins that
    hold a vertical edge in sight of each point (module docstring): an
    edge at distance d and bearing b fills the bins of ``b +- asin(slack_m
    / d)``, the bearings it takes from within ``slack_m`` of the point."""
    P, E = len(points), len(structure.edges)
    occupied = np.zeros((P, bins), dtype=bool)
    if E and P:
        d = structure.edges[None] - points[:, None]  # (P, E, 2)
        dist = np.hypot(d[..., 0], d[..., 1])
        bearing = np.arctan2(d[..., 1], d[..., 0])
        seen = dist > 1e-6
        if structure.sight is not None:
            rows = np.broadcast_to(np.arange(E), (P, E))
            reach = structure.sight.reach_along(structure.edges, rows, bearing + math.pi)
            seen &= dist <= reach + slack_m
        half = np.arcsin(np.minimum(1.0, slack_m / np.maximum(dist, 1e-6)))
        width = 2.0 * math.pi / bins
        lo = np.floor((bearing - half) / width).astype(np.int64)
        hi = np.floor((bearing + half) / width).astype(np.int64)
        p, e = np.nonzero(seen)
        lo, hi = lo[p, e] + bins, hi[p, e] + bins  # in [0, 3 bins): bearings within one turn either way
        diff = np.zeros((P, 3 * bins + 1), dtype=np.int32)
        np.add.at(diff, (p, lo), 1)
        np.add.at(diff, (p, hi + 1), -1)
        count = np.cumsum(diff, axis=1)[:, :3 * bins]
        occupied = (count[:, :bins] + count[:, bins:2 * bins] + count[:, 2 * bins:]) > 0
    twice = np.concatenate([occupied, occupied], axis=1).astype(np.int32)
    return np.concatenate([np.zeros((P, 1), np.int32), np.cumsum(twice, axis=1, dtype=np.int32)], axis=1)
