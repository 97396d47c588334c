"""Shapely geometry as plain parts and rings, shared by every build stage.

Importers, the edge stage, visibility, the region partition and the map
assembler all take a geometry that may be a Polygon, a MultiPolygon or a
GeometryCollection and need its polygons or its rings as arrays. This
module holds those two helpers so that no stage imports them from another.
"""

from __future__ import annotations

import numpy as np
from shapely.geometry import Polygon


def polygon_parts(geom) -> list[Polygon]:
    """The non-empty polygons of a Polygon, MultiPolygon or GeometryCollection."""
    if geom is None or geom.is_empty:
        return []
    if isinstance(geom, Polygon):
        return [geom]
    return [g for g in getattr(geom, "geoms", []) for g in polygon_parts(g)]


def rings_of(geom) -> list[tuple[np.ndarray, bool]]:
    """(points (n, 2) without the closing repeat, is_hole) for every ring of ``geom``."""
    out = []
    for poly in polygon_parts(geom):
        out.append((np.asarray(poly.exterior.coords)[:-1, :2], False))
        out += [(np.asarray(r.coords)[:-1, :2], True) for r in poly.interiors]
    return [(p, h) for p, h in out if len(p) >= 3]


__all__ = ["polygon_parts", "rings_of"]
