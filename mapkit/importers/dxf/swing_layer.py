"""Where a plan is drawn when no layer's name says so: the layer of its door swings.

A drawing sheet keeps its floor plans on a layer whose name says nothing of
walls ('DETAILS'), beside layers of sections, elevations and a site plan
that hold as much linework ('SECTION-A', 'FRONT-ELEVATION', 'SITE-PLAN').
No layer is named like walls and several of unknown role hold lines, so
the plan is refused (:func:`mapkit.importers.dxf.layers.resolve_layer_roles`).
The floor plans are where the doors swing: of the layers of unknown role,
the one holding the most door swings (an arc a door's width in radius and
its leaf line, :func:`.door_swings.find_door_swings`) is named in the
refusal, with the unit its swings are read in when the header says
another; the plan is not built from it unasked, since such a layer also
holds furniture, fittings and details that the user should look at first
('mapkit preview --walls LAYER').

The swings must say one unit: read in each unit a plan is drawn in
(``SWING_LAYER_UNITS``), only one may find at least ``SWING_LAYER_MIN_SWINGS``
swings on the layer. Door leaves are 0.6 to 1.2 m wide, within a factor
of ten of each other; arcs found as swings in units a factor of ten or more
apart are not one building's doors (a framing plan's lettering drawn as
arcs of every size).
"""

from __future__ import annotations

from collections import Counter

from mapkit.importers.dxf.door_swings import find_door_swings
from mapkit.importers.dxf.entities import SILENT
from mapkit.tolerances import SWING_LAYER_MIN_SWINGS
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


def swing_layer_hint(found: tuple[str, int, str], header_unit: str | None) -> str:
    """The refusal's clause naming the options that read the plan of the
    swing layer ``found`` (:func:`swing_layer`); ``--units`` too when the
    header's unit (``header_unit``, None if it states none) is not the
    swings'."""
    layer, n, unit = found
    plain = layer.replace("-", "").replace("_", "").isalnum()
    options = f"--walls {layer}" if plain else f"--walls '{layer}'"
    why = f"{n} door swings, each an arc and its leaf, read in {unit}"
    if header_unit != unit:
        options += f" --units {unit}"
        why += f"; its header says {header_unit}" if header_unit else "; its header gives no unit"
    return f"the floor plans are probably drawn on '{layer}' ({why}): try {options} and check it with 'mapkit preview'"
