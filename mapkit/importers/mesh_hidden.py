"""Drop the parts of mesh feature edges that are no edges of the solid the eye sees.

Meshes built from separate boxes (a desk running into a pillar, two wall
pieces overlapping, walls standing flush on a floor slab) keep the edges of
each box where it pokes into, or lines up with, the other: real edges of the
triangles, but buried in material or lying in a flat face of the union.

Tests per height level (metres, z up, floor at 0), with sections just above
and just below a horizontal edge (z +- ``_PROBE``):

- a horizontal edge is kept only where it lies on the outline of the
  material above or below, or on an open sheet (single-surface walls);
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

from mapkit.importers.mesh_section import MeshSections
from mapkit.lmap import SegmentKind
from mapkit.tolerances import MERGE, MESH_LEVEL

#: Sections probe this far above and below a horizontal edge, metres: off
#: the millimetre grid the vertices were welded to, so the plane misses them.
_PROBE = 1.5 * MERGE

#: A horizontal edge is on a probed outline if within this distance of it,
#: metres. A face sloping away from the edge at angle a moves the outline
#: by ``_PROBE / tan(a)``: faces steeper than about 20 degrees stay within
#: reach. Buried pieces are cut this close to the surface they enter.
_REACH = 4 * MERGE

#: The quadrant test looks this far to either side of an edge, metres.
_SIDE = 3 * _REACH

#: At most this many distinct heights are probed; edges at other heights
#: are kept unchecked (a warning says so).
MAX_LEVELS = 64

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
    if len(levels) > MAX_LEVELS:
        warnings.append(f"{len(levels)} edge heights; only {MAX_LEVELS} checked for hidden edges")
        levels = levels[:MAX_LEVELS]

    keep = ~checked  # obliques pass
    out_segments, out_kinds = [], []
    for lv in levels:
        at = level == lv
        z = float(z_mid[at].mean())
        hz = np.nonzero(at & horizontal)[0]
        if len(hz):
            above, below = sections.section(z + _PROBE), sections.section(z - _PROBE)
            outline = shapely.union_all([above.solid.boundary, below.solid.boundary, above.sheets, below.sheets])
            pieces = _clip_horizontal(segments[hz], outline.buffer(_REACH), min_length)
            owner = np.repeat(hz, [len(p) for p in pieces])
            flat = np.concatenate([np.asarray(p).reshape(-1, 2, 3) for p in pieces])
            if len(flat):
                real = _is_crease(flat, above, below)
                out_segments.append(flat[real])
                out_kinds.append(kinds[owner[real]])
        vt = np.nonzero(at & vertical)[0]
        if len(vt):
            core = sections.section(z).solid.buffer(-MESH_LEVEL)
            if not core.is_empty:
                keep[vt] = ~shapely.contains_xy(core, segments[vt, 0, 0], segments[vt, 0, 1])
            else:
                keep[vt] = True
    keep[checked & ~np.isin(level, levels)] = True
    seg = np.concatenate([segments[keep], *out_segments]) if out_segments else segments[keep]
    kin = np.concatenate([kinds[keep], *out_kinds]).astype(np.uint8) if out_kinds else kinds[keep]
    return seg, kin, warnings


def _clip_horizontal(segments: np.ndarray, region, min_length: float) -> list[list[np.ndarray]]:
    """For each segment (N, 2, 3): its pieces (2, 3) inside the 2D ``region``."""
    inside = shapely.intersection(shapely.linestrings(segments[:, :, :2]), region)
    out = []
    for seg, geom in zip(segments, inside):
        a, b = seg[0], seg[1]
        d2 = b[:2] - a[:2]
        len2 = float(d2 @ d2)
        pieces = []
        for part in shapely.get_parts(geom):
            if part.geom_type != "LineString" or part.length < min_length:
                continue
            xy = np.asarray(part.coords)[[0, -1]]
            t = np.clip((xy - a[:2]) @ d2 / len2, 0.0, 1.0)
            pieces.append(a + t[:, None] * (b - a))
        out.append(pieces)
    return out


def _is_crease(segments: np.ndarray, above, below) -> np.ndarray:
    """(N,) bool: the quadrants around each horizontal segment's midpoint
    (left/right of it, in the sections above/below) make an edge, not a
    flat face. Segments on open sheets always count."""
    mid = segments[:, :, :2].mean(axis=1)
    d = segments[:, 1, :2] - segments[:, 0, :2]
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.linalg.norm(d, axis=1, keepdims=True)
    left, right = mid + _SIDE * n, mid - _SIDE * n

    def solid(sec, p):
        return shapely.contains_xy(sec.solid, p[:, 0], p[:, 1]) if not sec.solid.is_empty else np.zeros(len(p), bool)

    ul, ur, ll, lr = solid(above, left), solid(above, right), solid(below, left), solid(below, right)
    wall_face = (ul == ll) & (ur == lr)  # same material above and below: a face going straight on
    level_face = (ul == ur) & (ll == lr)  # same on both sides: a level face going on
    sheets = shapely.union_all([above.sheets, below.sheets])
    on_sheet = (
        shapely.dwithin(shapely.points(mid), sheets, _REACH) if not sheets.is_empty else np.zeros(len(mid), bool)
    )
    return on_sheet | ~(wall_face | level_face)
