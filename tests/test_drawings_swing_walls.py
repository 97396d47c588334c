"""No layer named like walls: the layer of the door swings is the walls.

The corpus's ciq_building keeps its floor plans (walls, door swings,
fixtures) on 'DETAILS', beside sections and an elevation on layers of
their own, no layer named like walls, and its header says inches while it
is drawn in millimetres. It was refused naming ``--walls DETAILS --units
mm``; now that layer is taken as the walls and read in the unit its swings
are, with a warning naming both and the options that choose otherwise. A
layer whose arcs are no door swings is not taken. The drawings are small
DXF files written here with ezdxf."""

from __future__ import annotations


import ezdxf
import pytest

from mapkit.errors import NoWallsError
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts

#: Rooms along the corridor, each this wide (mm); rooms 4 m deep, the corridor 1.8 m.
ROOMS = 5
ROOM_W = 3200.0
DEPTH = 5800.0
CORRIDOR = 1800.0
#: Door leaves (mm): the swings' radius.
LEAF = 850.0


def write_plan(path, insunits: int = 1, swings: bool = True, walls_layer: str = "A1", frames: bool = False,
               lettering: int = 0):
    """A drawing in millimetres, its header saying ``insunits`` (1: inches):
    on 'A1' a plan of ``ROOMS`` rooms along a corridor, single wall lines,
    each room's doorway in the corridor wall with its swing (an arc and its
    leaf; with ``swings`` False an arc alone, a window's head in a wall
    face, no leaf; with ``frames`` a jamb block each side) and a washbasin
    against a room's back wall, and ``lettering`` letters 'C' in its title
    block below (each an arc a door's radius); on 'ELEV' an
    elevation beside it (no layer says walls). The walls may be on a layer
    of their own, ``walls_layer``."""
    doc = ezdxf.new("R2013", setup=False)
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    for name in sorted({"A1", "ELEV", walls_layer}):
        doc.layers.add(name)
    plan = {"layer": walls_layer}
    width = ROOMS * ROOM_W
    msp.add_lwpolyline([(0, 0), (width, 0), (width, DEPTH), (0, DEPTH)], close=True, dxfattribs=plan)
    for k in range(1, ROOMS):
        msp.add_line((k * ROOM_W, CORRIDOR), (k * ROOM_W, DEPTH), dxfattribs=plan)
    for k in range(ROOMS):
        hinge = k * ROOM_W + 600  # the doorway runs from the hinge to hinge + LEAF
        msp.add_line((k * ROOM_W, CORRIDOR), (hinge, CORRIDOR), dxfattribs=plan)
        msp.add_line((hinge + LEAF, CORRIDOR), ((k + 1) * ROOM_W, CORRIDOR), dxfattribs=plan)
        msp.add_arc((hinge, CORRIDOR), LEAF, 0, 90, dxfattribs={"layer": "A1"})
        if swings:
            msp.add_line((hinge, CORRIDOR + LEAF), (hinge, CORRIDOR), dxfattribs={"layer": "A1"})
        if frames:
            for x in (hinge - 100, hinge + LEAF):
                msp.add_lwpolyline([(x, CORRIDOR - 50), (x + 100, CORRIDOR - 50), (x + 100, CORRIDOR + 50),
                                    (x, CORRIDOR + 50)], close=True, dxfattribs={"layer": "A1"})
    msp.add_lwpolyline([(1200, DEPTH - 450), (1700, DEPTH - 450), (1700, DEPTH), (1200, DEPTH)], close=True,
                       dxfattribs={"layer": "A1"})  # a washbasin against the back wall
    for k in range(lettering):  # a 'C': an arc of 120 degrees, no stroke from its ends
        msp.add_arc((1000.0 * k + 800, -2250), 866, 120, 240, dxfattribs={"layer": "A1"})
    elev = {"layer": "ELEV"}
    msp.add_lwpolyline([(0, 9000), (width, 9000), (width, 12000), (0, 12000)], close=True, dxfattribs=elev)
    for k in range(ROOMS):  # windows of the elevation
        x = k * ROOM_W + 1000
        msp.add_lwpolyline([(x, 10000), (x + 1200, 10000), (x + 1200, 11200), (x, 11200)], close=True,
                           dxfattribs=elev)
    doc.saveas(path)
    return path


def test_the_layer_of_the_swings_is_the_walls_read_in_their_unit(tmp_path):
    """Refused before ("no recognisable walls", naming --walls A1 --units
    mm); now built: its five doors found, its rooms connected through them,
    inside the walls, with a warning naming what was assumed."""
    scene = load_scene(write_plan(tmp_path / "plan.dxf"), BuildOptions())
    assert [o.kind for o in scene.openings].count("door") == ROOMS
    assert len(polygon_parts(scene.free_space)) == 1
    assert scene.free_space.area < ROOMS * ROOM_W * DEPTH / 1e6
    assert scene.info["units"] == "mm"
    assert scene.info["layers"]["walls"] == ["A1"]
    [warning] = [w for w in scene.info["warnings"] if "named like walls" in w]
    assert "taking 'A1'" in warning and f"{ROOMS} door swings" in warning
    assert "read in mm as the swings are (its header says in)" in warning
    assert "--walls and --units to choose otherwise" in warning


def test_a_header_in_the_swings_unit_is_named_no_unit(tmp_path):
    """The header says millimetres, as the swings: the warning names the layer only."""
    scene = load_scene(write_plan(tmp_path / "plan.dxf", insunits=4), BuildOptions())
    assert [o.kind for o in scene.openings].count("door") == ROOMS
    [warning] = [w for w in scene.info["warnings"] if "named like walls" in w]
    assert "read in" not in warning and warning.endswith("pass --walls to choose otherwise")


def test_the_users_options_win(tmp_path):
    """--units reads the drawing in the user's unit; --scale keeps the
    header's; --walls names the walls (the swings' layer then plays no part)."""
    from mapkit.importers.dxf import load_drawing

    path = write_plan(tmp_path / "plan.dxf")
    _, info = load_drawing(path, BuildOptions(units="cm"))
    assert info["units"] == "cm" and info["layers"]["walls"] == ["A1"]
    assert not any("read in mm" in w for w in info["warnings"])
    _, info = load_drawing(path, BuildOptions(scale=0.04))  # inches x 0.04: a unit about a millimetre
    assert info["units"] == "in" and info["scale"] == pytest.approx(0.0254 * 0.04)
    _, info = load_drawing(path, BuildOptions(walls=["ELEV"]))
    assert info["layers"]["walls"] == ["ELEV"] and info["units"] == "in"
    assert not any("named like walls" in w for w in info["warnings"])


def test_layers_says_which_rule_decided(tmp_path, capsys):
    """'mapkit layers' gives the swing layer the role walls, says why, and notes the warning."""
    from mapkit.cli import main

    assert main(["layers", str(write_plan(tmp_path / "plan.dxf"))]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("A1 "))
    assert "walls" in row and f"no layer is named like walls: it holds the drawing's door swings ({ROOMS}, read " \
                                "in mm)" in row
    assert "note: no layer is named like walls: taking 'A1'" in out


def test_arcs_without_leaves_are_not_swings_and_name_no_walls(tmp_path):
    """Arcs a door's radius with no leaf line (a window head, a bay) are no
    door swings: no layer is taken, the drawing is refused as before."""
    with pytest.raises(NoWallsError, match=r"no recognisable walls: layers are 'A1', 'ELEV'; name the wall layers "
                                           r"with --walls \(see 'mapkit layers PLAN'\)$"):
        load_scene(write_plan(tmp_path / "plan.dxf", swings=False), BuildOptions())


def test_a_layer_whose_door_sized_arcs_are_mostly_no_swings_is_not_adopted(tmp_path):
    """The five swings beside twelve letters whose bowls are arcs a door's
    radius (a title block drawn on the plan's layer, a framing plan's
    lettering): most of the layer's door-sized arcs are no door's; refused."""
    path = write_plan(tmp_path / "plan.dxf", lettering=12)
    with pytest.raises(NoWallsError, match="name the wall layers with --walls"):
        load_scene(path, BuildOptions())
    assert len(load_scene(write_plan(tmp_path / "few.dxf", lettering=2), BuildOptions()).openings) == ROOMS


@pytest.mark.parametrize("frames", [False, True], ids=["doors and furniture", "doors and their frames"])
def test_a_layer_of_swings_whose_walls_are_on_another_is_not_adopted(tmp_path, frames):
    """The swings (with a washbasin, or with their jamb blocks) on 'A1', the
    walls they hang in on 'A3' (a name that says nothing): 'A1' is no wall
    layer (its swings' hinges meet none of its lines, or its lines are a
    metre or two a door); refused, naming no layer."""
    path = write_plan(tmp_path / "plan.dxf", walls_layer="A3", frames=frames)
    with pytest.raises(NoWallsError, match=r"layers are 'A1', 'A3', 'ELEV'; name the wall layers with --walls"):
        load_scene(path, BuildOptions())
    assert load_scene(path, BuildOptions(walls=["A3"], doors=["A1"])).openings  # the walls named: built


def test_two_layers_with_as_many_swings_are_not_adopted(tmp_path):
    """No strict winner (two layers hold as many swings): no layer is taken."""
    path = write_plan(tmp_path / "plan.dxf")
    doc = ezdxf.readfile(path)
    doc.layers.add("B2")
    msp = doc.modelspace()
    for e in list(msp.query("LINE ARC LWPOLYLINE[layer=='A1']")):
        copy = e.copy()
        copy.dxf.layer = "B2"
        copy.translate(0, -20000, 0)
        msp.add_entity(copy)
    doc.saveas(path)
    with pytest.raises(NoWallsError, match="name the wall layers with --walls"):
        load_scene(path, BuildOptions())
