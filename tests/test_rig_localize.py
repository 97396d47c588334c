"""A rig of cameras localised as one robot (matcher.rig): synthetic frames
with one set of lines per camera, each rendered at its camera's pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

import matcher
from linemap.camera import Camera
from linemap.errors import InputError
from linemap.rig import Mount, Rig, RigCamera
from mapkit_harness.simulate import PEQ, add_noise, clutter_lines, pose_error, random_free_pose, visible_lines
from matcher.rig import localize_rig, localize_rig_global


def ring(n: int, radius: float = 0.2, hfov: float = 70.0) -> Rig:
    """``n`` cameras evenly around the robot, each looking outwards."""
    cam = Camera.from_fov(hfov, 640, 480, 1.2, 0.0)
    return Rig(tuple(RigCamera(f"c{i}", cam, Mount(radius * math.cos(2 * math.pi * i / n),
                                                   radius * math.sin(2 * math.pi * i / n), 360.0 * i / n))
                     for i in range(n)))


def rig_frame(linemap, rig: Rig, rng, pose=None, clutter: int = 3):
    """``(pose, lines per camera, segment ids seen per camera)`` at ``pose``
    (x, y, yaw_deg; drawn in free space when None), noisy lines with
    ``clutter`` random lines per camera."""
    pose = random_free_pose(linemap, rng) if pose is None else pose
    P = np.array([pose[0], pose[1], math.radians(pose[2])])
    lines, seen = [], []
    for rc in rig:
        q = rc.mount.camera_poses(P)
        ideal, ids = visible_lines(linemap, rc.camera, (q[0], q[1], math.degrees(q[2])))
        noisy = add_noise(ideal, rng, 1.0, 1.0, 3.0, rc.camera) if len(ideal) else np.zeros((0, 2, 2))
        lines.append(np.concatenate([noisy, clutter_lines(rng, clutter, rc.camera)]))
        seen.append(set(int(i) for i in ids))
    return pose, lines, seen


def prior_near(pose, rng, peq: int):
    dt, dyaw = PEQ[peq]
    r, phi = dt * math.sqrt(rng.uniform()), rng.uniform(0, 2 * math.pi)
    return (pose[0] + r * math.cos(phi), pose[1] + r * math.sin(phi), pose[2] + rng.uniform(-dyaw, dyaw)), dt, dyaw


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map("maps/flat.lmap")


def test_four_camera_rig_localised_from_a_prior(flat):
    rng = np.random.default_rng(3)
    rig = ring(4)
    for _ in range(4):
        pose, lines, _ = rig_frame(flat, rig, rng)
        prior, dt, dyaw = prior_near(pose, rng, 3)
        res = localize_rig(flat, rig, lines, prior, dt, dyaw)
        assert res, res.reason
        dist, dyaw_err = pose_error(res.pose, pose)
        assert dist < 0.01 and dyaw_err < 0.1
        assert [c["name"] for c in res.cameras] == rig.names
        # Every match of every camera is a segment that camera sees.
        assert sum(len(c["matches"]) for c in res.cameras) == len(res.matches)
        d = res.to_dict()
        assert [c["name"] for c in d["cameras"]] == rig.names


def test_cameras_seeing_different_places_give_one_pose(flat):
    # A front and a back camera 0.4 m apart whose views share no segment:
    # neither camera's lines are those of the other's place, one robot pose
    # explains both.
    cam = Camera.from_fov(60, 640, 480, 1.2, 0.0)
    rig = Rig((RigCamera("front", cam, Mount(0.2, 0.0, 0.0)), RigCamera("back", cam, Mount(-0.2, 0.0, 180.0))))
    rng = np.random.default_rng(11)
    done = 0
    while done < 2:
        pose, lines, seen = rig_frame(flat, rig, rng)
        if seen[0] & seen[1] or min(len(s) for s in seen) < 3:
            continue
        prior, dt, dyaw = prior_near(pose, rng, 2)
        res = localize_rig(flat, rig, lines, prior, dt, dyaw)
        assert res, res.reason
        assert pose_error(res.pose, pose)[0] < 0.01
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
    rig = ring(4)
    for _ in range(2):
        pose, lines, _ = rig_frame(flat, rig, rng)
        res = localize_rig_global(flat, rig, lines)
        assert res, res.reason
        assert pose_error(res.pose, pose)[0] < 0.01


def test_rig_frames_checked_per_camera(flat):
    rig = ring(2)
    with pytest.raises(InputError, match="the rig has 2 cameras"):
        localize_rig(flat, rig, [np.zeros((3, 2, 2))], (1, 1, 0), 0.5, 10)
    bad = [np.array([[[10, 10], [100, 100]]], float), np.array([[[10, 10], [float("nan"), 5]]])]
    with pytest.raises(InputError, match="camera c1: lines"):
        localize_rig(flat, rig, bad, (1, 1, 0), 0.5, 10)
    with pytest.raises(InputError, match="one array of lines per camera"):
        localize_rig(flat, rig, np.zeros((2, 3, 2, 2)), (1, 1, 0), 0.5, 10)
    with pytest.raises(InputError, match="matcher.Rig"):
        localize_rig(flat, "rig.json", [], (1, 1, 0), 0.5, 10)


def test_a_rig_that_sees_nothing_says_why(flat):
    rig = ring(2)
    res = localize_rig(flat, rig, [np.zeros((0, 2, 2)), np.zeros((0, 2, 2))], (2.0, 2.0, 0.0), 0.5, 10)
    assert not res and "usable image lines" in res.reason
