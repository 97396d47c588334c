"""The VIR partition: the superset property at random points against the
brute-force reference, tightness, and that the regions tile the free space."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, box
from mapkit_harness.visibility_oracle import VisibilityOracle, random_points

from mapkit.assemble import assemble_map
from linemap.lmap import load_map, save_map
from mapkit.vir import RegionSettings, build_regions
from mapkit_harness.plans import apartment, scene_from_walls, single_room, two_rooms
from linemap.camera import Camera

CAMERA = Camera(640, 480, 457.0, 457.0, 320.0, 240.0, 1.2, 0.0)
EPS = 0.05


@pytest.fixture(scope="module")
def flat():
    scene = apartment()
    part = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, RegionSettings(eps=EPS))
    return scene, part


@pytest.fixture(scope="module")
def samples(flat):
    """300 seeded free-space points with their reference visible sets."""
    scene, _ = flat
    oracle = VisibilityOracle(scene.segments, scene.walls, CAMERA.height_m, CAMERA.elevation_range(), 10.0, 0.3)
    pts = random_points(scene.free_space, 300, np.random.default_rng(2024))
    return pts, [oracle.visible(q) for q in pts]


@pytest.mark.slow
def test_every_visible_segment_is_listed_by_every_region_within_eps(flat, samples):
    _, part = flat
    polys = np.array(part.polygons + [None])[:-1]
    tree = shapely.STRtree(polys)
    checked = 0
    for q, vis in zip(*samples):
        near = tree.query(Point(q), predicate="dwithin", distance=EPS)
        assert len(near), q
        for r in near:
            missing = np.setdiff1d(vis, part.lists[r])
            assert len(missing) == 0, f"region {r} near {q} lacks {missing}"
            checked += 1
    assert checked > 300  # some points see several regions within eps


@pytest.mark.slow
def test_lists_are_tight(flat, samples):
    """The list of the region holding q is close to what q really sees."""
    _, part = flat
    polys = np.array(part.polygons + [None])[:-1]
    tree = shapely.STRtree(polys)
    listed, seen = [], []
    for q, vis in zip(*samples):
        inside = tree.query(Point(q), predicate="intersects")
        listed.append(max(len(part.lists[r]) for r in inside))
        seen.append(len(vis))
    ratio = np.mean(listed) / np.mean(seen)
    assert 1.0 <= ratio < 1.6, ratio
    assert np.mean(seen) > 10  # the scene is not trivial
    assert part.stats["mean_list_length"] < 0.5 * len(flat[0].segments)


def test_regions_tile_the_free_space(flat):
    scene, part = flat
    polys = np.array(part.polygons + [None])[:-1]
    assert shapely.is_valid(polys).all()
    total = shapely.area(polys).sum()
    assert total == pytest.approx(scene.free_space.area, rel=1e-6)
    assert shapely.union_all(polys).symmetric_difference(scene.free_space).area < 1e-6
    a, b = shapely.STRtree(polys).query(polys, predicate="overlaps")
    pairs = a < b
    overlap = shapely.area(shapely.intersection(polys[a[pairs]], polys[b[pairs]]))
    assert overlap.sum() < 1e-6


def test_lists_sorted_unique_int64_and_stats_json(flat):
    import json

    scene, part = flat
    assert len(part.polygons) == len(part.lists) == part.stats["regions"]
    for lst in part.lists:
        assert lst.dtype == np.int64 and (np.diff(lst) > 0).all()
        assert lst.min() >= 0 and lst.max() < len(scene.segments)
    json.dumps(part.stats)
    assert part.stats["time_total_s"] > 0 and part.stats["quadtree_leaves"] >= part.stats["regions"]


def test_neighbouring_ids_are_neighbouring_regions(flat):
    """Morton order: consecutive regions are close (the file XOR-codes them)."""
    _, part = flat
    polys = part.polygons
    gaps = [polys[i].distance(polys[i + 1]) for i in range(len(polys) - 1)]
    shuffled = np.random.default_rng(0).permutation(len(polys))
    gaps_random = [polys[shuffled[i]].distance(polys[shuffled[i + 1]]) for i in range(len(polys) - 1)]
    assert np.median(gaps) < 0.5 * np.median(gaps_random) + 1e-9


def test_map_round_trip_is_small(flat, tmp_path):
    scene, part = flat
    m = assemble_map(scene.segments, scene.kinds, part.polygons, part.lists, scene.walls, {"wall_height": 2.5})
    size = save_map(tmp_path / "flat.lmap", m)
    back = load_map(tmp_path / "flat.lmap")
    assert size < 100_000
    for r, lst in enumerate(part.lists):
        assert np.array_equal(back.region_list(r), lst)
    # A point lookup in the loaded map lists what the point sees.
    q = scene.free_space.representative_point()
    assert len(back.candidate_segments(q.x, q.y, EPS)) > 0


@pytest.mark.slow
def test_merging_trades_regions_for_list_length():
    scene = apartment()
    exact = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, RegionSettings(merge_growth=0.0))
    merged = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, RegionSettings(merge_growth=0.5))
    assert merged.stats["regions"] < exact.stats["regions"]
    assert exact.stats["mean_list_length"] <= merged.stats["mean_list_length"] <= 1.5 * exact.stats["mean_list_length"] + 1e-9


def test_one_room_is_one_region_when_all_is_seen_everywhere():
    """A 6 x 4 m room seen whole from every point beyond the near field?
    No: near a wall its floor edge is too close. But merging equal lists
    must still leave few regions, each listing only existing segments."""
    scene = single_room(6.0, 4.0)
    part = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA)
    assert 1 <= part.stats["regions"] <= 40
    centre = [r for r, g in enumerate(part.polygons) if g.intersects(Point(3.0, 2.0))]
    assert all(len(part.lists[r]) == 12 for r in centre)


def test_progress_bar_goes_to_stderr(capsys):
    scene = single_room(3.0, 3.0)
    build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, progress=True)
    captured = capsys.readouterr()
    assert captured.out == ""


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"segments": np.zeros((3, 3))}, "expected shape"),
        ({"segments": np.full((1, 2, 3), np.nan)}, "finite"),
        ({"max_range": 0.0}, "max_range"),
        ({"min_visible_length": -1.0}, "min_visible_length"),
        ({"eps": -0.1}, "eps"),
        ({"free_space": shapely.MultiPolygon()}, "free_space"),
        ({"min_cell": float("inf")}, "min_cell"),
        ({"merge_growth": -1.0}, "merge_growth"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    scene = single_room(3.0, 3.0)
    args = {"segments": scene.segments, "occluders": scene.walls, "free_space": scene.free_space, "camera": CAMERA}
    settings = {k: kwargs.pop(k) for k in list(kwargs) if k in RegionSettings.__dataclass_fields__}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        build_regions(**args, settings=RegionSettings(**settings))


def test_no_occluders_and_no_segments_work():
    free = box(0, 0, 4, 4)
    part = build_regions(np.zeros((0, 2, 3)), shapely.MultiPolygon(), free, CAMERA)
    assert part.stats["regions"] == 1 and len(part.lists[0]) == 0
    seg = np.array([[[2.0, 9.0, 0.0], [2.0, 9.0, 2.5]]])  # a pole 5+ m away, no walls
    part = build_regions(seg, shapely.MultiPolygon(), free, CAMERA)
    assert sum(len(x) for x in part.lists) > 0


@pytest.mark.parametrize("pitch, height, max_range, min_len", [(20.0, 1.2, 10.0, 0.3), (-15.0, 0.6, 6.0, 0.5), (0.0, 2.0, 4.0, 0.1)])
@pytest.mark.slow
def test_property_holds_for_other_cameras_and_limits(pitch, height, max_range, min_len):
    """Pitched down (ceiling mostly out of view), pitched up and low (floor
    edges out of view), short range with a short minimum length."""
    scene = apartment()
    cam = Camera(640, 480, 457.0, 457.0, 320.0, 240.0, height, pitch)
    part = build_regions(scene.segments, scene.walls, scene.free_space, cam,
                         RegionSettings(max_range=max_range, min_visible_length=min_len, eps=EPS))
    oracle = VisibilityOracle(scene.segments, scene.walls, height, cam.elevation_range(), max_range, min_len)
    _assert_property(part, oracle, random_points(scene.free_space, 60, np.random.default_rng(int(pitch) + 100)))


def _assert_property(part, oracle, points):
    polys = np.array(part.polygons + [None])[:-1]
    tree = shapely.STRtree(polys)
    seen_any = 0
    for q in points:
        vis = oracle.visible(q)
        seen_any += len(vis) > 0
        near = tree.query(Point(q), predicate="dwithin", distance=EPS)
        assert len(near), q
        for r in near:
            assert len(np.setdiff1d(vis, part.lists[r])) == 0, (q, r)
    assert seen_any > 0


@settings(max_examples=6, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31 - 1))
@pytest.mark.slow
def test_property_holds_in_random_rooms_with_pillars(seed):
    """A random room with random free-standing pillars, segments a little off
    the wall faces."""
    rng = np.random.default_rng(seed)
    w, d = rng.uniform(3.0, 9.0, 2)
    blocks = []
    for _ in range(rng.integers(1, 5)):
        cx, cy = rng.uniform([0.8, 0.8], [w - 0.8, d - 0.8])
        sx, sy = rng.uniform(0.1, 1.5, 2) * (rng.random(2) < [0.5, 0.5]) + 0.1
        blocks.append(box(cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2))
    interior = box(0, 0, w, d)
    walls = shapely.union_all([interior.buffer(0.2, join_style="mitre").difference(interior), *blocks])
    scene = scene_from_walls(walls, interior, [])
    if scene.free_space.is_empty:
        return
    # End points off the wall faces by up to 0.5 mm, as imported drawings
    # leave them: verticals slant slightly, sight lines graze corners.
    segs = scene.segments + rng.uniform(-5e-4, 5e-4, scene.segments.shape) * [1, 1, 0]
    part = build_regions(segs, scene.walls, scene.free_space, CAMERA, RegionSettings(eps=EPS))
    oracle = VisibilityOracle(segs, scene.walls, CAMERA.height_m, CAMERA.elevation_range(), 10.0, 0.3)
    _assert_property(part, oracle, random_points(scene.free_space, 25, rng))


def test_a_huge_plan_caps_the_quadtree_depth():
    """A 600 m corridor: smallest cells widen rather than memory exploding."""
    free = box(0, 0, 600, 3)
    seg = np.array([[[5.0, 3.0, 0.0], [5.0, 3.0, 2.5]], [[300.0, 0.0, 0.0], [303.0, 0.0, 0.0]]])
    part = build_regions(seg, box(0, 3, 600, 3.4), free, CAMERA)
    assert part.stats["quadtree_depth"] == 11
    assert part.stats["smallest_cell_m"] == pytest.approx(600 / 2048)
    assert sum(p.area for p in part.polygons) == pytest.approx(1800.0)
    q = [r for r, g in enumerate(part.polygons) if g.intersects(Point(5.0, 1.5))]
    assert all(0 in part.lists[r] for r in q)


@pytest.mark.parametrize("growth", [0.02, 0.15, 1.0])
def test_merging_follows_the_cheapest_pair_first(growth):
    """merge_leaves queues one entry per region (its cheapest merge); it must
    merge exactly as the plain greedy that looks at every pair each time."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from mapkit.tolerances import VIR_MIN_CELL
    from mapkit.vir import adjacent_pairs, equal_lists, grow_regions, leaf_raster, list_bitsets, merge_leaves, quadtree_leaves
    from mapkit.visibility import Occluders, segment_regions

    scene = two_rooms()
    sr = segment_regions(scene.segments, Occluders.from_geometry(scene.walls), CAMERA.height_m, CAMERA.elevation_range(),
                         max_range=10.0, min_visible_length=0.3)
    leaves = quadtree_leaves(grow_regions(sr.regions, scene.free_space, EPS), scene.free_space, VIR_MIN_CELL)
    group, bits = merge_leaves(leaves, growth)

    # The plain greedy: equal lists first, then the cheapest current pair
    # (cost, then the smaller ids) until the budget is spent.
    m = len(leaves.level)
    pairs = adjacent_pairs(leaf_raster(leaves).labels)
    same = pairs[equal_lists(leaves, pairs)]
    _, comp = connected_components(coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(m, m)), directed=False)
    n = comp.max() + 1
    first = np.full(n, -1)
    first[comp[::-1]] = np.arange(m)[::-1]
    area = np.bincount(comp, weights=(leaves.size / 2.0**leaves.level) ** 2, minlength=n).tolist()
    lists = list_bitsets(leaves, first)
    count = [b.bit_count() for b in lists]
    label = list(range(n))

    def cost(p):
        a, b = p
        u = (lists[a] | lists[b]).bit_count()
        return area[a] * (u - count[a]) + area[b] * (u - count[b])

    links = {(int(a), int(b)) for a, b in np.unique(np.sort(comp[pairs], axis=1), axis=0) if a != b}
    costs = {p: cost(p) for p in links}
    budget, spent = growth * sum(a * c for a, c in zip(area, count)), 0.0
    while costs:
        a, b = min(costs, key=lambda p: (costs[p], p))
        if spent + costs[(a, b)] > budget:
            break
        spent += costs[(a, b)]
        lists[a] |= lists[b]
        count[a], area[a] = lists[a].bit_count(), area[a] + area[b]
        label = [a if x == b else x for x in label]
        moved = {}
        for (x, y), c in costs.items():
            x, y = sorted((a if x == b else x, a if y == b else y))
            if x != y:
                moved[(x, y)] = cost((x, y)) if a in (x, y) else c
        costs = moved
    reps, ref_group = np.unique(np.array(label)[comp], return_inverse=True)
    assert len(bits) == len(reps) < n
    assert np.array_equal(group, ref_group.ravel())
    assert bits == [lists[r] for r in reps]


@pytest.mark.slow
@pytest.mark.parametrize("workers", [2, 3])
def test_threads_give_the_same_partition(flat, workers):
    scene, part = flat
    other = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, RegionSettings(eps=EPS), workers=workers)
    assert [shapely.to_wkb(p) for p in other.polygons] == [shapely.to_wkb(p) for p in part.polygons]
    assert all(np.array_equal(a, b) for a, b in zip(other.lists, part.lists, strict=True))


def test_chunks_that_run_together_share_no_geometry():
    from mapkit.parallel import map_chunks, map_owned, run_all

    rng = np.random.default_rng(1)
    owner = rng.integers(0, 50, 1000)
    seen: dict[int, set] = {}

    def fn(rows):
        seen[int(rows[0])] = set(owner[rows].tolist())
        return owner[rows] * 2

    assert np.array_equal(map_owned(fn, owner, 50, 2, dtype=np.int64), owner * 2)
    groups = list(seen.values())
    assert sum(len(g) for g in groups) == len(set(owner.tolist()))  # no owner in two groups
    x = rng.random(1000)
    assert np.array_equal(map_chunks(np.sqrt, [x], 3), np.sqrt(x))
    with pytest.raises(ZeroDivisionError):  # a failing chunk fails the call
        run_all([lambda: 1, lambda: 1 // 0, lambda: 2], 2)
