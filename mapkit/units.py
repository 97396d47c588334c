"""Length units by name: what ``--units`` accepts, in metres per unit.

Shared by every importer (DXF, meshes) so a unit means the same everywhere.
"""

from __future__ import annotations

from mapkit.errors import MapkitError

#: Unit name -> metres per unit. Names accepted by ``--units``.
UNIT_METRES = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "dm": 0.1,
    "km": 1000.0,
    "in": 0.0254,
    "ft": 0.3048,
    "yd": 0.9144,
    "us-ft": 1200.0 / 3937.0,
}

_ALIASES = {
    "metre": "m", "meter": "m", "metres": "m", "meters": "m",
    "centimetre": "cm", "centimeter": "cm", "centimetres": "cm", "centimeters": "cm",
    "millimetre": "mm", "millimeter": "mm", "millimetres": "mm", "millimeters": "mm",
    "decimetre": "dm", "decimeter": "dm",
    "inch": "in", "inches": "in", '"': "in",
    "foot": "ft", "feet": "ft", "'": "ft",
    "yard": "yd", "yards": "yd",
}


def parse_units(name: str) -> float:
    """Metres per unit for a ``--units`` value such as "mm" or "feet"."""
    key = name.strip().lower()
    key = _ALIASES.get(key, key)
    if key not in UNIT_METRES:
        known = ", ".join(UNIT_METRES)
        raise MapkitError(f"unknown units '{name}'; use one of {known}")
    return UNIT_METRES[key]


def canonical_units(name: str) -> str:
    """The short name of a unit ("millimetres" -> "mm"); validates like :func:`parse_units`."""
    parse_units(name)
    key = name.strip().lower()
    return _ALIASES.get(key, key)
