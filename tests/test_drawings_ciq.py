"""A drawing sheet whose floor plans are on a layer named for nothing.

The corpus's ciq_building: four floor plans, two sections, an elevation and
a site plan on one sheet; the plans' walls, doors and furniture on
'DETAILS', the sections on 'SECTION-A', 'SECTION-B', no layer named like
walls; its header says inches, it is drawn in millimetres. Refused before
with "name the wall layers with --walls" and no word of which; then the
refusal named the layer its door swings are drawn on and the unit they are
read in; now that layer is taken as the walls, read in that unit, with a
warning (tests/test_drawings_swing_walls.py). The drawings are small DXF
files written here with ezdxf."""

from __future__ import annotations

import math

import ezdxf
import pytest

from mapkit.errors import NoWallsError
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts

#: Rooms along the corridor, each this wide (mm), the corridor 2 m deep.
ROOMS = 6
ROOM_W = 3000.0
#: Door leaves (mm): the swings' radius.
LEAF = 900.0


def write_sheet(path, insunits: int = 1):
    """A sheet in millimetres (its header saying ``insunits``): on 'DETAILS'
    a plan of ``ROOMS`` rooms 3 x 5 m along a 2 m corridor, single wall
    lines, each room's door a swing (arc and leaf) in the corridor wall,
    and a table in the first room; on 'SECTION-A' a section beside it."""
    doc = ezdxf.new("R2013", setup=False)
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    for name in ("DETAILS", "SECTION-A", "NOTES"):
        doc.layers.add(name)
    plan = {"layer": "DETAILS"}
    width = ROOMS * ROOM_W
    msp.add_lwpolyline([(0, 0), (width, 0), (width, 7000), (0, 7000)], close=True, dxfattribs=plan)
    for k in range(1, ROOMS):
        msp.add_line((k * ROOM_W, 2000), (k * ROOM_W, 7000), dxfattribs=plan)
    for k in range(ROOMS):
        x0 = k * ROOM_W + 1000  # the hinge; the gap runs to x0 + LEAF
        msp.add_line((k * ROOM_W, 2000), (x0, 2000), dxfattribs=plan)
        msp.add_line((x0 + LEAF, 2000), ((k + 1) * ROOM_W, 2000), dxfattribs=plan)
        msp.add_arc((x0, 2000), LEAF, 0, 90, dxfattribs=plan)
        msp.add_line((x0, 2000 + LEAF), (x0, 2000), dxfattribs=plan)
    msp.add_lwpolyline([(400, 5000), (1600, 5000), (1600, 5800), (400, 5800)], close=True, dxfattribs=plan)
    section = {"layer": "SECTION-A"}
    for y in (10000, 13000, 16000):  # floor slabs, and the outer walls of the section
        msp.add_lwpolyline([(0, y), (width, y), (width, y + 200), (0, y + 200)], close=True, dxfattribs=section)
    msp.add_line((0, 10000), (0, 16200), dxfattribs=section)
    msp.add_line((width, 10000), (width, 16200), dxfattribs=section)
    msp.add_text("FIRST FLOOR PLAN", dxfattribs={"layer": "NOTES", "insert": (0, -1500), "height": 300})
    doc.saveas(path)
    return path


def test_a_sheet_without_wall_layers_builds_the_layer_of_its_swings(tmp_path):
    """Built as with '--walls DETAILS --units mm' (what the refusal named
    before), with a warning naming the layer of the door swings and the
    unit they are read in (not the header's)."""
    path = write_sheet(tmp_path / "sheet.dxf")
    scene = load_scene(path, BuildOptions())
    named = load_scene(path, BuildOptions(walls=["DETAILS"], units="mm"))
    assert scene.walls.equals(named.walls) and scene.free_space.equals(named.free_space)
    [message] = [w for w in scene.info["warnings"] if "named like walls" in w]
    assert "taking 'DETAILS', the layer of the drawing's 6 door swings" in message
    assert "read in mm as the swings are (its header says in)" in message
    assert "\n" not in message


def test_the_options_named_build_the_plan(tmp_path):
    """What the refusal names builds the plan: its six doors, its rooms
    connected through them, inside the walls."""
    scene = load_scene(write_sheet(tmp_path / "sheet.dxf"), BuildOptions(walls=["DETAILS"], units="mm"))
    assert [o.kind for o in scene.openings].count("door") == ROOMS
    assert len(polygon_parts(scene.free_space)) == 1
    assert scene.free_space.area < ROOMS * ROOM_W * 7000 / 1e6


def test_a_header_in_the_swings_unit_is_not_overruled(tmp_path):
    """With the header in millimetres the warning names the layer only."""
    scene = load_scene(write_sheet(tmp_path / "sheet.dxf", insunits=4), BuildOptions())
    [message] = [w for w in scene.info["warnings"] if "named like walls" in w]
    assert "the layer of the drawing's 6 door swings" in message and "read in" not in message


def test_arcs_that_read_as_swings_in_several_units_name_no_layer(tmp_path):
    """A framing plan's lettering drawn as arcs of every size, each with a
    radial stroke, reads as door swings in units ten times apart: no
    building's doors, and the refusal names no layer (as before)."""
    doc = ezdxf.new("R2013", setup=False)
    msp = doc.modelspace()
    for name in ("F-0", "F-4"):
        doc.layers.add(name)
    for k, radius in enumerate([0.5, 0.8, 1.2] * 2 + [5.0, 8.0, 12.0] * 2):
        cx = 40.0 * k
        msp.add_arc((cx, 0), radius, 0, 60, dxfattribs={"layer": "F-0"})
        a = math.radians(60)
        msp.add_line((cx + radius * math.cos(a), radius * math.sin(a)), (cx, 0), dxfattribs={"layer": "F-0"})
    msp.add_line((0, -50), (400, -50), dxfattribs={"layer": "F-4"})
    doc.saveas(tmp_path / "framing.dxf")
    with pytest.raises(NoWallsError) as caught:
        load_scene(tmp_path / "framing.dxf", BuildOptions())
    assert str(caught.value).endswith("name the wall layers with --walls (see 'mapkit layers PLAN')")


def test_layers_notes_the_swings_layer(tmp_path, capsys):
    """'mapkit layers' says it too."""
    from mapkit.cli import main

    assert main(["layers", str(write_sheet(tmp_path / "sheet.dxf"))]) == 0
    assert "note: no layer is named like walls: taking 'DETAILS'" in capsys.readouterr().out
