"""Vertical connections of an IFC building: stairs, ramps and lifts, per storey.

A connection's footprint in a storey is the part of its body between the
storey's floor and the next floor, seen from above: the whole flight in
the storey it rises from, the top tread in the one it arrives at. The
storeys it has a footprint in are the storeys it connects.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from shapely.geometry import MultiPolygon

from mapkit.importers.ifc.geometry import Mesh
from mapkit.importers.ifc.read import Storey
from mapkit.tolerances import IFC_LEVEL

#: IFC class -> the manifest's ``kind``.
KINDS = {"IfcStair": "stair", "IfcStairFlight": "stair", "IfcRamp": "ramp", "IfcRampFlight": "ramp",
         "IfcTransportElement": "lift"}


@dataclass
class Connection:
    """A stair, ramp or lift: ``kind`` (``KINDS``), its IFC ``ifc_class``,
    ``name``, ``guid``, and its ``footprints`` per storey (by the storey's
    index in the model's storeys, lowest first), metres, world frame."""

    kind: str
    ifc_class: str
    name: str
    guid: str
    footprints: dict[int, MultiPolygon] = field(default_factory=dict)


def vertical_connections(elements: list, meshes: dict[int, Mesh], storeys: list[Storey]) -> list[Connection]:
    """The connections among ``elements`` (the model's stairs, ramps, lifts)
    with a body, leaving out the flights of a stair (ramp) also listed:
    the whole stands for them."""
    import ifcopenshell.util.element as ue

    ids = {e.id() for e in elements}
    parts_of_listed = {p.id() for e in elements for p in ue.get_decomposition(e) if p.id() in ids and e.id() in meshes}
    out = []
    for e in elements:
        if e.id() in parts_of_listed or e.id() not in meshes:
            continue
        cls = next(c for c in KINDS if e.is_a(c))
        c = Connection(KINDS[cls], cls, str(e.Name or ""), str(e.GlobalId))
        for k, s in enumerate(storeys):
            # Reaching the storey's floor (less a level's slack) and starting below the next floor.
            fp = meshes[e.id()].footprint(s.elevation - IFC_LEVEL, s.elevation + s.height - IFC_LEVEL)
            if not fp.is_empty:
                c.footprints[k] = fp
        if c.footprints:
            out.append(c)
    return out


def obstacles_in(connections: list[Connection], storey: int) -> MultiPolygon:
    """The footprints of ``connections`` in storey number ``storey``: where the robot cannot stand."""
    import shapely

    from mapkit.shapes import polygon_parts

    parts = [c.footprints[storey] for c in connections if storey in c.footprints]
    return MultiPolygon(polygon_parts(shapely.union_all(parts or [MultiPolygon()])))
