"""Drop the parts of mesh feature edges that are buried inside other solids.

Meshes built from separate boxes (a desk running into a pillar, two wall
pieces overlapping) keep the edges of each box where it pokes into the
other: real edges of the triangles, but inside material, so never seen.

Test, per height level (heights in metres, z up, floor at 0):

- a horizontal edge at height z is real where it lies on the outline of the
  material just above it or just below it (sections at z +- ``_PROBE``);
  where both sections agree (material on both sides, or air) it is no edge
  of the union and goes;
- a vertical edge is buried if, at its mid-height, it lies inside the
  section's material farther than ``MESH_LEVEL`` from its outline.

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

#: At most this many distinct heights are probed; edges at other heights
#: are kept unchecked (a warning says so).
MAX_LEVELS = 64

_HORIZONTAL = (SegmentKind.FLOOR, SegmentKind.CEILING, SegmentKind.HORIZONTAL)


def drop_hidden(
    segments: np.ndarray, kinds: np.ndarray, sections: MeshSections, min_length: float
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Segments (N, 2, 3) and kinds (N,) without their buried parts.

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
        warnings.append(f"{len(levels)} edge heights; only {MAX_LEVELS} checked for edges buried in solids")
        levels = levels[:MAX_LEVELS]

    keep = ~checked  # obliques pass
    out_segments, out_kinds = [], []
    for lv in levels:
        at = level == lv
        z = float(z_mid[at].mean())
        hz = np.nonzero(at & horizontal)[0]
        if len(hz):
            above, _ = sections.cut(z + _PROBE)
            below, _ = sections.cut(z - _PROBE)
            outline = shapely.union_all([above.boundary, below.boundary]).buffer(_REACH)
            pieces = _clip_horizontal(segments[hz], outline, min_length)
            for i, piece in zip(hz, pieces):
                out_segments += piece
                out_kinds += [kinds[i]] * len(piece)
        vt = np.nonzero(at & vertical)[0]
        if len(vt):
            walls, _ = sections.cut(z)
            core = walls.buffer(-MESH_LEVEL)
            pts = shapely.points(segments[vt, 0, :2])
            keep[vt] = ~shapely.contains(core, pts) if not core.is_empty else True
    keep[checked & ~np.isin(level, levels)] = True
    seg = np.concatenate([segments[keep], np.asarray(out_segments).reshape(-1, 2, 3)])
    kin = np.concatenate([kinds[keep], np.asarray(out_kinds, dtype=np.uint8)])
    return seg, kin, warnings


def _clip_horizontal(segments: np.ndarray, outline, min_length: float) -> list[list[np.ndarray]]:
    """For each segment (N, 2, 3): its pieces (2, 3) inside ``outline`` (2D)."""
    lines = shapely.linestrings(segments[:, :, :2])
    inside = shapely.intersection(lines, outline)
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
