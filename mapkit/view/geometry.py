"""Arrays the inspector draws, computed once from a loaded map.

Everything here is vectorised over all regions or rings at once (shapely 2
array functions, numpy): the Barcelona pavilion map has thousands of
regions and the inspector must open in well under three seconds.

Conventions: 2D points are (n, 2) float arrays in the world frame (metres);
segments (n, 2, 3); edges (n, 2, 2) as (start, end).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
import trimesh

from linemap.lmap import LineMap


def ring_edges(points: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed rings in CSR form -> ((E, 2, 2) edges, (E,) ring index of each edge).

    Ring k is ``points[offsets[k]:offsets[k+1]]`` without its closing repeat;
    each ring yields as many edges as it has points.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    offsets = np.asarray(offsets, dtype=np.int64)
    ring = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    if len(points) == 0:
        return np.zeros((0, 2, 2)), ring
    nxt = np.arange(len(points)) + 1
    full = np.diff(offsets) > 0
    nxt[offsets[1:][full] - 1] = offsets[:-1][full]  # the last point of a ring closes it
    return np.stack([points, points[nxt]], axis=1), ring


def unique_edges(edges: np.ndarray, quantum: float = 1e-4) -> np.ndarray:
    """(E, 2, 2) edges without repeats: an edge shared by two neighbouring
    regions is drawn once (end points compared at ``quantum`` metres, either order)."""
    if len(edges) == 0:
        return edges
    q = np.round(edges / quantum).astype(np.int64).reshape(-1, 4)
    swap = (q[:, 0] > q[:, 2]) | ((q[:, 0] == q[:, 2]) & (q[:, 1] > q[:, 3]))
    q[swap] = q[swap][:, [2, 3, 0, 1]]
    _, first = np.unique(q, axis=0, return_index=True)
    return edges[np.sort(first)]


def _even_odd_polygons(points: np.ndarray, offsets: np.ndarray, group: np.ndarray, n_groups: int) -> np.ndarray:
    """One shapely geometry per group from rings under the even-odd rule.

    ``group`` (K,) says which group each ring belongs to. Most regions are a
    single ring, which becomes a Polygon directly; only groups of several
    rings pay for a symmetric difference.
    """
    k = len(offsets) - 1
    out = np.array([shapely.Polygon()] * n_groups, dtype=object)
    if k == 0:
        return out
    ring_of_point = np.repeat(np.arange(k), np.diff(offsets))
    polys = shapely.polygons(shapely.linearrings(points, indices=ring_of_point))
    polys = shapely.make_valid(polys)  # self-touching rings from quantisation stay drawable
    counts = np.bincount(group, minlength=n_groups)
    single = counts[group] == 1
    out[group[single]] = polys[single]
    for g in np.nonzero(counts > 1)[0]:
        geom = shapely.Polygon()
        for p in polys[group == g]:
            geom = geom.symmetric_difference(p)
        out[g] = geom
    return out


def region_polygons(m: LineMap) -> np.ndarray:
    """(R,) object array: the shapely geometry of every region."""
    return _even_odd_polygons(m.ring_points, m.ring_offsets, m.ring_region, m.n_regions)


def wall_polygon(m: LineMap):
    """The wall solids seen from above as one shapely geometry (even-odd rings)."""
    w = len(m.wall_offsets) - 1
    parts = _even_odd_polygons(m.wall_points, m.wall_offsets, np.zeros(w, dtype=np.int64), 1)
    return parts[0]


@dataclass
class Triangles:
    """A flat triangulation of many polygons at once.

    - ``vertices`` (3T, 2): three corners per triangle, not shared, so every
      triangle can carry its own polygon's colour.
    - ``faces`` (T, 3) int32 into ``vertices``.
    - ``owner`` (T,): the index of the polygon each triangle belongs to.
    - ``start`` (P+1,): polygon p's triangles are ``start[p]:start[p+1]``.
    """

    vertices: np.ndarray
    faces: np.ndarray
    owner: np.ndarray
    start: np.ndarray

    def subset(self, polygons: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (3t, 2), faces (t, 3)) of the triangles of the given polygons."""
        polygons = np.asarray(polygons, dtype=np.int64)
        if polygons.size == 0:
            return np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int32)
        tri = np.concatenate([np.arange(self.start[p], self.start[p + 1]) for p in polygons])
        verts = self.vertices.reshape(-1, 3, 2)[tri].reshape(-1, 2)
        return verts, np.arange(len(verts), dtype=np.int32).reshape(-1, 3)


def triangulate(polygons: np.ndarray) -> Triangles:
    """Constrained Delaunay triangulation of every polygon (holes respected)."""
    polygons = np.asarray(polygons, dtype=object)
    n = len(polygons)
    if n == 0:
        return Triangles(np.zeros((0, 2)), np.zeros((0, 3), dtype=np.int32), np.zeros(0, dtype=np.int64),
                         np.zeros(1, dtype=np.int64))
    colls = shapely.constrained_delaunay_triangles(polygons)
    tris, owner = shapely.get_parts(colls, return_index=True)
    coords = shapely.get_coordinates(tris)
    # Every triangle is a closed ring of 4 points; keep the first 3.
    corners = coords.reshape(-1, 4, 2)[:, :3, :] if len(coords) else np.zeros((0, 3, 2))
    start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(owner, minlength=n), out=start[1:])
    verts = corners.reshape(-1, 2)
    return Triangles(verts, np.arange(len(verts), dtype=np.int32).reshape(-1, 3), owner.astype(np.int64), start)


def region_adjacency(polygons: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j), i != j, of regions whose outlines touch (for colouring)."""
    polygons = np.asarray(polygons, dtype=object)
    if len(polygons) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    tree = shapely.STRtree(polygons)
    # A small buffer makes regions separated by a quantisation crack neighbours too.
    i, j = tree.query(shapely.buffer(polygons, 1e-3, quad_segs=1), predicate="intersects")
    keep = i != j
    return i[keep], j[keep]


def extrude(polygon, height: float) -> trimesh.Trimesh:
    """A closed prism from the floor to ``height`` over a shapely (Multi)Polygon.

    Caps come from the constrained triangulation, sides from the ring edges;
    the mesh is drawn double-sided, so face winding does not matter.
    """
    tri = triangulate(np.array([polygon], dtype=object))
    cap = tri.vertices
    rings = []
    for part in getattr(polygon, "geoms", [polygon]):
        if part.is_empty or part.geom_type != "Polygon":
            continue
        rings += [np.asarray(r.coords)[:-1, :2] for r in [part.exterior, *part.interiors]]
    if rings:
        offsets = np.zeros(len(rings) + 1, dtype=np.int64)
        np.cumsum([len(r) for r in rings], out=offsets[1:])
        edges, _ = ring_edges(np.concatenate(rings), offsets)
    else:
        edges = np.zeros((0, 2, 2))
    z0, z1 = np.zeros((len(cap), 1)), np.full((len(cap), 1), height)
    a, b = edges[:, 0], edges[:, 1]
    e = len(edges)
    side = np.concatenate(
        [np.c_[a, np.zeros(e)], np.c_[b, np.zeros(e)], np.c_[b, np.full(e, height)], np.c_[a, np.full(e, height)]]
    ).reshape(4, e, 3).transpose(1, 0, 2).reshape(-1, 3)
    vertices = np.concatenate([np.c_[cap, z0], np.c_[cap, z1], side])
    nc = len(cap)
    cap_faces = tri.faces
    q = 2 * nc + 4 * np.arange(e)[:, None]
    side_faces = np.concatenate([q + [0, 1, 2], q + [0, 2, 3]])
    faces = np.concatenate([cap_faces, cap_faces + nc, side_faces]).astype(np.int64)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def disk_outline(x: float, y: float, radius: float, z: float = 0.0, n: int = 72) -> np.ndarray:
    """(n, 2, 3) segments of a circle of ``radius`` around (x, y) at height ``z``."""
    t = np.linspace(0.0, 2.0 * math.pi, n + 1)
    p = np.stack([x + radius * np.cos(t), y + radius * np.sin(t), np.full_like(t, z)], axis=1)
    return np.stack([p[:-1], p[1:]], axis=1)


def disk_mesh(x: float, y: float, radius: float, z: float = 0.0, n: int = 72) -> tuple[np.ndarray, np.ndarray]:
    """A flat fan (vertices (n+1, 3), faces (n, 3)) filling the same circle."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    ring = np.stack([x + radius * np.cos(t), y + radius * np.sin(t), np.full_like(t, z)], axis=1)
    verts = np.concatenate([[[x, y, z]], ring])
    i = np.arange(n)
    faces = np.stack([np.zeros(n, dtype=np.int64), 1 + i, 1 + (i + 1) % n], axis=1)
    return verts, faces


def lift(edges_2d: np.ndarray, z: float) -> np.ndarray:
    """(E, 2, 2) planar edges -> (E, 2, 3) at height ``z``."""
    e = np.asarray(edges_2d, dtype=np.float64).reshape(-1, 2, 2)
    return np.concatenate([e, np.full(e.shape[:2] + (1,), z)], axis=2)


def map_bounds(m: LineMap) -> tuple[np.ndarray, np.ndarray]:
    """((3,) min, (3,) max) over segments, region outlines and walls."""
    pts = [m.segments.reshape(-1, 3)]
    for p in (m.ring_points, m.wall_points):
        if len(p):
            pts.append(np.c_[p, np.zeros(len(p))])
    allp = np.concatenate(pts) if any(len(p) for p in pts) else np.zeros((1, 3))
    if len(allp) == 0:
        allp = np.zeros((1, 3))
    return allp.min(axis=0), allp.max(axis=0)
