"""The region builder overlays only the sample pairs that can matter: those
whose visibility polygons reach the free space (``segment_regions(within=)``)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from linemap.camera import Camera
from mapkit.visibility import Occluders, Sight, segment_regions_within
from mapkit.vir import build_regions
from mapkit_harness.plans import single_room

CAMERA = Camera(640, 480, 457.0, 457.0, 320.0, 240.0, 1.2, 0.0)
RANGE, MIN_LEN = 10.0, 0.3


def _room_with_outer_faces():
    """A 6 x 4 m room (walls 0.2 m thick) with its inner-face edges, plus
    edges on the outside of its walls: a floor edge along the south wall's
    outer face and a vertical at the outer south-west corner."""
    scene = single_room(6.0, 4.0)
    outer = np.array([[[1.0, -0.2, 0.0], [4.0, -0.2, 0.0]], [[-0.2, -0.2, 0.0], [-0.2, -0.2, 2.5]]])
    return scene, np.concatenate([scene.segments, outer]), len(scene.segments)


def _regions(segments, scene, within=None):
    sight = Sight(CAMERA.height_m, CAMERA.elevation_range(), RANGE, MIN_LEN)
    return segment_regions_within(segments, Occluders.from_geometry(scene.walls), sight, within)


def test_faces_seen_only_from_outside_get_no_region():
    scene, segments, n_inner = _room_with_outer_faces()
    everywhere = _regions(segments, scene)
    inside = _regions(segments, scene, within=scene.free_space)
    # Without a free space the outer faces are seen from outside the room...
    assert all(not g.is_empty for g in everywhere.regions[n_inner:])
    # ...which the free space never reaches: no overlays, empty regions.
    assert all(g.is_empty for g in inside.regions[n_inner:])
    # The faces seen from the room keep their regions exactly.
    assert all(a.equals_exact(b, 0.0) for a, b in zip(everywhere.regions[:n_inner], inside.regions[:n_inner]))
    # The stats count every pair, overlaid or not (the map's META does not change).
    assert inside.stats["sample_pairs"] == everywhere.stats["sample_pairs"]


def test_outer_faces_are_listed_nowhere_in_the_partition():
    scene, segments, n_inner = _room_with_outer_faces()
    part = build_regions(segments, scene.walls, scene.free_space, CAMERA)
    listed = np.unique(np.concatenate(part.lists))
    assert n_inner not in listed and n_inner + 1 not in listed
    assert set(range(n_inner)) <= set(listed.tolist())
    assert sum(p.area for p in part.polygons) == pytest.approx(shapely.area(scene.free_space))


def test_points_walled_off_from_the_free_space_are_not_swept():
    """A room no opening leads into, seen from a free space outside it: the
    room's points are skipped (their polygons lie in the room), and its
    faces get no region, as if swept and found to see nothing outside."""
    from mapkit.tolerances import CIRCLE_SIDES
    from mapkit.visibility import _cut_off

    scene = single_room(6.0, 4.0)
    outside = shapely.box(7.0, 0.0, 9.0, 4.0)
    occ = Occluders.from_geometry(scene.walls)
    box = RANGE / np.cos(np.pi / CIRCLE_SIDES) + 0.01
    xy = np.array([[0.1, 0.1], [3.0, 2.0], [6.25, 2.0], [8.0, 1.0], [3.0, -0.1]])  # room x2, outside x2, in a wall
    assert _cut_off(xy, occ, box, outside).tolist() == [True, True, False, False, False]
    assert not _cut_off(xy, occ, box, scene.free_space)[:2].any()
    res = _regions(scene.segments, scene, within=outside)
    assert all(g.is_empty for g in res.regions)


def test_pairs_whose_annulus_stays_away_are_left_out_and_their_points_not_swept():
    """A 24 x 24 m room, the free space asked for a 2 m square in a corner
    (a tile's, say): the pairs whose annulus (the sight range around the
    pair, as ``annuli`` draws it) stays 1 mm away from it are left out, the
    points only they use are not swept, and every region is unchanged over
    the square."""
    from shapely.geometry import box

    from mapkit.tolerances import VIS_WITHIN_MARGIN, VIS_VERTICAL_XY
    from mapkit.visibility import _samples, _samples_reaching, annuli

    scene = single_room(24.0, 24.0)
    within = box(0.0, 0.0, 2.0, 2.0)
    sight = Sight(CAMERA.height_m, CAMERA.elevation_range(), RANGE, MIN_LEN)
    segs = np.asarray(scene.segments, dtype=float)
    samples = _samples(segs, np.linalg.norm(segs[:, 1, :2] - segs[:, 0, :2], axis=1) <= VIS_VERTICAL_XY, sight)
    kept, used = _samples_reaching(samples, sight, within)
    assert 0 < len(kept.pair_seg) < len(samples.pair_seg) and 0 < used.sum() < len(samples.xy)
    left = set(zip(kept.pair_seg.tolist(), kept.pair_a.tolist(), kept.pair_b.tolist()))
    dropped = np.array([p not in left for p in zip(samples.pair_seg.tolist(), samples.pair_a.tolist(),
                                                     samples.pair_b.tolist())])
    far = annuli(samples.pair_mid[dropped], samples.pair_rin[dropped], samples.pair_rout[dropped])
    assert (shapely.distance(within, far) > VIS_WITHIN_MARGIN).all()
    assert set(np.nonzero(used)[0]) == set(kept.pair_a) | set(kept.pair_b) | set(kept.vert_keys)
    everywhere, near = _regions(segs, scene), _regions(segs, scene, within=within)
    for a, b in zip(everywhere.regions, near.regions):
        assert shapely.symmetric_difference(a.intersection(within), b.intersection(within)).area < 1e-9
