"""Plans drawn as architects draw them (issue 27), written here with ezdxf by
mapkit_harness/plans/drawings.py: each builds with defaults, its doors are found,
and its free space is the known answer, inside the building only.

Classes: an open-plan office with AIA numbered layer names, facade pieces
and piers, round columns, door blocks at the hinge (rotated, mirrored, a
double door), virtual partitions, furniture and text, and no closed
outline; an office of rooms of wall-piece outlines; a plan drawn as room
polygons with a facade contour and no wall layer; a room drawn as two
nested outlines; doors as nested, scaled blocks and at a wall's end.
The big versions of these plans are tools/bench_build.py's."""

from __future__ import annotations

import json

import pytest
import shapely
from shapely.geometry import LineString, box

from cli_helpers import run
from mapkit.importers import load_scene
from mapkit.importers.dxf.layer_roles import explain_role
from mapkit.options import BuildOptions
from mapkit.pipeline import build_map
from mapkit_harness.plans.drawings import (
    DOORS,
    FURNITURE,
    PARTITIONS,
    STRUCTURE,
    VIRTUAL,
    add_door,
    add_rect,
    define_door_block,
    nested_room,
    new_document,
    office_grid,
    open_office,
    zone_plan,
)

ROBOT = 0.2


def _expected_free(facts, radius: float) -> float:
    """Area of the known free space: the inside with its door gaps, less the
    walls, shrunk by the robot radius."""
    inside = shapely.union_all([facts.interior, *facts.extra.get("door_gaps", [])])
    free = inside.difference(facts.walls)
    return free.buffer(-radius).area if radius > 0 else free.area


@pytest.fixture(scope="module")
def office(tmp_path_factory):
    path = tmp_path_factory.mktemp("open") / "open_office.dxf"
    facts = open_office(path)
    return path, facts, load_scene(path, BuildOptions(robot_radius=0.0))


def test_aia_numbered_layer_names_get_their_roles_and_say_why():
    for name, role in [(STRUCTURE, "walls"), (PARTITIONS, "walls"), (DOORS, "doors"), (VIRTUAL, "ignore"),
                       (FURNITURE, "ignore"), ("A-WALL", "walls"), ("ABY_Zone_ZIND", "floor"),
                       ("ABY_Contour_Facade", "walls"), ("Pièces", "floor"), ("Raum", "floor"), ("Space 3", "floor")]:
        got, why = explain_role(name)
        assert got == role, (name, got, why)
        assert why.startswith("'")
    assert "blocks nothing" in explain_role(VIRTUAL)[1]


def test_layers_command_says_what_it_uses_and_why(office, capsys):
    path, _, _ = office
    code, out, _ = run(capsys, "layers", path, "--json")
    assert code == 0
    rows = {r["name"]: r for r in json.loads(out)["layers"]}
    assert rows[VIRTUAL]["role"] == "ignored" and "virtual" in rows[VIRTUAL]["why"]
    assert rows[STRUCTURE]["role"] == "walls" and "structure" in rows[STRUCTURE]["why"]
    assert rows[DOORS]["role"] == "doors"


def test_open_plan_office_doors_found_and_free_space_inside_the_facade(office):
    path, facts, scene = office
    assert not [w for w in scene.info["warnings"] if "door" in w or "convex hull" in w], scene.info["warnings"]
    assert scene.info["counts"]["doors"] == facts.doors == 7  # the double entrance door is one
    assert scene.info["interior"] == "enclosed"
    # Window gaps (no glass drawn) are shut, the outside is not free space.
    building = box(0.0, 0.0, 30.0, 20.0)
    assert scene.free_space.difference(building).area < 1e-6
    for gap in facts.extra["window_gaps"]:
        assert scene.free_space.intersection(gap).area < 1e-6
    assert scene.free_space.area == pytest.approx(_expected_free(facts, 0.0), rel=2e-3)


def test_open_plan_office_virtual_partitions_and_furniture_block_nothing(office):
    _, facts, scene = office
    # The virtual partition at x = 6 m between columns, and every desk.
    assert scene.walls.intersection(LineString([(6.0, 1.0), (6.0, 4.0)])).length == 0
    for desk in facts.extra["desks_and_lines"]:
        assert not scene.walls.intersects(desk)
        assert scene.free_space.covers(desk.buffer(-0.01))


def test_office_of_rooms_builds_with_defaults(tmp_path):
    path = tmp_path / "office.dxf"
    facts = office_grid(path, n=2, room=4.0)
    m, report = build_map(path, BuildOptions())
    scene = m.meta["scene"]
    assert scene["counts"]["doors"] == facts.doors == 4
    assert not [w for w in report.warnings if "door" in w], report.warnings
    assert scene["areas_m2"]["free_space"] == pytest.approx(_expected_free(facts, ROBOT), rel=5e-3)
    assert report.counts["regions"] > 4 and report.counts["segments"] > 50


def test_room_polygons_with_a_facade_contour_build_without_a_wall_layer(tmp_path):
    path = tmp_path / "zones.dxf"
    facts = zone_plan(path)
    m, report = build_map(path, BuildOptions())
    scene = m.meta["scene"]
    # The rooms are the free space; the strips between them are walls.
    assert scene["areas_m2"]["free_space"] == pytest.approx(facts.interior.buffer(-ROBOT).area, rel=1e-3)
    assert report.counts["regions"] >= 6


@pytest.mark.slow
def test_room_drawn_as_two_nested_outlines_builds_and_previews(tmp_path, capsys):
    path = tmp_path / "nested.dxf"
    facts = nested_room(path)
    m, _ = build_map(path, BuildOptions())
    # The table (A-FURN) and the text are not walls; the inner outline is the room.
    assert m.meta["scene"]["areas_m2"]["free_space"] == pytest.approx(facts.interior.buffer(-ROBOT, join_style="mitre").area, rel=1e-3)
    code, out, err = run(capsys, "preview", path, "-o", tmp_path / "nested.png")
    assert code == 0 and "free space 16.6" in out
    assert (tmp_path / "nested.png").stat().st_size > 1000


def test_preview_draws_a_plan_that_leaves_no_free_space(tmp_path, capsys):
    path = tmp_path / "tiny.dxf"
    nested_room(path, width=1.2, depth=1.2, thickness=0.45, furniture=False)  # 0.3 m inside: no room for the robot
    code, out, err = run(capsys, "build", path, "-o", tmp_path / "tiny.lmap")
    assert code == 2 and "no free space" in err and "mapkit preview" in err
    code, out, err = run(capsys, "preview", path, "-o", tmp_path / "tiny.png")
    assert code == 0 and (tmp_path / "tiny.png").exists() and "no free space" in err


def _two_rooms(msp, t=0.2):
    """Two 4 x 4 m rooms side by side, wall pieces as outlines, a 0.9 m gap
    in the wall between them from y = 1.5 to 2.4 m (x = 4 .. 4 + t)."""
    x = 4.0
    for x0, y0, x1, y1 in [(0, 0, 8 + t, t), (0, 4, 8 + t, 4 + t), (0, 0, t, 4 + t), (8, 0, 8 + t, 4 + t),
                           (x, 0, x + t, 1.5), (x, 2.4, x + t, 4 + t)]:
        add_rect(msp, x0, y0, x1, y1, "A-WALL")


@pytest.mark.parametrize("rotation_case", ["plain", "mirrored", "nested-scaled"])
def test_door_blocks_at_the_hinge_are_found(tmp_path, rotation_case):
    doc = new_document()
    msp = doc.modelspace()
    _two_rooms(msp)
    if rotation_case == "plain":  # hinge at the bottom jamb, swinging into the left room
        add_door(msp, define_door_block(doc, 0.9), (4.0, 1.5), (4.0, 2.4), 1, "A-DOOR")
    elif rotation_case == "mirrored":  # hinge at the top jamb, on the right face, swinging right
        add_door(msp, define_door_block(doc, 0.9), (4.2, 2.4), (4.2, 1.5), -1, "A-DOOR")
    else:  # a 1 m door block scaled to 0.9 m inside a door-set block, turned and mirrored
        inner = define_door_block(doc, 1.0)
        outer = doc.blocks.new("DOORSET")
        outer.add_blockref(inner, (0, 0), dxfattribs={"xscale": -0.9, "yscale": 0.9, "rotation": 180.0})
        msp.add_blockref("DOORSET", (4.2, 1.5), dxfattribs={"layer": "A-DOOR", "rotation": 90.0})
    path = tmp_path / "door.dxf"
    doc.saveas(path)
    scene = load_scene(path, BuildOptions())
    doors = [o for o in scene.openings if o.kind == "door"]
    assert len(doors) == 1, scene.info["warnings"]
    gap = doors[0].footprint
    assert gap.area == pytest.approx(0.9 * 0.2, rel=0.05)
    assert gap.centroid.distance(shapely.Point(4.1, 1.95)) < 0.05
    # Closed for the free space (one region of both rooms joined through it), open for sight.
    assert len(shapely.get_parts(scene.free_space)) == 1
    assert not scene.walls.intersects(gap.buffer(-0.01))
    # Two rooms drawn alone: their whole floor is free, the door covers no room.
    rooms = shapely.union_all([box(0.2, 0.2, 4.0, 4.0), box(4.2, 0.2, 8.0, 4.0), box(4.0, 1.5, 4.2, 2.4)])
    assert scene.free_space.area == pytest.approx(rooms.buffer(-ROBOT, join_style="mitre").area, rel=0.01)


def test_door_at_the_end_of_a_wall_is_found(tmp_path):
    """A partition stops 0.9 m short of the facade; the door hinged at its end."""
    doc = new_document()
    msp = doc.modelspace()
    for x0, y0, x1, y1 in [(0, 0, 8.2, 0.2), (0, 4, 8.2, 4.2), (0, 0, 0.2, 4.2), (8, 0, 8.2, 4.2)]:
        add_rect(msp, x0, y0, x1, y1, "A-WALL")
    add_rect(msp, 4.0, 1.1, 4.1, 4.0, "A-WALL")  # partition from y = 1.1 up to the north wall
    # Hinge at the partition's free end, closing onto nothing but the drawing: the leaf reaches y = 0.2.
    add_door(msp, define_door_block(doc, 0.9), (4.0, 1.1), (4.0, 0.2), 1, "A-DOOR")
    path = tmp_path / "end.dxf"
    doc.saveas(path)
    scene = load_scene(path, BuildOptions())
    doors = [o for o in scene.openings if o.kind == "door"]
    assert len(doors) == 1, scene.info["warnings"]
    assert doors[0].footprint.bounds == pytest.approx((4.0, 0.2, 4.1, 1.1), abs=0.02)
