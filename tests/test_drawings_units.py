"""A drawing whose header states the wrong units, told by its doors (the
corpus's mall level says metres and is drawn in decimetres, its doors 10 m
wide; its house says feet and is drawn in inches), reproduced in a small
drawing written here."""

from __future__ import annotations

import ezdxf
import pytest

from mapkit.errors import InconsistentDrawingError
from mapkit.importers import load_scene
from mapkit.importers.dxf.units import units_from_doors
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts


def _row_of_rooms(path, insunits: int, unit_per_m: float):
    """Six 4 x 4 m rooms in a row off a corridor, single-line walls on
    'A-WALL', each room's 0.9 m door a leaf and its swing on 'A-DOOR' in a
    gap of the corridor wall; drawn ``unit_per_m`` drawing units to the
    metre under the header code ``insunits``."""
    k = unit_per_m
    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    wall, door = {"layer": "A-WALL"}, {"layer": "A-DOOR"}
    n, w = 6, 4.0
    msp.add_lwpolyline([(0, 0), (n * w * k, 0), (n * w * k, 6 * k), (0, 6 * k)], close=True, dxfattribs=wall)
    for i in range(1, n):
        msp.add_line((i * w * k, 0), (i * w * k, 4 * k), dxfattribs=wall)
    for i in range(n):  # the corridor wall at y = 4 m, broken by each room's door
        x0, x1 = i * w * k, (i + 1) * w * k
        hinge = x0 + 1.0 * k
        msp.add_line((x0, 4 * k), (hinge, 4 * k), dxfattribs=wall)
        msp.add_line((hinge + 0.9 * k, 4 * k), (x1, 4 * k), dxfattribs=wall)
        msp.add_line((hinge, 4 * k), (hinge, 3.1 * k), dxfattribs=door)  # the leaf, open into the room
        msp.add_arc((hinge / k * k, 4 * k), 0.9 * k, 270, 360, dxfattribs=door)
    doc.saveas(path)
    return path


def test_doors_ten_times_too_wide_say_the_drawing_is_in_decimetres(tmp_path):
    # Says metres ($INSUNITS 6), drawn in decimetres: read as stated, the
    # rooms are 40 m across and the doors 9 m wide.
    scene = load_scene(_row_of_rooms(tmp_path / "dm.dxf", 6, 10.0))
    assert scene.info["units"] == "dm"
    assert any("doors are a median 9.00 m wide" in w and "read in dm" in w for w in scene.info["warnings"])
    assert len(polygon_parts(scene.free_space)) == 1
    assert 90.0 < scene.free_space.area < 144.0  # 24 x 6 m less the walls and the robot's margin


def test_doors_in_feet_that_are_inches(tmp_path):
    scene = load_scene(_row_of_rooms(tmp_path / "in.dxf", 2, 1.0 / 0.0254))  # says feet, drawn in inches
    assert scene.info["units"] == "in"


def test_right_units_and_an_explicit_choice_are_kept(tmp_path):
    scene = load_scene(_row_of_rooms(tmp_path / "m.dxf", 6, 1.0))
    assert scene.info["units"] == "m"
    assert not any("doors are a median" in w for w in scene.info["warnings"])
    # --units is the user's word: the doors do not overrule it; the map
    # then contradicts its drawing (9 m doors in no wall gap), so it is
    # written only with --accept-inconsistent, warned.
    path = _row_of_rooms(tmp_path / "dm.dxf", 6, 10.0)
    with pytest.raises(InconsistentDrawingError, match="contradicts its drawing"):
        load_scene(path, BuildOptions(units="m"))
    scene = load_scene(path, BuildOptions(units="m", accept_inconsistent=True))
    assert scene.info["units"] == "m"
    assert any("contradicts its drawing" in w for w in scene.info["warnings"])


@pytest.mark.parametrize("widths, unit, expected", [
    ([10.0] * 5, "m", "dm"),       # a mall level in decimetres
    ([9.1] * 5, "ft", "in"),       # feet that are inches
    ([0.09] * 5, "mm", "cm"),      # said mm, drawn in cm: doors ten times too narrow
    ([0.9] * 5, "m", None),        # doors a door's width
    ([10.0] * 4, "m", None),       # too few doors to tell
    ([1.6, 1.8, 1.5, 1.5, 0.9], "mm", None),  # a college's double doors
])
def test_the_unit_the_doors_say(widths, unit, expected):
    found = units_from_doors(widths, unit, 50.0)
    assert (found[0] if found else None) == expected


@pytest.mark.parametrize("layer, role", [
    ("Staircase_innerwall", "walls"), ("Staircase_outertwall", "walls"), ("Innenwand", "walls"),
    ("Trennwaende", "walls"), ("curtainwall", "windows"), ("Glaswand", "windows"), ("Walkway", None),
])
def test_compound_words_ending_in_a_wall_are_walls(layer, role):
    # smh_dxf28's staircase walls ('Staircase_innerwall', 'Staircase_outertwall') were read as nothing.
    from mapkit.importers.dxf.layer_roles import guess_role

    assert guess_role(layer) == role
