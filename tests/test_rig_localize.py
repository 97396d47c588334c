"""A rig of cameras localised as one robot (matcher.rig): synthetic frames
with one set of lines per camera, each rendered at its camera's pose."""

from __future__ import annotations


import numpy as np
import pytest

import matcher
from linemap.camera import Camera
from linemap.errors import InputError
from linemap.rig import Mount, Rig, RigCamera
from mapkit_harness.rigs import ring_rig
from mapkit_harness.simulate import make_rig_frame, pose_error
from matcher.rig import localize_rig, localize_rig_global


def rig_frame(linemap, rig: Rig, rng, peq: int = 3):
    """A seeded frame of ``rig`` (mapkit_harness.simulate.make_rig_frame)
    and the segment ids each camera sees."""
    f = make_rig_frame(linemap, rig, rng, peq)
    return f, [set(int(s) for s in c.truth if s >= 0) for c in f.cameras]


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map("maps/flat.lmap")


@pytest.mark.slow
def test_four_camera_rig_localised_from_a_prior(flat):
    rng = np.random.default_rng(3)
    rig = ring_rig(4, hfov_deg=70.0, radius_m=0.2)
    for _ in range(4):
        f, _ = rig_frame(flat, rig, rng)
        res = localize_rig(flat, rig, f.lines, f.prior, f.dt, f.dyaw)
        assert res, res.reason
        dist, dyaw_err = pose_error(res.pose, f.pose)
        assert dist < 0.01 and dyaw_err < 0.1
        assert [c["name"] for c in res.cameras] == rig.names
        # Every match of every camera is a segment that camera sees.
        assert sum(len(c["matches"]) for c in res.cameras) == len(res.matches)
        d = res.to_dict()
        assert [c["name"] for c in d["cameras"]] == rig.names


@pytest.mark.slow
def test_cameras_seeing_different_places_give_one_pose(flat):
    # A front and a back camera 0.4 m apart whose views share no segment:
    # neither camera's lines are those of the other's place, one robot pose
    # explains both.
    cam = Camera.from_fov(60, 640, 480, 1.2, 0.0)
    rig = Rig((RigCamera("front", cam, Mount(0.2, 0.0, 0.0)), RigCamera("back", cam, Mount(-0.2, 0.0, 180.0))))
    rng = np.random.default_rng(11)
    done = 0
    while done < 2:
        f, seen = rig_frame(flat, rig, rng, peq=2)
        if seen[0] & seen[1] or min(len(s) for s in seen) < 3:
            continue
        res = localize_rig(flat, rig, f.lines, f.prior, f.dt, f.dyaw)
        assert res, res.reason
        assert pose_error(res.pose, f.pose)[0] < 0.01
        assert all(c["matches"] for c in res.cameras)  # both cameras explain lines
        done += 1


def test_one_camera_rig_is_the_single_camera(flat, cam):
    from mapkit_harness.simulate import make_frame

    rng = np.random.default_rng(5)
    rig = Rig.single(cam)
    for _ in range(3):
        f = make_frame(flat, cam, rng, 3)
        a = matcher.localize(flat, cam, f.lines, f.prior, f.dt, f.dyaw)
        b = localize_rig(flat, rig, [f.lines], f.prior, f.dt, f.dyaw)
        assert a.to_dict() | {"time_ms": None} == b.to_dict() | {"time_ms": None}
        assert a.ranked == b.ranked


@pytest.mark.slow
def test_four_camera_rig_lost(flat):
    rng = np.random.default_rng(8)
    rig = ring_rig(4, hfov_deg=70.0, radius_m=0.2)
    for _ in range(2):
        f, _ = rig_frame(flat, rig, rng)
        res = localize_rig_global(flat, rig, f.lines)
        assert res, res.reason
        assert pose_error(res.pose, f.pose)[0] < 0.01


def test_rig_frames_checked_per_camera(flat):
    rig = ring_rig(2)
    with pytest.raises(InputError, match="the rig has 2 cameras"):
        localize_rig(flat, rig, [np.zeros((3, 2, 2))], (1, 1, 0), 0.5, 10)
    bad = [np.array([[[10, 10], [100, 100]]], float), np.array([[[10, 10], [float("nan"), 5]]])]
    with pytest.raises(InputError, match="camera cam1: lines"):
        localize_rig(flat, rig, bad, (1, 1, 0), 0.5, 10)
    with pytest.raises(InputError, match="one array of lines per camera"):
        localize_rig(flat, rig, np.zeros((2, 3, 2, 2)), (1, 1, 0), 0.5, 10)
    with pytest.raises(InputError, match="matcher.Rig"):
        localize_rig(flat, "rig.json", [], (1, 1, 0), 0.5, 10)


def test_a_rig_that_sees_nothing_says_why(flat):
    rig = ring_rig(2)
    res = localize_rig(flat, rig, [np.zeros((0, 2, 2)), np.zeros((0, 2, 2))], (2.0, 2.0, 0.0), 0.5, 10)
    assert not res and "usable image lines" in res.reason


@pytest.mark.slow
def test_cli_localizes_a_simulated_rig_frame(tmp_path):
    """``tools/simulate.py --rig`` writes a frame that ``matcher localize
    --rig`` localises from a prior and lost; a wrong number of files is one
    line and exit 2."""
    import json
    import subprocess
    import sys

    from cli_helpers import localize_rig_frame, simulated_rig_frame

    out, truth, lines = simulated_rig_frame(tmp_path, ring_rig(4, hfov_deg=70.0, radius_m=0.2), 3, 2)
    run = localize_rig_frame(out, truth, lines, "--json")
    assert run.returncode == 0, run.stderr
    res = json.loads(run.stdout)
    p = truth["pose"]
    assert pose_error((res["pose"]["x"], res["pose"]["y"], res["pose"]["yaw_deg"]), (p["x"], p["y"], p["yaw_deg"]))[0] < 0.01
    assert [c["name"] for c in res["cameras"]] == [c["name"] for c in truth["cameras"]]
    bad = subprocess.run([sys.executable, "-m", "matcher", "localize", "--map", "maps/flat.lmap", "--rig",
                          str(out / "rig.json"), "--lines", lines[0], "--lost"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "give one per camera" in bad.stderr


def _ranked(poses, score, n):
    from matcher.rig.verify import RigRanked

    poses, score, n = np.array(poses, float), np.array(score, float), np.array(n)
    order = np.lexsort((score, -n * np.isfinite(score)))
    return RigRanked(poses, (), n, n, score, np.zeros(len(n)), order, "", np.full(len(n), np.inf))


def test_confirmed_by_counts_the_cameras_whose_seeds_reached_the_best_pose():
    tol = matcher.Tolerances()
    near_m, near_rad = 0.5 * tol.rig.settled_m, np.radians(0.5 * tol.rig.settled_deg)
    far_m = 2.0 * tol.rig.settled_m
    from matcher.rig.localize import confirmed_by

    # The best (camera 0), its own camera's other seed, camera 2's seed near it
    # (and across the +-pi seam), camera 1's seed too far off.
    poses = [(1.0, 2.0, np.pi - 0.001), (1.0 + near_m, 2.0, np.pi), (1.0, 2.0 + far_m, np.pi),
             (1.0, 2.0 - near_m, -np.pi + near_rad)]
    ranked = _ranked(poses, [1e-3, 2e-3, 1e-3, 2e-3], [30, 20, 15, 18])
    assert confirmed_by(ranked, [0, 0, 1, 2], tol) == 2
    assert confirmed_by(ranked, [0, 0, 1, 0], tol) == 1
    # A near seed dropped as a duplicate of the best (E inf, same matches) still counts.
    ranked = _ranked(poses, [1e-3, 2e-3, 1e-3, np.inf], [30, 20, 15, 30])
    assert confirmed_by(ranked, [0, 0, 1, 2], tol) == 2
    # Nothing verified: no camera confirms anything.
    assert confirmed_by(_ranked(poses, [np.inf] * 4, [3] * 4), [0, 1, 2, 3], tol) == 0


@pytest.mark.slow
def test_search_stops_once_two_cameras_found_the_accepted_pose(flat):
    # The same frame with the stop and without it (more cameras than the
    # rig's needed to settle): one answer, fewer tree nodes with the stop.
    from dataclasses import replace

    rng = np.random.default_rng(3)
    rig = ring_rig(4, hfov_deg=70.0, radius_m=0.2)
    rig_frame(flat, rig, rng)  # the first frame's other two cameras see too little to make a difference
    f, _ = rig_frame(flat, rig, rng)
    tol = matcher.Tolerances(search="tree")  # the tree's own early stop
    never = replace(tol, rig=replace(tol.rig, settled_cameras=len(rig) + 1))
    a = localize_rig(flat, rig, f.lines, f.prior, f.dt, f.dyaw, tolerances=tol)
    b = localize_rig(flat, rig, f.lines, f.prior, f.dt, f.dyaw, tolerances=never)
    assert a and b, (a.reason, b.reason)
    assert pose_error(a.pose, f.pose)[0] < 0.01 and pose_error(a.pose, b.pose)[0] < 0.01
    assert a.stage1.tree_nodes < b.stage1.tree_nodes
