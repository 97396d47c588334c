"""The structure search (matcher.search.structure): yaw from level lines,
every place of the prior ranked, the best verified; synthetic frames of
mapkit_harness.simulate on the example map and a box room, seeded."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import matcher
from mapkit_harness.plans import make_box_map
from mapkit_harness.rigs import ring_rig
from mapkit_harness.simulate import make_rig_frame, pose_error, visible_lines
from matcher.rig.frame import prepare_rig_frame
from matcher.search import default_search
from matcher.search.structure.observed import observe
from matcher.search.structure.profiles import first_hits, grid_profiles
from matcher.search.structure.ranking import rank_places
from matcher.search.structure.yaw import yaw_bins
from matcher.verdict import NOT_LOCALISED, Evidence, decide

STRUCTURE = matcher.Tolerances(search="structure")


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map("maps/flat.lmap")


@pytest.fixture(scope="module")
def ring():
    """Four 90-degree cameras at the robot's centre, a panorama's cut in four."""
    return ring_rig(4, hfov_deg=90.0, radius_m=0.0)


def _frames(linemap, rig, seed: int, count: int, peq: int = 3):
    rng = np.random.default_rng(seed)
    return [make_rig_frame(linemap, rig, rng, peq, min_seen=12) for _ in range(count)]


def test_first_hits_is_the_nearest_crossing_of_each_ray():
    """Rays from a point, binned by bearing, against two parallel walls
    ahead and a short one behind: each bin's middle ray meets the nearer
    wall ahead; behind, only the ray of the bin the short wall spans
    (146 to 162 degrees: the middle ray at 157.5) meets it."""
    walls = np.array([[[1.0, -5.0], [1.0, 5.0]], [[2.0, -5.0], [2.0, 5.0]], [[-3.0, 1.0], [-3.0, 2.0]]])
    dist, index = first_hits(np.zeros((1, 2)), 8, walls)
    middle = (np.arange(8) + 0.5) * (2 * math.pi / 8)
    ahead = np.cos(middle) > 0
    assert np.allclose(dist[0, ahead], 1.0 / np.cos(middle[ahead]))
    assert (index[0, ahead] == 0).all()
    assert np.isclose(dist[0, 3], 3.0 / math.cos(math.radians(22.5))) and index[0, 3] == 2
    assert np.isinf(dist[0, [2, 4, 5]]).all()


def test_yaw_from_level_lines_of_a_rig(flat, ring):
    """The true heading is among the yaw hypotheses (within a bin), and
    they are few: the example map's walls run two ways."""
    tol = matcher.Tolerances()
    grid = grid_profiles(flat, tol)
    width = 360.0 / grid.bins
    for f in _frames(flat, ring, 11, 4):
        frame = prepare_rig_frame(ring, f.lines, tol)
        yaws = yaw_bins(observe(frame.views, math.radians(width)), grid.directions, grid.bins, None,
                        tol.shared.yaw_peak_share)
        off = np.abs((yaws * width - f.pose[2] + 180.0) % 360.0 - 180.0)
        assert off.min() <= 1.5 * width, (f.pose, yaws * width)
        # Four headings (two wall directions, both ways), each a few neighbouring bins.
        gaps = np.diff(np.concatenate([yaws, yaws[:1] + grid.bins]))
        assert (gaps > 3).sum() <= 4, yaws


def test_ranking_of_the_whole_floor_puts_the_truth_first(flat, ring):
    """Lost (the whole floor, every yaw hypothesis): the first peak is the
    true pose, to within the lattice's step and a couple of degrees."""
    tol = matcher.Tolerances()
    for f in _frames(flat, ring, 5, 4):
        frame = prepare_rig_frame(ring, f.lines, tol)
        ranking = rank_places(flat, frame.views, None, tol, tol.rig.seeds_per_camera)
        x, y, theta = ranking.peaks.poses[0]
        d, a = pose_error((x, y, math.degrees(theta)), f.pose)
        assert d <= 0.2 and a <= 2.0, (f.pose, ranking.peaks.poses[:3])
        assert len(ranking.peaks.poses) >= 2  # the runner-up elsewhere is known


def test_rig_localised_by_the_structure_search(flat, ring):
    """From a prior and lost, the verified answer is the truth."""
    for f in _frames(flat, ring, 7, 3):
        res = matcher.localize_rig(flat, ring, f.lines, f.prior, f.dt, f.dyaw, tolerances=STRUCTURE)
        assert res and pose_error(res.pose, f.pose)[0] < 0.05, (f.pose, res.reason)
        lost = matcher.localize_rig_global(flat, ring, f.lines, tolerances=STRUCTURE)
        assert lost and pose_error(lost.pose, f.pose)[0] < 0.05, (f.pose, lost.reason)


def test_a_rectangular_room_seen_from_its_twin_pose_is_refused_naming_the_rival(ring):
    """A bare rectangular room looks the same from a pose and its half
    turn about the room's centre: lost, the two tie and the result names
    both."""
    room = make_box_map(6.0, 4.0)
    pose = (2.0, 1.4, 30.0)
    lines = []
    for rc in ring:
        cam_yaw = pose[2] + rc.mount.yaw_deg
        lines.append(visible_lines(room, rc.camera, (pose[0], pose[1], cam_yaw))[0])
    res = matcher.localize_rig_global(room, ring, lines, tolerances=STRUCTURE)
    assert not res
    twin = (6.0 - pose[0], 4.0 - pose[1], pose[2] + 180.0)
    named = [(c["x"], c["y"], c["yaw_deg"]) for c in res.candidates]
    assert any(pose_error(p, pose)[0] < 0.05 for p in named), (named, res.reason)
    assert any(pose_error(p, twin)[0] < 0.05 and pose_error(p, twin)[1] < 1.0 for p in named), (named, res.reason)


def test_the_verdict_names_the_rankings_runner_up():
    """A best pose refused (here for its E) names the ranking's runner-up
    beside it; a runner-up that explains as many lines refuses the best."""
    tol = matcher.Tolerances()
    best = ((1.0, 2.0, 30.0), 20, 1e-2, 5.0)
    rival = ((4.0, 1.0, 210.0), 0, math.inf, math.inf)
    v = decide(Evidence(score=1e-2, answers=(best,), runner_up=rival), tol)
    assert v.status == NOT_LOCALISED and "best pose elsewhere is (4.00, 1.00, 210 deg)" in v.reason
    assert [(c["x"], c["y"]) for c in v.candidates] == [(1.0, 2.0), (4.0, 1.0)]
    good = (best[0], 20, 1e-4, 5.0)
    ev = Evidence(score=1e-4, answers=(good,), clear_ratio=1.5, runner_up=((4.0, 1.0, 210.0), 18, 1e-4, 5.0))
    v = decide(ev, tol)
    assert v.status == NOT_LOCALISED and "a pose elsewhere 18" in v.reason
    assert decide(replace(ev, runner_up=rival), tol)  # a runner-up that explains nothing is no rival


def test_search_chosen_by_the_tolerances():
    assert default_search(None) == "tree" and default_search("structure") == "structure"
    with pytest.raises(matcher.InputError, match="search must be"):
        matcher.Tolerances(search="grid")


@pytest.mark.slow
@pytest.mark.parametrize("search", ["tree", "structure"])
def test_cli_search_option(tmp_path, search):
    """``matcher localize --search`` runs either search on a rig frame."""
    import json

    from cli_helpers import localize_rig_frame, simulated_rig_frame

    out, truth, lines = simulated_rig_frame(tmp_path, ring_rig(4, hfov_deg=90.0, radius_m=0.0), 2, 2)
    run = localize_rig_frame(out, truth, lines, "--search", search, "--json")
    assert run.returncode == 0, run.stderr
    res = json.loads(run.stdout)
    p = truth["pose"]
    assert pose_error((res["pose"]["x"], res["pose"]["y"], res["pose"]["yaw_deg"]), (p["x"], p["y"], p["yaw_deg"]))[0] < 0.05
