"""The view-invariant region (VIR) partition of the free space.

:func:`build_regions` cuts the free space into regions, each with the sorted
ids of every segment visible from within ``eps`` of it (docs/visibility.md).
Steps, each timed in ``stats``:

1. ``segment_regions``: per segment S a superset R_S of the floor points it
   is visible from (:mod:`mapkit.visibility`).
2. ``grow``: ``R_S^eps = (R_S & free_space) + disk(eps)`` (circumscribed).
3. ``quadtree``: adaptive cells over the free space; a cell is a leaf when
   every R_S^eps meeting it contains it, or at the minimum cell size (its
   list then holds every R_S^eps that meets it: still a superset).
4. ``merge``: leaves with equal lists that touch become one region; then
   neighbours whose lists differ little are merged (lists united, so still
   supersets) while the area-weighted mean list length grows by at most
   ``merge_growth``: fewer regions, a smaller map.
5. ``geometry``: each region is the union of its cells (a coverage union of
   squares noded on the finest grid) cut to the free space; regions are
   ordered along a Morton curve so that neighbours have close ids (the file
   XOR-codes consecutive lists).
"""

from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import Polygon
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from mapkit.memory import release_memory
from mapkit.options import option_default
from mapkit.parallel import map_chunks, map_owned
from mapkit.progress import step
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (
    OVERLAY_GRID,
    VIR_EPS_SLACK,
    VIR_LIST_CHUNK,
    VIR_MAX_DEPTH,
    VIR_MIN_CELL,
    VIR_PAIR_CHUNK,
    VIR_QUAD_SEGS,
    ZERO,
)
from mapkit.visibility import Occluders, Sight, polygonal, segment_regions_within


@dataclass
class RegionPartition:
    """The partition and its lists.

    - ``polygons``: R shapely Polygon/MultiPolygon, pairwise non-overlapping,
      their union is the free space (up to float noise).
    - ``lists``: R sorted int64 arrays of visible segment ids.
    - ``stats``: JSON-able timings (s) per step, counts, mean list length.
    """

    polygons: list
    lists: list
    stats: dict = field(default_factory=dict)


@dataclass(frozen=True)
class RegionSettings:
    """What "visible" and "region" mean to :func:`build_regions` (docs/visibility.md).

    - ``max_range`` (m): segments farther than this are not listed;
    - ``min_visible_length`` (m): a segment counts as visible if a
      contiguous piece this long is seen;
    - ``eps`` (m): a region's list holds everything visible within this of it;
    - ``min_cell`` (m): the smallest quadtree cell;
    - ``merge_growth``: the allowed relative growth of the mean list length
      when merging regions (0: merge equal lists only).

    The defaults are those of :class:`mapkit.options.BuildOptions`; a
    value out of range raises ValueError naming it.
    """

    max_range: float = option_default("max_range")
    min_visible_length: float = option_default("min_visible_length")
    eps: float = option_default("eps")
    min_cell: float = VIR_MIN_CELL
    merge_growth: float = option_default("merge_growth")

    def __post_init__(self):
        for name in ("max_range", "min_visible_length", "min_cell"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a finite number > 0.0, got {v}")
        for name in ("eps", "merge_growth"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {v}")

    @classmethod
    def from_options(cls, options) -> RegionSettings:
        """The settings a :class:`~mapkit.options.BuildOptions` asks for."""
        return cls(max_range=options.max_range, min_visible_length=options.min_visible_length, eps=options.eps,
                   merge_growth=options.merge_growth)


def _checked_segments(segments: np.ndarray, free_space) -> np.ndarray:
    """``segments`` as an (N, 2, 3) float array; ValueError naming what is
    wrong with them or with ``free_space``."""
    segs = np.asarray(segments, dtype=float)
    if segs.ndim != 3 or segs.shape[1:] != (2, 3):
        raise ValueError(f"segments: expected shape (N, 2, 3), got {segs.shape}")
    if not np.isfinite(segs).all():
        raise ValueError("segments: coordinates must be finite")
    if free_space is None or free_space.is_empty:
        raise ValueError("free_space is empty: no place for the camera")
    return segs


def build_regions(
    segments: np.ndarray,
    occluders,
    free_space,
    camera,
    settings: RegionSettings | None = None,
    *,
    progress: bool = False,
    workers: int = 1,
) -> RegionPartition:
    """Partition ``free_space`` into view-invariant regions.

    - ``segments`` (N, 2, 3) float, metres, world frame z up.
    - ``occluders``: shapely (Multi)Polygon, wall solids (full height, opaque).
    - ``free_space``: shapely (Multi)Polygon, where the camera centre may be.
    - ``camera``: :class:`linemap.camera.Camera` (``height_m``,
      ``elevation_range()``).
    - ``settings``: :class:`RegionSettings` (None: the defaults).
    - ``workers``: threads for the GEOS overlays and predicates
      (:mod:`mapkit.parallel`); the result does not depend on it.

    Guarantee: for every point q of the free space and every segment S
    visible from q, S is in the list of every region within ``eps`` of q.
    """
    settings = settings or RegionSettings()
    segs = _checked_segments(segments, free_space)
    stats: dict = {"segments": len(segs)}
    t0 = time.perf_counter()
    sight = Sight(camera.height_m, camera.elevation_range(), settings.max_range, float(settings.min_visible_length))
    sr = segment_regions_within(segs, Occluders.from_geometry(occluders), sight, free_space, progress=progress,
                                workers=workers)
    stats.update(sr.stats)
    t1 = time.perf_counter()
    stats["time_segment_regions_total_s"] = t1 - t0

    with step("region growth", progress):
        grown = grow_regions(sr.regions, free_space, settings.eps, workers)
    del sr  # memory: each step's input is freed once the next holds what it needs
    release_memory()
    t2 = time.perf_counter()
    stats["time_grow_s"] = t2 - t1

    leaves = quadtree_leaves(grown, free_space, settings.min_cell, progress=progress, workers=workers)
    del grown
    release_memory()
    t3 = time.perf_counter()
    stats["time_quadtree_s"] = t3 - t2
    stats["quadtree_leaves"] = len(leaves.level)
    stats["quadtree_depth"] = int(leaves.depth)
    stats["smallest_cell_m"] = float(leaves.size / 2.0**leaves.depth)

    release_memory()
    with step("region merging", progress):
        groups, bits = merge_leaves(leaves, settings.merge_growth)
    t4 = time.perf_counter()
    stats["time_merge_s"] = t4 - t3

    with step("region outlines", progress):
        polygons, lists, _ = region_geometry(leaves, groups, bits, free_space, len(segs), workers)
    t5 = time.perf_counter()
    stats["time_geometry_s"] = t5 - t4
    stats["time_total_s"] = t5 - t0
    stats.update(_partition_stats(polygons, lists, free_space))
    return RegionPartition(polygons, lists, stats)


def _partition_stats(polygons: list, lists: list, free_space) -> dict:
    """The partition's counts: regions, the area-weighted mean and the
    longest list length, the regions' and the free space's areas (m2)."""
    areas = np.array([g.area for g in polygons])
    lengths = np.array([len(x) for x in lists], dtype=float)
    return {
        "regions": len(polygons),
        "mean_list_length": float((areas * lengths).sum() / max(areas.sum(), ZERO.divisor)),
        "max_list_length": int(lengths.max()) if len(lengths) else 0,
        "region_area": float(areas.sum()),
        "free_space_area": float(free_space.area),
    }


# --------------------------------------------------------------------------
# Step 2: grow the visibility regions by eps


def grow_regions(regions: np.ndarray, free_space, eps: float, workers: int = 1) -> np.ndarray:
    """``(R_S & free_space) + disk(eps + VIR_EPS_SLACK)``, the disk circumscribed
    by the buffer's chords. ``regions`` (N,) object array; returns (N,) prepared
    geometries (empty where S is never visible). ``workers`` threads."""
    radius = (eps + VIR_EPS_SLACK) / math.cos(math.pi / (4 * VIR_QUAD_SEGS))

    def grow(part: np.ndarray) -> np.ndarray:
        # Each region meets the free space only within its own extent: clip
        # that first (cheap, no overlay), so each overlay sees the few rooms
        # near it and not the whole plan's outline.
        bounds = shapely.bounds(part)
        local = np.array([shapely.clip_by_rect(free_space, *b) if np.isfinite(b).all() else Polygon() for b in bounds] + [None])[:-1]
        clipped = polygonal(shapely.intersection(part, local, grid_size=OVERLAY_GRID))
        grown = shapely.buffer(clipped, radius, quad_segs=VIR_QUAD_SEGS)
        shapely.prepare(grown)
        return grown

    return map_chunks(grow, [regions], workers)


# --------------------------------------------------------------------------
# Step 3: adaptive quadtree


@dataclass
class Leaves:
    """Quadtree leaves and their lists, kept as the tree decided them.

    Cell (level, ix, iy) spans ``[x0 + ix*s, x0 + (ix+1)*s] x [y0 + iy*s, ...]``,
    ``s = size / 2**level``. A leaf's list is the union of the segments its
    own cell and each of its ancestors were found to be covered by (every
    segment is decided at one node only, so the sets are disjoint): storing
    them per node keeps memory linear in the plan, where one row per leaf
    over all segments would grow with its square.

    - ``level``, ``ix``, ``iy`` (M,) int64; ``node`` (M,) each leaf's node id;
    - ``parent`` (K,) int64, every node's parent node (-1 for the root);
    - ``node_ptr`` (K + 1,) int64, ``node_segs`` int32: the segments decided
      at node k are ``node_segs[node_ptr[k]:node_ptr[k + 1]]``;
    - ``n_segments``, ``depth`` the finest level, ``origin``, ``size``.
    """

    level: np.ndarray
    ix: np.ndarray
    iy: np.ndarray
    node: np.ndarray
    parent: np.ndarray
    node_ptr: np.ndarray
    node_segs: np.ndarray
    n_segments: int
    origin: np.ndarray
    size: float
    depth: int

    def lists(self, leaves: np.ndarray, ordered: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """The lists of ``leaves`` (L,) leaf indices as ``(owner, seg)``, both
        int32: pairs sorted by position in ``leaves`` then segment id
        (``owner`` indexes ``leaves``); in no particular order if not
        ``ordered`` (the sort is most of the cost)."""
        # Every (leaf position, node) of the leaves and their ancestors, then
        # the nodes' segments gathered once (few numpy calls per level).
        positions, nodes = [np.zeros(0, dtype=np.int32)], [np.zeros(0, dtype=np.int64)]
        cur = self.node[np.asarray(leaves, dtype=np.int64)]
        pos = np.arange(len(cur), dtype=np.int32)
        while len(cur):
            positions.append(pos)
            nodes.append(cur)
            up = self.parent[cur]
            pos, cur = pos[up >= 0], up[up >= 0]
        pos, cur = np.concatenate(positions), np.concatenate(nodes)
        start, count = self.node_ptr[cur], self.node_ptr[cur + 1] - self.node_ptr[cur]
        owner = np.repeat(pos, count)
        seg = self.node_segs[_ranges(start, count)]
        if not ordered:
            return owner, seg
        # One sort of owner * n + seg: a value sort, much cheaper than lexsort.
        n = max(self.n_segments, 1)
        key = owner.astype(np.int64) * n + seg
        key.sort()
        return (key // n).astype(np.int32), (key % n).astype(np.int32)


def _ranges(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Concatenated ``arange(start[i], start[i] + count[i])`` for all i."""
    total = int(count.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(count)
    first = np.repeat(start - (ends - count), count)
    return first + np.arange(total)


def _pairwise(predicate, geoms: np.ndarray, gi: np.ndarray, bi: np.ndarray, *cells: np.ndarray, workers: int = 1) -> np.ndarray:
    """``predicate(geoms[gi], *(c[bi] for c in cells))`` (P,) bool,
    ``VIR_PAIR_CHUNK`` pairs at a time: the gathered arrays would otherwise
    take 16 bytes a pair. In ``workers`` threads, each chunk of pairs with
    geometries of its own (``geoms`` are prepared: see :mod:`mapkit.parallel`)."""

    def test(g: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.empty(len(g), dtype=bool)
        for i in range(0, len(g), VIR_PAIR_CHUNK):
            j = b[i : i + VIR_PAIR_CHUNK]
            out[i : i + VIR_PAIR_CHUNK] = predicate(geoms[g[i : i + VIR_PAIR_CHUNK]], *(c[j] for c in cells))
        return out

    if workers <= 1:
        return test(gi, bi)
    return map_owned(lambda rows: test(gi[rows], bi[rows]), gi, len(geoms), workers)


def _meets(grown: np.ndarray, ps: np.ndarray, pc: np.ndarray, boxes: np.ndarray, centre: tuple, workers: int = 1,
           corner: tuple | None = None, need_centre: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(hit, centre_in)`` (P,) bool each: whether ``grown[ps]`` meets cell
    box ``boxes[pc]``, and whether it holds the cell's centre ``centre =
    (cx, cy)`` ((C,) each) in its interior. A region holding the centre
    meets the cell; that point test costs a quarter of the box test and
    settles most pairs (GEOS's predicates are exact, so the answers are
    those of the box test alone).

    ``corner`` is None or ``(pin, qx, qy, shared)`` (:func:`_parent_corner`):
    ``pin`` (P,) whether the pair's region held the parent cell's centre in
    its interior, ``(qx, qy)`` (C,) each cell's box corner at that centre,
    ``shared`` (C,) whether the two are the same point bit for bit. A box
    corner in the region's interior makes the pair meet, so pairs with
    ``pin`` where ``shared`` are asked nothing, and where not, the corner
    before the box. Without ``need_centre`` the caller needs only ``hit``: the
    centre is then not asked of pairs with ``pin`` (the corner, next to the
    point their region held, is the likelier hit), and ``centre_in`` is
    False for them."""
    n = len(ps)
    pin, qx, qy, shared = corner if corner is not None else (np.zeros(n, dtype=bool), None, None, None)
    known = pin & shared[pc] if corner is not None else pin
    ask = np.arange(n) if need_centre else np.nonzero(~pin)[0]
    centre_in = np.zeros(n, dtype=bool)
    centre_in[ask] = _pairwise(shapely.contains_xy, grown, ps[ask], pc[ask], *centre, workers=workers)
    hit = centre_in | known
    near = np.nonzero(~hit & pin)[0]
    if len(near):
        hit[near] = _pairwise(shapely.contains_xy, grown, ps[near], pc[near], qx, qy, workers=workers)
    rest = np.nonzero(~hit)[0]
    hit[rest] = _pairwise(shapely.intersects, grown, ps[rest], pc[rest], boxes, workers=workers)
    return hit, centre_in


def _quadtree_frame(free_space, min_cell: float) -> tuple[int, float, np.ndarray]:
    """``(depth, size, origin)`` of the quadtree over ``free_space``: the
    root square of side ``size`` (m) centred on its bounding box, with
    lower-left corner ``origin`` (2,), halved ``depth`` times down to cells
    of ``min_cell`` (wider on plans past ``VIR_MAX_DEPTH`` levels)."""
    x0, y0, x1, y1 = free_space.bounds
    span = max(x1 - x0, y1 - y0, min_cell)
    depth = max(0, math.ceil(math.log2(span / min_cell) - ZERO.whole_number))
    if depth > VIR_MAX_DEPTH:  # huge plan: wider smallest cells, bounded memory
        depth = VIR_MAX_DEPTH
        min_cell = span / 2.0**depth
    size = min_cell * 2.0**depth
    origin = np.array([(x0 + x1 - size) / 2.0, (y0 + y1 - size) / 2.0])
    return depth, size, origin


@dataclass
class _Level:
    """One level of the quadtree while it is built: its cells ``ix``, ``iy``
    (C,) and their node ids ``node`` (C,); the still-undecided (cell,
    segment) pairs ``pc``, ``ps`` (P,) int32 (cell index into this level,
    segment id), and ``pin`` (P,) bool, whether the pair's region holds the
    centre of the cell's parent in its interior (False at the root)."""

    ix: np.ndarray
    iy: np.ndarray
    node: np.ndarray
    pc: np.ndarray
    ps: np.ndarray
    pin: np.ndarray


def _parent_corner(ix: np.ndarray, iy: np.ndarray, origin: np.ndarray, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(qx, qy, shared)`` (C,) each: the corner of each cell's box (as
    this level builds it) at the centre of its parent (as the parent's level
    computed it), and whether the two are the same point bit for bit.
    Mathematically they always are (the parent's centre is the corner its
    four children share); in floats the sums giving them may round apart."""
    parent = 2.0 * s  # exact: a power of two apart
    px = (origin[0] + (ix // 2) * parent) + parent / 2
    py = (origin[1] + (iy // 2) * parent) + parent / 2
    bx, by = origin[0] + ix * s, origin[1] + iy * s
    # Even children lie left of (below) the parent's centre: their right (top) side.
    qx = np.where(ix % 2 == 0, bx + s, bx)
    qy = np.where(iy % 2 == 0, by + s, by)
    return qx, qy, (px == qx) & (py == qy)


def _decide_level(cells: _Level, grown: np.ndarray, free, boxes_at: tuple, last: bool, workers: int):
    """Decide one level's pairs: cells off ``free`` dropped, pairs whose
    region misses the cell dropped, pairs whose region covers the cell (all
    at the ``last`` level) decided. ``boxes_at`` is ``(origin, s)``, the
    tree's origin and this level's cell side. Returns the cells kept (with
    their undecided pairs), the decided ``(node, seg)`` int32 arrays, and
    ``done`` (C,) bool, the cells left with nothing to decide."""
    origin, s = boxes_at
    bx, by = origin[0] + cells.ix * s, origin[1] + cells.iy * s
    boxes = shapely.box(bx, by, bx + s, by + s)
    # Cells off the free space are dropped; pairs follow their cells.
    keep = shapely.intersects(free, boxes)
    remap = (np.cumsum(keep) - 1).astype(np.int32)
    alive = keep[cells.pc]
    pc, ps, pin = remap[cells.pc[alive]], cells.ps[alive], cells.pin[alive]
    ix, iy, node, boxes = cells.ix[keep], cells.iy[keep], cells.node[keep], boxes[keep]
    # Pairs whose region held the parent's centre meet the cell where that
    # point is one of its corners, and most likely where it is a float away.
    corner = _parent_corner(ix, iy, origin, s)
    corner = None if corner is None else (pin, *corner)  # None: the tests' plain form
    hit, centre_in = _meets(grown, ps, pc, boxes, (bx[keep] + s / 2, by[keep] + s / 2), workers, corner, not last)
    pc, ps, centre_in = pc[hit], ps[hit], centre_in[hit]
    if last:  # smallest cells keep every segment that may be seen
        full = np.ones(len(pc), dtype=bool)
    else:
        # A region covering the cell holds its centre (strictly inside the
        # box) in its interior: only pairs whose centre test hit can be
        # covered, so the box test is asked of those alone (the predicates
        # are exact: the answers are those of asking every pair).
        full = np.zeros(len(pc), dtype=bool)
        inside = np.nonzero(centre_in)[0]
        full[inside] = _pairwise(shapely.covers, grown, ps[inside], pc[inside], boxes, workers=workers)
    decided = (node[pc[full]].astype(np.int32), ps[full].astype(np.int32))
    pc, ps, centre_in = pc[~full], ps[~full], centre_in[~full]
    open_count = np.bincount(pc, minlength=len(ix))
    done = open_count == 0 if not last else np.ones(len(ix), dtype=bool)
    return _Level(ix, iy, node, pc, ps, centre_in), decided, done


def _split_cells(cells: _Level, done: np.ndarray, n_nodes: int) -> tuple[_Level, np.ndarray]:
    """The next level: each undecided cell of ``cells`` split in four, the
    children numbered from ``n_nodes`` on and inheriting their parent's
    undecided pairs. Returns it and the children's parent node ids."""
    split = np.nonzero(~done)[0]
    child_of = np.full(len(cells.ix), -1)
    child_of[split] = np.arange(len(split))
    dx = np.array([0, 1, 0, 1])
    dy = np.array([0, 0, 1, 1])
    ix = (2 * cells.ix[split][:, None] + dx).ravel()
    iy = (2 * cells.iy[split][:, None] + dy).ravel()
    parents = np.repeat(cells.node[split], 4)
    node = n_nodes + np.arange(4 * len(split), dtype=np.int64)
    base = (child_of[cells.pc] * 4).astype(np.int32)
    pc = (base[:, None] + np.arange(4, dtype=np.int32)).ravel()
    ps = np.repeat(cells.ps, 4)
    pin = np.repeat(cells.pin, 4)  # the parent's centre test, for each child
    return _Level(ix, iy, node, pc, ps, pin), parents


def _node_lists(dec_node: list, dec_seg: list, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """``(node_ptr, node_segs)`` of :class:`Leaves` from the per-level
    decided (node, segment) arrays (emptied as they are used: memory)."""
    dn = np.concatenate(dec_node)
    dec_node.clear()
    node_ptr = np.zeros(n_nodes + 1, dtype=np.int64)
    np.cumsum(np.bincount(dn, minlength=n_nodes), out=node_ptr[1:])
    node_segs = np.concatenate(dec_seg)
    dec_seg.clear()
    node_segs = node_segs[np.argsort(dn, kind="stable")]
    return node_ptr, node_segs


@dataclass(frozen=True)
class QuadRoots:
    """Where a quadtree starts when it covers part of a floor (a tile,
    :mod:`mapkit.tiles`): the whole floor's frame (``depth``, ``size``,
    ``origin`` of :func:`_quadtree_frame`) and the cells ``ix``, ``iy`` (C,)
    int64 of ``level`` it starts from. The cells, their boxes and the tests
    on them are those of the whole floor's tree, bit for bit."""

    depth: int
    size: float
    origin: np.ndarray
    level: int
    ix: np.ndarray
    iy: np.ndarray


def quadtree_roots(free_space, min_cell: float) -> QuadRoots:
    """The one root of the whole floor's quadtree (level 0)."""
    depth, size, origin = _quadtree_frame(free_space, min_cell)
    return QuadRoots(depth, size, origin, 0, np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64))


def _root_level(grown: np.ndarray, roots: QuadRoots) -> _Level:
    """The first level of a tree starting at ``roots``: one node per root
    cell, each paired with every region whose box meets the cell's."""
    s = roots.size / 2.0**roots.level
    bx, by = roots.origin[0] + roots.ix * s, roots.origin[1] + roots.iy * s
    tree = shapely.STRtree(grown)
    if roots.level == 0:  # the whole floor's square, as it has always been asked
        ps = tree.query(shapely.box(bx[0], by[0], bx[0] + s, by[0] + s))
        pc = np.zeros(len(ps), dtype=np.int32)
    else:
        pc, ps = tree.query(shapely.box(bx, by, bx + s, by + s))
    n = len(roots.ix)
    return _Level(roots.ix.astype(np.int64), roots.iy.astype(np.int64), np.arange(n, dtype=np.int64),
                  pc.astype(np.int32), ps.astype(np.int32), np.zeros(len(ps), dtype=bool))


def quadtree_leaves(grown: np.ndarray, free_space, min_cell: float, progress: bool = False, workers: int = 1,
                    roots: QuadRoots | None = None) -> Leaves:
    """Subdivide until each cell's list is decided (see the module docstring).

    Per level, every still-undecided (cell, segment) pair is tested at once
    with shapely's vectorised predicates on prepared geometries: ``intersects``
    (S may be listed) then ``covers`` (S is listed for every child too; asked
    only where S's region holds the cell's centre, and not at the finest
    level, which lists whatever meets it).
    Children test only their parent's undecided segments; a child whose
    segment's region held the parent's centre (a corner of the child) meets
    it without a test. What a cell is covered by is stored once, at that
    cell (:class:`Leaves`). The pair tests run in ``workers`` threads.

    ``roots`` (None: the whole floor's one root) starts the tree at some
    cells of the whole floor's tree instead (a tile): their leaves are
    those of the whole floor's tree within them, with the same lists (a
    leaf of the whole tree larger than a root cell comes out cut along it).
    """
    from tqdm import tqdm

    roots = roots or quadtree_roots(free_space, min_cell)
    depth, size, origin = roots.depth, roots.size, roots.origin
    free = free_space
    shapely.prepare(free)

    cells = _root_level(grown, roots)
    parents = [np.full(len(cells.node), -1, dtype=np.int64)]
    n_nodes = len(cells.node)
    out_level, out_ix, out_iy, out_node = [], [], [], []
    dec_node, dec_seg = [], []
    for lev in tqdm(range(roots.level, depth + 1), desc="region quadtree", disable=not progress, leave=False):
        cells, decided, done = _decide_level(cells, grown, free, (origin, size / 2.0**lev), lev == depth, workers)
        dec_node.append(decided[0])
        dec_seg.append(decided[1])
        out_level.append(np.full(int(done.sum()), lev))
        out_ix.append(cells.ix[done])
        out_iy.append(cells.iy[done])
        out_node.append(cells.node[done])
        if lev == depth or done.all():
            break
        # Split the undecided cells in four; children inherit the parent's list.
        cells, parent_row = _split_cells(cells, done, n_nodes)
        parents.append(parent_row)
        n_nodes += len(cells.node)
        release_memory()  # this level's cells and tests
    del cells
    node_ptr, node_segs = _node_lists(dec_node, dec_seg, n_nodes)
    return Leaves(
        np.concatenate(out_level).astype(np.int64),
        np.concatenate(out_ix).astype(np.int64),
        np.concatenate(out_iy).astype(np.int64),
        np.concatenate(out_node).astype(np.int64),
        np.concatenate(parents),
        node_ptr,
        node_segs,
        len(grown),
        origin,
        size,
        depth,
    )


# --------------------------------------------------------------------------
# Step 4: merge leaves into regions


@dataclass
class Raster:
    """Leaf labels on the finest grid, cropped to the leaves' extent.

    ``labels`` (H, W) int32: the leaf covering fine cell ``(oy + row, ox + col)``
    (in finest-level cell indices), -1 where none (off the free space)."""

    labels: np.ndarray
    ox: int
    oy: int


def leaf_raster(leaves: Leaves) -> Raster:
    """Paint every leaf on the finest grid (see :class:`Raster`)."""
    w = 2 ** (leaves.depth - leaves.level)
    if len(w) == 0:
        return Raster(np.full((0, 0), -1, dtype=np.int32), 0, 0)
    x0, y0 = leaves.ix * w, leaves.iy * w
    ox, oy = int(x0.min()), int(y0.min())
    lab = np.full((int((y0 + w).max()) - oy, int((x0 + w).max()) - ox), -1, dtype=np.int32)
    for lev in np.unique(leaves.level):
        k = np.nonzero(leaves.level == lev)[0]
        side = 2 ** (leaves.depth - int(lev))
        off = np.arange(side)
        # Every fine cell of every leaf of this level, by broadcasting.
        ys = (y0[k] - oy)[:, None, None] + off[None, :, None]
        xs = (x0[k] - ox)[:, None, None] + off[None, None, :]
        lab[ys, xs] = k[:, None, None]
    return Raster(lab, ox, oy)


def adjacent_pairs(labels: np.ndarray) -> np.ndarray:
    """(P, 2) distinct unordered pairs of labels that share a cell side."""
    pairs = np.concatenate(
        [
            np.stack([labels[:, :-1].ravel(), labels[:, 1:].ravel()], 1),
            np.stack([labels[:-1, :].ravel(), labels[1:, :].ravel()], 1),
        ]
    )
    pairs = pairs[(pairs[:, 0] != pairs[:, 1]) & (pairs >= 0).all(axis=1)]
    return unique_pairs(pairs)


def unique_pairs(pairs: np.ndarray) -> np.ndarray:
    """``np.unique(np.sort(pairs, axis=1), axis=0)`` for (P, 2) non-negative
    ints: each pair as (low, high), the distinct ones in lexicographic order,
    same dtype. One value sort of ``low * base + high`` (``base`` past every
    label), duplicates dropped by hand: the row sort, and ``np.unique`` even
    on plain values, cost tens of times more."""
    lo = np.minimum(pairs[:, 0], pairs[:, 1]).astype(np.int64)
    hi = np.maximum(pairs[:, 0], pairs[:, 1]).astype(np.int64)
    base = int(hi.max()) + 1 if len(hi) else 1
    key = np.sort(lo * base + hi)
    key = key[np.concatenate([key[:1] == key[:1], key[1:] != key[:-1]])]
    return np.stack([key // base, key % base], axis=1).astype(pairs.dtype)


def _leaf_fingerprints(leaves: Leaves) -> tuple[np.ndarray, np.ndarray]:
    """(M,) uint64 sums of a random key per listed segment, and (M,) list lengths:
    equal lists have equal fingerprints (the sum of disjoint sets adds up)."""
    key = np.random.default_rng(0).integers(0, 2**63, size=max(leaves.n_segments, 1), dtype=np.uint64)
    run = np.zeros(len(leaves.node_segs) + 1, dtype=np.uint64)
    np.cumsum(key[leaves.node_segs], out=run[1:])  # wraps modulo 2**64, as wanted
    node_hash = run[leaves.node_ptr[1:]] - run[leaves.node_ptr[:-1]]
    node_count = np.diff(leaves.node_ptr)
    fp = np.zeros(len(leaves.node), dtype=np.uint64)
    count = np.zeros(len(leaves.node), dtype=np.int64)
    cur, pos = leaves.node.copy(), np.arange(len(leaves.node))
    while len(cur):
        fp[pos] += node_hash[cur]
        count[pos] += node_count[cur]
        up = leaves.parent[cur]
        pos, cur = pos[up >= 0], up[up >= 0]
    return fp, count


def equal_lists(leaves: Leaves, pairs: np.ndarray) -> np.ndarray:
    """(P,) bool: whether the leaves of each pair (P, 2) have the same list.

    Fingerprints rule most pairs out; the rest are compared segment by
    segment, ``VIR_LIST_CHUNK`` listed segments at a time."""
    fp, count = _leaf_fingerprints(leaves)
    maybe = np.nonzero((fp[pairs[:, 0]] == fp[pairs[:, 1]]) & (count[pairs[:, 0]] == count[pairs[:, 1]]))[0]
    out = np.zeros(len(pairs), dtype=bool)
    chunk = max(1, VIR_LIST_CHUNK // max(1, int(count.max(initial=1))))
    for i in range(0, len(maybe), chunk):
        k = maybe[i : i + chunk]
        owner_a, seg_a = leaves.lists(pairs[k, 0])
        _, seg_b = leaves.lists(pairs[k, 1])
        # Equal lengths pair by pair, so the two concatenations line up.
        differs = np.bincount(owner_a[seg_a != seg_b], minlength=len(k))
        out[k] = differs == 0
    return out


def list_bitsets(leaves: Leaves, which: np.ndarray) -> list[int]:
    """The lists of leaves ``which`` as Python int bitsets (bit i: segment i)."""
    n = leaves.n_segments
    out: list[int] = []
    chunk = max(1, VIR_LIST_CHUNK // max(n, 1))
    for i in range(0, len(which), chunk):
        k = np.asarray(which[i : i + chunk])
        owner, seg = leaves.lists(k, ordered=False)
        rows = np.zeros((len(k), n), dtype=bool)
        rows[owner, seg] = True
        packed = np.packbits(rows, axis=1, bitorder="little")
        out.extend(int.from_bytes(r.tobytes(), "little") for r in packed)
    return out


def _equal_list_components(leaves: Leaves) -> tuple[int, np.ndarray, np.ndarray]:
    """``(n_comp, comp, pairs)``: touching leaves with equal lists joined
    (connected components): ``comp`` (M,) each leaf's component, ``pairs``
    (P, 2) the touching leaves."""
    m = len(leaves.level)
    pairs = adjacent_pairs(leaf_raster(leaves).labels)
    same = pairs[equal_lists(leaves, pairs)]
    graph = coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(m, m))
    n_comp, comp = connected_components(graph, directed=False)
    return n_comp, comp, pairs


class _Agglomeration:
    """The greedy merge of :func:`merge_leaves` over regions 0..R-1: each
    region's ``area`` (m2), list ``bits`` (Python int bitsets) and their
    ``count``; ``nbrs[n]`` maps each current neighbour x of n to the cost of
    merging n and x (:meth:`entry`'s first member, kept at both ends);
    ``parent`` says which region each joined (itself while it stands),
    ``version`` how often it grew."""

    def __init__(self, area: list, bits: list, pair_ids: list):
        n = len(area)
        self.area, self.bits = area, bits
        self.count = [b.bit_count() for b in bits]
        self.nbrs: list[dict] = [{} for _ in range(n)]
        for a, b in pair_ids:
            self.nbrs[a][b] = None  # costed by first_queue
            self.nbrs[b][a] = None
        self.parent = list(range(n))
        self.version = [0] * n

    def entry(self, a: int, b: int, owner: int) -> tuple:
        """The queue entry of merging a and b (a < b): cost, then ties broken
        by (a, b, their versions); ``owner`` the end it is the cheapest of."""
        bits, area, count, version = self.bits, self.area, self.count, self.version
        u = (bits[a] | bits[b]).bit_count()
        return (area[a] * (u - count[a]) + area[b] * (u - count[b]), a, b, version[a], version[b], owner)

    def _entry_of(self, n: int, x: int, cost: float) -> tuple:
        """The entry, owned by ``n``, of merging n with its neighbour x at ``cost``."""
        version = self.version
        if n < x:
            return (cost, n, x, version[n], version[x], n)
        return (cost, x, n, version[x], version[n], n)

    def cheapest(self, n: int):
        """The entry of n's cheapest merge with a current neighbour, or None,
        from the costs kept in ``nbrs``.

        Only the costs are compared, the entry made once at the end: among
        n's own pairs, entries of equal cost are ordered by the pair, which
        is the lower partner first whichever side of n it is on, so the
        entry chosen is the least of all of them."""
        best_c, best_x = math.inf, -1
        for x, c in self.nbrs[n].items():
            if c < best_c or (c == best_c and x < best_x):
                best_c, best_x = c, x
        return None if best_x < 0 else self._entry_of(n, best_x, best_c)

    def rescore(self, n: int):
        """Cost every pair of n anew (n's list or area changed), keep the
        costs at both ends, and return :meth:`cheapest` of n (inlined: this
        is the hot loop). Each cost is the sum :meth:`entry` makes, in its
        order: the same float."""
        bits, area, count, nbrs = self.bits, self.area, self.count, self.nbrs
        bits_n, count_n, area_n, nbrs_n = bits[n], count[n], area[n], nbrs[n]
        best_c, best_x = math.inf, -1
        for x in nbrs_n:
            u = (bits_n | bits[x]).bit_count()
            if n < x:
                c = area_n * (u - count_n) + area[x] * (u - count[x])
            else:
                c = area[x] * (u - count[x]) + area_n * (u - count_n)
            nbrs_n[x] = c  # a value replaced, the keys unchanged: safe while iterating
            nbrs[x][n] = c
            if c < best_c or (c == best_c and x < best_x):
                best_c, best_x = c, x
        return None if best_x < 0 else self._entry_of(n, best_x, best_c)

    def first_queue(self, pair_ids: list) -> list:
        """Cost every pair of ``pair_ids`` ((a, b), a < b, each once) into
        ``nbrs``; a heap holding every region's cheapest merge among them."""
        bits, area, count, nbrs = self.bits, self.area, self.count, self.nbrs
        for a, b in pair_ids:
            u = (bits[a] | bits[b]).bit_count()
            c = area[a] * (u - count[a]) + area[b] * (u - count[b])
            nbrs[a][b] = c
            nbrs[b][a] = c
        heap = [e for e in map(self.cheapest, range(len(area))) if e is not None]
        heapq.heapify(heap)
        return heap

    def join(self, a: int, b: int) -> None:
        """Region b joins region a: lists united, areas added, neighbours
        moved. The costs of a's pairs are left stale: :meth:`rescore` a next."""
        bits, nbrs = self.bits, self.nbrs
        self.parent[b] = a
        bits[a] |= bits[b]
        self.count[a] = bits[a].bit_count()
        bits[b] = 0  # b's list lives on in a's
        self.area[a] += self.area[b]
        self.version[a] += 1
        nbrs_a = nbrs[a]
        for x in nbrs[b]:
            del nbrs[x][b]
            if x != a:
                nbrs[x][a] = None
                nbrs_a[x] = None
        nbrs_a.pop(b, None)
        nbrs[b] = {}

    def run(self, heap: list, budget: float) -> None:
        """Merge the cheapest current pair first until the summed cost would
        pass ``budget``.

        The queue holds, for every region, its cheapest merge (and outdated
        entries, skipped when popped). Every current pair (a, b) then has an
        entry in the queue no later than its own: that of a or b, or of the
        one of them whose cheapest merge it was when it last changed. So the
        first current entry popped is the cheapest current pair, ties broken
        by (a, b, versions), as if every pair were queued. When an outdated
        entry's owner is still as it was (its partner changed), the owner's
        cheapest merge is queued anew; it cannot come before the popped one.
        Only a join changes costs, those of the joined region's pairs, which
        are costed anew at once: every kept cost is current."""
        parent, version = self.parent, self.version
        spent = 0.0
        while heap and budget > 0:
            c, a, b, va, vb, owner = heapq.heappop(heap)
            if version[a] != va or version[b] != vb or parent[a] != a or parent[b] != b:
                vo = va if owner == a else vb
                if parent[owner] == owner and version[owner] == vo:
                    e = self.cheapest(owner)
                    if e is not None:
                        heapq.heappush(heap, e)
                continue
            if spent + c > budget:
                break
            spent += c
            self.join(a, b)
            e = self.rescore(a)
            if e is not None:
                heapq.heappush(heap, e)

    def groups(self) -> tuple[np.ndarray, list[int]]:
        """Each region's final group (R,) and the groups' list bitsets."""
        root = np.array(self.parent)
        while True:  # path compression to the final representatives
            nxt = root[root]
            if (nxt == root).all():
                break
            root = nxt
        reps, group = np.unique(root, return_inverse=True)
        return group.ravel(), [self.bits[r] for r in reps]


def merge_leaves(leaves: Leaves, merge_growth: float) -> tuple[np.ndarray, list[int]]:
    """Group leaves into regions. Returns ``group`` (M,) region index of each
    leaf and the region lists as Python int bitsets (bit i: segment i).

    First, touching leaves with equal lists join (connected components).
    Then a greedy agglomeration: the cost of merging A and B is the growth of
    the summed area x list length, ``a_A (|A u B| - |A|) + a_B (|A u B| - |B|)``;
    the cheapest pair is merged first, until the total growth would exceed
    ``merge_growth`` times the starting sum.
    """
    m = len(leaves.level)
    n_comp, comp, pairs = _equal_list_components(leaves)
    first = np.full(n_comp, -1)
    first[comp[::-1]] = np.arange(m)[::-1]
    cell_area = (leaves.size / 2.0**leaves.level) ** 2
    area = np.bincount(comp, weights=cell_area, minlength=n_comp).tolist()
    cpairs = unique_pairs(comp[pairs])
    cpairs = cpairs[cpairs[:, 0] != cpairs[:, 1]]
    # One int object per component, shared by the sets and heap entries
    # below (ids from .tolist() would be new objects each: tens of MB).
    ids = list(range(n_comp))
    pair_ids = [(ids[a], ids[b]) for a, b in zip(cpairs[:, 0].tolist(), cpairs[:, 1].tolist())]
    merge = _Agglomeration(area, list_bitsets(leaves, first), pair_ids)
    budget = merge_growth * sum(a * c for a, c in zip(merge.area, merge.count))
    heap = merge.first_queue(pair_ids)
    del pair_ids
    merge.run(heap, budget)
    group_of_comp, bits = merge.groups()
    return group_of_comp[comp], bits


# --------------------------------------------------------------------------
# Step 5: region outlines


def _morton(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Interleave the bits of non-negative ints x, y (< 2**31): Z-order keys."""
    def spread(v):
        v = v.astype(np.uint64) & np.uint64(0xFFFFFFFF)
        for shift, mask in ((16, 0x0000FFFF0000FFFF), (8, 0x00FF00FF00FF00FF), (4, 0x0F0F0F0F0F0F0F0F), (2, 0x3333333333333333), (1, 0x5555555555555555)):
            v = (v | (v << np.uint64(shift))) & np.uint64(mask)
        return v

    return spread(x) | (spread(y) << np.uint64(1))


def leaf_squares(leaves: Leaves) -> np.ndarray:
    """(M,) shapely squares of the leaves, each ring holding every finest-grid
    point along its sides, all taken from one array of grid lines: squares
    that touch then share their boundary vertices bit for bit, which is what
    GEOS's coverage union (linear time: shared edges cancel) needs."""
    lines = np.arange(2**leaves.depth + 1) * (leaves.size / 2.0**leaves.depth)
    gx, gy = leaves.origin[0] + lines, leaves.origin[1] + lines
    out = np.empty(len(leaves.level), dtype=object)
    for lev in np.unique(leaves.level):
        k = np.nonzero(leaves.level == lev)[0]
        w = 2 ** (leaves.depth - int(lev))
        t = np.arange(w)
        x0, y0 = (leaves.ix[k] * w)[:, None], (leaves.iy[k] * w)[:, None]
        # Counter-clockwise: bottom, right, top, left side, then close.
        xi = np.concatenate([x0 + t, np.broadcast_to(x0 + w, (len(k), w)), x0 + w - t, np.broadcast_to(x0, (len(k), w)), x0], 1)
        yi = np.concatenate([np.broadcast_to(y0, (len(k), w)), y0 + t, np.broadcast_to(y0 + w, (len(k), w)), y0 + w - t, y0], 1)
        out[k] = shapely.polygons(np.stack([gx[xi], gy[yi]], axis=-1))
    return out


def region_geometry(leaves: Leaves, group: np.ndarray, bits: list[int], free_space, n_segments: int, workers: int = 1):
    """Outlines (union of each region's leaf squares, cut to the free space),
    lists, and each region's Morton key (R,) uint64, in which order they
    come. Regions left empty by the cut are dropped.

    Squares are unioned with GEOS's coverage union (see :func:`leaf_squares`),
    collinear grid vertices are dropped, then the free space, clipped to the
    region's bounding box, cuts the result, in ``workers`` threads. Regions
    are numbered by the Morton key of their first leaf (an aligned quadtree
    cell's lowest key is its lower-left finest cell)."""
    n_groups = len(bits)
    scale = 2 ** (leaves.depth - leaves.level)
    key = _morton(leaves.ix * scale, leaves.iy * scale)
    first_key = np.full(n_groups, np.iinfo(np.uint64).max, dtype=np.uint64)
    np.minimum.at(first_key, group, key)
    order = np.argsort(first_key, kind="stable")
    squares = leaf_squares(leaves)
    by_group = np.argsort(group, kind="stable")
    bounds = np.searchsorted(group[by_group], np.arange(n_groups + 1))

    def outline(groups: np.ndarray) -> np.ndarray:
        merged = np.array(
            [shapely.coverage_union_all(squares[by_group[bounds[g] : bounds[g + 1]]]) for g in groups] + [None]
        )[:-1]
        merged = shapely.simplify(merged, 0.0)
        # Each region meets the free space only near itself: clip that first,
        # so the overlay sees a few local edges rather than the whole plan's.
        local = np.array([shapely.clip_by_rect(free_space, *b) for b in shapely.bounds(merged)] + [None])[:-1]
        return polygonal(shapely.intersection(merged, polygonal(local)))

    cut = map_chunks(outline, [np.arange(n_groups)], workers)
    polygons, lists, keys = [], [], []
    ids = np.arange(n_segments)
    for g in order:
        parts = [p for p in polygon_parts(cut[g]) if p.area > 0]
        if not parts:
            continue
        keys.append(first_key[g])
        polygons.append(parts[0] if len(parts) == 1 else shapely.MultiPolygon(parts))
        row = np.frombuffer(bits[g].to_bytes((n_segments + 7) // 8, "little"), dtype=np.uint8)
        lists.append(ids[np.unpackbits(row, count=n_segments, bitorder="little").astype(bool)].astype(np.int64))
    return polygons, lists, np.array(keys, dtype=np.uint64)


__all__ = ["Leaves", "RegionPartition", "RegionSettings", "build_regions", "grow_regions", "merge_leaves", "quadtree_leaves", "quadtree_roots", "region_geometry", "QuadRoots"]
