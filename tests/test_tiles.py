"""The region stage in tiles (mapkit.tiles): on a generated office cut into
small tiles, the list at every one of thousands of random points is the
one-piece build's before merging, and a superset of it after."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from linemap.camera import Camera
from mapkit.edges import extract_edges
from mapkit.importers import load_scene
from mapkit.options import BuildOptions
from mapkit.tiles import Floor, build_regions_in_tiles, plan_tiles, reach, tile_segments
from mapkit.vir import RegionSettings, build_regions
from mapkit_harness.plans.drawings import office_grid

#: A short sight range keeps tiles of a few metres meaningful (a tile
#: computes every segment within reach) and the test quick.
RANGE = 3.0
TILE_SIDE = 6.0


@pytest.fixture(scope="module")
def office(tmp_path_factory):
    """A 2 x 2 office of 5 m rooms: its floor (segments, walls, free space,
    camera) at merge growth 0 and at the default."""
    path = tmp_path_factory.mktemp("tiles") / "office.dxf"
    office_grid(path, n=2)
    options = BuildOptions()
    scene = load_scene(path, options)
    segments, _ = extract_edges(scene, options)
    camera = Camera.from_dict(options.camera).to_dict()
    floors = {growth: Floor(segments, scene.walls, scene.free_space, camera,
                            RegionSettings(max_range=RANGE, merge_growth=growth)) for growth in (0.0, 0.15)}
    return floors


def _lists_at(polygons: list, lists: list, pts: np.ndarray) -> list:
    """The list of the region holding each point (None off every region)."""
    tree = shapely.STRtree(np.array(polygons + [None])[:-1])
    i, j = tree.query(shapely.points(pts), predicate="within")
    out = [None] * len(pts)
    for a, b in zip(i, j):
        out[a] = lists[b]
    return out


def _points(free_space, n: int) -> np.ndarray:
    x0, y0, x1, y1 = free_space.bounds
    pts = np.random.default_rng(46).uniform([x0, y0], [x1, y1], (n, 2))
    return pts[shapely.contains_xy(free_space, pts[:, 0], pts[:, 1])]


@pytest.fixture(scope="module")
def builds(office):
    """Per merge growth: the one-piece partition, the tiled one, the tiling."""
    out = {}
    for growth, floor in office.items():
        camera = Camera.from_dict(floor.camera)
        one = build_regions(floor.segments, floor.occluders, floor.free_space, camera, floor.settings)
        plan = plan_tiles(floor.free_space, floor.settings, TILE_SIDE)
        out[growth] = (one, build_regions_in_tiles(floor, plan), plan)
    return out


@pytest.mark.slow
def test_tiles_list_what_the_one_piece_build_lists_before_merging(office, builds):
    floor = office[0.0]
    one, tiled, plan = builds[0.0]
    assert len(plan.tiles) == 4 and plan.side <= TILE_SIDE
    pts = _points(floor.free_space, 6000)
    a, b = _lists_at(one.polygons, one.lists, pts), _lists_at(tiled.polygons, tiled.lists, pts)
    held = [k for k in range(len(pts)) if a[k] is not None]
    assert len(held) > 5000 and all(b[k] is not None for k in held)
    differ = [pts[k] for k in held if not np.array_equal(a[k], b[k])]
    assert not differ, f"{len(differ)} of {len(held)} points list otherwise, e.g. at {differ[0]}"
    # Tile borders cut regions: more of them, a few.
    assert len(one.polygons) <= len(tiled.polygons) <= 1.15 * len(one.polygons)
    assert abs(shapely.union_all(tiled.polygons).area - floor.free_space.area) < 1e-6 * floor.free_space.area


@pytest.mark.slow
def test_merged_tiles_keep_every_leaf_list_and_the_region_count(office, builds):
    merged_one, merged_tiles, _ = builds[0.15]
    exact = builds[0.0][1]
    pts = _points(office[0.15].free_space, 3000)
    leaf = _lists_at(exact.polygons, exact.lists, pts)
    merged = _lists_at(merged_tiles.polygons, merged_tiles.lists, pts)
    assert all(np.isin(leaf[k], merged[k]).all() for k in range(len(pts)) if leaf[k] is not None)
    # Tiles of 6 m on a floor of 10 m: the borders cut a large share of the
    # regions here (10 % more measured); at real tile sizes, a few per cent.
    assert abs(len(merged_tiles.polygons) - len(merged_one.polygons)) <= 0.15 * len(merged_one.polygons)
    ratio = merged_tiles.stats["mean_list_length"] / merged_one.stats["mean_list_length"]
    assert 0.95 < ratio < 1.05


def test_a_tile_takes_every_segment_within_reach(office):
    floor = office[0.0]
    plan = plan_tiles(floor.free_space, floor.settings, TILE_SIDE)
    lines = shapely.linestrings(floor.segments[:, :, :2])
    for tile in plan.tiles:
        ids = tile_segments(floor.segments, tile.bounds, floor.settings)
        near = np.nonzero(shapely.distance(lines, shapely.box(*tile.bounds)) <= reach(floor.settings))[0]
        assert np.isin(near, ids).all() and len(ids) < len(floor.segments)


def test_a_failing_tile_is_named_with_its_place(office, monkeypatch):
    import mapkit.tiles as tiles

    floor = office[0.0]
    plan = plan_tiles(floor.free_space, floor.settings, TILE_SIDE)

    monkeypatch.setattr(tiles, "build_tile", lambda *a: (_ for _ in ()).throw(ZeroDivisionError("boom")))
    with pytest.raises(tiles.TileFailed, match=r"tile 1 of 4 \(x -?\d+\.\d to -?\d+\.\d m, y .*\) failed: ZeroDivisionError: boom"):
        build_regions_in_tiles(floor, plan)


def test_the_memory_budget_chooses_one_piece_or_the_tile_side():
    from shapely.geometry import box

    from mapkit.errors import MapkitError
    from mapkit.tiles import predicted_peak_mb, tile_side_for_budget

    settings = RegionSettings()
    assert tile_side_for_budget(box(0, 0, 50, 50), settings, 2000.0) is None  # an office of 10 x 10 rooms
    side = tile_side_for_budget(box(0, 0, 200, 200), settings, 2000.0)
    assert 2 * reach(settings) < side < 200
    assert predicted_peak_mb((side + 2 * reach(settings)) ** 2) == pytest.approx(2000.0)
    assert tile_side_for_budget(box(0, 0, 200, 200), settings, 500.0) < side
    with pytest.raises(MapkitError, match="--memory-budget 150 MB is too small .* give at least"):
        tile_side_for_budget(box(0, 0, 200, 200), settings, 150.0)


@pytest.mark.slow
def test_a_tile_in_a_process_of_its_own_gives_the_tile_built_here(office):
    """ChildTiles (a floor past --memory-budget) builds the tile in a fresh
    process: the same compact result, array for array; the outlines and
    lists come back as built."""
    from dataclasses import replace

    from mapkit.tile_runner import ChildTiles
    from mapkit.tiles import build_tile

    floor = office[0.0]
    plan = plan_tiles(floor.free_space, floor.settings, TILE_SIDE)
    one = replace(plan, tiles=plan.tiles[:1])
    here = build_tile(floor, one, one.tiles[0])
    (child,) = ChildTiles(1).run(floor, one)
    assert len(here.keys) > 10 and here.stats == child.stats
    for name in ("wkb", "wkb_ends", "ids", "list_ends", "keys"):
        assert np.array_equal(getattr(here, name), getattr(child, name)), name
    assert all(p.equals_exact(q, 0.0) for p, q in zip(here.polygons(), child.polygons()))
    assert [len(x) for x in here.lists()] == [int(n) for n in np.diff(here.list_ends, prepend=0)]
