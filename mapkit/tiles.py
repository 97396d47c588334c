"""The region stage in tiles: a floor of any size in bounded memory.

What a point sees depends only on the segments within the map's sight
range of it, so a floor's regions can be built tile by tile
(docs/tiles.md):

- the tiles are blocks of cells of the whole floor's quadtree
  (:func:`plan_tiles`): their cells, boxes and tests are those of the
  one-piece build, bit for bit;
- a tile lists the segments within reach of its square
  (:func:`tile_segments`: ``max_range`` plus the growth by ``eps``) and
  computes their regions among the whole floor's walls and free space,
  exactly as the one-piece build computes them; its quadtree starts at its
  own cells (:class:`mapkit.vir.QuadRoots`). Its leaves, and their lists,
  are those of the one-piece build within the tile;
- each tile merges its own leaves (the same greedy merge, within the
  tile) and cuts their outlines; the tiles' regions are put together in
  the Morton order of their first cells (:func:`build_regions_in_tiles`).

So, before merging, the list at every point is the one-piece build's;
merging unites lists within a tile rather than across the floor (the same
growth budget, so lists are as long), and a region the tile borders cut is
several regions. Every list remains a superset of what is visible within
``eps`` (docs/visibility.md).

Peak memory follows the tile, not the floor (:func:`tile_side_for_budget`);
the tiles run one after the other here, or as Dask tasks
(:mod:`mapkit.tile_runner`), with the same result byte for byte.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import shapely

from mapkit.errors import MapkitError
from mapkit.memory import release_memory
from mapkit.tolerances import (
    CIRCLE_SIDES,
    REGION_PEAK_BASE_MB,
    REGION_PEAK_MB_PER_M2,
    TILE_MIN_SIDE_PER_REACH,
    TILE_REACH_SLACK,
    VIR_EPS_SLACK,
    VIR_MIN_CELL,
    VIR_QUAD_SEGS,
    VIS_VERTICAL_XY,
    ZERO,
)
from mapkit.vir import QuadRoots, RegionPartition, RegionSettings, _partition_stats, _quadtree_frame

#: Cells of the whole floor's quadtree at least this many to a tile's side:
#: tiles are then within 1 / this of the side asked for (blocks of whole
#: cells), where one cell per tile could be half of it.
_CELLS_PER_SIDE = 4


@dataclass(frozen=True)
class Tile:
    """One tile: its place in the list (``index``), its cells ``ix``, ``iy``
    (C,) int64 at the plan's level, and its square ``bounds`` (x0, y0, x1,
    y1) metres."""

    index: int
    ix: np.ndarray
    iy: np.ndarray
    bounds: tuple

    def place(self) -> str:
        """Where the tile is, for messages."""
        x0, y0, x1, y1 = self.bounds
        return f"x {x0:.1f} to {x1:.1f} m, y {y0:.1f} to {y1:.1f} m"


@dataclass(frozen=True)
class TilePlan:
    """The whole floor's quadtree frame (``depth``, ``size``, ``origin``),
    the ``level`` of the cells tiles are made of, ``cells`` of them along a
    tile's side (so a tile is ``side`` m wide) and the ``tiles`` meeting the
    free space."""

    depth: int
    size: float
    origin: np.ndarray
    level: int
    cells: int
    side: float
    tiles: list

    def roots(self, tile: Tile) -> QuadRoots:
        """Where the tile's quadtree starts."""
        return QuadRoots(self.depth, self.size, self.origin, self.level, tile.ix, tile.iy)

    def record(self) -> dict:
        """What the map's META records of the tiling."""
        return {"tiles": len(self.tiles), "tile_side_m": self.side, "tile_level": self.level,
                "tile_cells": self.cells}


@dataclass(frozen=True)
class Floor:
    """What every tile needs of the floor: ``segments`` (N, 2, 3) metres,
    the wall solids ``occluders`` and the ``free_space`` (shapely), the
    ``camera`` (camera.json dict) and the region ``settings``."""

    segments: np.ndarray
    occluders: object
    free_space: object
    camera: dict
    settings: RegionSettings


@dataclass
class TileRegions:
    """One tile's regions in compact form, a few flat arrays (what a tile
    hands back, across processes too, and what is held until the join):
    ``wkb`` (B,) uint8 the R outlines' WKB one after the other, ``wkb_ends``
    (R,) int64 where each ends; ``ids`` (L,) int64 the lists (global segment
    ids) one after the other, ``list_ends`` (R,) int64; ``keys`` (R,) uint64
    the Morton key of each region's first cell; the tile's ``stats`` (counts).

    Held as shapely geometries and one array per list, the tiles' results
    were hundreds of thousands of small blocks spread over the heap, each
    keeping its page from being handed back between tiles; WKB keeps every
    coordinate bit for bit."""

    index: int
    wkb: np.ndarray
    wkb_ends: np.ndarray
    ids: np.ndarray
    list_ends: np.ndarray
    keys: np.ndarray
    stats: dict = field(default_factory=dict)

    @classmethod
    def pack(cls, index: int, polygons: list, lists: list, keys: np.ndarray, stats: dict) -> TileRegions:
        """The compact form of ``polygons`` (R shapely) and ``lists`` (R int arrays)."""
        wkb = [bytes(b) for b in shapely.to_wkb(np.array(polygons + [None], dtype=object)[:-1])]
        ends = np.cumsum([len(b) for b in wkb], dtype=np.int64)
        ids = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists] + [np.zeros(0, dtype=np.int64)])
        list_ends = np.cumsum([len(x) for x in lists], dtype=np.int64)
        return cls(index, np.frombuffer(b"".join(wkb), dtype=np.uint8), ends, ids, list_ends,
                   np.asarray(keys, dtype=np.uint64), stats)

    def polygons(self) -> list:
        """The R outlines as shapely geometries."""
        starts = np.concatenate([[0], self.wkb_ends[:-1]]).astype(np.int64)
        return list(shapely.from_wkb([self.wkb[a:b].tobytes() for a, b in zip(starts, self.wkb_ends)]))

    def lists(self) -> list:
        """The R lists, (K,) int64 arrays of global segment ids."""
        return np.split(self.ids, self.list_ends[:-1]) if len(self.list_ends) else []


def _growth(settings: RegionSettings) -> float:
    """How far, metres, the growth by ``eps`` moves a region's outline (its
    circumscribed buffer, :func:`mapkit.vir.grow_regions`), plus ``TILE_REACH_SLACK``."""
    return (settings.eps + VIR_EPS_SLACK) / math.cos(math.pi / (4 * VIR_QUAD_SEGS)) + TILE_REACH_SLACK


def reach(settings: RegionSettings) -> float:
    """How far from a segment, metres (horizontally), its grown region can
    reach: the sight range's circumscribed polygon, then the growth by
    ``eps`` (:func:`_growth`)."""
    return settings.max_range / math.cos(math.pi / CIRCLE_SIDES) + _growth(settings)


def free_space_near(free_space, bounds: tuple, settings: RegionSettings):
    """The free space within the growth by ``eps`` of a tile's square
    ``bounds``: all of a region ``R_S`` that the tile's cells can see
    through ``R_S^eps = (R_S & free space) + eps`` lies in it.

    A tile computes its segments' regions ``within`` it
    (:func:`mapkit.visibility.segment_regions_within`, which keeps
    ``R_S & within`` and skips the sample points walled off from it and the
    pieces whose visibility polygons stay away from it): a segment near the
    tile but facing away from it costs the sweep of its points, no more."""
    g = _growth(settings)
    x0, y0, x1, y1 = bounds
    return shapely.clip_by_rect(free_space, x0 - g, y0 - g, x1 + g, y1 + g)


def predicted_peak_mb(free_area_m2: float) -> float:
    """The region stage's predicted peak memory, MB, working on this much free space."""
    return REGION_PEAK_BASE_MB + REGION_PEAK_MB_PER_M2 * free_area_m2


def tile_side_for_budget(free_space, settings: RegionSettings, budget_mb: float) -> float | None:
    """The tile side, metres, that keeps the predicted peak under
    ``budget_mb``; None when the whole floor already does (one piece).
    MapkitError when even the narrowest tile allowed would not."""
    if predicted_peak_mb(free_space.area) <= budget_mb:
        return None
    x0, y0, x1, y1 = free_space.bounds
    density = free_space.area / max((x1 - x0) * (y1 - y0), ZERO.divisor)
    r = reach(settings)
    # A tile works on the free space within reach of its square.
    allowed_m2 = (budget_mb - REGION_PEAK_BASE_MB) / REGION_PEAK_MB_PER_M2
    side = math.sqrt(max(allowed_m2, 0.0) / density) - 2.0 * r
    if side < TILE_MIN_SIDE_PER_REACH * r:
        need = predicted_peak_mb(density * ((2.0 + TILE_MIN_SIDE_PER_REACH) * r) ** 2)
        raise MapkitError(f"--memory-budget {budget_mb:g} MB is too small for tiles at --max-range "
                          f"{settings.max_range:g} m: give at least {math.ceil(need)} MB")
    return side


def plan_tiles(free_space, settings: RegionSettings, side: float) -> TilePlan:
    """Tiles of about ``side`` metres (at most) over ``free_space``: blocks
    of ``cells`` x ``cells`` cells of the whole floor's quadtree (at the
    coarsest level with ``_CELLS_PER_SIDE`` cells to ``side``), those whose
    cells meet the free space, in row order; each keeps only such cells."""
    depth, size, origin = _quadtree_frame(free_space, settings.min_cell)
    level = min(depth, max(0, math.ceil(math.log2(size * _CELLS_PER_SIDE / side))))
    cell = size / 2.0**level
    cells = max(1, math.floor(side / cell + ZERO.whole_number))  # 8 / 1.6 is 4.999...
    x0, y0, x1, y1 = free_space.bounds
    lo = np.floor((np.array([x0, y0]) - origin) / cell).astype(np.int64)
    hi = np.ceil((np.array([x1, y1]) - origin) / cell).astype(np.int64)
    lo = np.maximum(lo, 0)
    ix, iy = np.meshgrid(np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1]))
    ix, iy = ix.ravel(), iy.ravel()
    bx, by = origin[0] + ix * cell, origin[1] + iy * cell
    shapely.prepare(free_space)
    keep = shapely.intersects(free_space, shapely.box(bx, by, bx + cell, by + cell))
    ix, iy = ix[keep], iy[keep]
    # Blocks counted from the floor's first cell (not the tree's): fewer tiles.
    tx, ty = (ix - lo[0]) // cells, (iy - lo[1]) // cells
    block = ty * (2**level) + tx
    tiles = []
    for b in np.unique(block):
        k = block == b
        x0, y0 = origin + (np.array([tx[k][0], ty[k][0]]) * cells + lo) * cell
        bounds = (float(x0), float(y0), float(x0 + cells * cell), float(y0 + cells * cell))
        tiles.append(Tile(len(tiles), ix[k], iy[k], bounds))
    return TilePlan(depth, size, origin, level, cells, cells * cell, tiles)


def _sample_keys(segs: np.ndarray, spacing: float) -> list[set]:
    """Each segment's sample points' xy keys, as :func:`mapkit.visibility._samples` makes them."""
    from mapkit.visibility import sample_segment

    out = []
    for s in segs:
        if np.linalg.norm(s[1, :2] - s[0, :2]) <= VIS_VERTICAL_XY:
            pts = [s[0, :2].tolist()]
        else:
            pts = sample_segment(s, spacing)[:, :2].tolist()
        out.append({(round(x, 7), round(y, 7)) for x, y in pts})
    return out


def tile_segments(segments: np.ndarray, bounds: tuple, settings: RegionSettings) -> np.ndarray:
    """(K,) ascending ids of the segments a tile computes: those within
    :func:`reach` of its square, and those sharing a sample point with them.

    The second kind cannot be listed in the tile; they are there so that
    the sample points are numbered in the order the one-piece build numbers
    them (by first appearance: the first segment holding a point is
    present), which decides the order of each overlay's operands and so
    its bits."""
    segs = np.asarray(segments, dtype=float)
    lines = shapely.linestrings(segs[:, :, :2])
    square = shapely.box(*bounds)
    near = np.nonzero(shapely.dwithin(lines, square, reach(settings)))[0]
    if not len(near):
        return near
    longest = float(shapely.length(lines[near]).max())
    around = np.nonzero(shapely.dwithin(lines, square, reach(settings) + longest + TILE_REACH_SLACK))[0]
    others = np.setdiff1d(around, near, assume_unique=True)
    if not len(others):
        return near
    spacing = settings.min_visible_length / 2.0
    keys = set().union(*_sample_keys(segs[near], spacing))
    sharing = [k for k, ks in zip(others, _sample_keys(segs[others], spacing)) if not ks.isdisjoint(keys)]
    return np.union1d(near, np.asarray(sharing, dtype=np.int64))


def _edges_near(occ, segs: np.ndarray, settings: RegionSettings):
    """``occ`` with only the edges whose boxes meet the squares the sweep
    looks at around the samples of ``segs`` (half-side ``max_range`` over
    the cosine, plus 1 cm, as :mod:`mapkit.visibility` sweeps), in their
    order: each sample's sweep sees the same edges in the same order, so
    its polygon is the same bit for bit, and the sweep does not pay for the
    whole floor's walls. ``geometry`` stays the whole floor's."""
    from mapkit.visibility import Occluders

    box = settings.max_range / math.cos(math.pi / CIRCLE_SIDES) + 0.01 + TILE_REACH_SLACK
    lo = segs[:, :, :2].reshape(-1, 2).min(axis=0) - box
    hi = segs[:, :, :2].reshape(-1, 2).max(axis=0) + box
    keep = (occ.hi[:, 0] >= lo[0]) & (occ.lo[:, 0] <= hi[0]) & (occ.hi[:, 1] >= lo[1]) & (occ.lo[:, 1] <= hi[1])
    return Occluders(occ.edges[keep], occ.lo[keep], occ.hi[keep], occ.geometry)


def build_tile(floor: Floor, plan: TilePlan, tile: Tile, workers: int = 1) -> TileRegions:
    """The regions of one tile (see the module docstring), ``workers`` threads."""
    from linemap.camera import Camera

    from mapkit.visibility import Occluders, Sight, segment_regions_within
    from mapkit.vir import grow_regions, merge_leaves, quadtree_leaves, region_geometry

    settings = floor.settings
    ids = tile_segments(floor.segments, tile.bounds, settings)
    if not len(ids):
        return TileRegions.pack(tile.index, [], [], np.zeros(0, dtype=np.uint64), {"segments": 0, "quadtree_leaves": 0})
    camera = Camera.from_dict(floor.camera)
    sight = Sight(camera.height_m, camera.elevation_range(), settings.max_range, float(settings.min_visible_length))
    occ = _edges_near(Occluders.from_geometry(floor.occluders), floor.segments[ids], settings)
    near = free_space_near(floor.free_space, tile.bounds, settings)
    sr = segment_regions_within(floor.segments[ids], occ, sight, near, workers=workers)
    grown = grow_regions(sr.regions, floor.free_space, settings.eps, workers)
    del sr
    release_memory()
    leaves = quadtree_leaves(grown, floor.free_space, settings.min_cell, workers=workers, roots=plan.roots(tile))
    del grown
    release_memory()
    groups, bits = merge_leaves(leaves, settings.merge_growth)
    polygons, lists, keys = region_geometry(leaves, groups, bits, floor.free_space, len(ids), workers)
    stats = {"segments": int(len(ids)), "quadtree_leaves": int(len(leaves.level))}
    return TileRegions.pack(tile.index, polygons, [ids[x] for x in lists], keys, stats)


def join_tiles(results: list, floor: Floor, plan: TilePlan) -> RegionPartition:
    """The tiles' regions as one partition, numbered along the Morton curve
    of their first cells (as the one-piece build numbers them)."""
    results = sorted(results, key=lambda r: r.index)
    polygons = [p for r in results for p in r.polygons()]
    lists = [x for r in results for x in r.lists()]
    keys = np.concatenate([r.keys for r in results] + [np.zeros(0, dtype=np.uint64)])
    order = np.argsort(keys, kind="stable")
    polygons, lists = [polygons[k] for k in order], [lists[k] for k in order]
    stats = {"segments": int(len(floor.segments)), **plan.record(),
             "tile_segments": int(sum(r.stats["segments"] for r in results)),
             "quadtree_leaves": int(sum(r.stats["quadtree_leaves"] for r in results)),
             "quadtree_depth": int(plan.depth), "smallest_cell_m": float(plan.size / 2.0**plan.depth)}
    stats.update(_partition_stats(polygons, lists, floor.free_space))
    return RegionPartition(polygons, lists, stats)


def build_regions_in_tiles(floor: Floor, plan: TilePlan, runner=None, progress: bool = False,
                           workers: int = 1) -> RegionPartition:
    """:func:`mapkit.vir.build_regions`'s partition, built tile by tile:
    one after the other in this process (``workers`` threads each), or by
    ``runner`` (:class:`mapkit.tile_runner.DaskTiles`). ``stats`` holds
    the tiling and ``time_total_s``."""
    t0 = time.perf_counter()
    if runner is None:
        results = run_here(floor, plan, progress, workers)
    else:
        results = runner.run(floor, plan, progress)
    part = join_tiles(results, floor, plan)
    part.stats["time_total_s"] = time.perf_counter() - t0
    return part


def run_here(floor: Floor, plan: TilePlan, progress: bool, workers: int) -> list:
    """Every tile in this process, one after the other (a bar over the tiles with ``progress``)."""
    from tqdm import tqdm

    out = []
    for tile in tqdm(plan.tiles, desc="tiles", unit="tile", disable=not progress, leave=False):
        try:
            out.append(build_tile(floor, plan, tile, workers))
        except Exception as exc:
            raise tile_error(tile, len(plan.tiles), exc) from exc
        release_memory()
    return out


def tile_error(tile: Tile, n_tiles: int, exc: Exception) -> Exception:
    """What a tile's failure is reported as: bad input (MapkitError) stays
    bad input, named with the tile's place; anything else is
    :class:`TileFailed` (a bug)."""
    if isinstance(exc, MapkitError):
        return MapkitError(f"tile {tile.index + 1} of {n_tiles} ({tile.place()}): {exc}")
    return TileFailed(tile, n_tiles, exc)


class TileFailed(RuntimeError):
    """A tile's build failed for a reason other than the input (a bug): the
    message says which tile, where, and what it raised."""

    def __init__(self, tile: Tile, n_tiles: int, exc: BaseException):
        super().__init__(f"tile {tile.index + 1} of {n_tiles} ({tile.place()}) failed: {type(exc).__name__}: {exc}")


__all__ = ["Floor", "Tile", "TileFailed", "TilePlan", "TileRegions", "build_regions_in_tiles", "build_tile",
           "free_space_near", "join_tiles", "plan_tiles", "predicted_peak_mb", "reach", "tile_error", "tile_segments",
           "tile_side_for_budget"]
