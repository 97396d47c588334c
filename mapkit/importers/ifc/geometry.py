"""The geometry of IFC elements: triangle meshes in world coordinates, metres.

``ifcopenshell.geom`` evaluates each element's body (extrusions, booleans:
a wall comes with its openings cut) placed in the world frame and in
metres. What the map needs of a mesh is seen from above: its footprint
(the union of its triangles projected on the floor, optionally only those
within a band of heights) and its extent in height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon

from mapkit.shapes import polygon_parts
from mapkit.tolerances import IFC_GRID


@dataclass(frozen=True)
class Mesh:
    """One element's body: ``triangles`` (m, 3, 3) world coordinates, metres, z up."""

    triangles: np.ndarray

    @property
    def z_range(self) -> tuple[float, float]:
        z = self.triangles[:, :, 2]
        return float(z.min()), float(z.max())

    def footprint(self, z_low: float = -np.inf, z_high: float = np.inf) -> MultiPolygon:
        """The mesh seen from above: the union of its triangles projected on
        the floor, only those reaching above ``z_low`` and starting below
        ``z_high`` (the part of a stair within a storey)."""
        z = self.triangles[:, :, 2]
        keep = (z.max(axis=1) >= z_low) & (z.min(axis=1) < z_high)
        return project(self.triangles[keep])


def project(triangles: np.ndarray) -> MultiPolygon:
    """Union of (m, 3, 3) triangles projected on the xy plane; triangles
    standing on edge (vertical faces) project to nothing."""
    if len(triangles) == 0:
        return MultiPolygon()
    xy = triangles[:, :, :2]
    d1, d2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    xy = xy[area > IFC_GRID**2]  # smaller than a cell of the union's grid: on edge, or a speck
    if len(xy) == 0:
        return MultiPolygon()
    rings = np.concatenate([xy, xy[:, :1]], axis=1)
    union = shapely.union_all(shapely.polygons(rings), grid_size=IFC_GRID)
    return MultiPolygon(polygon_parts(union))


def element_meshes(model_file, elements: list, threads: int = 1) -> dict[int, Mesh]:
    """The body mesh of each of ``elements`` that has one, by entity id.

    A whole without a body of its own (an IfcStair made of flights) gets
    the meshes of its parts, joined."""
    import ifcopenshell.geom
    import ifcopenshell.util.element as ue

    wanted = {e.id(): e for e in elements}
    parts = {}
    for e in elements:
        for part in ue.get_decomposition(e):
            if part.id() not in wanted:
                parts[part.id()] = part
    meshes = _iterate(model_file, list(wanted.values()) + list(parts.values()), threads, ifcopenshell.geom)
    for e in elements:
        if e.id() in meshes:
            continue
        pieces = [meshes[p.id()].triangles for p in ue.get_decomposition(e) if p.id() in meshes]
        if pieces:
            meshes[e.id()] = Mesh(np.concatenate(pieces))
    return {k: v for k, v in meshes.items() if k in wanted}


def _iterate(model_file, elements: list, threads: int, geom) -> dict[int, Mesh]:
    """Run ifcopenshell's geometry iterator over ``elements``, world coordinates."""
    if not elements:
        return {}
    settings = geom.settings()
    settings.set("use-world-coords", True)
    iterator = geom.iterator(settings, model_file, max(1, int(threads)), include=elements)
    meshes: dict[int, Mesh] = {}
    if not iterator.initialize():
        return meshes
    while True:
        shape = iterator.get()
        verts = np.asarray(shape.geometry.verts, dtype=float).reshape(-1, 3)
        faces = np.asarray(shape.geometry.faces, dtype=np.int64).reshape(-1, 3)
        if len(faces) and np.isfinite(verts).all():
            meshes[shape.id] = Mesh(verts[faces])
        if not iterator.next():
            break
    return meshes
