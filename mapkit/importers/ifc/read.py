"""An IFC model's spatial structure: its storeys and the elements of each.

Opens the file with ``ifcopenshell`` (the ``ifc`` extra), lists the
building storeys in order of elevation, with their heights, and sorts the
elements the map uses by storey (through the model's containment and
aggregation: an element contained in a space is in that space's storey)
and by role (:data:`ROLES`). No geometry here: :mod:`.geometry` does that.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from mapkit.errors import MapkitError

#: IFC class -> what it becomes in the map, in the order ``mapkit layers``
#: lists them. Subclasses count as their class (IfcWallStandardCase is an
#: IfcWall). ``wall``: an opaque solid seen from above (walls, columns);
#: ``door``/``window``: a gap in its host wall between the heights of its
#: opening; ``opening``: an opening element no door or window fills (a
#: passage or a hole); ``space``: the free space; ``slab``: the floor, where
#: a storey has no spaces; ``connection``: a stair, ramp or lift, kept out
#: of the free space and listed in the building manifest.
ROLES = {
    "IfcWall": "wall",
    "IfcColumn": "wall",
    "IfcDoor": "door",
    "IfcWindow": "window",
    "IfcOpeningElement": "opening",
    "IfcSpace": "space",
    "IfcSlab": "slab",
    "IfcStair": "connection",
    "IfcStairFlight": "connection",
    "IfcRamp": "connection",
    "IfcRampFlight": "connection",
    "IfcTransportElement": "connection",
}

#: Classes the map leaves out, named in ``mapkit layers`` so a user sees
#: what was not taken.
LISTED_UNUSED = ("IfcCurtainWall", "IfcRailing", "IfcMember", "IfcPlate", "IfcBeam", "IfcRoof", "IfcCovering",
                 "IfcFurnishingElement", "IfcBuildingElementProxy", "IfcFlowTerminal")

INSTALL_HINT = "pip install 'mapkit[ifc]'"


def import_ifcopenshell():
    """The ``ifcopenshell`` module, or a one-line MapkitError saying how to install it."""
    try:
        import ifcopenshell
        import ifcopenshell.geom  # noqa: F401 - loaded here so a broken install fails here
        import ifcopenshell.util.element  # noqa: F401
        import ifcopenshell.util.placement  # noqa: F401
        import ifcopenshell.util.unit  # noqa: F401
    except ImportError:
        raise MapkitError(f"reading IFC models needs ifcopenshell: {INSTALL_HINT}") from None
    return ifcopenshell


@dataclass
class Storey:
    """A building storey: ``name``, ``elevation`` of its floor and ``height``
    to the next storey's floor (the top storey: to the highest top of its
    walls), metres; ``elements`` its elements per role of :data:`ROLES`."""

    name: str
    elevation: float
    height: float
    entity: object = field(repr=False)
    elements: dict[str, list] = field(default_factory=dict, repr=False)

    def of(self, role: str) -> list:
        return self.elements.get(role, [])


@dataclass
class Model:
    """An opened IFC model: ``schema`` (IFC2X3, IFC4, ...), its storeys from
    the lowest up, the elements of each role in no storey, and the count of
    every class of :data:`ROLES` and :data:`LISTED_UNUSED` present."""

    file: object = field(repr=False)
    schema: str
    storeys: list[Storey]
    unplaced: dict[str, list] = field(default_factory=dict, repr=False)
    class_counts: dict[str, int] = field(default_factory=dict)

    def all_of(self, role: str) -> list:
        """Every element of ``role``, storey by storey, then those in no storey."""
        return [e for s in self.storeys for e in s.of(role)] + self.unplaced.get(role, [])


def open_model(path: Path) -> Model:
    """Open ``path`` and sort its elements; MapkitError if it is not an IFC
    model or has no building storey."""
    ifcopenshell = import_ifcopenshell()
    if path.stat().st_size == 0:  # ifcopenshell says "Unable to open file for reading", which it could
        raise MapkitError(f"{path.name}: the file is empty, not an IFC model; export the model again (an IFC file, "
                          "ISO-10303-21 text)")
    try:
        f = ifcopenshell.open(str(path))
    except Exception as exc:  # noqa: BLE001 - ifcopenshell raises its own and RuntimeErrors for any bad file
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0][:120]
        raise MapkitError(f"{path.name}: not a readable IFC model ({first})") from None
    entities = sorted(f.by_type("IfcBuildingStorey"), key=lambda s: s.id())
    if not entities:
        raise MapkitError(f"{path.name}: the model has no building storey (IfcBuildingStorey); "
                          "export it with its spatial structure")
    scale = ifcopenshell.util.unit.calculate_unit_scale(f)
    elevations = [float(ifcopenshell.util.placement.get_storey_elevation(s)) * scale for s in entities]
    order = sorted(range(len(entities)), key=lambda k: (elevations[k], entities[k].id()))
    storeys = [Storey(_name(entities[k]), elevations[k], 0.0, entities[k]) for k in order]
    by_id = {s.entity.id(): s for s in storeys}
    model = Model(f, f.schema, storeys)
    for cls, role in ROLES.items():
        for element in f.by_type(cls):
            if not _is_exactly(element, cls):
                continue
            storey = storey_of(element, by_id)
            (storey.elements if storey else model.unplaced).setdefault(role, []).append(element)
    model.class_counts = dict(Counter(_class_of(e) for cls in (*ROLES, *LISTED_UNUSED) for e in f.by_type(cls)
                                      if _is_exactly(e, cls)))
    return model


def storey_of(element, storeys_by_id: dict) -> Storey | None:
    """The storey holding ``element``: up its containment (or, for spaces
    and parts, aggregation) until a storey of ``storeys_by_id``; openings
    are in their host's storey, a door's part in its whole's."""
    import ifcopenshell.util.element as ue

    seen = set()
    node = element
    while node is not None and node.id() not in seen:
        seen.add(node.id())
        if node.id() in storeys_by_id:
            return storeys_by_id[node.id()]
        if node.is_a("IfcOpeningElement") and getattr(node, "VoidsElements", None):
            node = node.VoidsElements[0].RelatingBuildingElement
            continue
        node = ue.get_container(node) or ue.get_aggregate(node)
    return None


def _is_exactly(element, cls: str) -> bool:
    """Whether ``element`` is counted under ``cls``: an instance of it and of
    no more specific class of the tables (an IfcStairFlight is no IfcStair)."""
    return _class_of(element) == cls


def _class_of(element) -> str:
    """The class of :data:`ROLES` or :data:`LISTED_UNUSED` ``element`` belongs to, most specific first."""
    for cls in (*ROLES, *LISTED_UNUSED):
        if element.is_a(cls):
            return cls
    return element.is_a()


def _name(storey) -> str:
    """A storey's name: its Name, else LongName, else its GlobalId."""
    for attr in ("Name", "LongName"):
        value = getattr(storey, attr, None)
        if isinstance(value, str) and value.strip():
            return value.strip()
    return str(storey.GlobalId)


def count_roles(elements: list) -> Counter:
    """Elements per IFC class (``_class_of``)."""
    return Counter(_class_of(e) for e in elements)
