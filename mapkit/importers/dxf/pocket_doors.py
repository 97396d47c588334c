"""Pocket (sliding) doors: a leaf drawn inside a wall, beside the doorway.

A pocket door slides into the wall's cavity: plans draw its leaf as one
straight line on the door layer, inside the wall, running to the wall's
end; the doorway is the gap beyond that end, as wide as the leaf. The leaf
sits in no gap (the door finders of :mod:`.openings` pass it by) and over
no break of the wall (cutting the wall where the leaf is drawn would open
the wrong place): :func:`pocket_opening` finds the gap it closes.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, MultiLineString, Polygon

from mapkit.importers.dxf.enclosure import wall_ends
from mapkit.shapes import polygon_parts
from mapkit.tolerances import BRIDGE_ANGLE_DEG, JAMB_REACH, MERGE, MIN_OPENING_WIDTH, POCKET_DOOR_MAX_LEAF


def pocket_opening(item: MultiLineString, walls, max_wall_thickness: float, ends=None) -> Polygon | None:
    """The doorway a pocket door's leaf (``item``: one straight line inside
    ``walls``, metres) slides across: the gap beyond the end face of the
    wall it lies in, along the leaf, up to the leaf's length or the next
    wall; None when ``item`` is not such a leaf.

    ``ends`` is :func:`.enclosure.wall_ends` of ``walls`` (computed when
    None; pass it when testing many items)."""
    parts = list(item.geoms) if isinstance(item, MultiLineString) else [item]
    if len(parts) != 1 or len(parts[0].coords) != 2:
        return None
    leaf = parts[0]
    length = leaf.length
    if not MIN_OPENING_WIDTH <= length <= POCKET_DOOR_MAX_LEAF:
        return None
    if not walls.buffer(MERGE * 10).covers(leaf):  # a leaf drawn in the room is a swing's, not a pocket's
        return None
    a, b, out = ends if ends is not None else wall_ends(walls, max_wall_thickness)
    if not len(a):
        return None
    p, q = np.asarray(leaf.coords)
    direction = (q - p) / length
    centre = (a + b) / 2.0
    cos_par = math.cos(math.radians(BRIDGE_ANGLE_DEG))
    # The wall end the leaf runs to: near one of its ends, facing along it.
    best = None
    for tip, along in ((p, -direction), (q, direction)):
        dist = np.hypot(*(centre - tip).T)
        for k in np.flatnonzero((dist <= max_wall_thickness + JAMB_REACH) & (np.abs(out @ along) > cos_par)):
            if out[k] @ along > 0 and (best is None or dist[k] < best[0]):
                best = (dist[k], k)
    if best is None:
        return None
    k = best[1]
    reach = out[k] * length
    probe = Polygon([a[k], b[k], b[k] + reach, a[k] + reach])
    if not probe.is_valid or probe.area <= 0:
        return None
    face = LineString([a[k], b[k]])
    free = [g for g in polygon_parts(shapely.make_valid(probe.difference(walls))) if g.distance(face) <= MERGE]
    if not free:
        return None
    doorway = free[0]
    width = float(np.max((np.asarray(doorway.exterior.coords) - a[k]) @ out[k]))
    return doorway if width >= MIN_OPENING_WIDTH else None


__all__ = ["pocket_opening"]
