"""The region stage's time, predicted before it runs.

:func:`mapkit.vir.build_regions` spends its time in three kinds of work,
each counted here on a sample of the points it will use (the distinct
sample points of :func:`mapkit.visibility.segment_regions`, one visibility
polygon each):

- the sweeps: each point against the occluder edges within ``max_range``
  of it (its *sight tests*);
- the overlays that follow (two neighbours' polygons, the distance
  annulus, the union per segment, the regions grown and cut by the
  quadtree): they pay per vertex of the visibility polygons, so each point
  counts the vertices of its own polygon (swept here, as the stage sweeps
  it, on a few of the points);
- a fixed cost per point (its polygon's setup, its pair, its share of the
  quadtree).

``seconds = REGION_SECONDS_PER_SIGHT_TEST * sight tests
+ REGION_SECONDS_PER_VISIBLE_VERTEX * polygon vertices
+ REGION_SECONDS_PER_POINT * points``, constants calibrated on real
drawings and meshes (``mapkit.tolerances``, where the calibration is
written down). Counts, not a timed trial: the estimate is the same on any
machine; its seconds are those of the machine it was calibrated on.

To refit the constants (when the region stage's speed changes): for each
build of the calibration table, take :func:`region_cost`'s three counts and
the processor time (``time.process_time``) of ``build_regions`` alone, and
solve for the three non-negative constants minimising the relative error
(``scipy.optimize.nnls`` on the rows divided by their times), on part of
the builds; check the rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from mapkit.tolerances import (
    CIRCLE_SIDES,
    REGION_COST_POLYGON_PROBES,
    REGION_COST_PROBES,
    REGION_SECONDS_PER_POINT,
    REGION_SECONDS_PER_SIGHT_TEST,
    REGION_SECONDS_PER_VISIBLE_VERTEX,
    VIS_VERTICAL_XY,
)
from mapkit.visibility import Occluders, sample_segment


@dataclass(frozen=True)
class RegionCost:
    """What :func:`region_cost` predicts of the region stage.

    - ``points``: its distinct sample points (one visibility polygon each);
    - ``sight_tests``: points times the mean occluder edges within range of
      a point (nan when not sampled);
    - ``polygon_vertices``: points times the mean vertices of a point's
      visibility polygon (nan when not sampled);
    - ``seconds``: the predicted time of :func:`mapkit.vir.build_regions`
      (processor seconds on the calibration machine).
    """

    points: int
    sight_tests: float
    polygon_vertices: float
    seconds: float


def region_cost(segments: np.ndarray, occluders, *, max_range: float, min_visible_length: float,
                stop_above: float = math.inf) -> RegionCost:
    """The region stage's work and predicted seconds for ``segments`` (N, 2, 3)
    metres among ``occluders`` (the wall solids, shapely), sampled as
    :func:`mapkit.visibility.segment_regions` samples them (every
    ``min_visible_length / 2``, ``max_range`` the sight distance).

    When the points' upper bound alone, at ``REGION_SECONDS_PER_POINT``,
    is past ``stop_above`` seconds, nothing is sampled (a damaged segment
    kilometres long would take gigabytes to sample): ``points`` is that
    bound and ``seconds`` its fixed cost, the counts nan."""
    segs = np.asarray(segments, dtype=float).reshape(-1, 2, 3)
    spacing = float(min_visible_length) / 2.0
    with np.errstate(over="ignore", invalid="ignore"):  # far coordinates: an infinite bound, refused
        vertical = np.linalg.norm(segs[:, 1, :2] - segs[:, 0, :2], axis=1) <= VIS_VERTICAL_XY
        lengths = np.linalg.norm(segs[~vertical, 1] - segs[~vertical, 0], axis=1)
        bound = float(vertical.sum() + np.sum(np.ceil(lengths / spacing) + 1.0))
    if not math.isfinite(bound):
        return RegionCost(0, math.nan, math.nan, math.inf)
    if bound * REGION_SECONDS_PER_POINT > stop_above:
        return RegionCost(int(bound), math.nan, math.nan, bound * REGION_SECONDS_PER_POINT)
    pts = [segs[vertical, 0, :2]] + [sample_segment(s, spacing)[:, :2] for s in segs[~vertical]]
    xy = np.unique(np.round(np.concatenate(pts), 7), axis=0) if len(segs) else np.zeros((0, 2))
    if not len(xy):
        return RegionCost(0, 0.0, 0.0, 0.0)
    occ = Occluders.from_geometry(occluders)
    box = max_range / math.cos(math.pi / CIRCLE_SIDES) + 0.01  # the sweep's square (segment_regions)
    probes = xy[:: max(1, -(-len(xy) // REGION_COST_PROBES))]
    near = [int(np.count_nonzero((occ.hi[:, 0] >= p[0] - box) & (occ.lo[:, 0] <= p[0] + box)
                                 & (occ.hi[:, 1] >= p[1] - box) & (occ.lo[:, 1] <= p[1] + box))) for p in probes]
    swept = probes[:: max(1, -(-len(probes) // REGION_COST_POLYGON_PROBES))]
    vertices = _polygon_vertices(swept, occ, max_range)
    n = len(xy)
    tests, verts = n * float(np.mean(near)), n * float(np.mean(vertices))
    seconds = (REGION_SECONDS_PER_SIGHT_TEST * tests + REGION_SECONDS_PER_VISIBLE_VERTEX * verts
               + REGION_SECONDS_PER_POINT * n)
    return RegionCost(n, tests, verts, seconds)


def _polygon_vertices(xy: np.ndarray, occ: Occluders, max_range: float) -> np.ndarray:
    """(P,) the vertices of the visibility polygon of each point of ``xy``
    (P, 2) as the region stage makes it (0 for a point buried in a wall,
    whose polygon is emptied)."""
    from mapkit.visibility import _sample_polygons

    return shapely.get_num_coordinates(_sample_polygons(xy, occ, max_range, progress=False, workers=1))


__all__ = ["RegionCost", "region_cost"]
