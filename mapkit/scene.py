"""The scene: what an importer understood of a building, in plain data.

Every importer (DXF plans, meshes) produces a :class:`Scene`; the edge and
visibility stages take it from there and know nothing of file formats.
All coordinates in metres, world frame (x, y horizontal, z up).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from shapely.geometry import MultiPolygon, Polygon


@dataclass(frozen=True)
class Opening:
    """A door or window: a gap in a wall, seen from above.

    ``footprint`` is the 2D polygon of the gap (between the two jambs, across
    the wall's thickness); the opening spans heights ``sill`` to ``head``
    (a door has ``sill == 0``).
    """

    footprint: Polygon
    kind: str  # "door" or "window"
    sill: float
    head: float


@dataclass(frozen=True)
class HeightZone:
    """A part of the floor under one ceiling height (a room).

    ``area`` is the room seen from above; ``height`` its ceiling, metres.
    The wall faces nearest a zone rise to its height (:mod:`mapkit.edges`).
    """

    area: Polygon
    height: float


@dataclass
class Scene:
    """A building as the map builder sees it.

    - ``walls``: wall solids seen from above (full height, opaque); they
      occlude sight lines and bound the free space.
    - ``openings``: door and window gaps in those walls.
    - ``obstacles``: things the robot cannot stand in that do not block the
      view (glass, window footprints); removed from the free space only.
    - ``free_space``: where the camera centre may be: the interior minus
      walls and obstacles, shrunk by the robot radius.
    - ``wall_height``: ceiling height (walls are extruded from 0 to it); with
      ``height_zones``, the tallest of them.
    - ``height_zones``: rooms with their own ceiling heights (ZInD
      annotations); each wall face rises to the height of the zone nearest
      it. Empty: every wall is ``wall_height`` high.
    - ``camera_height``: the height above the floor of the camera the source
      was recorded with (ZInD's panoramas), or ``None``; the map's camera
      takes it unless the user chose a camera.
    - ``segments`` / ``kinds``: 3D model edges when the importer already has
      them (meshes); ``None`` lets the edge stage derive them from the walls.
    - ``ignored``: geometry drawn but not used (for previews), per layer.
    - ``info``: what the importer decided (units, layers used, warnings).
    """

    walls: MultiPolygon
    openings: list[Opening]
    free_space: MultiPolygon
    wall_height: float
    obstacles: MultiPolygon = field(default_factory=MultiPolygon)
    height_zones: list[HeightZone] = field(default_factory=list)
    camera_height: float | None = None
    segments: np.ndarray | None = None
    kinds: np.ndarray | None = None
    ignored: dict[str, Any] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)
