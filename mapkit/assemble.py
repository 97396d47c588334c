"""Turn the builder's geometry (shapely) into a :class:`~linemap.lmap.LineMap`.

This is the one place where shapely polygons become the flat ring arrays of
the file format, and where the region-lookup grid is computed (exactly, with
shapely, so that the runtime needs none).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from linemap.lmap import LineMap
from mapkit.shapes import rings_of
from mapkit.tolerances import LOOKUP_GRID_CELL


def _flatten_rings(rings: list[tuple[np.ndarray, bool]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pts = [p for p, _ in rings]
    offsets = np.zeros(len(rings) + 1, dtype=np.int64)
    np.cumsum([len(p) for p in pts], out=offsets[1:])
    points = np.concatenate(pts).astype(np.float64) if pts else np.zeros((0, 2))
    return points, offsets, np.array([h for _, h in rings], dtype=bool)


def lookup_grid(
    regions: Sequence, cell: float = LOOKUP_GRID_CELL
) -> tuple[np.ndarray, float, tuple[int, int], np.ndarray, np.ndarray]:
    """Exact candidate lists: region r is listed in a cell iff it meets the cell.

    Returns ``(origin (2,), cell, (ny, nx), offsets (ny*nx+1,), regions)``.
    """
    if not regions:
        return np.zeros(2), cell, (1, 1), np.zeros(2, dtype=np.int64), np.zeros(0, dtype=np.int64)
    bounds = np.array([g.bounds for g in regions])
    x0, y0 = bounds[:, 0].min(), bounds[:, 1].min()
    x1, y1 = bounds[:, 2].max(), bounds[:, 3].max()
    nx = max(1, int(np.ceil((x1 - x0) / cell)) + 1)
    ny = max(1, int(np.ceil((y1 - y0) / cell)) + 1)
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny))
    boxes = shapely.box(x0 + ix.ravel() * cell, y0 + iy.ravel() * cell, x0 + (ix.ravel() + 1) * cell, y0 + (iy.ravel() + 1) * cell)
    tree = shapely.STRtree(np.asarray(regions, dtype=object))
    cell_idx, reg_idx = tree.query(boxes, predicate="intersects")
    order = np.lexsort((reg_idx, cell_idx))
    cell_idx, reg_idx = cell_idx[order], reg_idx[order]
    offsets = np.zeros(ny * nx + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell_idx, minlength=ny * nx), out=offsets[1:])
    return np.array([x0, y0]), float(cell), (ny, nx), offsets, reg_idx.astype(np.int64)


def assemble_map(
    segments: np.ndarray,
    kinds: np.ndarray,
    region_polygons: Sequence,
    region_lists: Sequence[np.ndarray],
    walls,
    meta: dict[str, Any],
    grid_cell: float = LOOKUP_GRID_CELL,
) -> LineMap:
    """Build a LineMap.

    - ``segments`` (N, 2, 3), ``kinds`` (N,) :class:`~linemap.lmap.SegmentKind` values.
    - ``region_polygons``: R shapely (Multi)Polygons, non-overlapping.
    - ``region_lists``: R integer arrays of visible segment ids.
    - ``walls``: shapely (Multi)Polygon of wall solids (occluders).
    - ``meta``: JSON-able dict stored as is (build parameters, camera, source).
    """
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    kinds = np.asarray(kinds, dtype=np.uint8).reshape(-1)
    if len(region_polygons) != len(region_lists):
        raise ValueError(f"{len(region_polygons)} region polygons but {len(region_lists)} lists")
    rings, ring_region = [], []
    for rid, geom in enumerate(region_polygons):
        rr = rings_of(geom)
        if not rr:
            raise ValueError(f"region {rid} has no outline")
        rings += rr
        ring_region += [rid] * len(rr)
    ring_points, ring_offsets, ring_is_hole = _flatten_rings(rings)
    lists = [np.unique(np.asarray(lst, dtype=np.int64)) for lst in region_lists]
    list_offsets = np.zeros(len(lists) + 1, dtype=np.int64)
    np.cumsum([len(lst) for lst in lists], out=list_offsets[1:])
    list_indices = np.concatenate(lists) if lists else np.zeros(0, dtype=np.int64)
    origin, cell, shape, goff, greg = lookup_grid(list(region_polygons), grid_cell)
    wall_points, wall_offsets, wall_is_hole = _flatten_rings(rings_of(walls))
    return LineMap(
        segments=segments,
        kinds=kinds,
        ring_points=ring_points,
        ring_offsets=ring_offsets,
        ring_region=np.asarray(ring_region, dtype=np.int64),
        ring_is_hole=ring_is_hole,
        list_offsets=list_offsets,
        list_indices=list_indices,
        grid_origin=origin,
        grid_cell=cell,
        grid_shape=shape,
        grid_offsets=goff,
        grid_regions=greg,
        wall_points=wall_points,
        wall_offsets=wall_offsets,
        wall_is_hole=wall_is_hole,
        meta=dict(meta),
    )


def region_geometry(m: LineMap, region: int):
    """The shapely (Multi)Polygon of one region of a loaded map (even-odd rings)."""
    geom = None
    for pts, _ in m.region_rings(region):
        g = Polygon(pts)
        geom = g if geom is None else geom.symmetric_difference(g)
    return geom if geom is not None else MultiPolygon()


def wall_geometry(m: LineMap):
    """The walls of a loaded map as one shapely geometry (even-odd rings)."""
    geom = MultiPolygon()
    for pts in m.wall_rings():
        geom = geom.symmetric_difference(Polygon(pts))
    return geom


__all__ = ["assemble_map", "lookup_grid", "region_geometry", "wall_geometry"]
