"""The region stage's faster forms compute what their plain forms compute,
bit for bit: sample pairing, leaf-pair deduplication, the sweep's grouped
sort, the quadtree's covers test asked only where the centre is inside, the
quadtree's pairs taken as met where the parent's centre was inside, and the
merge's queue built from kept costs."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from mapkit.vir import RegionSettings, build_regions, unique_pairs
from mapkit.visibility import _samples, Sight, distance_band, sample_segment
from mapkit.visibility_batch import _by_group
from mapkit_harness.plans import two_rooms
from linemap.camera import Camera

CAMERA = Camera(640, 480, 457.0, 457.0, 320.0, 240.0, 1.2, 0.0)


def _samples_one_by_one(segs: np.ndarray, vertical: np.ndarray, sight: Sight) -> dict:
    """The per-segment, per-pair loop :func:`mapkit.visibility._samples` replaced."""
    e_min, e_max = sight.elevation
    keys: dict = {}

    def key_of(pt):
        k = (round(float(pt[0]), 7), round(float(pt[1]), 7))
        return keys.setdefault(k, len(keys))

    out = {k: [] for k in ("pair_seg", "pair_a", "pair_b", "pair_mid", "pair_rin", "pair_rout")}
    vert_ids = np.nonzero(vertical)[0]
    vert_keys = [key_of(segs[i, 0, :2]) for i in vert_ids]
    for i in np.nonzero(~vertical)[0]:
        pts = sample_segment(segs[i], sight.min_visible_length / 2.0)
        dmin, dmax = distance_band(pts[:, 2], sight.h, e_min, e_max, sight.max_range)
        ks = [key_of(pt) for pt in pts[:, :2]]
        for j in range(len(pts) - 1):
            if dmax[j] < 0 or dmax[j + 1] < 0:
                continue
            delta2 = float(np.sum((pts[j + 1, :2] - pts[j, :2]) ** 2))
            r_out2 = (dmax[j] ** 2 + dmax[j + 1] ** 2) / 2.0 - delta2 / 4.0
            r_in2 = min(dmin[j], dmin[j + 1]) ** 2 - delta2 / 4.0
            if r_out2 <= max(r_in2, 0.0):
                continue
            out["pair_seg"].append(i)
            out["pair_a"].append(ks[j])
            out["pair_b"].append(ks[j + 1])
            out["pair_mid"].append((pts[j, :2] + pts[j + 1, :2]) / 2.0)
            out["pair_rin"].append(math.sqrt(r_in2) if r_in2 > 0 else 0.0)
            out["pair_rout"].append(math.sqrt(r_out2))
    return {
        "xy": np.array(list(keys)).reshape(-1, 2),
        "vert_ids": vert_ids,
        "vert_keys": np.asarray(vert_keys, dtype=np.int64),
        "pair_seg": np.array(out["pair_seg"], dtype=np.int64),
        "pair_a": np.array(out["pair_a"], dtype=np.int64),
        "pair_b": np.array(out["pair_b"], dtype=np.int64),
        "pair_mid": np.array(out["pair_mid"]).reshape(-1, 2),
        "pair_rin": np.array(out["pair_rin"]),
        "pair_rout": np.array(out["pair_rout"]),
    }


def test_samples_match_the_per_pair_loop():
    rng = np.random.default_rng(3)
    n = 60
    a = rng.uniform(-4, 4, (n, 3))
    b = a + rng.normal(0, 1.5, (n, 3))
    a[:, 2], b[:, 2] = rng.choice([0.0, 2.6, 5.0], n), rng.choice([0.0, 2.6, 5.0], n)
    b[:10, :2] = a[:10, :2]  # vertical edges
    b[:10, 2] = a[:10, 2] + 2.6
    a[20:25] = a[25:30]  # shared sample points
    b[20:25] = b[25:30]
    segs = np.stack([a, b], axis=1)
    vertical = np.linalg.norm(segs[:, 1, :2] - segs[:, 0, :2], axis=1) <= 1e-9
    for sight in (Sight(1.2, (-0.4, 0.4), 6.0, 0.3), Sight(1.2, (-0.9, 0.1), 3.0, 0.5)):
        got = _samples(segs, vertical, sight)
        want = _samples_one_by_one(segs, vertical, sight)
        assert len(want["pair_seg"]) > 0
        for name, value in want.items():
            mine = getattr(got, name)
            assert mine.dtype == value.dtype and mine.shape == value.shape, name
            assert mine.tobytes() == value.tobytes(), name


def test_samples_of_vertical_segments_only():
    segs = np.array([[[0.0, 0.0, 0.0], [0.0, 0.0, 2.6]], [[1.0, 0.0, 0.0], [1.0, 0.0, 2.6]]])
    got = _samples(segs, np.array([True, True]), Sight(1.2, (-0.4, 0.4), 6.0, 0.3))
    assert got.xy.shape == (2, 2) and got.vert_keys.tolist() == [0, 1]
    assert got.pair_seg.shape == (0,) and got.pair_mid.shape == (0, 2)


def test_unique_pairs_is_the_row_unique():
    rng = np.random.default_rng(0)
    for dtype in (np.int32, np.int64):
        for n in (0, 1, 7, 5000):
            pairs = rng.integers(0, 50, (n, 2)).astype(dtype)
            want = np.unique(np.sort(pairs, axis=1), axis=0)
            got = unique_pairs(pairs)
            assert got.dtype == want.dtype and got.shape == want.shape
            assert (got == want).all()


def test_grouped_sort_is_the_lexsort():
    rng = np.random.default_rng(1)
    group = np.sort(rng.integers(0, 40, 3000))
    key = rng.choice(np.linspace(-math.pi, math.pi, 50), 3000)  # many ties
    assert (_by_group(key, group) == np.lexsort((key, group))).all()
    big = np.sort(rng.integers(0, 70_000, 3000))  # past 16-bit ids
    assert (_by_group(key, big) == np.lexsort((key, big))).all()
    assert _by_group(np.zeros(0), np.zeros(0, dtype=np.int64)).shape == (0,)


def test_quadtree_asks_covers_only_where_the_centre_is_inside(monkeypatch):
    """Asking covers of every met pair gives the same partition."""
    import mapkit.vir as vir

    scene = two_rooms()
    settings = RegionSettings(eps=0.05)
    fast = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, settings)
    asked = []
    real = vir._pairwise

    def every_pair(predicate, geoms, gi, bi, *cells, workers=1):
        if predicate is shapely.covers:
            asked.append(len(gi))
        return real(predicate, geoms, gi, bi, *cells, workers=workers)

    original_meets = vir._meets

    def meets_all_inside(*args, **kwargs):
        hit, centre_in = original_meets(*args, **kwargs)
        return hit, hit.copy()  # every met pair a covers candidate: the plain form

    monkeypatch.setattr(vir, "_pairwise", every_pair)
    monkeypatch.setattr(vir, "_meets", meets_all_inside)
    # centre_in is the parent's centre test for the children too: the plain form asks them everything
    monkeypatch.setattr(vir, "_parent_corner", lambda *args: None)
    plain = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, settings)
    assert sum(asked) > 0
    assert len(fast.polygons) == len(plain.polygons)
    for p, q in zip(fast.polygons, plain.polygons):
        assert shapely.to_wkb(p) == shapely.to_wkb(q)
    for a, b in zip(fast.lists, plain.lists):
        assert a.tolist() == b.tolist()


def test_quadtree_takes_pairs_as_met_where_the_parent_centre_is_inside(monkeypatch):
    """Children whose pair's region held the parent's centre (their shared
    corner) are asked nothing where that point is their box's corner bit for
    bit, and their corner before the box where it is not; asking them
    everything gives the same partition."""
    import mapkit.vir as vir

    scene = two_rooms()
    settings = RegionSettings(eps=0.05)
    pins = []
    real_meets = vir._meets

    def counting(*args, **kwargs):
        corner = args[6] if len(args) > 6 else None
        if corner is not None:
            pin, _, _, shared = corner
            pc = args[2]
            pins.append((int(np.count_nonzero(pin & shared[pc])), int(np.count_nonzero(pin & ~shared[pc]))))
        return real_meets(*args, **kwargs)

    monkeypatch.setattr(vir, "_meets", counting)
    fast = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, settings)
    assert sum(p[0] for p in pins) > 0 and sum(p[1] for p in pins) > 0  # both kinds occur
    monkeypatch.setattr(vir, "_parent_corner", lambda *args: None)
    plain = build_regions(scene.segments, scene.walls, scene.free_space, CAMERA, settings)
    assert len(fast.polygons) == len(plain.polygons)
    for p, q in zip(fast.polygons, plain.polygons):
        assert shapely.to_wkb(p) == shapely.to_wkb(q)
    for a, b in zip(fast.lists, plain.lists):
        assert a.tolist() == b.tolist()


def test_parent_corner_is_a_corner_of_the_child_box():
    from mapkit.vir import _parent_corner

    origin, s = np.array([-3.7, 12.1]), 0.1 * 2.0**3
    ix, iy = np.meshgrid(np.arange(64), np.arange(64))
    ix, iy = ix.ravel(), iy.ravel()
    qx, qy, shared = _parent_corner(ix, iy, origin, s)
    bx, by = origin[0] + ix * s, origin[1] + iy * s
    assert ((qx == bx) | (qx == bx + s)).all() and ((qy == by) | (qy == by + s)).all()
    px = (origin[0] + (ix // 2) * (2 * s)) + s
    py = (origin[1] + (iy // 2) * (2 * s)) + s
    assert (shared == ((px == qx) & (py == qy))).all()
    assert 0 < shared.mean() < 1  # both kinds here
    assert np.abs(qx - px).max() < 1e-12 and np.abs(qy - py).max() < 1e-12


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_merge_queue_from_kept_costs_is_the_plain_greedy(seed):
    """The agglomeration with costs kept per pair and entries made once per
    region merges as the plain greedy that costs every current pair anew,
    on a graph with many equal costs (ties go to the lower pair)."""
    from mapkit.vir import _Agglomeration

    rng = np.random.default_rng(seed)
    n = 120
    area = rng.integers(1, 3, n).astype(float).tolist()
    bits = [int(b) for b in rng.integers(0, 2**6, n)]
    links = {tuple(sorted(map(int, rng.choice(n, 2, replace=False)))) for _ in range(300)}
    links |= {(k, k + 1) for k in range(n - 1)}
    pair_ids = sorted(links)
    merge = _Agglomeration(list(area), list(bits), pair_ids)
    budget = 0.3 * sum(a * b.bit_count() for a, b in zip(area, bits))
    merge.run(merge.first_queue(pair_ids), budget)
    group, got_bits = merge.groups()

    lists, count, label = list(bits), [b.bit_count() for b in bits], list(range(n))

    def cost(a, b):
        u = (lists[a] | lists[b]).bit_count()
        return area[a] * (u - count[a]) + area[b] * (u - count[b])

    current, spent = set(links), 0.0
    while current:
        a, b = min(current, key=lambda p: (cost(*p), p))
        if spent + cost(a, b) > budget:
            break
        spent += cost(a, b)
        lists[a] |= lists[b]
        count[a], area[a] = lists[a].bit_count(), area[a] + area[b]
        label = [a if x == b else x for x in label]
        current = {tuple(sorted((a if x == b else x, a if y == b else y))) for x, y in current}
        current = {p for p in current if p[0] != p[1]}
    reps, want = np.unique(np.array(label), return_inverse=True)
    assert len(reps) < n // 2
    assert np.array_equal(group, want.ravel())
    assert got_bits == [lists[r] for r in reps]
