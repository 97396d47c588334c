"""What the interpretation tree searches: one frame's correspondences with
their strips, masks, half-planes and pairwise table, and the map's walls
and free space for the set checks."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from matcher.budget import NO_LIMIT, Deadlines


@dataclass
class TreeInput:
    """Per correspondence k: strip quadratics ``quad`` (K, Y, 6) and yaw masks
    ``mask`` (K, Y) on the grid ``yaws`` (Y,); ``compat`` (K, K) bool pairwise
    compatibility (the tree relies on it: a pair in compat is taken as
    feasible, as :func:`matcher.search.tree.pairwise.pair_compatibility` tests it, and two
    correspondences on one segment are in compat only if their lines may be
    pieces of one line); ``segments``
    (K, 2, 3) the matched model segment (world); ``centre`` (3,) the prior
    camera centre, ``dt`` the disk radius; ``forward`` (Y, 3) the optical axis
    at each grid yaw; ``walls`` a pair of (E, 2) arrays, the wall edges' end
    points, or None; ``vertical`` (K,) bool, correspondences of vertical
    segments (explored last: each fixes only a bearing, so they are compatible
    with much and prune little); ``line`` (K,) the image line of each
    correspondence; ``free`` the map's :class:`~matcher.map_geometry.freespace.FreeSpace`
    (or None) and ``free_m`` how far outside it the camera may stand;
    ``front_c`` (K, Y, 2) and ``front_b`` (K, Y) half-planes ``c . z <= b`` on
    the camera position relative to the centre that keep a vertical edge ahead
    of the camera (c = 0, b = inf for the others), or None; ``single_fit`` (K,)
    each correspondence's best value alone (the root's look-ahead: the summed
    quadratic's minimum over the yaws where it passes every test of the
    look-ahead, inf where none), or None to compute it at the root; ``sight``
    the walls' :class:`~matcher.map_geometry.occlusion.SightRays` (how far one sees from a
    vertical edge, per bearing), or None to cast sight lines; ``shown`` the
    :class:`~matcher.projection.ShownSpans` of the correspondences (``segments``
    with their image lines), or None: with it, visibility is tested on the
    part of the segment the line shows at the set's pose (else on points
    spread over the whole segment); ``deadlines`` the caller's time budget
    (:class:`~matcher.budget.Deadlines`): past its ``search`` the tree stops
    as at ``max_nodes``, past its ``checks`` the final tests of the sets
    found stop."""

    quad: np.ndarray
    mask: np.ndarray
    yaws: np.ndarray
    compat: np.ndarray
    segments: np.ndarray
    centre: np.ndarray
    dt: float
    forward: np.ndarray
    walls: tuple[np.ndarray, np.ndarray] | None
    vertical: np.ndarray | None = None
    line: np.ndarray | None = None
    free: object | None = None
    free_m: float = 0.0
    front_c: np.ndarray | None = None
    front_b: np.ndarray | None = None
    single_fit: np.ndarray | None = None
    sight: object | None = None
    shown: object | None = None
    deadlines: Deadlines = NO_LIMIT

    def __post_init__(self):
        self.seg_length = np.maximum(np.linalg.norm(self.segments[:, 1] - self.segments[:, 0], axis=1), 1e-9)

    def in_free_space(self, xy: np.ndarray) -> np.ndarray:
        """(...) bool: camera positions ``xy`` (..., 2) within ``free_m`` of
        the map's regions (:mod:`matcher.map_geometry.freespace`); all True without a map."""
        if self.free is None:
            return np.ones(np.shape(xy)[:-1], dtype=bool)
        return self.free.distance(xy) <= self.free_m
