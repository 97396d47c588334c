"""Wall solids from wall linework.

Recipe: node all wall lines, join small gaps (``SNAP_GAP``), cap the open
ends of double-line walls (pairs of parallel lines ending side by side
within ``max_wall_thickness``), then polygonize each connected drawing
separately and classify its faces:

- a face thinner than ``max_wall_thickness`` is wall material (the space
  between the two lines of a double-line wall, a thin closed outline);
- a lone closed outline (one face) is a solid when it is small (a column)
  or sits inside another drawing's face (a block, a core, a pillar);
- anything else is a room. Lines that bound no wall material (single-line
  walls, room outlines, loose strokes) are thickened to ``THIN_WALL``.

Fills (hatches, SOLIDs) are solids as drawn.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely
from scipy.spatial import cKDTree
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from shapely.geometry import LineString, MultiLineString, MultiPolygon, Point, Polygon
from shapely.ops import nearest_points, unary_union

from mapkit.shapes import polygon_parts
from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import COLUMN_MAX_AREA, MERGE, SNAP_GAP, THIN_WALL, WALL_CAP_ANGLE_DEG


@dataclass
class WallResult:
    """Walls and what was learnt on the way (for openings, interior and info).

    ``walls``: all wall solids (MultiPolygon, metres); ``rooms``: faces
    classified as rooms; ``lines``: the noded, cleaned linework;
    ``single_lines``: the part of ``walls`` that is single wall lines
    thickened to ``THIN_WALL`` (lines that bound no double-line wall).
    """

    walls: MultiPolygon
    rooms: list[Polygon]
    lines: MultiLineString
    counts: dict
    single_lines: Polygon | MultiPolygon = field(default_factory=Polygon)


def build_walls(strokes: list[Stroke], max_wall_thickness: float) -> WallResult:
    """Wall solids from the strokes of wall layers; see the module docstring."""
    fills = _fills(strokes)
    raw = [_as_line(s) for s in strokes if not s.filled]
    raw = [g for g in raw if g is not None]
    counts = {"wall_strokes": len(strokes), "fills": len(fills)}
    if not raw:
        walls = _as_multi(unary_union(fills)) if fills else MultiPolygon()
        return WallResult(walls, [], MultiLineString(), counts | {"faces": 0})

    noded = unary_union(raw)
    connectors = _snap_gaps(noded)
    if connectors:
        noded = unary_union([noded, *connectors])
    caps = _cap_ends(noded, max_wall_thickness)
    if caps:
        noded = unary_union([noded, *caps])
    counts |= {"gaps_closed": len(connectors), "ends_capped": len(caps)}

    parts = list(shapely.get_parts(shapely.line_merge(noded)))
    comp = _components(parts)
    half = max_wall_thickness / 2.0
    material, solids, rooms = [], [], []
    faces_by_comp = {}
    for c in np.unique(comp):
        lines = MultiLineString([parts[i] for i in np.flatnonzero(comp == c)])
        faces_by_comp[c] = [f for f in shapely.get_parts(shapely.polygonize(shapely.get_parts(lines))) if f.area > 0]
    all_faces = [(c, f) for c, fs in faces_by_comp.items() for f in fs]
    tree = shapely.STRtree([f for _, f in all_faces])
    faces_of_double = _double_line_faces(all_faces, tree, half)
    for c, faces in faces_by_comp.items():
        for f in faces:
            if f.buffer(-half).is_empty:
                material.append(f)
            elif id(f) in faces_of_double:
                rooms.append(f)  # the inner face of a wall drawn as two outlines
            elif len(faces) == 1 and (f.area <= COLUMN_MAX_AREA or _nested(f, c, all_faces, tree)):
                solids.append(f)
            else:
                rooms.append(f)
    material.extend(faces_of_double.values())
    solid = unary_union(material + solids + fills)
    # Lines not bordering a solid are walls drawn as a single line.
    loose = noded.difference(solid.buffer(MERGE)) if not solid.is_empty else noded
    thin = loose.buffer(THIN_WALL / 2.0, cap_style="square", join_style="mitre") if not loose.is_empty else Polygon()
    walls = _as_multi(unary_union([solid, thin]).buffer(0))
    counts |= {"faces": len(all_faces), "wall_faces": len(material), "solid_blocks": len(solids), "rooms": len(rooms)}
    return WallResult(walls, rooms, _as_multiline(noded), counts, thin)


def _as_line(stroke: Stroke) -> LineString | None:
    pts = np.asarray(stroke.coords, dtype=float)
    if stroke.closed and len(pts) >= 3:
        pts = np.vstack([pts, pts[:1]])
    # Drop repeated vertices: zero-length pieces upset noding.
    keep = np.r_[True, np.any(np.abs(np.diff(pts, axis=0)) > MERGE * 1e-3, axis=1)]
    pts = pts[keep]
    if len(pts) < 2:
        return None
    return LineString(pts)


def _fills(strokes: list[Stroke]) -> list[Polygon]:
    """Filled outlines; paths of one group combine even-odd (inner paths are holes)."""
    by_group: dict[object, list[Polygon]] = {}
    for i, s in enumerate(strokes):
        if s.filled and len(s.coords) >= 3:
            poly = shapely.make_valid(Polygon(s.coords))
            key = ("g", s.group, s.layer) if s.group is not None else ("s", i)
            by_group.setdefault(key, []).append(poly)
    out = []
    for polys in by_group.values():
        acc = polys[0]
        for p in polys[1:]:
            acc = acc.symmetric_difference(p)
        out.extend(g for g in shapely.get_parts(acc) if isinstance(g, Polygon) and g.area > 0)
    return out


def _endpoints(parts: list[LineString]) -> tuple[np.ndarray, np.ndarray]:
    """End points (2P, 2) of the parts and the degree of each (how many ends share it)."""
    ends = np.array([[p.coords[0][:2], p.coords[-1][:2]] for p in parts], dtype=float).reshape(-1, 2)
    keys = np.round(ends / MERGE).astype(np.int64)
    _, inverse, cnt = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return ends, cnt[inverse.ravel()]


def _snap_gaps(noded) -> list[LineString]:
    """Short connectors from dangling ends to linework within ``SNAP_GAP``."""
    parts = list(shapely.get_parts(noded))
    if not parts:
        return []
    ends, degree = _endpoints(parts)
    tree = shapely.STRtree(parts)
    out = []
    for k in np.flatnonzero(degree == 1):
        p = Point(ends[k])
        own = k // 2
        best = None
        for j in tree.query(p, predicate="dwithin", distance=SNAP_GAP):
            target = parts[j]
            if j == own:
                # Only the far part of its own line counts (a nearly closed outline).
                target = target.difference(p.buffer(2 * SNAP_GAP))
                if target.is_empty:
                    continue
            d = target.distance(p)
            if d > MERGE * 1e-3 and d <= SNAP_GAP and (best is None or d < best[0]):
                best = (d, target)
        if best is not None:
            q = nearest_points(best[1], p)[0]
            out.append(LineString([ends[k], (q.x, q.y)]))
    return out


def _cap_ends(noded, max_gap: float) -> list[LineString]:
    """Caps across pairs of dangling ends of double-line walls."""
    parts = list(shapely.get_parts(shapely.line_merge(noded)))
    if not parts:
        return []
    ends, degree = _endpoints(parts)
    dangling = np.flatnonzero(degree == 1)
    if len(dangling) < 2:
        return []
    # Direction in which each dangling end points (out of its line).
    dirs = []
    for k in dangling:
        coords = np.asarray(parts[k // 2].coords)[:, :2]
        a, b = (coords[1], coords[0]) if k % 2 == 0 else (coords[-2], coords[-1])
        v = b - a
        dirs.append(v / (np.linalg.norm(v) or 1.0))
    dirs = np.array(dirs)
    pts = ends[dangling]
    cos_par = np.cos(np.radians(WALL_CAP_ANGLE_DEG))
    sin_off = np.sin(np.radians(WALL_CAP_ANGLE_DEG))
    candidates = []
    for i, j in sorted(cKDTree(pts).query_pairs(max_gap)):
        if dangling[i] // 2 == dangling[j] // 2 and len(parts[dangling[i] // 2].coords) == 2:
            continue  # the two ends of one straight line
        gap = pts[j] - pts[i]
        dist = float(np.hypot(*gap))
        if dist <= MERGE:
            continue
        if float(dirs[i] @ dirs[j]) < cos_par:
            continue  # not parallel, or pointing at each other (a door gap)
        u = gap / dist
        if abs(float(u @ dirs[i])) > sin_off or abs(float(u @ dirs[j])) > sin_off:
            continue  # staggered ends, not a square cap
        candidates.append((dist, i, j))
    used: set[int] = set()
    caps = []
    for dist, i, j in sorted(candidates):
        if i in used or j in used:
            continue
        cap = LineString([pts[i], pts[j]])
        # A cap must not cut through other linework (that would be a real wall).
        if cap.crosses(noded):
            continue
        used |= {i, j}
        caps.append(cap)
    return caps


def _components(parts: list[LineString]) -> np.ndarray:
    """Connected-component label of each noded part (parts sharing an end point)."""
    ends, _ = _endpoints(parts)
    keys = np.round(ends / MERGE).astype(np.int64)
    _, node = np.unique(keys, axis=0, return_inverse=True)
    node = node.ravel()
    n_nodes = int(node.max()) + 1
    a, b = node[0::2], node[1::2]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n_nodes, n_nodes))
    _, labels = connected_components(graph, directed=False)
    return labels[a]


def _double_line_faces(all_faces, tree, half: float) -> dict[int, Polygon]:
    """Walls drawn as nested outlines: their inner faces and the wall between.

    An outline whose face holds, from other drawings, outlines that leave
    between them and it only a band thinner than ``2 * half`` (a room drawn
    with its wall's outer and inner faces, or a building outline around its
    rooms' outlines) is the outer face of a wall. Returns ``{id(inner face):
    band}`` for every inner face so found (the band once, on the first)."""
    out: dict[int, Polygon] = {}
    for c, outer in all_faces:
        if outer.buffer(-half).is_empty:
            continue  # already wall material
        inner = [f for j in tree.query(outer, predicate="contains_properly")
                 for cj, f in [all_faces[j]] if cj != c and f.area < outer.area]
        if not inner:
            continue
        band = outer.difference(unary_union(inner))
        if band.is_empty or not band.buffer(-half).is_empty:
            continue
        # The rooms are the outermost nested faces that are not wall material
        # themselves (a column inside a room is not a room).
        rooms = [f for f in inner if not f.buffer(-half).is_empty
                 and not any(g is not f and g.contains(f) for g in inner)]
        for k, f in enumerate(rooms):
            out[id(f)] = band if k == 0 else Polygon()
    return out


def _nested(face: Polygon, comp: int, all_faces, tree) -> bool:
    """Whether ``face`` lies inside a bigger face of another connected drawing."""
    probe = face.representative_point()
    for j in tree.query(probe, predicate="within"):
        c, other = all_faces[j]
        if c != comp and other.area > face.area:
            return True
    return False


def _as_multi(geom) -> MultiPolygon:
    return MultiPolygon(polygon_parts(geom))


def _as_multiline(geom) -> MultiLineString:
    lines = [g for g in shapely.get_parts(geom) if isinstance(g, LineString) and not g.is_empty]
    return MultiLineString(lines)
