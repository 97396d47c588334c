"""The building's footprint closed from its walls, for plans without a
closed outline.

Many plans never draw the building's outline: the outer walls stop at the
entrance, beside a door next to a corner, at an opening whose wall ends do
not face each other (:mod:`.enclosure` bridges only those that do). The
inside is then what the outer walls surround once every gap up to a
building's typical opening (``OUTLINE_MAX_GAP``) is bridged: a
morphological closing of the barriers (walls, windows, glass, door gaps)
by half that width, whose outer boundaries follow the outer walls, and
whose parts are filled (rooms, corridors and courtyards inside are inside,
however narrow). It is not the walls' convex hull: the notch of an L-shaped
building stays outside.

A gap in the outer walls wider than that leaves the inside open to the
outside: the closing then encloses little (less than ``OPEN_PLAN_FRACTION``
of the walls' convex hull) and the plan is refused by the caller, naming
``--floor``.
"""

from __future__ import annotations

import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union

from mapkit.shapes import polygon_parts
from mapkit.tolerances import OUTLINE_MAX_GAP, OUTLINE_MITRE_LIMIT


def closed_footprint(barriers, max_gap: float = OUTLINE_MAX_GAP) -> Polygon | MultiPolygon:
    """The area the ``barriers`` (walls and everything that shuts a gap;
    metres) surround once their gaps up to ``max_gap`` metres are closed:
    the filled outer boundaries of their closing by ``max_gap / 2``.

    Mitred offsets keep square corners square (a round closing would fill
    each re-entrant corner of the facade with a fillet)."""
    if barriers.is_empty:
        return Polygon()
    half = max_gap / 2.0
    grown = barriers.buffer(half, join_style="mitre", mitre_limit=OUTLINE_MITRE_LIMIT)
    closed = grown.buffer(-half, join_style="mitre", mitre_limit=OUTLINE_MITRE_LIMIT)
    # The closing may give back a hair less than it got at acute corners:
    # the barriers themselves are always part of what they surround.
    filled = [Polygon(p.exterior) for p in polygon_parts(closed)]
    filled += [Polygon(p.exterior) for p in polygon_parts(barriers)]
    footprint = unary_union(filled) if filled else Polygon()
    return MultiPolygon([p for p in polygon_parts(shapely.make_valid(footprint)) if p.area > 0])


__all__ = ["closed_footprint"]
