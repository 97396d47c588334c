"""The 3D model of a plan-based :class:`~mapkit.scene.Scene`: walls, floor, ceiling.

The walls are the same 2.5D solid the edge stage (:mod:`mapkit.edges`)
reasons about: between consecutive breakpoint heights (0, every sill and
head, the wall height) the solid is a prism over a constant footprint, the
walls plus every opening that is closed in that band (the lintel above a
door, the parapet under a window). The bands are stitched into one surface
rather than stacked as separate boxes: every ring is split at every vertex
of every other band, so a wall face that continues across a band boundary
is two coplanar quads sharing their edge (no visible line there), and the
horizontal caps (door lintel undersides, window sills, the wall tops) share
their edges with the quads around them. Loaded back through the mesh
importer, the model gives the plan's edges.

A floor slab (``SLAB_THICKNESS`` under z = 0) covers the rooms and the
doorways, not the walls, so the wall/floor junctions stay feature edges; an
optional ceiling slab sits on the walls. Units: metres, z up.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from mapkit.errors import MapkitError
from mapkit.shapes import polygon_parts
from mapkit.importers.mesh.load import weld
from mapkit.scene import Scene
from mapkit.tolerances import EXTRUDE_CHUNK, EXTRUDE_CLEAN, EXTRUDE_GRID, MERGE

#: Thickness of the floor and ceiling slabs, metres.
SLAB_THICKNESS = 0.1


def scene_to_mesh(scene: Scene, ceiling: bool = False, robot_radius: float = 0.0):
    """A closed triangle mesh (``trimesh.Trimesh``) of the scene's building.

    ``robot_radius`` is what the importer shrank the free space by; the
    floor slab grows it back where the free space is not enclosed by walls
    (open plans).
    """
    import trimesh

    height = float(scene.wall_height)
    if not height > 0:
        raise MapkitError(f"the walls' height must be positive, got {height}; check --wall-height")
    levels, bands = wall_bands(scene)
    slab = floor_region(scene, bands[0], robot_radius)

    # (region, z, faces up?) for every horizontal cap.
    caps = [(bands[0], 0.0, False)]
    for k in range(1, len(bands)):
        caps.append((_snap(shapely.difference(bands[k - 1], bands[k])), levels[k], True))
        caps.append((_snap(shapely.difference(bands[k], bands[k - 1])), levels[k], False))
    caps.append((bands[-1], height, True))
    prisms = [(bands[k], levels[k], levels[k + 1]) for k in range(len(bands))]
    if not slab.is_empty:
        caps += [(slab, 0.0, True), (slab, -SLAB_THICKNESS, False)]
        prisms.append((slab, -SLAB_THICKNESS, 0.0))
    if ceiling:
        roof = _snap(shapely.union_all([slab, bands[-1]]))
        caps += [(roof, height, False), (roof, height + SLAB_THICKNESS, True)]
        prisms.append((roof, height, height + SLAB_THICKNESS))

    splits = _all_vertices([g for g, *_ in caps] + [g for g, *_ in prisms])
    tris = [_side_quads(_split_ring(r, splits), z0, z1) for g, z0, z1 in prisms for r in _rings(g)]
    tris += [_cap_triangles(g, z, up, splits) for g, z, up in caps]
    tris = [t for t in tris if len(t)]
    if not tris:
        raise MapkitError("no walls to extrude (too thin at this scale?); check --units and the layers with "
                          "'mapkit preview'")
    tri = np.concatenate(tris)  # (T, 3, 3)
    vertices, faces = weld(tri.reshape(-1, 3), np.arange(len(tri) * 3).reshape(-1, 3))
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def wall_bands(scene: Scene) -> tuple[list[float], list[MultiPolygon]]:
    """Breakpoint heights (K + 1,) and the wall footprint in each of the K bands.

    In a band, an opening whose sill..head interval covers the band is open
    (a gap); every other opening footprint is wall material.
    """
    height = float(scene.wall_height)
    cuts = {0.0, height}
    for o in scene.openings:
        cuts.update(z for z in (float(o.sill), float(o.head)) if 0.0 < z < height)
    levels = sorted(cuts)
    bands = []
    for z0, z1 in zip(levels[:-1], levels[1:]):
        mid = 0.5 * (z0 + z1)
        shut = [o.footprint for o in scene.openings if not (o.sill <= mid <= o.head)]
        gaps = [o.footprint for o in scene.openings if o.sill <= mid <= o.head]
        solid = shapely.union_all([scene.walls, *shut])
        if gaps:
            solid = shapely.difference(solid, shapely.union_all(gaps))
        bands.append(_snap(_clean(solid)))
    return levels, bands


def floor_region(scene: Scene, ground_band, robot_radius: float = 0.0) -> MultiPolygon:
    """Where the floor slab goes: the rooms the walls enclose, the free space
    (grown back by ``robot_radius``: open plans) and the doorways, minus the
    wall material standing at z = 0."""
    full = shapely.union_all([scene.walls, *[o.footprint for o in scene.openings]])
    rooms = [Polygon(ring) for p in polygon_parts(full) for ring in p.interiors]
    free = scene.free_space
    if robot_radius > 0 and not free.is_empty:
        free = free.buffer(robot_radius, join_style="mitre")
    doors = [o.footprint for o in scene.openings if o.sill <= MERGE]
    region = shapely.union_all([*rooms, free, *doors])
    return _snap(shapely.difference(region, ground_band))


def _clean(geom):
    """Close hairline gaps and remove hairline notches, keeping corners square."""
    if geom.is_empty:
        return geom
    g = geom.buffer(EXTRUDE_CLEAN, join_style="mitre").buffer(-2 * EXTRUDE_CLEAN, join_style="mitre")
    return g.buffer(EXTRUDE_CLEAN, join_style="mitre")


def _snap(geom) -> MultiPolygon:
    """Polygonal parts of ``geom`` on the ``EXTRUDE_GRID`` grid, slivers dropped."""
    geom = shapely.set_precision(geom, EXTRUDE_GRID) if not geom.is_empty else geom
    parts = [p for p in polygon_parts(geom) if p.area > MERGE * MERGE]
    return MultiPolygon([orient(p, 1.0) for p in parts])


def _rings(geom) -> list[np.ndarray]:
    """Every ring (n, 2) of ``geom``, material on the left: exteriors
    counter-clockwise, holes clockwise; the closing point not repeated."""
    out = []
    for p in polygon_parts(geom):
        p = orient(p, 1.0)
        out.append(np.asarray(p.exterior.coords)[:-1, :2])
        out += [np.asarray(r.coords)[:-1, :2] for r in p.interiors]
    return [r for r in out if len(r) >= 3]


def _all_vertices(geoms) -> np.ndarray:
    """(P, 2) distinct ring vertices of all ``geoms`` (on the ``EXTRUDE_GRID`` grid)."""
    rings = [r for g in geoms for r in _rings(g)]
    if not rings:
        return np.zeros((0, 2))
    pts = np.concatenate(rings)
    return np.unique(np.round(pts / EXTRUDE_GRID), axis=0) * EXTRUDE_GRID


def _split_ring(ring: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Insert into a ring (n, 2) every point (P, 2) lying on one of its edges.

    A point is on an edge if it is within ``MERGE / 2`` of it and strictly
    between its ends; inserted points keep their order along the edge.
    """
    a = ring
    b = np.roll(ring, -1, axis=0)
    d = b - a
    length2 = np.einsum("ij,ij->i", d, d)
    lo, hi = np.minimum(a, b) - MERGE, np.maximum(a, b) + MERGE
    # Candidate points inside the ring's bounding box only.
    box = (points >= ring.min(axis=0) - MERGE).all(axis=1) & (points <= ring.max(axis=0) + MERGE).all(axis=1)
    pts = points[box]
    if len(pts) == 0:
        return ring
    hit_edge, hit_t, hit_pt = [], [], []
    step = max(1, EXTRUDE_CHUNK // len(pts))
    for i in range(0, len(a), step):
        sl = slice(i, i + step)
        rel = pts[None, :, :] - a[sl, None, :]
        t = np.einsum("epj,ej->ep", rel, d[sl]) / length2[sl, None]
        off = rel - t[..., None] * d[sl, None, :]
        near = np.einsum("epj,epj->ep", off, off) <= (MERGE / 2) ** 2
        inside = (pts[None] >= lo[sl, None]).all(-1) & (pts[None] <= hi[sl, None]).all(-1)
        end = MERGE / np.sqrt(length2[sl, None])
        e, q = np.nonzero(near & inside & (t > end) & (t < 1 - end))
        hit_edge.append(e + i)
        hit_t.append(t[e, q])
        hit_pt.append(pts[q])
    edges = np.concatenate(hit_edge)
    if len(edges) == 0:
        return ring
    tt = np.concatenate(hit_t)
    ins = np.concatenate(hit_pt)
    # Original vertex i sorts as (i, 0); a point on edge i as (i, t).
    key_e = np.r_[np.arange(len(ring)), edges]
    key_t = np.r_[np.zeros(len(ring)), tt]
    order = np.lexsort((key_t, key_e))
    return np.concatenate([ring, ins])[order]


def _side_quads(ring: np.ndarray, z0: float, z1: float) -> np.ndarray:
    """(2n, 3, 3) triangles of the vertical faces of a ring (material on the
    left) from ``z0`` to ``z1``, normals pointing out of the material."""
    a = ring
    b = np.roll(ring, -1, axis=0)
    n = len(ring)
    lo_a = np.c_[a, np.full(n, z0)]
    lo_b = np.c_[b, np.full(n, z0)]
    hi_a = np.c_[a, np.full(n, z1)]
    hi_b = np.c_[b, np.full(n, z1)]
    return np.concatenate([np.stack([lo_a, lo_b, hi_b], axis=1), np.stack([lo_a, hi_b, hi_a], axis=1)])


def _cap_triangles(geom, z: float, up: bool, splits: np.ndarray) -> np.ndarray:
    """(T, 3, 3) triangles covering ``geom`` at height ``z``, facing up or down.

    Rings are split at ``splits`` first so the cap shares its edges with the
    side quads around it.
    """
    out = []
    for p in polygon_parts(geom):
        p = orient(p, 1.0)
        shell = _split_ring(np.asarray(p.exterior.coords)[:-1, :2], splits)
        holes = [_split_ring(np.asarray(r.coords)[:-1, :2], splits) for r in p.interiors]
        tri = shapely.get_parts(shapely.constrained_delaunay_triangles(Polygon(shell, holes)))
        if len(tri) == 0:
            continue
        xy = shapely.get_coordinates(shapely.get_exterior_ring(tri)).reshape(len(tri), 4, 2)[:, :3]
        out.append(xy)
    if not out:
        return np.zeros((0, 3, 3))
    xy = np.concatenate(out)
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    ccw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0
    flip = ccw != up
    xy[flip] = xy[flip][:, ::-1]
    return np.concatenate([xy, np.full((len(xy), 3, 1), z)], axis=2)
