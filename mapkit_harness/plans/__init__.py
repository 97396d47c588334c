"""The synthetic plans of the harness, one import surface for every plan
with known geometry that tests, simulators and benchmarks use (metres
unless said otherwise, z up):

- :mod:`.buildings`: buildings made in code, as shapely scenes
  (:class:`SyntheticScene`: walls, free space, segments) for the region
  builder and the visibility tests, and as line maps (``LineMap``, lists by
  brute-force visibility or by room) for the matcher and the inspector;
- :mod:`.drawings`: DXF plans drawn as architects draw them (an office of
  rooms, an open-plan office, zones, nested outlines), each with the facts
  a test asserts against (:class:`PlanFacts`);
- :mod:`.flat_dxf`: the bundled example plan ``maps/flat.dxf`` (millimetres),
  written byte for byte reproducibly by :func:`write_flat_dxf`;
- :mod:`.meshes`: a grid of rooms as a mesh of separate wall boxes, with the
  count of edges it must give;
- :mod:`.grid_layout`: the one layout of a grid of rooms joined by doorways
  (:class:`RoomGridLayout`: wall pieces, doorways and their doors, the
  outline and the inside, the doorways' places along their walls) that
  :func:`office_grid`, :func:`grid_flat` and :func:`room_grid` render as a
  DXF, a LineMap and a mesh.

All of them are deterministic: a seed, where there is one, is an argument.
"""

from mapkit_harness.plans.buildings import (
    DEMO_CAMERA,
    ROBOT_RADIUS,
    WALL_HEIGHT,
    SyntheticScene,
    apartment,
    cached_flat_map,
    flat_geometry,
    flat_segments,
    grid_flat,
    l_room,
    lintels,
    make_box_map,
    make_flat_map,
    make_small_flat,
    open_hall,
    outline_segments,
    room_or_near_lists,
    scene_from_walls,
    single_room,
    two_rooms,
)
from mapkit_harness.plans.drawings import PlanFacts, nested_room, office_grid, open_office, zone_plan
from mapkit_harness.plans.flat_dxf import write as write_flat_dxf
from mapkit_harness.plans.grid_layout import RoomGridLayout
from mapkit_harness.plans.meshes import expected_grid_edges, room_grid

__all__ = [
    "DEMO_CAMERA", "ROBOT_RADIUS", "WALL_HEIGHT", "PlanFacts", "RoomGridLayout", "SyntheticScene", "apartment",
    "cached_flat_map", "expected_grid_edges", "flat_geometry", "flat_segments", "grid_flat", "l_room", "lintels",
    "make_box_map", "make_flat_map", "make_small_flat", "nested_room", "office_grid", "open_hall", "open_office",
    "outline_segments", "room_grid", "room_or_near_lists", "scene_from_walls", "single_room", "two_rooms",
    "write_flat_dxf", "zone_plan",
]
