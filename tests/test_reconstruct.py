"""Plan reconstruction from synthetic strokes with known answers, and the real plans."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import box

from mapkit.errors import MapkitError, NoFreeSpaceError, NoWallsError
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.importers.dxf.reconstruct import reconstruct_scene
from mapkit.importers.dxf.openings import opening_width
from mapkit.importers.dxf.strokes import PlanDrawing, Stroke
from mapkit.importers.dxf.walls import build_walls
from mapkit.tolerances import THIN_WALL

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"


def line(a, b, layer="W", group=None) -> Stroke:
    return Stroke(np.array([a, b], dtype=float), layer=layer, group=group)


def outline(x0, y0, x1, y1, layer="W") -> Stroke:
    return Stroke(np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], dtype=float), closed=True, layer=layer)


def double_wall_room(w=6.0, h=4.0, t=0.2, gap=(2.0, 2.9), caps=False) -> list[Stroke]:
    """Room [0, w] x [0, h] with walls of thickness t outside it, a gap in the bottom wall."""
    g0, g1 = gap
    s = [
        line((0, 0), (g0, 0)), line((g1, 0), (w, 0)),
        line((-t, -t), (g0, -t)), line((g1, -t), (w + t, -t)),
        line((w, 0), (w, h)), line((w, h), (0, h)), line((0, h), (0, 0)),
        line((w + t, -t), (w + t, h + t)), line((w + t, h + t), (-t, h + t)), line((-t, h + t), (-t, -t)),
    ]
    if caps:
        s += [line((g0, 0), (g0, -t)), line((g1, 0), (g1, -t))]
    return s


def door(g0: float, width: float, group=1) -> list[Stroke]:
    """Leaf hinged at (g0, 0) standing open into the room, swing arc down to (g0 + width, 0)."""
    theta = np.radians(np.linspace(0, 90, 19))
    arc = np.c_[g0 + width * np.cos(theta), width * np.sin(theta)]
    return [line((g0, 0), (g0, width), "D", group), Stroke(arc, layer="D", group=group)]


def scene_of(walls, doors=(), windows=(), floor=(), **opts):
    drawing = PlanDrawing(strokes={"walls": list(walls), "doors": list(doors), "windows": list(windows), "floor": list(floor)})
    return reconstruct_scene(drawing, BuildOptions(**opts), {})


# ---- walls -------------------------------------------------------------------


@pytest.mark.parametrize("caps", [False, True])
def test_double_line_wall_becomes_one_solid(caps):
    strokes = [line((0, 0), (4, 0)), line((0, 0.2), (4, 0.2))]
    if caps:
        strokes += [line((0, 0), (0, 0.2)), line((4, 0), (4, 0.2))]
    result = build_walls(strokes, max_wall_thickness=0.8)
    assert len(result.walls.geoms) == 1
    assert result.walls.area == pytest.approx(0.8, abs=1e-9)
    assert result.walls.symmetric_difference(box(0, 0, 4, 0.2)).area < 1e-9


def test_parallel_lines_farther_than_max_thickness_stay_thin_walls():
    strokes = [line((0, 0), (4, 0)), line((0, 1.0), (4, 1.0))]
    walls = build_walls(strokes, max_wall_thickness=0.8).walls
    assert len(walls.geoms) == 2
    # Each line thickened to THIN_WALL, with square caps adding half of it at each end.
    assert walls.area == pytest.approx(2 * (4 + THIN_WALL) * THIN_WALL, rel=1e-6)


def test_nested_outline_and_small_column_are_solids_loose_line_is_thin():
    strokes = [outline(0, 0, 10, 8), outline(2, 2, 4, 5), outline(7, 6, 7.4, 6.4), line((6, 1), (6, 3))]
    result = build_walls(strokes, max_wall_thickness=0.8)
    walls = result.walls
    assert walls.contains(box(2.01, 2.01, 3.99, 4.99))  # the block is filled
    assert walls.contains(box(7.01, 6.01, 7.39, 6.39))  # the column is filled
    # The 0.4 m column is thinner than max_wall_thickness: wall material, not a "block".
    assert result.counts["solid_blocks"] == 1
    assert not walls.contains(shapely.Point(5, 4))  # the room is not
    assert walls.intersection(box(5.5, 0.5, 6.5, 3.5)).area == pytest.approx((2 + THIN_WALL) * THIN_WALL, rel=1e-6)


def test_drawing_dirt_gaps_duplicates_overlaps_still_enclose_the_room():
    clean = scene_of([line((0, 0), (8, 0)), line((8, 0), (8, 5)), line((8, 5), (0, 5)), line((0, 5), (0, 0))])
    dirty = scene_of(
        [
            line((0, 0), (7.99, 0)),  # 1 cm short of the corner
            line((8, 0), (8, 5)), line((8, 0), (8, 5)),  # duplicated
            line((8, 5), (3, 5)), line((4, 5), (0, 5)),  # overlapping pieces
            line((0, 5), (0, 0.005)),  # 5 mm gap
        ]
    )
    assert clean.info["interior"] == dirty.info["interior"] == "enclosed"
    assert dirty.free_space.area == pytest.approx(clean.free_space.area, rel=1e-3)
    assert dirty.info["counts"]["gaps_closed"] >= 2


# ---- openings ------------------------------------------------------------------


@pytest.mark.parametrize("caps", [False, True])
def test_door_opening_spans_the_gap_across_the_wall(caps):
    scene = scene_of(double_wall_room(caps=caps), doors=door(2.0, 0.9), door_height=2.05)
    (opening,) = scene.openings
    assert opening.kind == "door" and opening.sill == 0.0 and opening.head == 2.05
    assert opening_width(opening.footprint) == pytest.approx(0.9, abs=1e-6)
    assert opening.footprint.symmetric_difference(box(2.0, -0.2, 2.9, 0.0)).area < 1e-6
    assert opening.footprint.intersection(scene.walls).area < 1e-9
    # The door gap is shut when deciding what is inside, and walkable after.
    assert scene.info["interior"] == "enclosed"
    assert len(scene.free_space.geoms) == 1


def test_window_is_an_opening_and_an_obstacle_but_not_a_wall():
    glass = [line((2.0, -0.07), (2.9, -0.07), "G"), line((2.0, -0.13), (2.9, -0.13), "G")]
    scene = scene_of(double_wall_room(caps=True), windows=glass, window_sill=0.8, window_head=2.0)
    (opening,) = scene.openings
    assert (opening.kind, opening.sill, opening.head) == ("window", 0.8, 2.0)
    assert opening_width(opening.footprint) == pytest.approx(0.9, abs=1e-6)
    assert scene.obstacles.contains(opening.footprint.buffer(-1e-6))
    assert scene.walls.intersection(opening.footprint).area < 1e-9
    assert scene.info["interior"] == "enclosed"


def test_door_between_two_rooms_joins_their_free_space():
    walls = [outline(0, 0, 10, 4), line((5, 0), (5, 1.5)), line((5, 2.4), (5, 4))]
    theta = np.radians(np.linspace(0, 90, 19))
    swing = [line((5, 1.5), (5.9, 1.5), "D", 3), Stroke(np.c_[5 + 0.9 * np.cos(theta), 1.5 + 0.9 * np.sin(theta)], layer="D", group=3)]
    scene = scene_of(walls, doors=swing)
    (opening,) = scene.openings
    assert opening_width(opening.footprint) == pytest.approx(0.9 - THIN_WALL, abs=1e-6)  # thin walls' square caps
    assert len(scene.free_space.geoms) == 1
    without = scene_of(walls)
    assert len(without.free_space.geoms) == 1  # the gap is open anyway...
    assert without.openings == []  # ...but only a drawn door makes an opening


# ---- free space ----------------------------------------------------------------


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    w=st.floats(3.0, 20.0), h=st.floats(3.0, 20.0), r=st.floats(0.0, 0.6),
)
def test_free_space_is_the_room_shrunk_by_the_robot_radius(w, h, r):
    scene = scene_of([outline(0, 0, w, h)], robot_radius=r)
    inner = (w - THIN_WALL - 2 * r) * (h - THIN_WALL - 2 * r)
    assert scene.free_space.area == pytest.approx(inner, rel=1e-9, abs=1e-9)
    assert scene.walls.distance(scene.free_space) == pytest.approx(r, abs=1e-6)


def test_open_plan_uses_the_floor_layer_else_it_is_refused():
    walls = [line((0, 0), (12, 0)), line((0, 6), (4, 6))]
    with pytest.raises(NoFreeSpaceError, match="enclose no building.*--floor"):
        scene_of(walls)  # two walls surround nothing, even with their gaps bridged
    floor = [outline(0, 0, 12, 6, layer="F")]
    floored = scene_of(walls, floor=floor)
    assert floored.info["interior"] == "floor layer"
    assert floored.free_space.area > 60.0


def test_no_free_space_is_a_user_error():
    with pytest.raises(MapkitError, match=r"no free space .* lower --robot-radius"):
        scene_of([outline(0, 0, 1.0, 1.0)], robot_radius=0.5)


def test_no_wall_geometry_is_a_user_error():
    with pytest.raises(NoWallsError, match="--walls"):
        scene_of([])


# ---- the real plans ------------------------------------------------------------


@pytest.fixture(scope="module")
def barcelona():
    return load_scene(DATA / "barcelona-pavilion.dxf", BuildOptions(walls=["Walls", "Columns"], windows=["Crystal"]))


@pytest.fixture(scope="module")
def thehouse():
    return load_scene(DATA / "thehouse.dxf", BuildOptions(walls=["s001-*"]))


@pytest.fixture(scope="module")
def flat():
    return load_scene(ROOT / "maps" / "flat.dxf", BuildOptions())


def test_barcelona_pavilion(barcelona):
    info = barcelona.info
    assert info["units"] == "m"
    assert info["layers"]["walls"] == ["Columns", "Walls"] and info["layers"]["windows"] == ["Crystal"]
    assert info["interior"] == "floor layer"
    # Wall slabs about 0.2 m thick (drawn as 8 closed outlines, some slabs
    # meeting in L shapes) and 8 cruciform steel columns of 0.01 m2 each.
    assert 15 < barcelona.walls.area < 22
    assert info["counts"]["wall_faces"] == 8 + 8
    # The podium's floor tiles up to the walls and glass (the annex's front row
    # too), one part: 513 m2; the light box between two glass panes is none.
    assert 480 < barcelona.free_space.area < 550
    assert len(barcelona.free_space.geoms) == 1
    assert sum(o.kind == "door" for o in barcelona.openings) >= 4
    assert barcelona.obstacles.area > 3  # the glass screens
    assert barcelona.walls.intersection(barcelona.obstacles).area < 0.5


def test_thehouse(thehouse):
    info = thehouse.info
    assert info["units"] == "m" and any("no units" in w for w in info["warnings"])
    assert info["interior"] == "enclosed"
    # Six solid blocks (about 283 m2 together) and the 0.6 m wide wall, inside a single-line envelope.
    assert info["counts"]["solid_blocks"] == 6
    assert 280 < thehouse.walls.area < 300
    assert 650 < thehouse.free_space.area < 730
    assert thehouse.openings == []


def test_example_flat_needs_no_options(flat):
    info = flat.info
    assert info["units"] == "mm"
    assert info["layers"]["walls"] == ["A-COLS", "A-WALL"]
    assert info["layers"]["doors"] == ["A-DOOR"] and info["layers"]["windows"] == ["A-GLAZ"]
    assert sum(o.kind == "door" for o in flat.openings) == 7
    assert sum(o.kind == "window" for o in flat.openings) == 6
    assert all(0.5 < opening_width(o.footprint) < 2.0 for o in flat.openings)
    assert len(flat.free_space.geoms) == 1  # every room reachable through its door
    assert 55 < flat.free_space.area < 70
    assert 10 < flat.walls.area < 15
    assert flat.wall_height == BuildOptions().wall_height
