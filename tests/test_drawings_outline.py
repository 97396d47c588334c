"""Plans without a closed outline: the building is closed from its walls
(no convex hull), and a plan whose outer walls stay open is refused.

The drawings are small DXF files written here with ezdxf, single wall
lines on layer ``WALLS`` as many real plans draw them, and read through
the whole importer (``load_scene``)."""

from __future__ import annotations

import ezdxf
import pytest
from shapely.geometry import Point, Polygon, box

from mapkit.errors import NoFreeSpaceError
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.tolerances import OUTLINE_MAX_GAP, THIN_WALL

#: The L: a 12 x 5 m wing along x and a 5 x 7 m wing up from its right end,
#: metres. The notch of the L ([0, 7] x [5, 12]) is outside.
L_SHAPE = [(0, 0), (12, 0), (12, 12), (7, 12), (7, 5), (0, 5)]


def write_plan(path, walls, doors=()):
    """A DXF in metres: wall lines on ``WALLS``, door swings (leaf + arc) on ``DOORS``."""
    doc = ezdxf.new(setup=False)
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    doc.layers.add("WALLS")
    doc.layers.add("DOORS")
    for a, b in walls:
        msp.add_line(a, b, dxfattribs={"layer": "WALLS"})
    for hinge, width in doors:  # hinged at (x, y) on a wall along x, opening up
        x, y = hinge
        msp.add_line((x, y), (x, y + width), dxfattribs={"layer": "DOORS"})
        msp.add_arc((x, y), width, 0, 90, dxfattribs={"layer": "DOORS"})
    doc.saveas(path)
    return path


def l_plan_walls(entrance: tuple[float, float], partition: bool = True):
    """The L's outer walls as lines, the bottom wall broken for the entrance
    ``(x0, x1)`` next to the left corner (no wall end faces its left jamb:
    the left wall runs on past it), and one partition splitting the long
    wing into two rooms, its doorway beside the outer wall (no wall end
    faces the partition's across it either): nothing is enclosed."""
    x0, x1 = entrance
    pts = L_SHAPE + [L_SHAPE[0]]
    walls = [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)]
    walls[0] = ((x1, 0), (12, 0))  # the bottom wall starts after the entrance
    if x0 > 0:
        walls.append(((0, 0), (x0, 0)))
    if partition:
        walls.append(((5, 0), (5, 4)))  # 1 m doorway at its top end (y 4..5)
    return walls


def test_l_shaped_plan_with_an_entrance_gap_is_closed_along_its_walls(tmp_path):
    # The entrance: 1.5 m beside the left corner (0, 0): the left wall's end
    # faces nothing across it, so only the closing of the outline bridges it.
    plan = write_plan(tmp_path / "l.dxf", l_plan_walls((0.0, 1.5)))
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    assert scene.info["interior"] == "closed from the walls"
    assert any("closed from its outer walls" in w for w in scene.info["warnings"])
    assert not any("convex hull" in w for w in scene.info["warnings"])
    building = Polygon(L_SHAPE)
    free = scene.free_space
    # Inside the building only: nothing in the L's notch, nothing beyond the entrance.
    assert free.difference(building).area < 1e-6
    assert not free.intersects(Point(3.5, 8.5).buffer(2.0))
    # All of the inside (less the robot radius and the thin walls): both
    # rooms and the wing, connected through the partition's doorway.
    assert len(free.geoms) == 1
    keep = THIN_WALL / 2 + 0.2  # half a thickened wall line and the robot radius
    partition = box(5 - keep, 0, 5 + keep, 4 + keep)
    expected = building.buffer(-keep, join_style="mitre").difference(partition).area
    assert free.area == pytest.approx(expected, rel=0.01)


def test_plan_whose_outer_wall_has_a_gap_too_wide_is_refused(tmp_path):
    # One room, the L, its entrance 5 m wide: no wall surrounds anything.
    wide = OUTLINE_MAX_GAP + 2.0
    plan = write_plan(tmp_path / "open.dxf", l_plan_walls((0.0, wide), partition=False))
    with pytest.raises(NoFreeSpaceError, match=r"enclose no building.* --floor") as exc:
        load_scene(plan, BuildOptions(robot_radius=0.2))
    message = str(exc.value)
    assert "\n" not in message
    assert f"{OUTLINE_MAX_GAP:g} m" in message
    # The preview still sees what was understood: the walls, no free space.
    assert exc.value.scene is not None and exc.value.scene.free_space.is_empty
    assert not exc.value.scene.walls.is_empty


def test_refusal_is_a_one_line_cli_error(tmp_path, capsys):
    from mapkit.cli import main

    plan = write_plan(tmp_path / "open.dxf", l_plan_walls((0.0, OUTLINE_MAX_GAP + 2.0), partition=False))
    code = main(["build", str(plan), "-o", str(tmp_path / "open.lmap")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and "--floor" in err and "Traceback" not in err
    assert not (tmp_path / "open.lmap").exists()


# ---- a facility-management plan: walls drawn, room fills, a floor outline beside it ----------


def write_fm_plan(path, *, floor_outside: bool = False, pocket: bool = False, chase: bool = False):
    """Two 4 x 4 m rooms in double-line walls 0.2 m thick (``A-WALL``),
    each also a room fill on ``Rooms-Color`` stopping at the wall faces.
    The shared wall (x 4.1..4.3) stops 1 m short of the top wall: a doorway
    (y 3.1..4.1) with no door swing. ``floor_outside``: an ``A-FLOR``
    outline of 6 x 4 m beside the building (x -7..-1), as the university
    floor's. ``pocket``: the doorway's door slides into the shared wall,
    its leaf a line inside it on ``A-DOOR``. ``chase``: a walled space
    (x 6.3..8.2, y 0.2..1.6) in the right room's corner, no fill, no door."""
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    wall, room = {"layer": "A-WALL"}, {"layer": "Rooms-Color"}
    msp.add_lwpolyline([(0, 0), (8.4, 0), (8.4, 4.3), (0, 4.3)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(0.2, 0.2), (8.2, 0.2), (8.2, 4.1), (0.2, 4.1)], close=True, dxfattribs=wall)
    msp.add_lwpolyline([(4.1, 0.2), (4.1, 3.1), (4.3, 3.1), (4.3, 0.2)], dxfattribs=wall)
    msp.add_lwpolyline([(0.2, 0.2), (4.1, 0.2), (4.1, 4.1), (0.2, 4.1)], close=True, dxfattribs=room)
    if chase:
        msp.add_lwpolyline([(6.1, 0.2), (6.1, 1.8), (8.2, 1.8)], dxfattribs=wall)
        msp.add_lwpolyline([(6.3, 0.2), (6.3, 1.6), (8.2, 1.6)], dxfattribs=wall)
        msp.add_lwpolyline([(4.3, 0.2), (6.1, 0.2), (6.1, 1.8), (8.2, 1.8), (8.2, 4.1), (4.3, 4.1)], close=True,
                           dxfattribs=room)
    else:
        msp.add_lwpolyline([(4.3, 0.2), (8.2, 0.2), (8.2, 4.1), (4.3, 4.1)], close=True, dxfattribs=room)
    if floor_outside:
        msp.add_lwpolyline([(-7, 0), (-1, 0), (-1, 4), (-7, 4)], close=True, dxfattribs={"layer": "A-FLOR"})
    if pocket:
        msp.add_line((4.2, 2.15), (4.2, 3.05), dxfattribs={"layer": "A-DOOR"})
    doc.saveas(path)
    return path


def test_a_floor_outline_beyond_the_walls_adds_no_free_space(tmp_path):
    """The university floor's A-FLOR held an outline beside the building:
    its 97 m2 were free space outside the walls."""
    plan = write_fm_plan(tmp_path / "fm.dxf", floor_outside=True)
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    building = box(0, 0, 8.4, 4.3)
    assert scene.free_space.difference(building).area < 1e-6
    assert scene.free_space.area < 2 * 3.5 * 3.5 + 1.0  # the two rooms and their doorway


def test_room_fills_beside_drawn_walls_leave_a_doorway_open(tmp_path):
    """The strips between room fills were walls even where the walls as
    drawn leave a doorway open (a vestibule, an alcove, a pocket door's
    gap): the university floor's rooms were sealed in 6 parts."""
    plan = write_fm_plan(tmp_path / "fm.dxf")
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    assert len(scene.free_space.geoms) == 1
    assert scene.free_space.area == pytest.approx(2 * 3.5 * 3.5 + 0.6 * 0.2, rel=0.02)


def test_a_pocket_door_leaf_inside_a_wall_is_the_door_of_the_gap_beside_it(tmp_path):
    """A pocket door's leaf lies inside the wall, running to its end: it was
    'not in a wall gap' and ignored (or cut through the wall where it lies)."""
    plan = write_fm_plan(tmp_path / "fm.dxf", pocket=True)
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    (door,) = [o for o in scene.openings if o.kind == "door"]
    x0, y0, x1, y1 = door.footprint.bounds
    assert (x0, x1) == pytest.approx((4.1, 4.3), abs=1e-6)
    assert (y0, y1) == pytest.approx((3.1, 4.0), abs=1e-6)  # the leaf's 0.9 m of the 1 m gap
    assert any("pocket door" in w for w in scene.info["warnings"])
    assert scene.walls.intersection(box(4.1, 0.2, 4.3, 3.1)).area == pytest.approx(0.2 * 2.9, rel=1e-3)  # not cut
    assert len(scene.free_space.geoms) == 1


def test_a_walled_space_with_no_room_fill_and_no_door_is_a_shaft(tmp_path):
    """Behind the university floor's restrooms a pipe chase (walls all
    round, no door, none of the 26 room fills) was a second part of free
    space: the rooms looked unconnected."""
    plan = write_fm_plan(tmp_path / "fm.dxf", chase=True)
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    assert len(scene.free_space.geoms) == 1
    assert not scene.free_space.intersects(box(6.3, 0.2, 8.2, 1.6))
    assert any("no room fill and no door" in w for w in scene.info["warnings"])


# ---- a courtyard the building surrounds, open to the outside wider than a door -----------------


def write_courtyard_plan(path, floor):
    """A U-shaped building, 30 x 20 m (single wall lines on ``WALLS``): a
    south and a north wing 6 m deep and a west wing between them, around a
    24 x 8 m courtyard (x 6..30, y 6..14) that opens east across its whole
    8 m (wider than ``OUTLINE_MAX_GAP``: no wall end faces another there).
    Each wing is a room entered from the courtyard through a 1 m doorway.
    ``floor``: the outlines drawn on layer ``Floor`` (x0, y0, x1, y1)."""
    walls = [((0, 0), (30, 0)), ((30, 0), (30, 6)), ((0, 0), (0, 20)), ((0, 20), (30, 20)), ((30, 20), (30, 14)),
             ((30, 6), (11, 6)), ((10, 6), (6, 6)), ((6, 6), (6, 9)), ((6, 10), (6, 14)), ((6, 14), (10, 14)),
             ((11, 14), (30, 14)), ((0, 6), (6, 6)), ((0, 14), (6, 14))]
    write_plan(path, walls)
    doc = ezdxf.readfile(path)
    for x0, y0, x1, y1 in floor:
        doc.modelspace().add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True,
                                         dxfattribs={"layer": "Floor"})
    doc.saveas(path)
    return path


def test_a_courtyard_the_floor_layer_covers_and_the_building_surrounds_is_inside(tmp_path):
    """The CityScope IDB level 0: its atrium, which the floor layer covers,
    opens to the outside through two vehicle ramps 8 m wide; clipped to the
    outer walls closed across 3 m gaps it was no free space, and its wings
    were separate parts (refused: the free space a quarter of the building)."""
    plan = write_courtyard_plan(tmp_path / "court.dxf", floor=[(0, 0, 30, 20)])
    scene = load_scene(plan, BuildOptions(robot_radius=0.2))
    assert scene.info["interior"] == "floor layer"
    assert scene.free_space.contains(Point(18, 10))  # the courtyard
    assert len(scene.free_space.geoms) == 1  # the wings joined through it
    assert scene.free_space.difference(box(0, 0, 30, 20)).area < 1e-6


def test_a_terrace_the_floor_layer_lays_along_one_side_of_the_building_is_outside(tmp_path):
    """A floor outline of a terrace beside the south wing's east wall meets
    the building along one side of four: no free space, as a floor outline
    drawn apart from it."""
    floor = [(0, 0, 30, 6), (0, 14, 30, 20), (0, 6, 6, 14), (30, 0, 36, 6)]
    scene = load_scene(write_courtyard_plan(tmp_path / "terrace.dxf", floor),
                       BuildOptions(robot_radius=0.2, accept_inconsistent=True))
    assert scene.free_space.difference(box(0, 0, 30, 20)).area < 1e-6
    assert scene.free_space.area > 3 * 0.5 * 48  # the wings are free space


def test_layers_lists_a_sheet_whose_wall_layer_by_name_is_empty(tmp_path, capsys):
    """The house sheet's only layer named like walls ('2ND-WALL') is empty:
    'mapkit layers', the command its refusal sends the user to, failed
    with that same refusal instead of listing the layers."""
    from mapkit.cli import main

    doc = ezdxf.new("R2013")
    doc.layers.add("2ND-WALL")
    for a, b in (((0, 0), (8, 0)), ((8, 0), (8, 6)), ((8, 6), (0, 6)), ((0, 6), (0, 0))):
        doc.modelspace().add_line(a, b, dxfattribs={"layer": "DETAILS"})
        doc.modelspace().add_line(a, b, dxfattribs={"layer": "SECTION-A"})
    doc.saveas(tmp_path / "sheet.dxf")
    code = main(["layers", str(tmp_path / "sheet.dxf")])
    out = capsys.readouterr().out
    assert code == 0
    assert "DETAILS" in out and "2ND-WALL" in out and "note: no recognisable walls" in out
