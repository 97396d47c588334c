"""3D edges of extruded plan walls: counts, kinds and positions on known scenes."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
from shapely.geometry import MultiPolygon, Point, Polygon, box

from mapkit.edges import extract_edges
from linemap.lmap import SegmentKind as K
from mapkit.options import BuildOptions
from mapkit.scene import Opening, Scene

T = 0.2  # wall thickness


def room_scene(openings=(), extra_walls=None, height=2.5):
    """A 4 x 3 m room (interior) with 0.2 m walls, minus the given opening gaps."""
    walls = box(-T, -T, 4 + T, 3 + T).difference(box(0, 0, 4, 3))
    for o in openings:
        walls = walls.difference(o.footprint)
    if extra_walls is not None:
        walls = walls.union(extra_walls)
    return Scene(walls=walls, openings=list(openings), free_space=MultiPolygon([box(0.2, 0.2, 3.8, 2.8)]), wall_height=height)


def kinds_of(scene, **opt):
    segs, kinds = extract_edges(scene, BuildOptions(**opt))
    return segs, kinds, Counter(K(k).label for k in kinds)


def test_closed_room():
    segs, kinds, c = kinds_of(room_scene())
    # Inner and outer rectangles at floor and ceiling; 4 + 4 corners.
    assert c == {"floor": 8, "ceiling": 8, "vertical": 8}
    v = segs[kinds == K.VERTICAL]
    assert np.allclose(v[:, 0, 2], 0) and np.allclose(v[:, 1, 2], 2.5)
    floor = segs[kinds == K.FLOOR]
    lengths = sorted(np.round(np.linalg.norm(floor[:, 1] - floor[:, 0], axis=1), 6))
    assert lengths == [3, 3, 3.4, 3.4, 4, 4, 4.4, 4.4]


def test_door_makes_jambs_and_lintel():
    door = Opening(box(1.0, -T, 1.9, 0.0), "door", 0.0, 2.1)
    segs, kinds, c = kinds_of(room_scene([door]))
    assert c["jamb"] == 4 and c["vertical"] == 8
    jambs = segs[kinds == K.JAMB]
    assert np.allclose(jambs[:, 0, 2], 0) and np.allclose(jambs[:, 1, 2], 2.1)
    assert {round(x, 6) for x in jambs[:, 0, 0]} == {1.0, 1.9}
    lintels = segs[kinds == K.LINTEL]
    assert np.allclose(lintels[:, :, 2], 2.1)
    long = lintels[np.linalg.norm(lintels[:, 1] - lintels[:, 0], axis=1) > 0.5]
    assert len(long) == 2  # one along each face of the wall
    # The floor junction is interrupted by the door; the ceiling runs across it.
    assert c["floor"] == 12 and c["ceiling"] == 8


def test_window_makes_sill_and_head():
    win = Opening(box(2.0, 3.0, 3.2, 3.0 + T), "window", 0.9, 2.1)
    segs, kinds, c = kinds_of(room_scene([win]))
    w = segs[kinds == K.WINDOW]
    assert sorted({round(z, 6) for z in w[:, 0, 2]}) == [0.9, 2.1]
    # Sill and head: two faces each, plus the two short ends across the wall.
    assert c["window"] == 8
    j = segs[kinds == K.JAMB]
    assert len(j) == 4 and np.allclose(j[:, 0, 2], 0.9) and np.allclose(j[:, 1, 2], 2.1)
    # Below the sill and above the head the wall is whole: floor and ceiling unbroken.
    assert c["floor"] == 8 and c["ceiling"] == 8


def test_concave_corner_of_l_shaped_room():
    inner = Polygon([(0, 0), (4, 0), (4, 2), (2, 2), (2, 4), (0, 4)])
    walls = inner.buffer(T, join_style="mitre").difference(inner)
    scene = Scene(walls=walls, openings=[], free_space=MultiPolygon([inner.buffer(-0.2)]), wall_height=2.5)
    segs, kinds, c = kinds_of(scene)
    v = segs[kinds == K.VERTICAL]
    assert len(v) == 12  # 6 inner corners (one concave) + 6 outer
    assert any(np.allclose(p[0, :2], [2, 2]) for p in v)


def test_round_column_makes_no_vertical_edges():
    column = Point(2, 1.5).buffer(0.3, quad_segs=16)
    segs, kinds, c = kinds_of(room_scene(extra_walls=column))
    assert c["vertical"] == 8  # only the room's corners
    floor = segs[kinds == K.FLOOR]
    assert not any(np.hypot(*(s[0, :2] - [2, 1.5])) < 0.31 for s in floor)  # facets shorter than min length


def test_collinear_pieces_are_merged():
    # A wall outline with redundant collinear vertices along its faces.
    inner = Polygon([(0, 0), (1, 0), (2, 0), (4, 0), (4, 3), (0, 3)])
    outer = Polygon([(-T, -T), (2, -T), (4 + T, -T), (4 + T, 3 + T), (-T, 3 + T)])
    scene = Scene(walls=outer.difference(inner), openings=[], free_space=MultiPolygon([box(1, 1, 2, 2)]), wall_height=2.5)
    _, _, c = kinds_of(scene)
    assert c == {"floor": 8, "ceiling": 8, "vertical": 8}


def test_min_edge_length_drops_short_pieces():
    door = Opening(box(1.0, -T, 1.9, 0.0), "door", 0.0, 2.1)
    _, _, c_keep = kinds_of(room_scene([door]), min_edge_length=0.1)
    _, _, c_drop = kinds_of(room_scene([door]), min_edge_length=0.25)
    # The 0.2 m floor edges across the wall thickness at the jambs go.
    assert c_keep["floor"] - c_drop["floor"] == 2


def test_empty_scene_has_no_edges():
    scene = Scene(walls=MultiPolygon(), openings=[], free_space=MultiPolygon(), wall_height=2.5)
    segs, kinds = extract_edges(scene)
    assert segs.shape == (0, 2, 3) and kinds.shape == (0,)


@pytest.mark.parametrize("height", [2.4, 3.0])
def test_ceiling_edges_at_wall_height(height):
    segs, kinds, _ = kinds_of(room_scene(height=height))
    assert np.allclose(segs[kinds == K.CEILING][:, :, 2], height)


def test_vertex_shared_by_two_wall_pieces_gives_one_vertical():
    # Two wall blocks touching at one corner (a common result of cleaning real plans).
    walls = MultiPolygon([box(0, 0, 1, 0.2), box(1, 0.2, 2, 0.4)])
    scene = Scene(walls=walls, openings=[], free_space=MultiPolygon([box(0, 1, 2, 2)]), wall_height=2.5)
    segs, kinds = extract_edges(scene)
    v = segs[kinds == K.VERTICAL]
    at_shared = [s for s in v if np.allclose(s[0, :2], [1, 0.2])]
    assert len(at_shared) == 1
