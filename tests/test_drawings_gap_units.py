"""A plan that draws no door symbols and whose header states the wrong units,
told by the gaps its walls leave at the doorways (the corpus's gallery,
depthmapX's test plan, says metres and is drawn at about 1/14 of its size:
no unit mends it, so its refusal names the --scale its doorways say),
reproduced in small drawings written here."""

from __future__ import annotations

from pathlib import Path

import ezdxf
import numpy as np
import pytest
from cli_helpers import assert_one_line_error, run

from mapkit.errors import NoFreeSpaceError
from mapkit.importers import load_scene
from mapkit.importers.dxf.doorway_gaps import doorway_gaps
from mapkit.importers.dxf.strokes import Stroke
from mapkit.importers.dxf.units import scale_from_gaps, units_from_gaps
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts

FLAT = Path(__file__).resolve().parent.parent / "maps" / "flat.dxf"

#: The rooms of :func:`_rooms_off_a_corridor`, metres.
ROOMS, ROOM, DEPTH, CORRIDOR, DOOR = 6, 4.0, 4.0, 2.0, 0.9


def _rooms_off_a_corridor(path, insunits: int, unit_per_m: float, double: bool = False, rooms: int = ROOMS):
    """``rooms`` (six) 4 x 4 m rooms in a row off a 2 m corridor, each entered through a
    0.9 m doorway (a gap in the corridor wall, no door drawn) on layer
    'A-WALL'; drawn ``unit_per_m`` drawing units to the metre under the
    header code ``insunits``. Single wall lines, or (``double``) each wall
    piece a closed outline 0.2 m thick, its ends capped at the doorways."""
    k = unit_per_m
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    wall = {"layer": "A-WALL"}
    width, top = rooms * ROOM, DEPTH + CORRIDOR
    t = 0.2 if double else 0.0

    def piece(x0, y0, x1, y1):
        if double:  # a closed outline t thick around the line, capped at its ends
            pts = [(x0, y0 - t / 2), (x1, y0 - t / 2), (x1, y1 + t / 2), (x0, y1 + t / 2)] if y0 == y1 else \
                  [(x0 - t / 2, y0), (x0 + t / 2, y0), (x1 + t / 2, y1), (x1 - t / 2, y1)]
            msp.add_lwpolyline([(x * k, y * k) for x, y in pts], close=True, dxfattribs=wall)
        else:
            msp.add_line((x0 * k, y0 * k), (x1 * k, y1 * k), dxfattribs=wall)

    # The outer walls, then the walls between rooms, then the corridor wall
    # broken by each room's doorway 1 m from its left wall.
    for x0, y0, x1, y1 in ((0, 0, width, 0), (0, top, width, top)):
        piece(x0, y0, x1, y1)
    for x in (0, width):
        piece(x, 0, x, top)
    for i in range(1, rooms):
        piece(i * ROOM, 0, i * ROOM, DEPTH)
    for i in range(rooms):
        x0, x1 = i * ROOM, (i + 1) * ROOM
        piece(x0, DEPTH, x0 + 1.0, DEPTH)
        piece(x0 + 1.0 + DOOR, DEPTH, x1, DEPTH)
    doc.saveas(path)
    return path


def _stroke(*points, closed=False):
    return Stroke(np.asarray(points, dtype=float), closed=closed)


def test_the_gaps_of_single_and_double_line_walls_are_measured():
    # Two collinear wall lines 0.9 apart; a wall line between two walls,
    # ending 0.5 short of one and 1.2 of the other; a double-line wall 0.2
    # thick, capped, broken by a 1.0 doorway. Lengths in any unit: the
    # measure is the drawing's.
    single = [_stroke((0, 0), (3, 0)), _stroke((3.9, 0), (8, 0))]
    facing = [_stroke((0, 5), (8, 5)), _stroke((4, 0.5), (4, 3.8))]
    double = [_stroke((0, 10), (3, 10), (3, 10.2), (0, 10.2), closed=True),
              _stroke((4, 10), (8, 10), (8, 10.2), (4, 10.2), closed=True)]
    gaps = np.sort(doorway_gaps(single + facing + double, 10.0))
    # The other free ends (the walls' outer ends) meet nothing within reach.
    assert gaps == pytest.approx([0.5, 0.9, 1.0, 1.2])


def test_closed_rooms_without_openings_have_no_gaps():
    # Rooms traced as closed rectangles (the corpus's scan-traced office): no
    # wall ends, so nothing to tell its units by.
    rooms = [_stroke((x, 0), (x + 3, 0), (x + 3, 4), (x, 4), closed=True) for x in (0, 3, 6)]
    assert len(doorway_gaps(rooms, 9.0)) == 0


@pytest.mark.parametrize("double", [False, True])
def test_doorways_ten_times_too_narrow_say_the_drawing_is_in_centimetres(tmp_path, double):
    # Says millimetres ($INSUNITS 4), drawn in centimetres: read as stated
    # the plan is 2.4 m across and its doorways 9 cm wide (refused before:
    # no free space).
    scene = load_scene(_rooms_off_a_corridor(tmp_path / "cm.dxf", 4, 100.0, double))
    assert scene.info["units"] == "cm"
    assert any("draws no doors and its 6 doorways" in w and "median 0.09 m" in w and "read in cm instead" in w
               for w in scene.info["warnings"]), scene.info["warnings"]
    assert len(polygon_parts(scene.free_space)) == 1
    assert 80.0 < scene.free_space.area < ROOMS * ROOM * (DEPTH + CORRIDOR)


def test_the_example_flat_without_its_doors_drawn_in_centimetres_is_read_in_centimetres(tmp_path):
    # maps/flat.dxf (double-line walls as outlines) with its door symbols
    # left out and drawn at a tenth of its size, still saying millimetres:
    # refused before (1.2 x 1.0 m as read); its doorways say centimetres.
    doc = ezdxf.readfile(FLAT)
    msp = doc.modelspace()
    for e in list(msp):
        if e.dxf.layer == "A-DOOR":
            msp.delete_entity(e)
        else:
            e.scale_uniform(0.1)
    doc.saveas(tmp_path / "flat-cm.dxf")
    scene = load_scene(tmp_path / "flat-cm.dxf")
    assert scene.info["units"] == "cm"
    assert any("doorways (gaps in its walls) are a median 0.08 m wide" in w for w in scene.info["warnings"])
    # As the flat itself (61.7 m2 of free space in one part, its doors drawn).
    assert len(polygon_parts(scene.free_space)) == 1 and scene.free_space.area == pytest.approx(61.7, rel=0.02)


def test_a_long_plan_whose_header_says_mm_is_read_in_cm_when_its_walls_say_so_too(tmp_path):
    # 28 rooms off a corridor, 112 m long, drawn in centimetres under a
    # header saying millimetres: as stated the plan is 11.2 m long (nearer
    # a typical building's 20 m than 112 m is), but its doorways are 9 mm
    # wide and its walls 2 cm thick. Before, the extent alone kept mm (the
    # map refused or built at a tenth of its size); the walls' thickness
    # outweighs it now.
    scene = load_scene(_rooms_off_a_corridor(tmp_path / "long.dxf", 4, 100.0, double=True, rooms=28))
    assert scene.info["units"] == "cm"
    assert any("read in cm instead" in w and "its walls 0.20 m thick" in w and "the plan 112 m across" in w
               for w in scene.info["warnings"]), scene.info["warnings"]
    assert len(polygon_parts(scene.free_space)) == 1
    assert 28 * ROOM * DEPTH * 0.5 < scene.free_space.area < 28 * ROOM * (DEPTH + CORRIDOR)


def test_doorways_in_feet_that_are_inches(tmp_path):
    scene = load_scene(_rooms_off_a_corridor(tmp_path / "in.dxf", 2, 1.0 / 0.0254))  # says feet, drawn in inches
    assert scene.info["units"] == "in"


def test_right_units_and_an_explicit_choice_are_kept(tmp_path):
    scene = load_scene(_rooms_off_a_corridor(tmp_path / "m.dxf", 6, 1.0))
    assert scene.info["units"] == "m"
    assert not any("doorways" in w for w in scene.info["warnings"])
    # Says metres, drawn in decimetres (a 240 m plan, doorways 9 m wide):
    # read in dm by default, but --units and --scale are the user's word.
    dm = _rooms_off_a_corridor(tmp_path / "dm.dxf", 6, 10.0)
    assert load_scene(dm).info["units"] == "dm"
    # (Read so, the map contradicts its drawing: written only when asked.)
    for options in (BuildOptions(units="m", accept_inconsistent=True), BuildOptions(scale=0.5, accept_inconsistent=True)):
        scene = load_scene(dm, options)
        assert scene.info["units"] == "m" and not any("doorways" in w for w in scene.info["warnings"])


@pytest.mark.parametrize("widths, unit, extent, expected", [
    ([0.09] * 6, "mm", 2.4, "cm"),        # said mm, drawn in cm
    ([9.0] * 6, "m", 240.0, "dm"),        # said m, drawn in dm
    ([0.075] * 6, "in", 2.0, "ft"),       # said inches, drawn in feet
    ([0.8, 0.9, 1.6, 0.9, 1.0], "m", 24.0, None),        # doorways a door's width
    ([0.09] * 4, "mm", 2.4, None),        # too few to tell
    ([2.7, 1.4, 4.3, 2.7, 6.0, 1.2], "m", 45.0, None),  # wide openings: m and ft are not told apart
    ([0.063] * 66, "m", 4.6, None),       # the gallery at 1/14 in metres: no unit mends it
    ([9.0, 9.0, 9.0, 0.3, 0.2, 0.2, 0.1], "m", 240.0, None),  # most would then be no door's width
    ([9.0] * 6, "m", 40.0, None),         # in dm the plan would be 4 m across, farther from a building's size
])
def test_the_unit_the_gaps_say(widths, unit, extent, expected):
    found = units_from_gaps(widths, unit, extent)
    assert (found[0] if found else None) == expected


@pytest.mark.parametrize("thickness, expected", [
    (None, None),     # single wall lines: the extent alone judges, 11.2 m is nearer a building's size than 112 m
    (0.02, "cm"),     # walls 2 cm thick as read: 0.2 m in cm, which outweighs the extent
    (0.2, None),      # 0.2 m as read, 2 m in cm: double lines no wall is (rooms facing each other), no sign
    (0.03, "cm"),     # 3 cm as read, 0.3 m in cm: both a wall's, cm the nearer a typical one
])
def test_the_walls_thickness_joins_the_extent_in_judging_the_unit_the_gaps_say(thickness, expected):
    found = units_from_gaps([0.09] * 6, "mm", 11.2, thickness, BuildOptions().max_wall_thickness)
    assert (found[0] if found else None) == expected


def test_a_plan_drawn_at_a_fraction_of_its_size_is_refused_naming_the_scale_its_doorways_say(tmp_path, capsys):
    # Says metres, drawn at 1/14 of its size (no unit gives that): the
    # refusal names the scale that makes its doorways 0.9 m (before: a
    # power of ten, --scale 10), and that scale builds it.
    plan = _rooms_off_a_corridor(tmp_path / "fourteenth.dxf", 6, 1 / 14)
    code, out, err = run(capsys, "build", plan, "-o", tmp_path / "fourteenth.lmap")
    assert_one_line_error(code, out, err, "no free space left inside the walls",
                          "its 6 doorways (gaps in its walls) are a median 0.064 m wide",
                          "if they are doors about 0.9 m wide, give --scale 14 (then 24 x 6 m)")
    assert not (tmp_path / "fourteenth.lmap").exists()
    assert load_scene(plan, BuildOptions(scale=14)).info["units"] == "m"
    # A --scale already given is part of what was read: the scale to give is the whole one.
    with pytest.raises(NoFreeSpaceError, match=r"median 0.032 m wide: .* give --scale 14 "):
        load_scene(plan, BuildOptions(scale=0.5))


def test_the_scale_the_gaps_say():
    assert scale_from_gaps([0.063] * 66) == (66, 0.063, 14.0)
    assert scale_from_gaps([0.9] * 6) is None      # a door's width: the scale is not what is wrong
    assert scale_from_gaps([0.063] * 4) is None    # too few to tell
