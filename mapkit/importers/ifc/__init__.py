"""IFC (BIM) models -> one :class:`~mapkit.scene.Scene` per building storey.

    file --read--> storeys in order of elevation, elements per storey and role
         --geometry--> each element's body in world coordinates (ifcopenshell.geom)
         --connections--> stairs, ramps, lifts and their footprint per storey
         --storey--> Scene of one storey, z from its floor: walls, door and
                     window gaps at their real heights, free space

``load_scene`` builds one storey (``--storey NAME``, or the model's only
one); :func:`load_building` reads the model once for every storey
(:mod:`mapkit.building` writes a map per storey and the manifest).
Needs the ``ifc`` extra (``ifcopenshell``), imported only here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mapkit.errors import MapkitError
from mapkit.importers.ifc.connections import Connection, obstacles_in, vertical_connections
from mapkit.importers.ifc.geometry import Mesh, element_meshes
from mapkit.importers.ifc.read import Model, Storey, open_model
from mapkit.options import BuildOptions
from mapkit.scene import Scene

SUFFIXES = (".ifc",)

#: Roles whose elements' bodies a storey's scene needs (read.ROLES).
_SCENE_ROLES = ("wall", "door", "window", "opening", "space", "slab")


@dataclass
class IfcBuilding:
    """An IFC model read for the map: its storeys (lowest first, with
    heights), their elements' bodies, the vertical connections, and
    ``info`` (source, schema) every storey's scene starts from."""

    model: Model
    meshes: dict[int, Mesh] = field(repr=False)
    connections: list[Connection]
    info: dict

    @property
    def storeys(self) -> list[Storey]:
        return self.model.storeys

    def scene(self, index: int, options: BuildOptions) -> Scene:
        """The scene of storey number ``index`` (its walls must have been read)."""
        from mapkit.importers.ifc.storey import standing_walls, storey_scene

        storey = self.storeys[index]
        standing = standing_walls(storey, self.model.all_of("wall"), self.meshes)
        return storey_scene(storey, self.meshes, standing, obstacles_in(self.connections, index), options, self.info)


def load_scene(path: Path, options: BuildOptions) -> Scene:
    """The scene of the storey ``options.floor_name`` names (``--storey``),
    or of the model's only storey."""
    path = Path(path)
    model = open_model(path)
    if options.floor_name is not None:
        index = find_storey(model, options.floor_name, path)
    elif len(model.storeys) == 1:
        index = 0
    else:
        names = ", ".join(f"'{s.name}'" for s in model.storeys)
        raise MapkitError(f"{path.name} has {len(model.storeys)} storeys ({names}): build them all with "
                          "'-o DIR' (a map per storey and building.json), or one with --storey NAME")
    building = read_building(model, path, options, [index])
    return building.scene(index, options)


def load_building(path: Path, options: BuildOptions) -> IfcBuilding:
    """Every storey of the model at ``path``, read once."""
    path = Path(path)
    model = open_model(path)
    return read_building(model, path, options, range(len(model.storeys)))


def read_building(model: Model, path: Path, options: BuildOptions, wanted) -> IfcBuilding:
    """The bodies of the elements of storeys ``wanted`` (indices), of every
    wall (a wall may stand in a storey other than the one holding it; the
    top storey's height is its walls'), the connections; storey heights set."""
    storeys = model.storeys
    top = len(storeys) - 1
    wanted = sorted(set(wanted))
    elements = [e for k in wanted for role in _SCENE_ROLES if role != "wall" for e in storeys[k].of(role)]
    elements += model.all_of("wall")
    connection_elements = model.all_of("connection")
    meshes = element_meshes(model.file, elements + connection_elements, threads=options.jobs)
    for k, s in enumerate(storeys[:-1]):
        s.height = storeys[k + 1].elevation - s.elevation
    tops = [meshes[e.id()].z_range[1] for e in storeys[top].of("wall") if e.id() in meshes]
    storeys[top].height = max(tops) - storeys[top].elevation if tops else 0.0
    connections = vertical_connections(connection_elements, meshes, storeys)
    info = {"source": path.name, "format": "ifc", "schema": model.schema, "warnings": []}
    return IfcBuilding(model, meshes, connections, info)


def find_storey(model: Model, name: str, path: Path) -> int:
    """Index of the storey called ``name`` (case and surrounding spaces
    aside); MapkitError listing the storeys if none is."""
    wanted = name.strip().casefold()
    for k, s in enumerate(model.storeys):
        if s.name.casefold() == wanted:
            return k
    names = ", ".join(f"'{s.name}'" for s in model.storeys)
    raise MapkitError(f"{path.name}: no storey named '{name}'; its storeys are {names}")
