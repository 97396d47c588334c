"""Horizontal sections of a mesh: wall material and enclosed rooms at a height.

A plane at height z cuts the mesh into 2D line segments. Segments of closed
solids are oriented with the solid on their left (from the face normals),
so the winding number of a point says whether it is inside wall material:
this stays right where solids touch or overlap (two wall boxes sharing a
face), where even-odd parity would not. Segments of open surfaces (walls
modelled as single sheets, inside-out room boxes) have no inside; they are
thickened to ``MESH_THIN_WALL``. The faces of the section's arrangement
that are not wall material are the rooms enclosed at that height.

2D arrays: points (P, 2), segments (S, 2, 2), metres, plan coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from shapely.geometry import MultiLineString, MultiPolygon

from mapkit.errors import MapkitError
from mapkit.importers.mesh.edges import edge_faces, face_normals
from mapkit.tolerances import (
    MERGE,
    MESH_OPEN_FRACTION,
    MESH_SECTION_CHUNK,
    MESH_SHEET_CROSSINGS,
    MESH_SHEET_MIN_LINES,
    MESH_THIN_WALL,
)


@dataclass
class Section:
    """A horizontal section of a mesh (2D, metres).

    - ``solid``: material of closed solids;
    - ``sheets``: lines where open surfaces (single-sheet walls) are cut;
    - ``walls``: ``solid`` plus the sheets thickened to ``MESH_THIN_WALL``;
    - ``enclosed``: bounded regions that are not wall material (rooms).
    """

    solid: MultiPolygon
    sheets: MultiLineString
    walls: MultiPolygon
    enclosed: MultiPolygon


class MeshSections:
    """Sections of one mesh (metres, z up) at any height; topology computed once."""

    def __init__(self, mesh) -> None:
        self.mesh = mesh
        faces = np.asarray(mesh.faces, dtype=np.int64)
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        self.normals, _ = face_normals(vertices, faces)
        self.open_face = open_faces(vertices, faces)

    def cut(self, z: float) -> tuple[MultiPolygon, MultiPolygon]:
        """``(walls, enclosed)`` at height ``z``: wall material, and the
        bounded regions of the section that are not wall material (rooms)."""
        sec = self.section(z)
        return sec.walls, sec.enclosed

    def section(self, z: float) -> Section:
        """Everything the plane at height ``z`` shows (see :class:`Section`)."""
        from trimesh.intersections import mesh_plane

        lines, face = mesh_plane(self.mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z], return_faces=True)
        if len(lines) == 0:
            return Section(MultiPolygon(), MultiLineString(), MultiPolygon(), MultiPolygon())
        seg = orient(np.asarray(lines)[:, :, :2], self.normals[face, :2])
        thin = self.open_face[face]
        crossings = sheet_crossings(seg[thin])
        if crossings > MESH_SHEET_CROSSINGS * max(int(thin.sum()), MESH_SHEET_MIN_LINES):
            raise MapkitError(f"the mesh's section at {z:.3f} m is a tangle: its {int(thin.sum())} lines of single "
                              f"surfaces cross one another {crossings} times (more than MESH_SHEET_CROSSINGS = "
                              f"{MESH_SHEET_CROSSINGS:g} a line): its faces cross the building; repair the model or "
                              "export it again")
        try:
            return section_regions(seg[~thin], seg[thin])
        except shapely.errors.GEOSException as exc:
            # A damaged mesh (faces naming the wrong vertices) crosses itself:
            # its section is no valid outline, and GEOS gives up on it.
            reason = str(exc).split(". ")[0][:100]
            raise MapkitError(f"the mesh's section at {z:.3f} m is not a valid outline ({reason}): its faces cross "
                              "each other; repair the model or export it again") from None


def sheet_crossings(thin: np.ndarray) -> int:
    """How many times the section lines ``thin`` (T, 2, 2) of single
    surfaces cross or touch one another: the pieces their noding makes
    beyond their own number."""
    if len(thin) == 0:
        return 0
    noded = shapely.get_parts(shapely.union_all(shapely.linestrings(snap_ends(thin))))
    return max(0, int(np.sum(shapely.get_num_coordinates(noded) - 1)) - len(thin))


def open_faces(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) bool: faces of surfaces that do not bound a solid.

    A connected surface (faces joined through shared edges) is open if its
    border edges make more than ``MESH_OPEN_FRACTION`` of its edge length,
    or if it is closed but inside out (negative volume: a room modelled as
    a box seen from within).
    """
    topo = edge_faces(faces)
    counts = topo.counts
    # Faces around one edge are consecutive entries: link each to the next.
    follows = np.ones(len(topo.face), dtype=bool)
    follows[topo.starts[:-1]] = False
    idx = np.nonzero(follows)[0]
    graph = coo_matrix((np.ones(len(idx), dtype=np.int8), (topo.face[idx - 1], topo.face[idx])), shape=(len(faces),) * 2)
    _, label = connected_components(graph, directed=False)
    # Border length per surface, against all its edge length: a few short
    # holes (a sliver lost in welding, a scan gap) leave a solid a solid.
    edge_len = np.linalg.norm(vertices[topo.edges[:, 1]] - vertices[topo.edges[:, 0]], axis=1)
    edge_label = label[topo.face[topo.starts[:-1]]]
    total = np.bincount(edge_label, weights=edge_len)
    border = np.bincount(edge_label, weights=edge_len * (counts == 1), minlength=len(total))
    bordered = border > MESH_OPEN_FRACTION * total
    tri = vertices[faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    volume = np.bincount(label, weights=signed)
    return (bordered | (volume < 0))[label]


def orient(segments: np.ndarray, normals_xy: np.ndarray) -> np.ndarray:
    """Flip segments (S, 2, 2) so that the outward normal (S, 2) is on their right."""
    d = segments[:, 1] - segments[:, 0]
    right = np.stack([d[:, 1], -d[:, 0]], axis=1)
    flip = np.einsum("ij,ij->i", right, normals_xy) < 0
    out = segments.copy()
    out[flip] = segments[flip][:, ::-1]
    return out


def winding_numbers(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(P,) int winding number of each point (P, 2) about oriented segments (S, 2, 2).

    Positive inside a solid whose boundary runs counter-clockwise (solid on
    the left); overlapping solids add up. Points on a segment are undefined.
    """
    out = np.zeros(len(points), dtype=np.int64)
    if len(segments) == 0 or len(points) == 0:
        return out
    a, b = segments[:, 0], segments[:, 1]
    step = max(1, MESH_SECTION_CHUNK // len(segments))
    for i in range(0, len(points), step):
        p = points[i : i + step, None, :]
        cross = (b[:, 0] - a[:, 0]) * (p[..., 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (p[..., 0] - a[:, 0])
        up = (a[:, 1] <= p[..., 1]) & (b[:, 1] > p[..., 1]) & (cross > 0)
        down = (b[:, 1] <= p[..., 1]) & (a[:, 1] > p[..., 1]) & (cross < 0)
        out[i : i + step] = up.sum(axis=1) - down.sum(axis=1)
    return out


def section_regions(closed: np.ndarray, thin: np.ndarray) -> Section:
    """The :class:`Section` made by section segments.

    ``closed`` (S, 2, 2): segments of solids, oriented solid-on-left;
    ``thin`` (T, 2, 2): segments of open surfaces (any orientation).
    """
    lines = shapely.linestrings(snap_ends(np.concatenate([closed, thin])))
    faces = np.asarray(shapely.get_parts(shapely.polygonize(shapely.get_parts(shapely.union_all(lines)))))
    faces = faces[shapely.area(faces) > MERGE * MERGE] if len(faces) else faces
    inside = winding_numbers(shapely.get_coordinates(shapely.point_on_surface(faces)), closed) > 0
    solid = shapely.union_all(faces[inside])
    # Solids that touch leave hairline slivers between them where their
    # section lines do not snap to the same grid points: close them.
    solid = solid.buffer(MERGE, join_style="mitre").buffer(-MERGE, join_style="mitre")
    sheets = MultiLineString()
    walls = solid
    if len(thin):
        sheets = shapely.line_merge(shapely.union_all(shapely.linestrings(snap_ends(thin))))
        thick = sheets.buffer(MESH_THIN_WALL / 2, cap_style="square", join_style="mitre")
        walls = shapely.union_all([solid, thick])
    enclosed = shapely.difference(shapely.union_all(faces[~inside]), walls)
    return Section(as_multipolygon(solid), sheets, as_multipolygon(walls), as_multipolygon(enclosed))


def snap_ends(segments: np.ndarray, tol: float = MERGE) -> np.ndarray:
    """Segments (S, 2, 2) with end points closer than ``tol`` made identical.

    Neighbouring faces compute their shared section point from the same
    mesh edge in different orders, so the two copies differ in the last
    bits; polygonize needs them equal. Points are clustered (k-d tree pairs,
    connected components), not rounded to a grid, so two copies straddling
    a grid line still meet.
    """
    from scipy.spatial import cKDTree

    pts = segments.reshape(-1, 2)
    if len(pts) == 0:
        return segments
    pairs = cKDTree(pts).query_pairs(tol, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])), shape=(len(pts),) * 2)
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, -1)
    first[label[::-1]] = np.arange(len(pts))[::-1]  # lowest index of each cluster
    return pts[first[label]].reshape(segments.shape)


def as_multipolygon(geom) -> MultiPolygon:
    """The polygonal parts of any shapely geometry as one MultiPolygon."""
    if geom is None or geom.is_empty:
        return MultiPolygon()
    return MultiPolygon([g for g in shapely.get_parts(geom) if g.geom_type == "Polygon" and not g.is_empty])


def boundary_outline(vertices: np.ndarray, faces: np.ndarray) -> MultiPolygon:
    """What a set of upward-facing faces covers, seen from above.

    The border edges of the face set keep their faces' orientation, which
    runs counter-clockwise around the covered area seen from above; their
    polygonized faces with positive winding number are the cover. Much
    faster than a union of thousands of triangles.
    """
    if len(faces) == 0:
        return MultiPolygon()
    topo = edge_faces(faces)
    border = topo.starts[:-1][topo.counts == 1]
    f = faces[topo.face[border]]
    opp = topo.opposite[border]
    k = np.argmax(f == opp[:, None], axis=1)  # the directed edge is the one after the opposite corner
    a = f[np.arange(len(f)), (k + 1) % 3]
    b = f[np.arange(len(f)), (k + 2) % 3]
    seg = np.stack([vertices[a, :2], vertices[b, :2]], axis=1)
    return section_regions(seg, np.zeros((0, 2, 2))).solid
