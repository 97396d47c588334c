"""How people mark doors in real drawings (the Hal9k hackerspace's plan and
the UK house of the corpus, docs/benchmarks/drawings.md), each reproduced in
a small drawing these tests write: jamb ticks across single-line walls,
loosely drawn swings, the two leaves of a double door, ..."""

from __future__ import annotations

import ezdxf
import pytest

from mapkit.importers import load_scene
from mapkit.importers.dxf.door_swings import find_door_swings
from mapkit.shapes import polygon_parts

WALL = {"layer": "0"}


def _single_line_plan(path, draw):
    """A plan drawn as the Hal9k hackerspace's is: single-line walls, door
    swings and jamb ticks all on layer 0, in cm; ``draw(msp)`` adds the
    walls and doors. A furniture layer beside it, as there."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 5  # cm
    msp = doc.modelspace()
    draw(msp)
    msp.add_lwpolyline([(600, 50), (650, 50), (650, 100), (600, 100)], close=True, dxfattribs={"layer": "Furniture"})
    doc.saveas(path)
    return path


def _tick(msp, x, y, vertical_wall: bool):
    """A 10 cm jamb tick across a wall line at (x, y)."""
    if vertical_wall:
        msp.add_line((x - 5, y), (x + 5, y), dxfattribs=WALL)
    else:
        msp.add_line((x, y - 5), (x, y + 5), dxfattribs=WALL)


def _parts(scene) -> int:
    return len(polygon_parts(scene.free_space))


def _doors(scene) -> list:
    return [o for o in scene.openings if o.kind == "door"]


def test_two_jamb_ticks_without_a_door_mark_a_doorway(tmp_path):
    """Two rooms whose shared single-line wall is unbroken, with two jamb
    ticks across it 0.8 m apart and no swing (a doorway; Hal9k's small
    rooms): the ticks were read as walls and the rooms stayed sealed. They
    mark a doorway, cut through the wall."""
    def draw(msp):
        msp.add_lwpolyline([(0, 0), (800, 0), (800, 400), (0, 400)], close=True, dxfattribs=WALL)
        msp.add_line((400, 0), (400, 400), dxfattribs=WALL)
        _tick(msp, 400, 150, vertical_wall=True)
        _tick(msp, 400, 230, vertical_wall=True)

    scene = load_scene(_single_line_plan(tmp_path / "doorway.dxf", draw))
    assert _parts(scene) == 1
    (door,) = _doors(scene)
    x0, y0, x1, y1 = door.footprint.bounds
    assert x0 < 4.0 < x1 and y0 == pytest.approx(1.5) and y1 == pytest.approx(2.3)
    assert any("1 doorway(s) marked by jamb ticks" in w for w in scene.info["warnings"])


def test_jamb_ticks_beside_doors_are_no_thick_wall(tmp_path):
    """Two doors side by side on one single-line wall, hinged on three jamb
    ticks (Hal9k's two doors at y 3.96 m): two ticks 0.7 m apart looked like
    the two faces of a 0.7 m thick wall, their ends were capped, and the
    wall line between became a face of it, only half cut by the door, which
    sealed the room behind. Both doors join their rooms."""
    def draw(msp):
        msp.add_lwpolyline([(0, 0), (800, 0), (800, 600), (0, 600)], close=True, dxfattribs=WALL)
        msp.add_line((0, 300), (800, 300), dxfattribs=WALL)
        msp.add_line((200, 300), (200, 600), dxfattribs=WALL)  # between the two doors, as there
        for x in (100, 173, 240):
            _tick(msp, x, 300, vertical_wall=False)
        msp.add_line((173, 300), (103, 328), dxfattribs=WALL)  # left door's leaf, hinged at 173
        msp.add_arc((173, 300), 73, 152, 182, dxfattribs=WALL)
        msp.add_line((240, 300), (313, 324), dxfattribs=WALL)  # right door's leaf, hinged at 240
        msp.add_arc((240, 300), 77, 0, 20, dxfattribs=WALL)

    scene = load_scene(_single_line_plan(tmp_path / "side_by_side.dxf", draw))
    assert len(_doors(scene)) == 2
    assert _parts(scene) == 1
    for door in _doors(scene):  # cut through the wall's whole thickness (0.1 m)
        x0, y0, x1, y1 = door.footprint.bounds
        assert y1 - y0 == pytest.approx(0.1)


def test_loose_door_swings_are_found():
    """Hal9k's two swings that stayed walls: an arc overshooting its leaf's
    tip by 12 cm (more than the tip snap), and an arc through three points
    whose centre is 0.39 m off the hinge (the leaf 2.1 times its radius)."""
    doc = ezdxf.new("R2013")
    msp = doc.modelspace()
    msp.add_line((18.13, 3.58), (17.887, 2.856))  # radial leaf; the arc runs on past its tip
    msp.add_arc((18.13, 3.58), 0.73, 242.8, 268.9)
    msp.add_line((20.128, 2.481), (20.845, 2.258))  # leaf from the hinge; the arc from its tip to the latch
    msp.add_arc((20.518, 2.491), 0.356, 315.7, 359.1)
    msp.add_line((17.0, 2.48), (21.0, 2.48))  # the wall, which is no leaf
    pairs = find_door_swings(list(msp), 1.0)
    assert sorted(round(leaf.dxf.start.x, 3) for _, leaf in pairs) == [18.13, 20.128]


def test_loose_swing_joins_its_rooms(tmp_path):
    """The three-point swing on a wall shared by two rooms: its opening is cut."""
    def draw(msp):
        msp.add_lwpolyline([(0, 0), (800, 0), (800, 400), (0, 400)], close=True, dxfattribs=WALL)
        msp.add_line((0, 200), (800, 200), dxfattribs=WALL)
        for x in (300, 374):
            _tick(msp, x, 200, vertical_wall=False)
        msp.add_line((300, 200), (371.7, 177.7), dxfattribs=WALL)
        msp.add_arc((339, 201), 35.6, 315.7, 359.1, dxfattribs=WALL)

    scene = load_scene(_single_line_plan(tmp_path / "loose.dxf", draw))
    assert len(_doors(scene)) == 1 and _parts(scene) == 1


def test_a_double_door_over_an_unbroken_facade_is_one_opening(tmp_path):
    """A double door in a single-line facade, its two leaves opening out
    (Hal9k's entrance): each leaf was cut on its own, two doors counted for
    one. The two cuts meet end to end in the wall: one opening 2 m wide."""
    def draw(msp):
        msp.add_lwpolyline([(0, 0), (800, 0), (800, 400), (0, 400)], close=True, dxfattribs=WALL)
        for x in (100, 200, 300):
            _tick(msp, x, 400, vertical_wall=False)
        msp.add_line((100, 400), (197, 427), dxfattribs=WALL)
        msp.add_arc((100, 400), 100, 0, 16, dxfattribs=WALL)
        msp.add_line((300, 400), (203, 427), dxfattribs=WALL)
        msp.add_arc((300, 400), 100, 164, 180, dxfattribs=WALL)

    scene = load_scene(_single_line_plan(tmp_path / "facade.dxf", draw))
    (door,) = _doors(scene)
    x0, _, x1, _ = door.footprint.bounds
    assert x0 == pytest.approx(1.0, abs=0.01) and x1 == pytest.approx(3.0, abs=0.01)


def _room_plan(path, across: bool, outlines):
    """A 6 x 4 m room of double-line walls 0.2 m thick on 'A210 - Ext Walls'
    (mm), the architect's room outlines ``outlines`` on 'Room - ...' layers,
    and, if ``across``, a single line on the wall layer across the room at
    y = 1.5 m from the outer face of one wall through to the other's (the UK
    house's utility room: an overhead line drawn on the wall layer)."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 4  # mm
    msp = doc.modelspace()
    wall = {"layer": "A210 - Ext Walls"}
    msp.add_lwpolyline([(0, 0), (6000, 0), (6000, 4000), (0, 4000)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(200, 200), (5800, 200), (5800, 3800), (200, 3800)], close=True, dxfattribs=wall)
    if across:
        msp.add_line((0, 1500), (6000, 1500), dxfattribs=wall)
    for name, corners in outlines:
        msp.add_lwpolyline(corners, close=True, dxfattribs={"layer": f"Room - {name}"})
    doc.saveas(path)
    return path


def test_a_wall_line_across_a_room_outline_is_no_wall(tmp_path):
    """A single line on the wall layer across a room whose outline the
    architect drew as one room, sealing part of it off with no door: it was
    a wall, and the room two sealed parts. The room is one."""
    room = [("Utility", [(200, 200), (5800, 200), (5800, 3800), (200, 3800)])]
    scene = load_scene(_room_plan(tmp_path / "across.dxf", True, room))
    assert _parts(scene) == 1
    assert scene.free_space.area == pytest.approx(load_scene(_room_plan(tmp_path / "plain.dxf", False, room))
                                                  .free_space.area, rel=0.01)
    assert any("single wall line(s) across a room's outline" in w for w in scene.info["warnings"])


def test_a_wall_line_between_two_room_outlines_stays(tmp_path):
    """The same line between two rooms the architect outlined apart is their
    wall: the two rooms stay apart (no door joins them)."""
    rooms = [("Store", [(200, 200), (5800, 200), (5800, 1500), (200, 1500)]),
             ("Utility", [(200, 1500), (5800, 1500), (5800, 3800), (200, 3800)])]
    scene = load_scene(_room_plan(tmp_path / "two.dxf", True, rooms))
    assert _parts(scene) == 2


def test_a_short_wall_whose_ends_meet_other_lines_is_no_tick():
    """A short stroke across a wall line is a jamb tick only with both ends
    free: the 0.2 m side of a pier, its ends on the pier's other sides, is
    a wall (the Chinese college's plan has such piers at wall junctions)."""
    import numpy as np

    from mapkit.importers.dxf.jamb_ticks import split_jamb_ticks
    from mapkit.importers.dxf.strokes import Stroke

    def line(a, b):
        return Stroke(np.array([a, b], dtype=float))

    wall = line((0, 0), (5, 0))
    tick = line((1, -0.05), (1, 0.05))
    pier_side = line((3, -0.1), (3, 0.1))
    pier = [line((3, 0.1), (3.2, 0.1)), line((3, -0.1), (3.2, -0.1))]
    kept, ticks = split_jamb_ticks([wall, tick, pier_side, *pier])
    assert [tuple(t.point) for t in ticks] == [(1.0, 0.0)]
    assert all(s is not tick for s in kept) and any(s is pier_side for s in kept) and len(kept) == 4
