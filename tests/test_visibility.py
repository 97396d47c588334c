"""Visibility polygons, distance bands and per-segment visibility regions,
against the definition (docs/visibility.md) and hand-worked scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import shapely.affinity
from shapely.geometry import Point, box
from mapkit_harness.visibility_oracle import VisibilityOracle, random_points

from linemap.lmap import SegmentKind
from mapkit.tolerances import OCCLUSION_SHRINK
from mapkit_harness.plans import apartment, l_room, single_room, two_rooms
from mapkit.visibility import (
    Occluders,
    annuli,
    clip_segments,
    distance_band,
    segment_regions,
    vertical_distance_band,
    vertical_extent,
    visibility_polygon,
)
from linemap.camera import Camera

CAMERA = Camera(640, 480, 457.0, 457.0, 320.0, 240.0, 1.2, 0.0)  # +-27.7 deg vertically
E_MIN, E_MAX = CAMERA.elevation_range()
RANGE, MIN_LEN = 10.0, 0.3


def regions_for(scene, **kw):
    occ = Occluders.from_geometry(scene.walls)
    return segment_regions(scene.segments, occ, CAMERA.height_m, (E_MIN, E_MAX), max_range=RANGE, min_visible_length=MIN_LEN, **kw)


def oracle_for(scene):
    return VisibilityOracle(scene.segments, scene.walls, CAMERA.height_m, (E_MIN, E_MAX), RANGE, MIN_LEN)


def listed_at(regions, q) -> np.ndarray:
    """Ids whose visibility region contains q (up to float noise)."""
    return np.nonzero(shapely.distance(regions, Point(q)) <= 1e-6)[0]


# --------------------------------------------------------------------------
# Distance bands


def test_camera_fixture_is_symmetric_27_7_degrees():
    assert E_MAX == pytest.approx(math.atan(240 / 457), abs=1e-3)
    assert E_MIN == pytest.approx(-E_MAX, abs=1e-9)


@pytest.mark.parametrize(
    "elev",
    [(E_MIN, E_MAX), (math.radians(-60), math.radians(-5)), (math.radians(5), math.radians(40)), (math.radians(-89.9), math.radians(89.9))],
)
def test_distance_band_matches_definition(elev):
    """For each height, the band [dmin, dmax] is exactly the set of horizontal
    distances where range and elevation hold (checked on a fine grid)."""
    z = np.array([0.0, 0.5, 1.2, 2.1, 2.5, 5.0, -9.0, 11.5])
    dmin, dmax = distance_band(z, 1.2, *elev, RANGE)
    d = np.linspace(1e-4, 12.0, 120001)
    for zi, lo, hi in zip(z, dmin, dmax):
        el = np.arctan2(zi - 1.2, d)
        ok = (np.hypot(d, zi - 1.2) <= RANGE) & (el >= elev[0]) & (el <= elev[1])
        if not ok.any():
            assert hi < 0, zi
            continue
        assert lo <= d[ok].min() + 1e-9 and d[ok].max() <= hi + 1e-9, zi
        assert d[ok].min() - lo < 2e-4 and hi - d[ok].max() < 2e-4, zi  # tight, not just a bound


def test_floor_near_field_is_h_over_tan_elevation():
    dmin, dmax = distance_band(np.array([0.0]), 1.2, E_MIN, E_MAX, RANGE)
    assert dmin[0] == pytest.approx(1.2 / math.tan(-E_MIN))
    assert dmax[0] == pytest.approx(math.sqrt(RANGE**2 - 1.2**2))


def test_vertical_band_matches_extent_on_a_grid():
    z0 = np.array([0.0, 0.0, 2.1, 0.0, 1.0])
    z1 = np.array([2.5, 0.2, 2.5, 2.5, 1.1])
    need = np.minimum(MIN_LEN, z1 - z0)
    dmin, dmax = vertical_distance_band(z0, z1, need, 1.2, E_MIN, E_MAX, RANGE)
    d = np.linspace(0.0, RANGE, 200001)
    for i in range(len(z0)):
        ok = vertical_extent(d, z0[i], z1[i], 1.2, E_MIN, E_MAX, RANGE) >= need[i] - 1e-12
        if not ok.any():
            assert dmax[i] < 0
            continue
        assert dmin[i] <= d[ok].min() and d[ok].max() <= dmax[i]
        assert d[ok].min() - dmin[i] < 1e-4 and dmax[i] - d[ok].max() < 1e-4
    # A 2.5 m corner seen from 0.2 m shows only 2 * 0.2 * tan(27.7 deg) = 0.21 m < 0.3 m.
    assert dmin[0] == pytest.approx(MIN_LEN / 2 / math.tan(E_MAX), abs=1e-5)


def test_annuli_are_supersets_of_their_true_shape():
    c = np.array([[1.0, 2.0], [0.0, 0.0]])
    ann = annuli(c, np.array([0.5, 0.0]), np.array([3.0, 2.0]))
    rng = np.random.default_rng(3)
    for k, (r_in, r_out) in enumerate([(0.5, 3.0), (0.0, 2.0)]):
        ang = rng.uniform(0, 2 * np.pi, 2000)
        rad = rng.uniform(r_in, r_out, 2000)
        pts = c[k] + rad[:, None] * np.stack([np.cos(ang), np.sin(ang)], 1)
        assert shapely.covers(ann[k], shapely.points(pts)).all()
        assert ann[k].area < np.pi * (r_out**2 - r_in**2) * 1.01


# --------------------------------------------------------------------------
# Visibility polygons


def test_clip_segments_to_box():
    a = np.array([[-5.0, 0.5], [0.2, 0.2], [5.0, 5.0], [0.5, -1.0]])
    b = np.array([[5.0, 0.5], [0.8, 0.8], [6.0, 6.0], [0.5, 2.0]])
    ca, cb = clip_segments(a, b, np.zeros(2), np.ones(2))
    assert np.allclose(ca, [[0, 0.5], [0.2, 0.2], [0.5, 0.0]])
    assert np.allclose(cb, [[1, 0.5], [0.8, 0.8], [0.5, 1.0]])


def _sight_clear(q, p, occluders):
    return not shapely.LineString([q, p]).intersects(occluders)


@pytest.mark.parametrize("case", ["apartment", "rotated_apartment", "wall_across_square"])
def test_visibility_polygon_matches_sight_lines(case):
    """Membership in the polygon agrees with a direct sight-line test at random
    points, except within 2 mm of the outline (the shrink tolerances)."""
    rng = np.random.default_rng(11)
    if case in ("apartment", "rotated_apartment"):
        walls = apartment().walls
        sources = apartment().segments[::7, 0, :2]
        radius = 10.0
        if case == "rotated_apartment":  # no wall parallel to an axis
            walls = shapely.affinity.rotate(walls, 23.0, origin=(0, 0))
            c, s = math.cos(math.radians(23.0)), math.sin(math.radians(23.0))
            sources = sources @ np.array([[c, s], [-s, c]])
    else:
        # A long wall crosses the sides of the range square: the outline must
        # follow the wall to the square's side, not cut across to the next ray.
        walls = box(-20, 0, 20, 0.2)
        sources = np.array([[0.0, 1.0], [1.3, 2.7]])
        radius = 3.0
    occ = Occluders.from_geometry(walls)
    shrunk = shapely.buffer(walls, -occ_shrink(), join_style="mitre")
    checked = 0
    for p in sources:
        poly = shapely.Polygon(visibility_polygon(p, occ, radius))
        assert poly.is_valid
        qs = p + rng.uniform(-radius, radius, size=(300, 2))
        qs = qs[~shapely.contains_xy(walls, qs[:, 0], qs[:, 1])]
        for q in qs:
            if poly.exterior.distance(Point(q)) < 2e-3:
                continue
            assert poly.contains(Point(q)) == _sight_clear(q, p, shrunk), (p, q)
            checked += 1
    assert checked > 200


def occ_shrink():
    """The builder's shrink, read back from the edges it made."""
    occ = Occluders.from_geometry(box(0, 0, 1, 1))
    return float(occ.edges[:, :, 0].min())


def test_builder_shrinks_at_least_twice_the_definition():
    """Brute-force checks shrink by 2 x OCCLUSION_SHRINK; the builder must see
    at least as much, so it shrinks by more."""
    assert occ_shrink() > 2 * OCCLUSION_SHRINK


def test_source_on_a_wall_face_sees_the_half_plane_in_front():
    walls = box(-5, -0.2, 5, 0.0)  # face y = 0, the source stands on it
    occ = Occluders.from_geometry(walls)
    poly = shapely.Polygon(visibility_polygon(np.array([0.0, 0.0]), occ, 4.0))
    assert poly.contains(Point(3.0, 0.01)) and poly.contains(Point(-3.9, 3.9))
    assert not poly.contains(Point(0.0, -0.1))
    assert poly.area == pytest.approx(32.0, rel=1e-3)


# --------------------------------------------------------------------------
# Hand-worked scenes (oracle and builder both)


def _ids(scene, kind=None, where=None):
    segs = scene.segments
    sel = np.ones(len(segs), dtype=bool)
    if kind is not None:
        sel &= scene.kinds == kind
    if where is not None:
        sel &= np.array([where(s) for s in segs])
    return set(np.nonzero(sel)[0].tolist())


def test_small_room_centre_sees_only_the_corners():
    """3 x 3 m room from its centre: every floor point is nearer than
    1.2 / tan(27.7 deg) = 2.28 m at 1.5..2.12 m, every ceiling point nearer than
    1.3 / tan(27.7 deg) = 2.47 m: only the four vertical corners are seen
    (at 2.12 m their visible extent is 2.2 m)."""
    scene = single_room(3.0, 3.0)
    corners = _ids(scene, SegmentKind.VERTICAL)
    assert len(corners) == 4
    q = (1.5, 1.5)
    assert set(oracle_for(scene).visible(q).tolist()) == corners
    assert set(listed_at(regions_for(scene).regions, q).tolist()) == corners


def test_room_centre_sees_everything():
    """6 x 4 m room from (3, 2): the nearest floor point of each wall is 2 m
    away but at least 1.9 m of every wall lies beyond 2.28 m (and beyond
    2.47 m for the ceiling): all 12 segments are visible."""
    scene = single_room(6.0, 4.0)
    assert len(scene.segments) == 12
    assert oracle_for(scene).visible((3.0, 2.0)).tolist() == list(range(12))
    assert listed_at(regions_for(scene).regions, (3.0, 2.0)).tolist() == list(range(12))


def test_l_room_corner_hides_the_far_wing():
    """From (7, 1.5) in the L's long arm, the reflex corner (3, 3) hides the
    wing's end wall (y = 8) while the wing's left wall is seen up to y = 4.1."""
    scene = l_room()
    q = (7.0, 1.5)
    end_wall = _ids(scene, where=lambda s: s[0, 1] == 8 and s[1, 1] == 8)
    left_wall = _ids(scene, where=lambda s: s[0, 0] == 0 and s[1, 0] == 0 and s[0, 2] == s[1, 2])
    assert len(end_wall) == 4 and len(left_wall) == 2  # end wall: floor, ceiling, two corners
    vis = set(oracle_for(scene).visible(q).tolist())
    assert not (end_wall & vis) and left_wall <= vis
    listed = set(listed_at(regions_for(scene).regions, q).tolist())
    assert vis <= listed and not (end_wall & listed)


def test_door_shows_the_far_wall_not_the_side_walls():
    """From (2, 2) in the left room, the 0.9 m door at x = 5..5.2 shows the
    right room's far wall (x = 10.2, seen for y in 0.72..3.02) but not its
    side wall y = 0 (a sight line to it would pass the door below y = 1.5)."""
    scene = two_rooms()
    q = (2.0, 2.0)
    far = _ids(scene, where=lambda s: s[0, 0] == 10.2 and s[1, 0] == 10.2 and s[0, 2] == s[1, 2])
    side = _ids(scene, where=lambda s: s[0, 1] == 0 and s[1, 1] == 0 and min(s[0, 0], s[1, 0]) >= 5.2)
    assert len(far) == 2 and len(side) == 4  # side wall: floor, ceiling, two corners
    vis = set(oracle_for(scene).visible(q).tolist())
    assert far <= vis and not (side & vis)
    listed = set(listed_at(regions_for(scene).regions, q).tolist())
    assert vis <= listed and not (side & listed)


def test_max_range_cuts_the_far_end_of_a_hall():
    """14 x 3 m hall from (0.5, 1.5): the end wall (x = 14) is 13.5 m away."""
    scene = single_room(14.0, 3.0)
    q = (0.5, 1.5)
    end = _ids(scene, where=lambda s: s[0, 0] == 14 and s[1, 0] == 14)
    assert len(end) == 4  # floor, ceiling, two corners
    vis = set(oracle_for(scene).visible(q).tolist())
    listed = set(listed_at(regions_for(scene).regions, q).tolist())
    assert not (end & vis) and not (end & listed) and vis <= listed


def test_min_visible_length_drops_a_sliver_behind_a_corner():
    """A wall seen only for its last few centimetres past a corner is not
    visible; moving so that more than 0.3 m shows makes it visible."""
    scene = l_room()
    oracle = oracle_for(scene)
    # End wall of the long arm (x = 8, y 0..3) seen from the wing, past (3, 3).
    end = _ids(scene, SegmentKind.FLOOR, where=lambda s: s[0, 0] == 8 and s[1, 0] == 8)
    (i,) = end
    # From (2.5, y0) the sight line to (8, y) passes x = 3 below the corner
    # iff y <= 3 - 10 (y0 - 3): the wall shows from its foot y = 0 up to there.
    q_sliver = (2.5, 3.29)  # shows 0.1 m
    q_enough = (2.5, 3.24)  # shows 0.6 m
    assert i not in oracle.visible(q_sliver)
    assert i in oracle.visible(q_enough)
    regions = regions_for(scene).regions
    assert i in listed_at(regions, q_enough)


# --------------------------------------------------------------------------
# The superset property of R_S at random points


@pytest.mark.parametrize("make", [two_rooms, l_room])
def test_segment_regions_hold_every_visible_segment(make):
    scene = make()
    res = regions_for(scene)
    oracle = oracle_for(scene)
    rng = np.random.default_rng(5)
    extra = []
    for q in random_points(scene.free_space, 60, rng):
        vis = oracle.visible(q)
        listed = listed_at(res.regions, q)
        assert set(vis.tolist()) <= set(listed.tolist()), q
        extra.append(len(listed) - len(vis))
    assert np.mean(extra) < 0.25 * len(scene.segments)  # a superset, not everything
    assert res.stats["visibility_polygons"] > 0 and res.stats["sample_pairs"] > 0


def test_a_segment_buried_in_a_wall_is_seen_from_nowhere():
    """5 mm inside a wall solid: every sight line crosses the solid."""
    scene = single_room(6.0, 4.0)
    buried = np.array([[[1.0, -0.005, 0.0], [3.0, -0.005, 0.0]], [[2.0, -0.1, 0.0], [2.0, -0.1, 2.5]]])
    occ = Occluders.from_geometry(scene.walls)
    res = segment_regions(buried, occ, CAMERA.height_m, (E_MIN, E_MAX), max_range=RANGE, min_visible_length=MIN_LEN)
    assert all(g.is_empty for g in res.regions)
    oracle = VisibilityOracle(buried, scene.walls, CAMERA.height_m, (E_MIN, E_MAX), RANGE, MIN_LEN)
    assert len(oracle.visible((3.0, 2.0))) == 0


def test_self_intersecting_walls_are_repaired_not_dropped():
    bowtie = shapely.Polygon([(0, 0), (2, 2), (2, 0), (0, 2)])  # invalid: crosses itself
    assert not bowtie.is_valid
    occ = Occluders.from_geometry(bowtie)
    assert len(occ.edges) == 6 and occ.geometry.area == pytest.approx(2.0, rel=0.03)  # two triangles, shrunk
    poly = shapely.Polygon(visibility_polygon(np.array([-1.0, 1.0]), occ, 5.0))
    assert not poly.contains(Point(3.0, 1.0))  # behind the bow tie's waist


# --------------------------------------------------------------------------
# The batched sweep (mapkit.visibility_batch) against the per-point one


@pytest.mark.parametrize("plan,options", [
    ("maps/flat.dxf", {}),
    ("tests/data/barcelona-pavilion.dxf", {"walls": ["Walls", "Columns"], "windows": ["Crystal"]}),
])
@pytest.mark.slow
def test_batched_visibility_polygons_equal_the_per_point_sweep(plan, options):
    """Bit for bit, at random free-space points and at wall vertices (rays
    through shared vertices, grazing faces) of a real plan."""
    from pathlib import Path

    from mapkit.importers import load_scene
    from mapkit.options import BuildOptions
    from mapkit.visibility_batch import polygons_of, visibility_polygons

    scene = load_scene(Path(__file__).resolve().parent.parent / plan, BuildOptions(**options))
    occ = Occluders.from_geometry(scene.walls)
    rng = np.random.default_rng(3)
    corners = occ.edges[rng.choice(len(occ.edges), 100), 0]
    points = np.concatenate([random_points(scene.free_space, 300, rng), corners])
    for radius in (RANGE, 2.0):
        coords, owner = visibility_polygons(points, occ, radius)
        assert np.array_equal(np.unique(owner), np.arange(len(points)))
        got = np.split(coords, np.cumsum(np.bincount(owner, minlength=len(points)))[:-1])
        for p, g in zip(points, got):
            assert np.array_equal(g, visibility_polygon(p, occ, radius))
        polys = polygons_of(coords, owner, len(points))
        assert shapely.equals_exact(polys[0], shapely.Polygon(got[0]), 0.0)
        # In threads, over chunks of the points: the same arrays.
        coords3, owner3 = visibility_polygons(points, occ, radius, workers=3)
        assert np.array_equal(coords3, coords) and np.array_equal(owner3, owner)


def test_polygons_of_keeps_points_without_vertices_in_place():
    from mapkit.visibility_batch import polygons_of

    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    polys = polygons_of(np.concatenate([square, square + 5.0]), np.repeat([0, 2], 4), 4)
    assert [p.is_empty for p in polys] == [False, True, False, True]
    assert polys[2].equals(shapely.Polygon(square + 5.0))
