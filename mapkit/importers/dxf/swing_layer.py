"""Where a plan is drawn when no layer's name says so: the layer of its door swings.

A drawing sheet keeps its floor plans on a layer whose name says nothing of
walls ('DETAILS'), beside layers of sections, elevations and a site plan
that hold as much linework ('SECTION-A', 'FRONT-ELEVATION', 'SITE-PLAN').
No layer is named like walls and several of unknown role hold lines, so
no rule of :func:`mapkit.importers.dxf.layers.resolve_layer_roles` finds
the walls. The floor plans are where the doors swing: of the layers of
unknown role, the one holding the most door swings (an arc a door's width
in radius and its leaf line, :func:`.door_swings.find_door_swings`) is
taken as the walls (:func:`adopt_swing_layer`), and the drawing is read in
the unit its swings are read in, with a warning naming both and the
options that choose otherwise (``--walls``, ``--units``). The options the
user gives win: ``--walls`` names the walls, ``--units`` or ``--scale``
the size. Such a layer also holds furniture and fittings; they are built
as the walls are (obstacles the robot keeps off), which the warning sends
the user to check in 'mapkit preview'.

The swings must say one unit: read in each unit a plan is drawn in
(``SWING_LAYER_UNITS``), only one may find at least ``SWING_LAYER_MIN_SWINGS``
swings on the layer, and no other layer as many. Door leaves are 0.6 to
1.2 m wide, within a factor of ten of each other; arcs found as swings in
units a factor of ten or more apart are not one building's doors (a
framing plan's lettering drawn as arcs of every size). And the layer must
draw doors in walls (:func:`draws_doors_in_walls`): most of its door-sized
arcs are swings (of a framing plan's lettering, few are), and the swings
hang in lines of that layer (a layer of doors alone, or of doors and
furniture beside walls drawn on another layer, is no wall layer).
Otherwise no layer is taken, and the drawing is refused for want of walls.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Point

from mapkit.importers.dxf.door_swings import find_door_swings, is_door_sized_arc
from mapkit.importers.dxf.entities import SILENT, flatten_entities
from mapkit.importers.dxf.layer_roles import assign_roles
from mapkit.importers.dxf.read import model_space
from mapkit.importers.dxf.units import INSUNITS
from mapkit.options import BuildOptions
from mapkit.tolerances import (CURVE_SAGITTA, SWING_LAYER_ARC_SHARE, SWING_LAYER_HINGE_GAP, SWING_LAYER_HINGED_SHARE,
                               SWING_LAYER_LINES_PER_SWING, SWING_LAYER_MIN_SWINGS)
from mapkit.units import UNIT_METRES

#: Units a floor plan is drawn in, tried in turn to read the arcs as door swings.
SWING_LAYER_UNITS = ("mm", "cm", "dm", "m", "in", "ft")


def swing_layer(msp, counts: dict[str, Counter], roles: dict[str, str | None]) -> tuple[str, int, str] | None:
    """The layer of unknown role that holds the plan's door swings, as
    ``(layer, number of swings, unit they are read in)``; None when no such
    layer holds ``SWING_LAYER_MIN_SWINGS`` of them in exactly one unit, or
    two layers hold as many.

    ``msp``: the model space (its loose ARCs and LINEs are read);
    ``counts``: entity counts per layer and type; ``roles``: each layer's role."""
    unknown = {name for name, role in roles.items()
               if role is None and any(kind not in SILENT and n for kind, n in counts.get(name, Counter()).items())}
    by_layer: dict[str, list] = {}
    for e in msp:
        layer = e.dxf.get("layer", "0")
        if layer in unknown and e.dxftype() in ("ARC", "LINE"):
            by_layer.setdefault(layer, []).append(e)
    found: dict[str, dict[str, int]] = {}  # layer -> unit -> swings
    for layer, entities in by_layer.items():
        for unit in SWING_LAYER_UNITS:
            n = len(find_door_swings(entities, UNIT_METRES[unit]))
            if n >= SWING_LAYER_MIN_SWINGS:
                found.setdefault(layer, {})[unit] = n
    one_unit = {layer: next(iter(units.items())) for layer, units in found.items() if len(units) == 1}
    ranked = sorted(((n, layer, unit) for layer, (unit, n) in one_unit.items()), reverse=True)
    if not ranked or (len(ranked) > 1 and ranked[1][0] == ranked[0][0]):
        return None
    n, layer, unit = ranked[0]
    return layer, n, unit


@dataclass(frozen=True)
class AdoptedSwingLayer:
    """The swing layer taken as the walls of a drawing with no wall layer.

    ``roles``: every layer's role, ``layer`` the walls'; ``unit``: the unit
    to read the drawing in (its swings'), None when the user's ``--units``
    or ``--scale`` decide; ``warning``: what was assumed and the options
    that choose otherwise; ``why``: the rule, for 'mapkit layers'."""

    roles: dict[str, str | None]
    layer: str
    unit: str | None
    warning: str
    why: str


def adopt_swing_layer(doc, counts: dict[str, Counter], options: BuildOptions) -> AdoptedSwingLayer | None:
    """The layer of unknown role holding the plan's door swings
    (:func:`swing_layer`), taken as the walls of the DXF document ``doc``
    (``counts``: its entity counts per layer and type) when no layer is
    walls by name and the user named none; None when the user named wall
    layers or no layer holds the swings as :func:`swing_layer` requires."""
    if options.walls:
        return None
    roles = assign_roles(counts, options.walls, options.doors, options.windows, options.ignore,
                         list(getattr(options, "floor", []) or []))
    msp = model_space(doc)
    found = swing_layer(msp, counts, roles)
    if found is None:
        return None
    layer, n, unit = found
    if not draws_doors_in_walls([e for e in msp if e.dxf.get("layer", "0") == layer], UNIT_METRES[unit]):
        return None
    roles = roles | {layer: "walls"}
    header_unit = INSUNITS.get(int(doc.header.get("$INSUNITS", 0) or 0))
    # The user's --units or --scale say the size: the swings' unit gives way.
    read_in = unit if options.units is None and float(options.scale) == 1.0 else None
    warning = (f"no layer is named like walls: taking '{layer}', the layer of the drawing's {n} door swings (each an "
               f"arc and its leaf), as the walls (all it holds is built as walls, furniture too)")
    options_named = "--walls"
    if read_in is not None and read_in != header_unit:
        said = f"its header says {header_unit}" if header_unit else "its header gives no unit"
        warning += f", read in {read_in} as the swings are ({said})"
        options_named += " and --units"
    warning += f"; check it with 'mapkit preview' and pass {options_named} to choose otherwise"
    why = f"no layer is named like walls: it holds the drawing's door swings ({n}, read in {unit})"
    return AdoptedSwingLayer(roles, layer, read_in, warning, why)


def draws_doors_in_walls(entities, metres_per_unit: float) -> bool:
    """Whether one layer's model-space ``entities`` draw doors in walls, read
    in the unit of ``metres_per_unit`` (the one its swings are found in):
    at least ``SWING_LAYER_ARC_SHARE`` of its door-sized arcs are door
    swings (a framing plan's lettering has arcs of every size, few with a
    leaf), most of their hinges (``SWING_LAYER_HINGED_SHARE``) lie within
    ``SWING_LAYER_HINGE_GAP`` of the layer's other linework, and that
    linework is ``SWING_LAYER_LINES_PER_SWING`` metres long per swing. A
    layer of doors alone (their frames, double-line leaves) or of doors and
    furniture beside walls drawn on another layer is not the walls."""
    swings = find_door_swings([e for e in entities if e.dxftype() in ("ARC", "LINE")], metres_per_unit)
    door_sized = [e for e in entities if e.dxftype() == "ARC" and is_door_sized_arc(e, metres_per_unit)]
    if not swings or len(swings) < SWING_LAYER_ARC_SHARE * len(door_sized):
        return False
    in_swings = {id(e) for pair in swings for e in pair}
    strokes, _ = flatten_entities([e for e in entities if id(e) not in in_swings], metres_per_unit,
                                  CURVE_SAGITTA / metres_per_unit, lambda layer: True)
    lines = [LineString(np.vstack([s.coords, s.coords[:1]]) if s.closed else s.coords) for s in strokes]
    if sum(line.length for line in lines) < SWING_LAYER_LINES_PER_SWING * len(swings):
        return False
    tree = shapely.STRtree(lines)
    hinged = sum(len(tree.query(_hinge(arc, leaf, metres_per_unit), predicate="dwithin",
                                distance=SWING_LAYER_HINGE_GAP)) > 0 for arc, leaf in swings)
    return hinged >= SWING_LAYER_HINGED_SHARE * len(swings)


def _hinge(arc, leaf, metres_per_unit: float) -> Point:
    """The hinge of a swing ``(arc, leaf)``, metres: the leaf's end away from
    its arc (the other end, the leaf's tip, lies on the arc)."""
    path = LineString([(v.x * metres_per_unit, v.y * metres_per_unit)
                       for v in arc.flattening(CURVE_SAGITTA / metres_per_unit)])
    ends = [Point(p.x * metres_per_unit, p.y * metres_per_unit) for p in (leaf.dxf.start, leaf.dxf.end)]
    return max(ends, key=path.distance)
