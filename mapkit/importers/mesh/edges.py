"""Feature edges of a triangle mesh: the straight lines a camera sees on a 3D model.

Conventions (the whole module): ``vertices`` (V, 3) float metres, world
frame, z up, the floor at ``floor_z`` (0 after import); ``faces`` (F, 3) int
vertex ids; ``segments`` (N, 2, 3) float metres; ``kinds`` (N,) uint8
:class:`~linemap.lmap.SegmentKind`.

An edge of the mesh is a *feature edge* when

- it is an open border (one face): the edge of a single-surface wall;
- its two faces meet at a dihedral angle above ``crease_deg``;
- it is shared by three or more faces (solids that touch, e.g. wall boxes
  meeting at a mitred corner) and, once the back-to-back coincident faces
  inside the solids are discounted, what remains is a border or a crease.

Edges between coplanar faces (the diagonals of a quad, the floor's
triangulation) are never features. Feature edges that continue each other
in a straight line through a shared vertex are merged into one segment;
parts below the floor or above the ceiling are cut off (nobody inside sees them); pieces shorter than
``min_length`` are dropped. Vertices must be merged first (see
:func:`mapkit.importers.mesh.load.weld`): split vertices make every edge a
border.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from linemap.lmap import SegmentKind
from mapkit.tolerances import (
    AXIS_DEG,
    COLLINEAR_DEG,
    MERGE,
    MESH_LEVEL,
    MESH_MAX_EDGE_FACES,
    MESH_OVERLAP_STEP,
    MESH_STEEP_DEG,
    ZERO,
)


@dataclass
class EdgeFaces:
    """The faces around every undirected edge of a mesh.

    - ``edges`` (E, 2) int64: vertex ids, smaller first, one row per edge.
    - ``starts`` (E + 1,) int64: the faces of edge e are entries
      ``starts[e]:starts[e + 1]`` of ``face`` and ``opposite``.
    - ``face`` (3F,) int64: face id of each entry, grouped by edge.
    - ``opposite`` (3F,) int64: that face's vertex not on the edge.
    """

    edges: np.ndarray
    starts: np.ndarray
    face: np.ndarray
    opposite: np.ndarray

    @property
    def counts(self) -> np.ndarray:
        """(E,) number of faces sharing each edge (1: border, 2: manifold)."""
        return np.diff(self.starts)


def edge_faces(faces: np.ndarray) -> EdgeFaces:
    """Group the three edges of every face (F, 3) by undirected edge."""
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(faces) == 0:
        z = np.zeros(0, dtype=np.int64)
        return EdgeFaces(np.zeros((0, 2), dtype=np.int64), np.zeros(1, dtype=np.int64), z, z)
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    opposite = faces[:, [2, 0, 1]].reshape(-1)
    face_id = np.repeat(np.arange(len(faces)), 3)
    key = pairs[:, 0] * (int(faces.max()) + 1) + pairs[:, 1]
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.r_[True, key[1:] != key[:-1]]
    starts = np.r_[np.nonzero(first)[0], len(key)].astype(np.int64)
    return EdgeFaces(pairs[order][first], starts, face_id[order], opposite[order])


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (F, 3) (right-hand rule) and areas (F,) in square metres.

    Degenerate faces get a zero normal and zero area.
    """
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(cross, axis=1)
    normals = np.divide(cross, norm[:, None], out=np.zeros_like(cross), where=norm[:, None] > 0)
    return normals, 0.5 * norm


def feature_edges(
    mesh,
    crease_deg: float,
    min_length: float,
    floor_z: float = 0.0,
    top_z: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Straight feature edges of ``mesh`` and what they are.

    ``mesh`` is anything with ``vertices`` (V, 3) and ``faces`` (F, 3)
    (a ``trimesh.Trimesh``), merged, in metres, z up. ``top_z`` is the
    ceiling height (default: the highest vertex). Returns ``segments``
    (N, 2, 3) float64 and ``kinds`` (N,) uint8 (see :func:`classify`).
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"Expected vertices (V, 3) and faces (F, 3), got {vertices.shape} and {faces.shape}")
    if not 0.0 < crease_deg < 180.0:
        raise ValueError(f"crease_deg must be in (0, 180), got {crease_deg}")
    normals, areas = face_normals(vertices, faces)
    faces = faces[areas > 0]
    normals = normals[areas > 0]
    if len(faces) == 0:
        return np.zeros((0, 2, 3)), np.zeros(0, dtype=np.uint8)
    if top_z is None:
        top_z = float(vertices[np.unique(faces)][:, 2].max())

    topo = edge_faces(faces)
    feature = _feature_mask(topo, vertices, normals, crease_deg)
    rises = _rising_face(topo, vertices, normals)[feature]
    segments, labels = merge_collinear(vertices, topo.edges[feature])
    rises = np.bincount(labels, weights=rises, minlength=len(segments)) > 0

    segments, keep = _cut_to_storey(segments, floor_z, top_z)
    rises = rises[keep]
    long = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1) >= min_length
    segments, rises = segments[long], rises[long]
    return segments, classify(segments, rises, floor_z, top_z)


def _feature_mask(topo: EdgeFaces, vertices: np.ndarray, normals: np.ndarray, crease_deg: float) -> np.ndarray:
    """(E,) bool: which edges of ``topo`` are feature edges (see module docstring)."""
    counts = topo.counts
    cos_crease = math.cos(math.radians(crease_deg))
    feature = counts == 1

    two = np.nonzero(counts == 2)[0]
    s = topo.starts[two]
    dots = np.einsum("ij,ij->i", normals[topo.face[s]], normals[topo.face[s + 1]])
    feature[two] = dots < cos_crease

    feature[counts > MESH_MAX_EDGE_FACES] = True
    many = np.nonzero((counts >= 3) & (counts <= MESH_MAX_EDGE_FACES))[0]
    if len(many):
        k = int(counts[many].max())
        slot = np.arange(k)
        valid = slot[None, :] < counts[many][:, None]  # (M, K)
        entry = np.minimum(topo.starts[many][:, None] + slot[None, :], topo.starts[many + 1][:, None] - 1)
        n = normals[topo.face[entry]]  # (M, K, 3)
        a = vertices[topo.edges[many, 0]]
        axis = vertices[topo.edges[many, 1]] - a
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        # Which side of the edge each face lies on, within its plane.
        side = vertices[topo.opposite[entry]] - a[:, None, :]
        side -= np.einsum("mkj,mj->mk", side, axis)[..., None] * axis[:, None, :]
        nn = np.einsum("mij,mkj->mik", n, n)
        ss = np.einsum("mij,mkj->mik", side, side)
        pair = valid[:, :, None] & valid[:, None, :]
        # Back-to-back: the two solids' faces on their shared wall; not seen.
        inside = (pair & (nn < -math.cos(math.radians(COLLINEAR_DEG))) & (ss > 0)).any(axis=2)
        seen = valid & ~inside
        n_seen = seen.sum(axis=1)
        seen_pair = seen[:, :, None] & seen[:, None, :]
        min_dot = np.where(seen_pair, nn, 1.0).min(axis=(1, 2))
        feature[many] = (n_seen == 1) | ((n_seen >= 2) & (min_dot < cos_crease))
    return feature


def _rising_face(topo: EdgeFaces, vertices: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(E,) bool: a steep face rises above the edge (a wall standing on it)."""
    steep = np.abs(normals[topo.face][:, 2]) < math.sin(math.radians(MESH_STEEP_DEG))
    edge_of_entry = np.repeat(np.arange(len(topo.edges)), topo.counts)
    edge_top = vertices[topo.edges[edge_of_entry]][:, :, 2].max(axis=1)
    above = vertices[topo.opposite, 2] > edge_top + MERGE
    flag = (steep & above).astype(np.int64)
    return np.add.reduceat(flag, topo.starts[:-1]) > 0 if len(flag) else np.zeros(0, dtype=bool)


def merge_collinear(vertices: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Join edges (E, 2) that continue each other straight through a shared vertex.

    Two edges are joined when they meet at a vertex going opposite ways
    within ``COLLINEAR_DEG``. A joined chain becomes the segment between its
    extreme points, provided every chain vertex lies within ``MERGE`` of that
    segment (a slowly curving chain is left in pieces). Returns ``segments``
    (S, 2, 3) and ``labels`` (E,): the segment each input edge went into.
    """
    n_edges = len(edges)
    if n_edges == 0:
        return np.zeros((0, 2, 3)), np.zeros(0, dtype=np.int64)
    p = vertices[edges]  # (E, 2, 3)
    d = p[:, 1] - p[:, 0]
    length = np.linalg.norm(d, axis=1)
    u = d / length[:, None]

    # Edge ends sorted by vertex: ends of one vertex are adjacent.
    end_vertex = edges.reshape(-1)
    end_edge = np.repeat(np.arange(n_edges), 2)
    leaving = np.stack([u, -u], axis=1).reshape(-1, 3)  # direction away from the vertex
    order = np.argsort(end_vertex, kind="stable")
    v_sorted = end_vertex[order]
    degree = np.unique(v_sorted, return_counts=True)[1].max()
    cos_c = math.cos(math.radians(COLLINEAR_DEG))
    rows, cols = [np.arange(n_edges)], [np.arange(n_edges)]
    for k in range(1, int(degree)):
        a, b = order[:-k], order[k:]
        link = (v_sorted[:-k] == v_sorted[k:]) & (np.einsum("ij,ij->i", leaving[a], leaving[b]) < -cos_c)
        rows.append(end_edge[a][link])
        cols.append(end_edge[b][link])
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r), dtype=np.int8), (r, c)), shape=(n_edges, n_edges))
    _, labels = connected_components(graph, directed=False)

    segments, straight = _chain_extremes(p, u, length, labels)
    if not straight.all():
        # Curved chains: give each of their edges its own label again.
        bent = ~straight[labels]
        labels = labels.copy()
        labels[bent] = labels.max() + 1 + np.arange(bent.sum())
        _, labels = np.unique(labels, return_inverse=True)
        segments, _ = _chain_extremes(p, u, length, labels)
    return segments, labels


def _chain_extremes(p: np.ndarray, u: np.ndarray, length: np.ndarray, labels: np.ndarray):
    """Per label: the segment between the chain's extreme points, and whether the chain is straight."""
    n = int(labels.max()) + 1
    # Reference direction of a chain: that of its longest edge.
    by_len = np.lexsort((-length, labels))
    first = np.r_[True, labels[by_len][1:] != labels[by_len][:-1]]
    ref = np.empty((n, 3))
    ref[labels[by_len][first]] = u[by_len][first]

    pts = p.reshape(-1, 3)
    lab = np.repeat(labels, 2)
    t = np.einsum("ij,ij->i", pts, ref[lab])
    order = np.lexsort((t, lab))
    lab_sorted = lab[order]
    lo = np.r_[True, lab_sorted[1:] != lab_sorted[:-1]]
    hi = np.r_[lab_sorted[1:] != lab_sorted[:-1], True]
    segments = np.stack([pts[order][lo], pts[order][hi]], axis=1)  # labels 0..n-1 in order

    chord = segments[:, 1] - segments[:, 0]
    chord /= np.maximum(np.linalg.norm(chord, axis=1, keepdims=True), ZERO.divisor)
    rel = pts - segments[lab, 0]
    off = rel - np.einsum("ij,ij->i", rel, chord[lab])[:, None] * chord[lab]
    dev = np.zeros(n)
    np.maximum.at(dev, lab, np.linalg.norm(off, axis=1))
    return segments, dev <= MERGE


def _cut_to_storey(segments: np.ndarray, floor_z: float, top_z: float) -> tuple[np.ndarray, np.ndarray]:
    """Keep what lies between floor and ceiling: drop segments wholly under
    the floor or over the ceiling, cut the others at ``floor_z`` / ``top_z``.

    Returns the kept segments and the (N,) bool mask of which were kept.
    Ends less than ``MESH_LEVEL`` beyond a level (objects sunk a few
    millimetres into the floor) are left as they are; a segment that was
    all beyond comes out with zero length (dropped later as too short).
    """
    z = segments[:, :, 2]
    keep = (z.max(axis=1) >= floor_z - MESH_LEVEL) & (z.min(axis=1) <= top_z + MESH_LEVEL)
    seg = segments[keep].copy()
    for level, beyond in ((floor_z, -1.0), (top_z, 1.0)):
        z = seg[:, :, 2]
        out = (beyond * (z - level)).max(axis=1) > MESH_LEVEL
        if not out.any():
            continue
        s = seg[out]
        rows = np.arange(len(s))
        far = np.argmax(beyond * s[:, :, 2], axis=1)  # the end beyond the level
        a, b = s[rows, far], s[rows, 1 - far]
        t = np.clip((level - a[:, 2]) / (b[:, 2] - a[:, 2]), 0.0, 1.0)
        s[rows, far] = a + t[:, None] * (b - a)
        seg[out] = s
    return seg, keep


def classify(segments: np.ndarray, rises: np.ndarray, floor_z: float, top_z: float) -> np.ndarray:
    """Kinds (N,) uint8 of segments (N, 2, 3) from their geometry.

    VERTICAL within ``AXIS_DEG`` of z; horizontal ones (within ``AXIS_DEG``
    of the horizontal plane) are FLOOR at the floor (within ``MESH_LEVEL``)
    when a wall rises from them (``rises`` (N,) bool), CEILING at ``top_z``,
    else HORIZONTAL (table tops, sills, the floor's own border); the rest
    are OBLIQUE.
    """
    d = segments[:, 1] - segments[:, 0]
    sin_z = np.abs(d[:, 2]) / np.maximum(np.linalg.norm(d, axis=1), ZERO.divisor)
    z = segments[:, :, 2].mean(axis=1)
    kinds = np.full(len(segments), SegmentKind.OBLIQUE, dtype=np.uint8)
    horizontal = sin_z <= math.sin(math.radians(AXIS_DEG))
    kinds[horizontal] = SegmentKind.HORIZONTAL
    kinds[horizontal & (np.abs(z - top_z) <= MESH_LEVEL)] = SegmentKind.CEILING
    kinds[horizontal & (np.abs(z - floor_z) <= MESH_LEVEL) & rises] = SegmentKind.FLOOR
    kinds[sin_z >= math.cos(math.radians(AXIS_DEG))] = SegmentKind.VERTICAL
    return kinds


def merge_overlapping(segments: np.ndarray, kinds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge segments of one kind that lie on one line and overlap or touch.

    Separate objects with coplanar faces (two wall pieces in a row, a box on
    a slab) give collinear edges that share no vertex, so
    :func:`merge_collinear` cannot join them. Two segments join when their
    directions differ by less than ``COLLINEAR_DEG``, each end of one is
    within ``MERGE`` of the other's line, and they overlap or their gap is
    under ``MERGE``. Candidate pairs come from a k-d tree over points
    sampled along the segments. Returns ``(segments (M, 2, 3), kinds (M,))``.
    """
    from scipy.spatial import cKDTree

    n = len(segments)
    if n < 2:
        return segments, kinds
    a, b = segments[:, 0], segments[:, 1]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, ZERO.divisor)[:, None]
    count = np.maximum(2, np.ceil(length / MESH_OVERLAP_STEP).astype(np.int64) + 1)
    owner = np.repeat(np.arange(n), count)
    start = np.r_[0, np.cumsum(count)[:-1]]
    t = (np.arange(len(owner)) - np.repeat(start, count)) / np.repeat(count - 1, count)
    pts = a[owner] + t[:, None] * d[owner]
    pairs = cKDTree(pts).query_pairs(MESH_OVERLAP_STEP / 2 + MERGE, output_type="ndarray")
    i, j = owner[pairs[:, 0]], owner[pairs[:, 1]]
    ok = (i != j) & (kinds[i] == kinds[j])
    i, j = i[ok], j[ok]
    ok = np.abs(np.einsum("ij,ij->i", u[i], u[j])) > math.cos(math.radians(COLLINEAR_DEG))
    i, j = i[ok], j[ok]

    def off_line(p, k):  # distance of points p (m, 3) from the lines of segments k
        rel = p - a[k]
        return np.linalg.norm(rel - np.einsum("ij,ij->i", rel, u[k])[:, None] * u[k], axis=1)

    ok = (off_line(a[j], i) <= MERGE) & (off_line(b[j], i) <= MERGE)
    ok &= (off_line(a[i], j) <= MERGE) & (off_line(b[i], j) <= MERGE)
    i, j = i[ok], j[ok]
    if len(i) == 0:
        return segments, kinds
    graph = coo_matrix((np.ones(len(i), dtype=np.int8), (i, j)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    merged, straight = _chain_extremes(segments, u, length, labels)
    if not straight.all():  # a fan of near-collinear pieces: leave it alone
        bent = ~straight[labels]
        labels = labels.copy()
        labels[bent] = labels.max() + 1 + np.arange(bent.sum())
        _, labels = np.unique(labels, return_inverse=True)
        merged, _ = _chain_extremes(segments, u, length, labels)
    out_kinds = np.zeros(len(merged), dtype=kinds.dtype)
    out_kinds[labels] = kinds
    return merged, out_kinds
