"""Drop the parts of mesh feature edges that are no edges of the solid the eye sees.

Meshes built from separate boxes (a desk running into a pillar, two wall
pieces overlapping, walls standing flush on a floor slab) keep the edges of
each box where it pokes into, or lines up with, the other: real edges of the
triangles, but buried in material or lying in a flat face of the union.

Tests per height level (metres, z up, floor at 0), with sections just above
and just below a horizontal edge (z +- ``MESH_HIDDEN_PROBE``):

- a horizontal edge is kept only where it runs along the outline of the
  material above or below, or along an open sheet (single-surface walls);
- and only where the four quadrants around it (left/right x above/below)
  do not make a flat face: material on one side only, continuing straight
  up and down (a wall flush on a slab's border), or above/below only,
  continuing level (two boxes' tops at one height) are no edges;
- a vertical edge is buried if, at its mid-height, it lies inside solid
  material farther than ``MESH_LEVEL`` from its outline.

Oblique edges are kept as they are.
"""

from __future__ import annotations

import numpy as np
import shapely

from mapkit.importers.mesh.section import MeshSections
from linemap.lmap import SegmentKind
from mapkit.tolerances import (
    MERGE,
    MESH_HIDDEN_MAX_LEVELS,
    MESH_HIDDEN_PROBE,
    MESH_HIDDEN_REACH,
    MESH_HIDDEN_SIDE,
    MESH_LEVEL,
)

_HORIZONTAL = (SegmentKind.FLOOR, SegmentKind.CEILING, SegmentKind.HORIZONTAL)


def drop_hidden(
    segments: np.ndarray, kinds: np.ndarray, sections: MeshSections, min_length: float
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Segments (N, 2, 3) and kinds (N,) without their hidden parts.

    Horizontal segments may be shortened or split; pieces shorter than
    ``min_length`` go. Returns ``(segments, kinds, warnings)``.
    """
    warnings: list[str] = []
    horizontal = np.isin(kinds, _HORIZONTAL)
    vertical = kinds == SegmentKind.VERTICAL
    z_mid = segments[:, :, 2].mean(axis=1)
    level = np.round(z_mid / MERGE).astype(np.int64)  # millimetre levels: probes must straddle each edge
    checked = horizontal | vertical
    levels = np.unique(level[checked])
    if len(levels) > MESH_HIDDEN_MAX_LEVELS:
        warnings.append(f"{len(levels)} edge heights; only {MESH_HIDDEN_MAX_LEVELS} checked for hidden edges")
        levels = levels[:MESH_HIDDEN_MAX_LEVELS]

    keep = ~checked  # obliques pass
    out_segments, out_kinds = [], []
    for lv in levels:
        at = level == lv
        z = float(z_mid[at].mean())
        hz = np.nonzero(at & horizontal)[0]
        if len(hz):
            above, below = sections.section(z + MESH_HIDDEN_PROBE), sections.section(z - MESH_HIDDEN_PROBE)
            outline = _outline_segments([above.solid, below.solid, above.sheets, below.sheets])
            flat, owner = _on_outline(segments[hz], outline, min_length)
            if len(flat):
                real = _is_crease(flat, above, below)
                out_segments.append(flat[real])
                out_kinds.append(kinds[hz[owner[real]]])
        vt = np.nonzero(at & vertical)[0]
        if len(vt):
            solid = sections.section(z).solid
            if solid.is_empty:
                keep[vt] = True
            else:
                x, y = segments[vt, 0, 0], segments[vt, 0, 1]
                deep = shapely.contains_xy(solid, x, y) & (shapely.distance(shapely.points(x, y), solid.boundary) > MESH_LEVEL)
                keep[vt] = ~deep
    keep[checked & ~np.isin(level, levels)] = True
    seg = np.concatenate([segments[keep], *out_segments]) if out_segments else segments[keep]
    kin = np.concatenate([kinds[keep], *out_kinds]).astype(np.uint8) if out_kinds else kinds[keep]
    return seg, kin, warnings


def _outline_segments(geoms) -> np.ndarray:
    """(K, 2, 2) straight pieces of the rings and lines of ``geoms``."""
    parts = []
    for g in geoms:
        if g.is_empty:
            continue
        lines = shapely.get_parts(shapely.boundary(g)) if g.geom_type.endswith("Polygon") else shapely.get_parts(g)
        lines = shapely.get_parts(shapely.line_merge(shapely.union_all(lines))) if len(lines) else lines
        coords, index = shapely.get_coordinates(lines, return_index=True)
        same = index[1:] == index[:-1]
        parts.append(np.stack([coords[:-1][same], coords[1:][same]], axis=1))
    return np.concatenate(parts) if parts else np.zeros((0, 2, 2))


def _on_outline(segments: np.ndarray, outline: np.ndarray, min_length: float) -> tuple[np.ndarray, np.ndarray]:
    """Pieces of horizontal segments (N, 2, 3) running along outline pieces (K, 2, 2).

    A segment runs along an outline piece where the piece lies within
    ``MESH_HIDDEN_REACH`` of the segment's line (both its ends) and their extents
    overlap; the overlaps of one segment are joined. Returns the pieces
    (M, 2, 3) at least ``min_length`` long and the segment each came from (M,).
    """
    from shapely import STRtree

    empty = np.zeros((0, 2, 3)), np.zeros(0, dtype=np.int64)
    if len(outline) == 0 or len(segments) == 0:
        return empty
    a, b = segments[:, 0, :2], segments[:, 1, :2]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    u = d / length[:, None]
    tree = STRtree(shapely.linestrings(outline))
    seg_i, out_j = tree.query(shapely.linestrings(segments[:, :, :2]), predicate="dwithin", distance=MESH_HIDDEN_REACH)
    p, q = outline[out_j, 0], outline[out_j, 1]
    ua, aa = u[seg_i], a[seg_i]

    def off(pt):  # distance of points from the segment's line
        rel = pt - aa
        return np.abs(rel[:, 0] * ua[:, 1] - rel[:, 1] * ua[:, 0])

    along = (off(p) <= MESH_HIDDEN_REACH) & (off(q) <= MESH_HIDDEN_REACH)
    seg_i, p, q, ua, aa = seg_i[along], p[along], q[along], ua[along], aa[along]
    tp = np.einsum("ij,ij->i", p - aa, ua) / length[seg_i]
    tq = np.einsum("ij,ij->i", q - aa, ua) / length[seg_i]
    lo = np.clip(np.minimum(tp, tq), 0.0, 1.0)
    hi = np.clip(np.maximum(tp, tq), 0.0, 1.0)
    keep = hi > lo
    seg_i, lo, hi = seg_i[keep], lo[keep], hi[keep]
    if len(seg_i) == 0:
        return empty
    # Join overlapping intervals per segment: offset each segment's
    # parameters by 4 x its index so one running maximum serves all.
    order = np.lexsort((lo, seg_i))
    seg_i, lo, hi = seg_i[order], lo[order] + 4 * seg_i[order], hi[order] + 4 * seg_i[order]
    gap = MESH_HIDDEN_REACH / length[seg_i]
    reach = np.maximum.accumulate(hi)
    start = np.r_[True, lo[1:] > reach[:-1] + gap[1:]]
    t0 = lo[start] - 4 * seg_i[start]
    t1 = np.maximum.reduceat(hi, np.nonzero(start)[0]) - 4 * seg_i[start]
    owner = seg_i[start]
    a3, b3 = segments[owner, 0], segments[owner, 1]
    pieces = np.stack([a3 + t0[:, None] * (b3 - a3), a3 + t1[:, None] * (b3 - a3)], axis=1)
    long = np.linalg.norm(pieces[:, 1] - pieces[:, 0], axis=1) >= min_length
    return pieces[long], owner[long]


def _is_crease(segments: np.ndarray, above, below) -> np.ndarray:
    """(N,) bool: the quadrants around each horizontal segment's midpoint
    (left/right of it, in the sections above/below) make an edge, not a
    flat face. Segments on open sheets always count."""
    mid = segments[:, :, :2].mean(axis=1)
    d = segments[:, 1, :2] - segments[:, 0, :2]
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.linalg.norm(d, axis=1, keepdims=True)
    left, right = mid + MESH_HIDDEN_SIDE * n, mid - MESH_HIDDEN_SIDE * n

    def solid(sec, p):
        return shapely.contains_xy(sec.solid, p[:, 0], p[:, 1]) if not sec.solid.is_empty else np.zeros(len(p), bool)

    ul, ur, ll, lr = solid(above, left), solid(above, right), solid(below, left), solid(below, right)
    wall_face = (ul == ll) & (ur == lr)  # same material above and below: a face going straight on
    level_face = (ul == ur) & (ll == lr)  # same on both sides: a level face going on
    sheets = shapely.union_all([above.sheets, below.sheets])
    on_sheet = (
        shapely.dwithin(shapely.points(mid), sheets, MESH_HIDDEN_REACH) if not sheets.is_empty else np.zeros(len(mid), bool)
    )
    return on_sheet | ~(wall_face | level_face)
