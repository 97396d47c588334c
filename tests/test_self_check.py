"""The map checks itself against its drawing (mapkit/importers/dxf/self_check.py).

Each kind of map built wrong without an error on real drawings (issue 44)
is reproduced in a small drawing written here (mapkit_harness.plans.inconsistent):
refused, one line naming what contradicts the drawing and the option that
fixes it; built right with that option; written with a warning under
--accept-inconsistent. Headers in the wrong units are read in the one unit
that makes the plan a building with doors a door's width.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from shapely.geometry import Point

from mapkit.errors import ImplausibleUnitsError, InconsistentDrawingError, MapkitError
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts
from mapkit_harness.plans.inconsistent import (doors_across_passages, doors_with_the_furniture, leaf_across_its_arc,
                                                plan_beside_elevation, room_outline_on_layer_0,
                                                room_polygons_off_an_open_corridor, rooms_beside_doorless_spaces,
                                                row_of_rooms,
                                                solid_walls_in_metres, storeys_in_a_frame, tiled_podium)


def test_a_consistent_plan_passes_without_a_word(tmp_path):
    scene = load_scene(row_of_rooms(tmp_path / "rooms.dxf", n=8))
    assert len(polygon_parts(scene.free_space)) == 1 and scene.info["counts"]["doors"] == 8
    assert not any("contradicts" in w for w in scene.info["warnings"])


def test_a_whole_floor_on_a_layer_named_for_windows(tmp_path):
    # The walls on 'A-GLAZ' (read as glass), one stray line on 'A-WALL':
    # the robot would see through every wall.
    path = row_of_rooms(tmp_path / "glaz.dxf", n=8, wall_layer="A-GLAZ", stray_wall_layer="A-WALL")
    with pytest.raises(InconsistentDrawingError, match=r"walls are 0\.0 m2 .* fix with --walls LAYER") as refused:
        load_scene(path)
    assert "\n" not in str(refused.value)
    scene = load_scene(path, BuildOptions(walls=["A-GLAZ"]))
    assert scene.info["counts"]["doors"] == 8 and len(polygon_parts(scene.free_space)) == 1


def test_a_room_outline_on_layer_0_beside_a_partition_on_the_wall_layer(tmp_path):
    # olymp's room: only the closet's partitions are on a wall layer.
    path = room_outline_on_layer_0(tmp_path / "room.dxf")
    with pytest.raises(InconsistentDrawingError, match=r"the free space is 5 m2 .* of the 3\d m2 .* --walls LAYER"):
        load_scene(path)
    scene = load_scene(path, BuildOptions(walls=["0", "Wand*"]))
    assert 30.0 < scene.free_space.area < 36.0  # 7.6 x 5.1 m less the closet's walls and the robot's margin


def test_a_plan_beside_an_elevation_and_a_framing_plan_on_the_same_layer(tmp_path):
    # The other views are built as walls: most of the drawn sheet is no free space.
    with pytest.raises(InconsistentDrawingError, match=r"the free space is 9\d m2 .*, 3\d % of the 2\d\d m2"):
        load_scene(plan_beside_elevation(tmp_path / "sheet.dxf"))


def test_door_drawings_ignored(tmp_path):
    # Eight door swings drawn off an unbroken wall: none is a door, every room sealed.
    path = row_of_rooms(tmp_path / "doors.dxf", n=8, door_offset=0.6)
    with pytest.raises(InconsistentDrawingError, match=r"0 of the 8 door drawings are used as doors.*--doors LAYER"):
        load_scene(path)


def test_rooms_whose_doors_were_missed_are_cut_off(tmp_path):
    # Six doors found, two drawn off the wall: their rooms are parts of their own no door reaches.
    path = row_of_rooms(tmp_path / "two.dxf", n=8, door_offset=0.6, lost_doors=2)
    with pytest.raises(InconsistentDrawingError, match=r"2 room\(s\) of 0\.5 m2 or more \(1\d, 1\d m2\) are cut off .*--doors"):
        load_scene(path)


def test_accept_inconsistent_writes_with_a_warning(tmp_path):
    path = row_of_rooms(tmp_path / "doors.dxf", n=8, door_offset=0.6)
    scene = load_scene(path, BuildOptions(accept_inconsistent=True))
    assert any("contradicts its drawing" in w and "--accept-inconsistent" in w for w in scene.info["warnings"])
    assert BuildOptions(accept_inconsistent=True).to_meta()["accept_inconsistent"] is True
    assert "accept_inconsistent" not in BuildOptions().to_meta()  # maps built without it keep their bytes


@pytest.mark.parametrize("insunits, unit_per_m, n, unit", [
    (4, 1.0, 8, "m"),              # says mm, drawn in m (fast3d, rehman_test)
    (4, 1.0 / 0.0254, 2, "in"),    # says mm, drawn in inches
])
def test_a_header_in_the_wrong_units_is_read_in_the_one_unit_that_makes_a_building(tmp_path, insunits, unit_per_m,
                                                                                     n, unit):
    scene = load_scene(row_of_rooms(tmp_path / "u.dxf", n=n, insunits=insunits, unit_per_m=unit_per_m))
    assert scene.info["units"] == unit
    assert any(f"only {unit} makes it a building" in w and "--units" in w for w in scene.info["warnings"])
    assert scene.info["counts"]["doors"] == n


def test_units_stay_refused_when_no_door_tells_them_apart(tmp_path):
    # Without door drawings or doorway gaps the size alone fits m, dm, ft and in: refused, naming --units.
    import ezdxf

    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 4
    doc.modelspace().add_lwpolyline([(0, 0), (12, 0), (12, 8), (0, 8)], close=True, dxfattribs={"layer": "A-WALL"})
    doc.saveas(tmp_path / "box.dxf")
    with pytest.raises(ImplausibleUnitsError, match="pass the right --units"):
        load_scene(tmp_path / "box.dxf")
    with pytest.raises(MapkitError, match="--units says mm"):  # --units is the user's word, never overruled
        load_scene(row_of_rooms(tmp_path / "u.dxf", n=8, insunits=4), BuildOptions(units="mm"))


@pytest.mark.slow
def test_the_command_line_refuses_with_exit_2_one_line_and_no_output(tmp_path):
    path = row_of_rooms(tmp_path / "doors.dxf", n=5, door_offset=0.6)
    out = tmp_path / "doors.lmap"
    run = subprocess.run([sys.executable, "-m", "mapkit", "build", str(path), "-o", str(out), "-q"],
                         capture_output=True, text=True)
    assert run.returncode == 2
    errors = [line for line in run.stderr.splitlines() if line.startswith("mapkit: error:")]
    assert len(errors) == 1 and "--accept-inconsistent" in errors[0] and "Traceback" not in run.stderr
    assert not out.exists()
    run = subprocess.run([sys.executable, "-m", "mapkit", "build", str(path), "-o", str(out), "-q",
                          "--accept-inconsistent"], capture_output=True, text=True)
    assert run.returncode == 0 and out.exists() and "contradicts its drawing" in run.stderr


@pytest.mark.parametrize("unit_per_m, measurement, unit", [
    (100.0, 0, "cm"),           # no units, $MEASUREMENT imperial, drawn in cm (proxy_cucs_l1, proxy_cut_lab)
    (1 / 0.0254, 0, "in"),      # no units, imperial, drawn in inches: stays inches
    (100.0, 1, "cm"),           # no units, metric, drawn in cm
])
def test_a_unitless_plan_is_read_in_the_unit_its_doors_and_walls_say(tmp_path, unit_per_m, measurement, unit):
    # Read in inches (the guess of an imperial header from the extent), the cm plan's doors are 2.29 m wide: a
    # door's width still, so the doors alone did not tell; with its walls' thickness (0.2 m in cm, 0.51 m in
    # inches) both say cm.
    scene = load_scene(row_of_rooms(tmp_path / "u.dxf", n=6, insunits=0, unit_per_m=unit_per_m,
                                    measurement=measurement, wall_thickness=0.2))
    assert scene.info["units"] == unit
    assert scene.info["counts"]["doors"] == 6
    assert 80 < scene.free_space.area < 6 * 24  # the plan is 24 x 6 m


def test_doors_across_passages_between_two_walls_faces_are_doors(tmp_path):
    # A door line from one wall's face to the other's, a double door hinged on a wall's face and stopping short
    # of a glass screen (proxy_hoteldieu's entrances, barcelona's double door): no wall gap holds them.
    scene = load_scene(doors_across_passages(tmp_path / "hall.dxf"))
    assert scene.info["counts"]["doors"] == 2
    assert not any("not in a wall gap" in w for w in scene.info["warnings"])
    assert len(polygon_parts(scene.free_space)) == 1


def test_a_tile_grid_stopped_at_glass_is_floor_and_a_doorless_light_box_is_not(tmp_path):
    # barcelona: the podium's last row of tiles is closed by the glass, not by a line of its own; the light box
    # between two glass panes has no door.
    from shapely.geometry import Point

    scene = load_scene(tiled_podium(tmp_path / "podium.dxf"))
    assert scene.info["interior"] == "floor layer"
    assert scene.free_space.contains(Point(3, 7.5))  # the last row of tiles, under the glass
    assert not scene.free_space.contains(Point(5.5, 4))  # inside the light box
    assert len(polygon_parts(scene.free_space)) == 1
    assert any("shut in by walls or glass" in w for w in scene.info["warnings"])


def test_door_swings_on_a_layer_read_as_furniture_hinged_on_a_wall_are_doors(tmp_path):
    # proxy_cityscience: its door swings are on 'Furniture' (arcs and leaves, or leaf and arc in one
    # polyline); read right otherwise, the map had no door at all and was refused.
    for plan in (row_of_rooms(tmp_path / "f.dxf", n=6, door_layer="Furniture"),
                 doors_with_the_furniture(tmp_path / "poly.dxf", n=4)):
        scene = load_scene(plan)
        n = 6 if plan.name == "f.dxf" else 4
        assert scene.info["counts"]["doors"] == n and len(polygon_parts(scene.free_space)) == 1
        assert any(f"{n} door swing(s) hinged on a wall, drawn on the layer(s) 'Furniture'" in w
                   for w in scene.info["warnings"])
        assert not any("contradicts" in w or "not in a wall gap" in w for w in scene.info["warnings"])


def test_door_swings_on_a_layer_read_as_furniture_off_the_walls_are_named_in_the_refusal(tmp_path):
    # Swings hinged on no wall (and the chairs' arcs) are not doors: the map, which found none, is refused.
    plan = doors_with_the_furniture(tmp_path / "off.dxf", n=4, hinged=False)
    with pytest.raises(InconsistentDrawingError, match=r"draws 8 door swing\(s\) on 'Furniture'.*--doors LAYER"):
        load_scene(plan)


def test_a_door_line_at_one_wall_gives_no_passage_and_no_error():
    # A straight door line touching one wall (its rotated box is a line): jps_einkauf, proxy_ensal.
    from shapely.geometry import MultiLineString, box

    from mapkit.importers.dxf.openings import passage_opening

    walls = box(-0.2, -5.0, 0.0, 5.0)
    assert passage_opening(MultiLineString([[(0.0, 0.0), (1.0, 0.0)]]), walls) is None
    assert passage_opening(MultiLineString([[(0.0, 0.0), (1.0, 0.0)]]), walls.union(box(2.0, -5.0, 2.2, 5.0))) \
        is not None  # the line reaches half way to the next wall: a door across the passage


def test_a_frame_around_a_sheet_of_storeys_belongs_to_no_storey(tmp_path):
    # proxy_escaldes: a polyline on a window layer frames the whole sheet; given
    # to the first storey, its building spanned the sheet and the map was refused.
    scene = load_scene(storeys_in_a_frame(tmp_path / "sheet.dxf"))
    assert scene.info["counts"]["doors"] == 4 and len(polygon_parts(scene.free_space)) == 1
    assert 60.0 < scene.free_space.area < 80.0  # one storey, 16 x 6 m less the walls and the robot's margin


def test_a_door_that_opens_into_one_room_only_does_not_spare_it():
    # proxy_escaldes' stair lobby: its door's opening was put along the open
    # leaf, inside the lobby, joining it to nothing; the lobby is cut off.
    from shapely.geometry import MultiPolygon, box

    from mapkit.importers.dxf.self_check import _rooms_cut_off
    from mapkit.scene import Opening, Scene

    walls = MultiPolygon([box(-0.1, -0.1, 8.1, 0.0), box(-0.1, 4.0, 8.1, 4.1), box(-0.1, 0, 0, 4),
                          box(8, 0, 8.1, 4), box(4.95, 0, 5.05, 4)])
    free = MultiPolygon([box(0.2, 0.2, 4.75, 3.8), box(5.25, 0.2, 7.8, 3.8)])

    def cut_off(door):
        scene = Scene(walls=walls, openings=[Opening(door, "door", 0.0, 2.0)], free_space=free, wall_height=2.5)
        return _rooms_cut_off(scene, 0.2)

    assert cut_off(box(5.1, 0.05, 6.0, 0.3))  # beside the doorway, in the east room only: not a door to it
    assert not cut_off(box(4.95, 1.0, 5.05, 1.9))  # in the partition, a door too narrow for the robot
    assert not cut_off(box(7.95, 1.0, 8.1, 1.9))  # in the outer wall: the east room's entrance


def test_a_swing_whose_leaf_cuts_its_arc_opens_where_the_leaf_closes(tmp_path):
    # proxy_escaldes: the open leaf's second line runs past the arc's end; the
    # drawing's lines, noded, cut the arc in two and the swing was not read.
    from pathlib import Path

    from mapkit.importers.dxf import load_drawing
    from mapkit.importers.dxf.closed_leaf import closed_leaf_opening
    from mapkit.importers.dxf.openings import drawing_items
    from mapkit.importers.dxf.walls import build_walls

    drawing, _ = load_drawing(Path(leaf_across_its_arc(tmp_path / "leaf.dxf")), BuildOptions())
    walls = build_walls(drawing.role("walls"), 0.6).walls
    swing = max(drawing_items(drawing.role("doors")), key=lambda item: len(item.geoms))
    assert len(swing.geoms) > 2  # the leaf's lines and the arc's pieces
    cut = closed_leaf_opening(swing, walls, 0.6)
    assert cut is not None
    x0, y0, x1, y1 = cut.bounds  # across the partition, from the hinge (5.13, 0.27) to the latch (5.51, 1.09)
    assert 5.0 < x0 < 5.2 and 5.45 < x1 < 5.6 and 0.2 < y0 < 0.35 and 1.0 < y1 < 1.15


def test_solid_walls_under_a_header_in_mm_are_read_in_the_unit_their_thickness_says(tmp_path):
    # plotpreview: no door and no doorway drawn; the size alone fits m, dm and ft, the walls' 0.4 m only m.
    scene = load_scene(solid_walls_in_metres(tmp_path / "house.dxf"))
    assert scene.info["units"] == "m"
    assert any("walls 0.40 m thick" in w and "--units" in w for w in scene.info["warnings"])
    assert len(polygon_parts(scene.free_space)) == 2 and 40.0 < scene.free_space.area < 45.0
    with pytest.raises(MapkitError, match="--units says mm"):  # --units is the user's word, never overruled
        load_scene(tmp_path / "house.dxf", BuildOptions(units="mm"))


def test_a_plan_drawn_at_a_fraction_of_its_size_is_refused_naming_the_scale_its_doors_say(tmp_path):
    # proxy_sansebastian: a 100 m building drawn 10 units across, its doors a fifth of a door's width as read.
    path = row_of_rooms(tmp_path / "small.dxf", n=8, insunits=6, unit_per_m=0.2)
    with pytest.raises(InconsistentDrawingError, match=r"its 8 door drawings are a median 0\.18 m wide, .* "
                                                       r"fix with --scale 5 or "):
        load_scene(path)
    scene = load_scene(path, BuildOptions(scale=5))
    assert scene.info["counts"]["doors"] == 8 and len(polygon_parts(scene.free_space)) == 1


def test_room_polygons_for_some_rooms_leave_the_corridor_between_them_inside(tmp_path):
    # proxy_learning, proxy_cucea: a floor layer of room polygons (some rooms only) said where the floor
    # ended; the corridor, open at its end, was no floor and the rooms four separate parts, built without error.
    scene = load_scene(room_polygons_off_an_open_corridor(tmp_path / "corridor.dxf"))
    parts = polygon_parts(scene.free_space)
    assert len(parts) == 1 and 65.0 < scene.free_space.area < 80.0  # 4 rooms and the corridor, 0.2 m off the walls
    assert scene.free_space.bounds[0] > 0.0  # nothing leaks out of the open end
    assert scene.info["interior"] == "rooms closed from the walls"
    assert any("'Meeting rooms' outline rooms, not the floor" in w for w in scene.info["warnings"])


def test_a_space_no_door_is_drawn_at_is_no_room_but_one_whose_door_was_missed_is_refused(tmp_path):
    # proxy_factory: with room polygons, a store and a duct with no door drawn were rooms cut off (refused);
    # a stall door hung on no wall in the next room, by the store's wall, is no door of the store.
    scene = load_scene(rooms_beside_doorless_spaces(tmp_path / "store.dxf"))
    assert len(polygon_parts(scene.free_space)) == 1 and scene.info["counts"]["doors"] == 3
    assert not scene.free_space.contains(Point(14.0, 2.0))  # the store (x 12 to 16 m, y 0 to 4 m) is left out
    assert scene.free_space.contains(Point(10.0, 2.0))  # the room beside it is not
    assert any("1 space(s) shut in by walls or glass no door opens and no door is drawn at" in w
               for w in scene.info["warnings"])
    # The room whose door is drawn off its wall (no gap holds it) is a room whose door was missed: refused.
    with pytest.raises(InconsistentDrawingError, match=r"1 room\(s\) of 0.5 m2 or more \(12 m2\) are cut off.*--doors"):
        load_scene(rooms_beside_doorless_spaces(tmp_path / "missed.dxf", missed_door=True))
