"""Stairs drawn on the wall layer (daoshi_f1 and daoshi_f3 of
docs/benchmarks/drawings.tsv): a run of treads is a stair, not walls; its
extent is no floor, and a stair well's landing that only the stair (and a
door to the outside) leads to is not this storey's free space. Reproduced
in a small drawing written here."""

from __future__ import annotations

import ezdxf
import numpy as np
import pytest
from shapely.geometry import Point

from mapkit.importers import load_scene
from mapkit.importers.dxf.stairs import find_stair_runs
from mapkit.importers.dxf.strokes import Stroke
from mapkit.options import BuildOptions
from mapkit.shapes import polygon_parts

WALL, DOOR = "墙线", "门线"
#: The flight of the drawing below: treads at x 7.6 .. 9.7 m, 0.3 m apart, across the well (y 0.2 .. 2.6 m).
TREADS_X = [7600 + 300 * k for k in range(8)]


def _line(msp, a, b, layer=WALL):
    msp.add_line(a, b, dxfattribs={"layer": layer})


def _swing(msp, hinge, width, start_deg, leaf_deg=None, layer=DOOR):
    """A door's quarter arc from ``start_deg`` about ``hinge`` and its open
    leaf (at ``leaf_deg``, default ``start_deg``), mm."""
    x, y = hinge
    a = np.radians(start_deg if leaf_deg is None else leaf_deg)
    _line(msp, (x, y), (x + width * np.cos(a), y + width * np.sin(a)), layer)
    msp.add_arc((x, y), width, start_deg, start_deg + 90, dxfattribs={"layer": layer})


def _stair_well_plan(path, exit_door: bool = True):
    """A room and a stair well (mm, the college's layers: 墙线 walls, 门线
    doors), 12.4 x 2.8 m outside, walls 200 mm as double lines. Room A
    (x 0.2 .. 6.2 m) has a door to the outside in its front wall and one
    into the well's lobby (x 6.4 .. 7.6 m); the well's flight (8 treads
    drawn on the wall layer, 0.3 m apart, 2.4 m wide) runs across the well
    to a landing (x 9.7 .. 12.2 m) whose only door (``exit_door``) opens to
    the outside: the stair's exit, as daoshi_f1's east stair."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    # Outer and inner faces, with the gaps of room A's front door (x 1000..1900) and the landing's exit (y 800..1700).
    right_outer = [(12400, 0), (12400, 800)] if exit_door else [(12400, 0)]
    right_inner = [(12200, 200), (12200, 800)] if exit_door else [(12200, 200)]
    msp.add_lwpolyline([(1900, 0), *right_outer], dxfattribs={"layer": WALL})
    msp.add_lwpolyline([(1900, 200), *right_inner], dxfattribs={"layer": WALL})
    top = 1700 if exit_door else 0
    msp.add_lwpolyline([(12400, top), (12400, 2800), (0, 2800), (0, 0), (1000, 0)], dxfattribs={"layer": WALL})
    msp.add_lwpolyline([(12200, max(top, 200)), (12200, 2600), (200, 2600), (200, 200), (1000, 200)],
                       dxfattribs={"layer": WALL})
    if exit_door:
        _line(msp, (12200, 800), (12400, 800))
        _line(msp, (12200, 1700), (12400, 1700))
        _swing(msp, (12400, 800), 900, 0)
    _line(msp, (1000, 0), (1000, 200))
    _line(msp, (1900, 0), (1900, 200))
    _swing(msp, (1000, 0), 900, 270)
    # The partition between room A and the well, its door gap y 800..1700.
    msp.add_lwpolyline([(6200, 200), (6200, 800), (6400, 800), (6400, 200)], dxfattribs={"layer": WALL})
    msp.add_lwpolyline([(6200, 2600), (6200, 1700), (6400, 1700), (6400, 2600)], dxfattribs={"layer": WALL})
    _swing(msp, (6200, 800), 900, 90, leaf_deg=180)
    # The flight's treads, wall face to wall face.
    for x in TREADS_X:
        _line(msp, (x, 200), (x, 2600))
    doc.saveas(path)
    return path


def _scene(path):
    return load_scene(path, BuildOptions())


@pytest.mark.parametrize("exit_door", [True, False])
def test_landing_that_only_the_stair_leads_to_is_not_this_storeys_free_space(tmp_path, exit_door):
    scene = _scene(_stair_well_plan(tmp_path / "stair_well.dxf", exit_door))
    parts = polygon_parts(scene.free_space)
    assert len(parts) == 1, [round(p.area, 1) for p in parts]
    # The landing (beyond the flight) is left out, named in a warning; room A and the lobby stay.
    assert not scene.free_space.intersects(Point(11.0, 1.4))
    assert scene.free_space.contains(Point(3.0, 1.4)) and scene.free_space.contains(Point(7.0, 1.4))
    stair_warnings = [w for w in scene.info["warnings"] if "only the stair leads to" in w]
    assert len(stair_warnings) == 1 and "at (1" in stair_warnings[0], scene.info["warnings"]
    assert scene.info["stair_left_out_m2"] == pytest.approx((12.2 - 9.7 - 0.4) * (2.4 - 0.4), abs=0.3)


def test_treads_are_no_walls_and_their_flight_no_floor(tmp_path):
    scene = _scene(_stair_well_plan(tmp_path / "stair_well.dxf"))
    assert scene.info["stair_runs"] == 1
    assert any("1 stair run(s)" in w and "8 treads" in w for w in scene.info["warnings"])
    # Between two treads is neither wall nor free space: a stair.
    for x in (7.75, 8.5, 9.55):
        assert not scene.walls.intersects(Point(x, 1.4)), x
        assert not scene.free_space.intersects(Point(x, 1.4)), x
    # The free space keeps the robot's radius from the flight.
    assert scene.free_space.distance(Point(7.6, 1.4)) == pytest.approx(0.2, abs=0.01)
    assert "stairs (treads)" in scene.ignored


def _strokes(lines):
    return [Stroke(np.array(line, float), layer=WALL) for line in lines]


def test_a_run_of_treads_is_found_in_any_direction():
    rng = np.random.default_rng(3)
    angle = np.radians(rng.uniform(0, 180))
    u, n = np.array([np.cos(angle), np.sin(angle)]), np.array([-np.sin(angle), np.cos(angle)])
    treads = [(5 * n + k * 0.28 * n + 1.0 * u, 5 * n + k * 0.28 * n + 2.5 * u) for k in range(6)]
    other = [((0, 0), (0, 4)), ((1, 0), (3, 0))]
    runs = find_stair_runs(_strokes(other + treads[::-1]))
    assert len(runs) == 1
    assert runs[0].treads == tuple(range(2, 8))
    assert runs[0].going == pytest.approx(0.28) and runs[0].width == pytest.approx(1.5)
    assert runs[0].footprint.area == pytest.approx(1.5 * 5 * 0.28)


@pytest.mark.parametrize("case", ["four lines", "window frame", "uneven", "unequal lengths", "partitions"])
def test_lines_that_are_no_run_of_treads(case):
    if case == "four lines":  # too few to be a flight
        lines = [((x, 0), (x, 1.5)) for x in (0, 0.3, 0.6, 0.9)]
    elif case == "window frame":  # glass and frame lines 0.1 m apart
        lines = [((0, y), (2.0, y)) for y in (0, 0.1, 0.2, 0.3, 0.4, 0.5)]
    elif case == "uneven":
        lines = [((x, 0), (x, 1.5)) for x in (0, 0.3, 0.55, 0.9, 1.15, 1.5)]
    elif case == "unequal lengths":  # a hatch's lines, clipped by its outline
        lines = [((0.3 * k, 0), (0.3 * k, 0.8 + 0.2 * k)) for k in range(6)]
    else:  # partitions a metre apart
        lines = [((1.2 * k, 0), (1.2 * k, 2.0)) for k in range(6)]
    assert find_stair_runs(_strokes(lines)) == []
