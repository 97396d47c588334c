"""Resection from vertical edges (matcher/resection.py): the closed form,
the triples it solves, the sets it proposes, and a view along a wall of
door jambs that the interpretation tree alone did not settle."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import matcher
from linemap.geometry import wrap
from matcher.tolerances import DEFAULT
from matcher.search.tree.resection import resect as _resect
from matcher.search.tree.resection import EdgeCorrespondences, triples, vertical_hypotheses
from mapkit_harness.simulate import make_frame, paper_camera, pose_error

WORK = DEFAULT.stage1


def resect(points, alpha):
    return _resect(points, alpha, WORK.resection_min_range_m)


def _bearings(points, pose):
    """Bearings, radians, right of the optical axis, of floor points (..., 2)
    from pose (x, y, yaw)."""
    rel = points - np.asarray(pose[:2])
    return wrap(pose[2] - np.arctan2(rel[..., 1], rel[..., 0]))


def test_resect_recovers_random_poses():
    rng = np.random.default_rng(3)
    P = 500
    c = rng.uniform(-5, 5, (P, 2))
    yaw = rng.uniform(-math.pi, math.pi, P)
    alpha = rng.uniform(-0.6, 0.6, (P, 3))
    r = rng.uniform(0.5, 9.0, (P, 3))
    world = yaw[:, None] - alpha
    pts = c[:, None, :] + r[..., None] * np.stack([np.cos(world), np.sin(world)], axis=-1)
    poses, ok = resect(pts, alpha)
    assert ok.all()
    assert np.abs(poses[:, :2] - c).max() < 1e-9
    assert np.abs(wrap(poses[:, 2] - yaw)).max() < 1e-9


def test_resect_refuses_edges_behind_and_degenerate_triples():
    pose = (1.0, 2.0, 0.3)
    pts = np.array([[4.0, 2.5], [3.0, 4.0], [5.0, 1.0]])
    alpha = _bearings(pts, pose)
    p, ok = resect(pts[None], alpha[None])
    assert ok[0] and np.allclose(p[0], pose)
    # One bearing turned by pi: the same sight lines, so the same position,
    # but that edge would stand behind the camera.
    _, ok = resect(pts[None], (alpha + np.array([0.0, math.pi, 0.0]))[None])
    assert not ok[0]
    # Three edges on one point: no pose.
    _, ok = resect(np.repeat(pts[:1], 3, axis=0)[None], alpha[None])
    assert not ok[0]


def test_triples_are_compatible_and_on_three_lines():
    rng = np.random.default_rng(0)
    K = 30
    line = rng.integers(0, 5, K)
    compat = rng.random((K, K)) < 0.5
    compat = np.triu(compat, 1)
    compat = compat | compat.T
    t = triples(compat, np.arange(K), line, WORK.resection_max_triples)
    assert len(t)
    assert (line[t[:, 0]] != line[t[:, 1]]).all() and (line[t[:, 1]] != line[t[:, 2]]).all()
    assert (line[t[:, 0]] != line[t[:, 2]]).all()
    assert compat[t[:, 0], t[:, 1]].all() and compat[t[:, 0], t[:, 2]].all() and compat[t[:, 1], t[:, 2]].all()
    # Every compatible triple on three lines is there (brute force).
    want = {(a, b, c) for a in range(K) for b in range(K) for c in range(K)
            if len({line[a], line[b], line[c]}) == 3 and compat[a, b] and compat[a, c] and compat[b, c]}
    assert {tuple(sorted(x)) for x in t.tolist()} == {tuple(sorted(x)) for x in want}


def test_vertical_hypotheses_find_the_true_set_first():
    """Six edges seen, every line a candidate of every edge: the set with
    all six lines, each on its own edge, comes first, at the pose."""
    rng = np.random.default_rng(1)
    pose = (2.0, 1.0, math.radians(40.0))
    world = pose[2] - np.radians([-30.0, -18.0, -6.0, 6.0, 18.0, 30.0]) - rng.uniform(-0.05, 0.05, 6)
    edges = np.array(pose[:2]) + rng.uniform(1.0, 6.0, 6)[:, None] * np.stack([np.cos(world), np.sin(world)], 1)
    lines_alpha = _bearings(edges, pose) + rng.uniform(-0.002, 0.002, 6)
    seg, line = np.meshgrid(np.arange(6), np.arange(6), indexing="ij")
    seg, line = seg.ravel(), line.ravel()
    K = len(seg)
    compat = (seg[:, None] != seg[None, :]) & (line[:, None] != line[None, :])
    prior = (2.3, 0.8, math.radians(30.0), 0.5, math.radians(20.0))
    corr = EdgeCorrespondences(edges[seg], seg, line, np.ones(K, bool), compat, lines_alpha, np.full(6, 0.004))
    sets, inits = vertical_hypotheses(corr, prior, None, DEFAULT, max_hypotheses=5, min_lines=4)
    assert sets
    best = sets[0]
    assert len(best) == 6 and (seg[best] == line[best]).all()
    assert np.hypot(*(inits[0, :2] - pose[:2])) < 0.05 and abs(wrap(inits[0, 2] - pose[2])) < 0.01
    # Outside the prior: nothing.
    far = (12.0, 9.0, 0.0, 0.5, math.radians(20.0))
    assert vertical_hypotheses(corr, far, None, DEFAULT, 25, 4)[0] == []


@pytest.mark.slow
def test_view_along_door_jambs_is_localised():
    """PEQ 5, seed 2, frame 40 of tools/bench_paper.py: five door jambs and
    corners of one wall, three clutter lines. The tree alone ran out of its
    node budget among thousands of loose sets and nothing was accepted; the
    resected poses hold the true set."""
    linemap = matcher.load_map(Path(__file__).resolve().parents[1] / "maps" / "flat.lmap")
    cam = paper_camera()
    rng = np.random.default_rng([2, 5])
    for _ in range(41):
        fr = make_frame(linemap, cam, rng, 5, 1.0, 1.0, clutter=3)
    res = matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    assert res, res.reason
    assert res.stage1.resection > 0
    assert res.hypotheses <= 25
    assert {tuple(m) for m in res.matches} == {tuple(m) for m in fr.true_matches()}
    pos, yaw = pose_error(res.pose, fr.pose)
    assert pos < 0.05 and yaw < 0.5
