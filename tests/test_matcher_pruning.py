"""Stage 1's pruning tests that come from the map rather than the image:
heights against the horizon, free space, and a frame that needs both."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mapkit_harness.simulate import make_frame, paper_camera

import matcher
from matcher.map_geometry.freespace import FreeSpace, free_space
from matcher.search.tree.correspondences import horizon_side_ok
from matcher.tolerances import DEFAULT

FLAT = Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(FLAT)


def test_height_side_hand_worked():
    cam = paper_camera(1.2, 0.0)  # horizon on row 240
    crossing = [[300.0, 100.0], [300.0, 400.0]]  # a vertical line across the horizon
    below = [[100.0, 300.0], [500.0, 420.0]]  # wholly below it
    above = [[100.0, 50.0], [500.0, 150.0]]  # wholly above it
    floor = [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]]
    ceiling = [[0.0, 0.0, 2.5], [5.0, 0.0, 2.5]]
    jamb = [[0.0, 0.0, 0.0], [0.0, 0.0, 2.1]]
    at_eye = [[0.0, 0.0, 1.2], [5.0, 0.0, 1.2]]  # a rail at camera height images on the horizon
    ok = horizon_side_ok(cam, np.array([crossing, below, above]), np.array([floor, ceiling, jamb, at_eye]), DEFAULT)
    assert ok.tolist() == [
        [False, True, False],  # floor: only below the horizon
        [False, False, True],  # ceiling: only above
        [True, True, True],  # a jamb spans both sides
        [True, True, True],  # at eye height: heights alone cannot rule it out (the direction test does)
    ]


def test_height_side_pitched_camera_uses_world_elevation():
    cam = paper_camera(1.2, 20.0)  # horizon row: 240 - 900 tan 20 deg = -88, above the image
    line = np.array([[[300.0, 100.0], [300.0, 400.0]]])  # whole image is below the horizon
    floor = [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]]
    ceiling = [[0.0, 0.0, 2.5], [5.0, 0.0, 2.5]]
    assert horizon_side_ok(cam, line, np.array([floor, ceiling]), DEFAULT)[:, 0].tolist() == [True, False]


@pytest.mark.slow
def test_free_space_raster_agrees_with_the_region_lookup(flat):
    fs = free_space(flat)
    assert free_space(flat) is fs  # cached with the map
    rng = np.random.default_rng(3)
    lo, hi = flat.ring_points.min(axis=0), flat.ring_points.max(axis=0)
    pts = rng.uniform(lo - 0.5, hi + 0.5, size=(1500, 2))
    inside = np.array([len(flat.regions_at(*p)) > 0 for p in pts])
    # Away from region borders (a raster cell's half diagonal) the two agree.
    near_border = np.array([len(flat.regions_near(*p, 0.04)) > 0 for p in pts]) & ~inside
    near_border |= inside & np.array([len(flat.regions_near(*p, 0.0)) > 0 for p in pts]) & (
        fs.distance(pts) > 0)
    d = fs.distance(pts)
    clear = ~near_border
    assert ((d[clear] == 0) == inside[clear]).all()
    # Distances grow away from the regions: a point 1 m out of every region reads >= 0.95 m.
    far = np.array([len(flat.regions_near(*p, 1.0)) == 0 for p in pts])
    assert (d[far] >= 0.95).all() and far.any()


def test_free_space_rejects_a_camera_inside_a_wall(flat):
    fs = free_space(flat)
    # The wall between y = 5.0 and 5.1 (maps/flat.dxf), away from its doorways.
    assert fs.distance(np.array([6.08, 5.05])) > DEFAULT.free_space_m
    assert fs.distance(np.array([6.08, 4.5])) == 0.0


def test_free_space_of_a_square():
    ring = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    fs = FreeSpace(ring, np.array([0, 4]))
    d = fs.distance(np.array([[1.0, 1.0], [2.5, 1.0], [1.0, -0.3], [2.6, 2.6]]))
    assert d[0] == 0.0
    assert d[1] == pytest.approx(0.5, abs=0.07)
    assert d[2] == pytest.approx(0.3, abs=0.07)
    assert d[3] == pytest.approx(0.6 * math.sqrt(2.0), abs=0.07)


@pytest.mark.slow
def test_frame_of_vertical_edges_only(flat):
    """A frame whose only true lines are five vertical edges (door jambs and
    corners) with three clutter lines. Floor and ceiling lines running along
    the sight lines used to pass as those vertical lines, and stage 1 found
    over a thousand sets without the true one among its first 25."""
    cam = paper_camera(1.2, 0.0)
    rng = np.random.default_rng([0, 4])
    for _ in range(15):
        fr = make_frame(flat, cam, rng, 4, 1.0, 1.0, clutter=3)
    truth = {tuple(m) for m in fr.true_matches()}
    assert len(truth) == 5 and all(flat.segments[s][0, 2] != flat.segments[s][1, 2] for s, _ in truth)
    res = matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    assert res, res.reason
    assert {tuple(m) for m in res.matches} == truth
    assert res.sets_found < 100


def test_halfplane_reachable_hand_worked():
    from matcher.search.tree import posegrid

    dt = 1.0
    # One strip x = 0 (|x| <= 0.1): its feasible set is the chord x ~ 0, y in [-1, 1].
    q = posegrid.strip_quadratics(np.array([1.0, 0.0]), np.array(0.0), np.array(0.1))
    val, zx, zy = posegrid.minimise(q, dt)
    low = (val, zx, zy)
    reach = lambda c, b: bool(posegrid.halfplane_reachable(q, low, 1, 1.5, dt, np.array(c), np.array(b)))  # noqa: E731
    assert reach([0.0, 1.0], -0.9)  # y <= -0.9: the chord's end
    assert not reach([0.0, 1.0], -1.1)  # beyond the disk
    assert reach([1.0, 0.0], 0.0)  # x <= 0 on the strip
    assert not reach([1.0, 0.0], -0.2)  # x <= -0.2: off the strip (0.1 * sqrt(1.5) = 0.12 wide)
    assert reach([0.0, 0.0], np.inf)  # no constraint


def test_stretch_and_weak_axis_against_sampling():
    """The pinned test's two pieces: the weak axis of two crossing strips and
    the extent of their common part along it, against a dense sampling."""
    from matcher.search.tree import posegrid

    dt, q_max = 1.0, 1.5
    rng = np.random.default_rng(3)
    for _ in range(20):
        ang = rng.uniform(0, np.pi, 2)
        a = np.stack([np.cos(ang), np.sin(ang)], axis=1)  # two strip normals
        d = rng.uniform(-0.3, 0.3, 2)
        t = rng.uniform(0.02, 0.2, 2)
        q = posegrid.strip_quadratics(a, d, t)  # (2, 6)
        val, zx, zy = posegrid.minimise(q.sum(axis=0), dt)
        e, lam_lo, lam_hi = posegrid.weak_axis(q.sum(axis=0))
        A = np.array([[q[:, 0].sum(), q[:, 1].sum()], [q[:, 1].sum(), q[:, 2].sum()]])
        assert np.allclose([lam_lo, lam_hi], np.linalg.eigvalsh(A), rtol=1e-9, atol=1e-9)
        assert np.allclose(A @ np.array(e), lam_lo * np.array(e), atol=1e-6 * lam_hi)
        lo, hi = posegrid.stretch(q, (float(zx), float(zy)), e, q_max, dt)
        s = np.linspace(-2.5, 2.5, 50001)
        pts_x, pts_y = zx + s * e[0], zy + s * e[1]
        inside = (posegrid.evaluate(q[:, None], pts_x, pts_y) <= q_max).all(axis=0) & (pts_x**2 + pts_y**2 <= dt * dt)
        if inside.any():
            assert lo == pytest.approx(s[inside].min(), abs=2e-4)
            assert hi == pytest.approx(s[inside].max(), abs=2e-4)
        else:
            assert lo > hi


def test_feasible_ellipse_reaches_equals_halfplane_reachable():
    from matcher.search.tree import posegrid

    rng = np.random.default_rng(5)
    a = rng.normal(size=(40, 2))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    q = posegrid.strip_quadratics(a, rng.uniform(-0.5, 0.5, 40), rng.uniform(0.05, 0.3, 40))
    val, zx, zy = posegrid.minimise(q, 1.0)
    c = rng.normal(size=(40, 2))
    b = rng.uniform(-1, 1, 40)
    ell = posegrid.feasible_ellipse(q, val, zx, zy, 1, 1.5, 1.0)
    # Sampled points of each strip's feasible chord that satisfy c . z <= b
    # exist only where the test says so (it is a necessary condition).
    reach = posegrid.ellipse_reaches(ell, c, b, 1.0)
    assert (reach == posegrid.halfplane_reachable(q, (val, zx, zy), 1, 1.5, 1.0, c, b)).all()
    g = rng.uniform(-1, 1, (4000, 2))
    g = g[(g**2).sum(axis=1) <= 1]
    feas = posegrid.evaluate(q[:, None], g[None, :, 0], g[None, :, 1]) <= 1.5  # (40, P)
    sat = (c @ g.T) <= b[:, None]
    assert not ((feas & sat).any(axis=1) & ~reach).any()


def test_face_normals_point_into_the_rooms(flat):
    from matcher.map_geometry.occlusion import face_normals, inside_walls, wall_edges

    walls = wall_edges(flat)
    f = face_normals(flat.segments, walls)
    has = np.abs(f).sum(axis=1) > 0
    vertical = np.abs(flat.segments[:, 1, 2] - flat.segments[:, 0, 2]) > 0.5
    assert not has[vertical].any()
    assert has.sum() > 0.5 * (~vertical).sum()  # most floor and ceiling lines lie on a wall face
    mid = flat.segments[has, :, :2].mean(axis=1)
    # A step along the normal leaves the wall, a step against it enters the wall.
    assert not inside_walls(mid + 0.03 * f[has], walls).any()
    assert inside_walls(mid - 0.03 * f[has], walls).all()


def test_vertical_edge_behind_the_camera_is_not_a_candidate():
    """A vertical edge right behind the prior's position (within dt) used to
    pass for any image line at some yaw: its bearing line runs through the
    disk, on both sides of the edge. The camera must stand behind the edge
    on the ray towards it."""
    from matcher.search.tree.correspondences import ModelLines, Pairs, YawGrid, _half_planes

    class _Img:
        alpha = np.array([0.0])  # the line is straight ahead

    yaws = np.array([0.0])
    ce = np.array([0.0, 0.0, 1.2])
    near = np.array([[1.0, 0.0, 0.0], [-0.5, 0.0, 0.0]])  # one ahead (+x), one behind
    grid = YawGrid(yaws, 0.0, None, None, ce, 1.0)
    pairs = Pairs(np.array([0, 1]), np.array([0, 0]), np.array([True, True]))
    c, b = _half_planes(_Img, ModelLines(None, None, near), pairs, grid, None, DEFAULT.stage1.front_slack_m)
    # At the disk centre (z = 0): c . z <= b holds for the edge ahead only.
    assert (0.0 <= b[0, 0]) and not (0.0 <= b[1, 0])
    assert np.allclose(c[:, 0], [[1.0, 0.0], [1.0, 0.0]])


def test_collinear_groups_hand_worked_and_from_map_labels(flat):
    from matcher.map_geometry.collinear import collinear_classes, collinear_labels

    angle, dist = DEFAULT.map_index.collinear_deg, DEFAULT.map_index.collinear_m

    segs = np.array([
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],  # a wall's floor line, split by a door...
        [[2.0, 0.0, 0.0], [3.0, 0.0, 0.0]],  # ...and its other piece
        [[0.0, 0.005, 2.5], [3.0, 0.005, 2.5]],  # the ceiling line above: parallel, not collinear
        [[1.5, 0.004, 0.0], [1.6, 0.004, 0.0]],  # 4 mm off the floor line: same line
        [[0.0, 0.0, 0.0], [0.0, 0.0, 2.1]],  # a jamb
    ])
    label, reps = collinear_classes(segs, angle, dist)
    assert label.tolist() == [0, 0, 1, 0, 2]
    assert np.allclose(reps[0], [[0, 0, 0], [3, 0, 0]], atol=1e-2)
    # Map-wide labels restricted to a subset give the same groups and spans.
    rng = np.random.default_rng(2)
    all_labels = collinear_labels(flat.segments, angle, dist, chunk=64)
    for _ in range(5):
        ids = np.sort(rng.choice(flat.n_segments, 120, replace=False))
        a, ra = collinear_classes(flat.segments[ids], angle, dist)
        b, rb = collinear_classes(flat.segments[ids], angle, dist, label=all_labels[ids])
        assert (a == b).all() and np.allclose(ra, rb)


def test_vectorised_stretches_and_weak_axes_match_the_scalar_ones():
    from matcher.search.tree import posegrid

    rng = np.random.default_rng(11)
    ang = rng.uniform(0, np.pi, (3, 12))
    a = np.stack([np.cos(ang), np.sin(ang)], axis=-1)  # (S, G, 2): three strips at twelve yaws
    q = posegrid.strip_quadratics(a, rng.uniform(-0.4, 0.4, (3, 12)), rng.uniform(0.02, 0.3, (3, 12)))
    qs = q.sum(axis=0)
    _, zx, zy = posegrid.minimise(qs, 1.0)
    ex, ey = posegrid.weak_axes(qs)
    lo, hi = posegrid.stretches(q, zx, zy, ex, ey, 1.5, 1.0)
    for g in range(12):
        e, _, _ = posegrid.weak_axis(qs[g])
        assert np.allclose([ex[g], ey[g]], e)
        assert np.allclose([lo[g], hi[g]], posegrid.stretch(q[:, g], (zx[g], zy[g]), e, 1.5, 1.0))


def _loose_set_facing_an_edge(walls):
    """Three strips along x through the disk centre (the position is loose
    along x), the last one a vertical edge at (3, 0) seen straight ahead."""
    from matcher.search.tree import posegrid
    from matcher.search.tree.tree import TreeInput

    strip = posegrid.strip_quadratics(np.array([0.0, 1.0]), np.array(0.0), np.array(0.05))
    quad = np.broadcast_to(strip, (3, 1, 6)).copy()
    segments = np.array([[[-5.0, 0.0, 0.0], [5.0, 0.0, 0.0]], [[-5.0, 0.0, 2.5], [5.0, 0.0, 2.5]],
                         [[3.0, 0.0, 0.0], [3.0, 0.0, 2.1]]])
    return TreeInput(quad, np.ones((3, 1), dtype=bool), np.zeros(1), np.ones((3, 3), dtype=bool), segments,
                     np.array([0.0, 0.0, 1.2]), 1.0, np.array([[1.0, 0.0, 0.0]]), walls,
                     vertical=np.array([False, False, True]), line=np.arange(3))


def test_edge_seen_from_a_loose_region_hand_worked():
    """A set loose along x (|y| < 0.06, x in the unit disk) and a vertical
    edge at (3, 0): a wall at x = 2 hides it from the whole region, a
    doorway in that wall lets it be seen, and a wall off to the side does
    not matter."""
    from matcher.search.tree.set_visibility import edge_seen_from_region

    from dataclasses import replace

    from matcher.map_geometry.occlusion import SightRays

    def seen(walls):
        inp = _loose_set_facing_an_edge(walls)
        args = ([0, 1, 2], inp.quad.sum(axis=0), np.ones(1, dtype=bool), replace(DEFAULT, q_max=1.5), 3)
        cast = edge_seen_from_region(inp, *args)  # sight lines cast
        table = edge_seen_from_region(replace(inp, sight=SightRays(walls)), *args)  # the map's sight table
        assert cast == table
        return cast

    wall = (np.array([[2.0, -2.0]]), np.array([[2.0, 2.0]]))
    door = (np.array([[2.0, -2.0], [2.0, 0.4]]), np.array([[2.0, -0.4], [2.0, 2.0]]))
    aside = (np.array([[2.0, 0.5]]), np.array([[2.0, 2.0]]))
    assert not seen(wall)
    assert seen(door)
    assert seen(aside)


@pytest.mark.slow
def test_loose_sets_cut_by_the_region_test(flat):
    """Frame 29 of the benchmark at PEQ 5: looking down a corridor, seven
    true lines, three of them door jambs that each fit some twenty jambs.
    The sets of wrong jambs leave the position loose, so the pinned test
    never runs on them; the test on their whole feasible region
    (set_visibility.edge_seen_from_region) cuts them: with a budget of 3000 nodes
    (the test starting after 300) the search ends at about 2300. Without it
    the full search takes over 10000 nodes."""
    from dataclasses import replace

    cam = paper_camera(1.2, 0.0)
    rng = np.random.default_rng([0, 5])
    for _ in range(30):
        fr = make_frame(flat, cam, rng, 5, 1.0, 1.0, clutter=3)
    truth = {tuple(m) for m in fr.true_matches()}
    assert len(truth) == 7
    res = matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw,
                           replace(DEFAULT, max_nodes=3000, max_sets=10**6))
    assert res, res.reason
    assert {tuple(m) for m in res.matches} == truth
    assert res.stage1.tree_nodes < 3000  # the search ended within its budget


@pytest.mark.slow
def test_aiming_at_large_sets_first_finds_the_same_sets_sooner(flat, monkeypatch):
    """Frame 41 of the benchmark at PEQ 5: nine lines, six of them true. A
    single pass from the minimum size dives first into sets of four and
    enumerates some thirty of them before it meets the six; the passes
    aiming at large sets first (tree.search's default) return the same sets
    in a fraction of the nodes."""
    import matcher.search.tree.generate as generate
    from matcher.search.tree.tree import search

    cam = paper_camera(1.2, 0.0)
    rng = np.random.default_rng([0, 5])
    for _ in range(42):
        fr = make_frame(flat, cam, rng, 5, 1.0, 1.0, clutter=3)
    inputs = []

    def capture(inp, tol, eager=False):
        inputs.append(inp)
        return search(inp, tol, eager)

    monkeypatch.setattr(generate, "search", capture)
    assert matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    aimed = search(inputs[0], DEFAULT)
    single = search(inputs[0], DEFAULT, aim_high=False)
    assert [s.tolist() for s in aimed[0]] == [s.tolist() for s in single[0]]
    assert max(len(s) for s in aimed[0]) == len(fr.true_matches()) == 6
    assert aimed[3] * 2 < single[3]  # nodes: about 35 against 90


@pytest.mark.parametrize("box_filter", [False, True])
def test_sight_clear_against_shapely(flat, box_filter):
    """matcher.map_geometry.occlusion.sight_clear against shapely on the example map's
    walls: sight lines from random cameras to random floor points and to
    points on wall faces, trimmed by the end margin, cross no wall edge
    exactly when the function says clear (with and without the edges'
    bounding-box filter that large maps use)."""
    from shapely.geometry import LineString, MultiLineString

    import matcher.map_geometry.occlusion as occlusion

    from dataclasses import replace

    shared = replace(DEFAULT.shared, box_filter_edges=0) if box_filter else DEFAULT.shared
    walls = occlusion.wall_edges(flat)
    outline = MultiLineString([[tuple(a), tuple(b)] for a, b in zip(*walls)])
    rng = np.random.default_rng(3)
    lo, hi = walls[0].min(axis=0), walls[0].max(axis=0)
    margin = 0.05
    n_blocked = 0
    for _ in range(40):
        cam = lo + rng.random(2) * (hi - lo)
        pts = lo + rng.random((30, 2)) * (hi - lo)
        on_wall = rng.integers(0, len(walls[0]), 15)
        pts[:15] = walls[0][on_wall] + rng.random((15, 1)) * (walls[1][on_wall] - walls[0][on_wall])
        got = occlusion.sight_clear(cam, pts, walls, margin, shared)
        for p, clear in zip(pts, got):
            r = p - cam
            u = r / np.linalg.norm(r)
            blocked = LineString([tuple(cam + margin * u), tuple(p - margin * u)]).intersects(outline)
            assert clear == (not blocked), (cam, p)
            n_blocked += blocked
    assert 100 < n_blocked < 1100  # both outcomes well represented


@pytest.mark.slow
def test_lines_reached_as_bits_equals_the_matrix_product(flat, monkeypatch):
    """The look-ahead counts the lines a candidate still reaches as bits of
    one integer (up to 63 lines) or by a one-hot matrix product (more): both
    give the same search, set for set and node for node."""
    import matcher.search.tree.generate as generate
    import matcher.search.tree.tree as tree

    cam = paper_camera(1.2, 0.0)
    rng = np.random.default_rng([1, 5])
    inputs = []

    def capture(inp, tol, eager=False):
        inputs.append(inp)
        return tree.search(inp, tol, eager)

    monkeypatch.setattr(generate, "search", capture)
    for _ in range(6):
        fr = make_frame(flat, cam, rng, 5, 1.0, 1.0, clutter=3)
        matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    bits = [tree.search(inp, DEFAULT) for inp in inputs]
    monkeypatch.setattr(tree, "_BIT_LEVELS", 0)
    product = [tree.search(inp, DEFAULT) for inp in inputs]
    assert sum(b[3] for b in bits) > 50  # the searches did some work
    for b, p in zip(bits, product):
        assert [s.tolist() for s in b[0]] == [s.tolist() for s in p[0]]
        assert b[3] == p[3]
