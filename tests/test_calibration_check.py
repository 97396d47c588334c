"""A camera file whose calibration does not fit the matched lines
(matcher/stage2/calibration_check.py): the fits recover the calibration,
the verdict refuses the pose with the reason, and right cameras are
answered as before."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import matcher
from matcher.result import Deferred
from matcher.stage2.calibration_check import calibration_fits, doubt, miscalibration
from matcher.tolerances import DEFAULT
from matcher.verdict import NOT_LOCALISED, Evidence, decide
from mapkit_harness.simulate import make_frame, pose_error, visible_lines

#: Frames of the example map at PEQ 2, as tools/bench_calibration.py's tuning seeds make them.
SEEDS, POSES = (0, 1, 2, 3), 6


@pytest.fixture(scope="module")
def flat():
    from pathlib import Path

    return matcher.load_map(Path(__file__).resolve().parent.parent / "maps" / "flat.lmap")


@pytest.fixture(scope="module")
def frames(flat, cam):
    return [make_frame(flat, cam, rng, 2) for s in SEEDS for rng in [np.random.default_rng([s, 2])]
            for _ in range(POSES)]


def _exact_view(linemap, camera, pose):
    """The lines (T, 2, 2) and their segments (T, 2, 3) a camera at ``pose``
    (x, y, yaw_deg) sees, without noise."""
    lines, ids = visible_lines(linemap, camera, pose)
    return lines, linemap.segments[ids]


def test_the_fits_recover_a_wrong_focal_length_and_height(flat, cam):
    pose = (4.0, 3.0, 30.0)
    lines, segs = _exact_view(flat, cam, pose)
    assert len(lines) >= 6
    at = np.array([pose[0], pose[1], math.radians(pose[2])])
    # The file's focal length 0.8 x the true one: freeing it finds 1.25 x the file's.
    short = replace(cam, fx=cam.fx * 0.8, fy=cam.fy * 0.8)
    focal = {f.name: f for f in calibration_fits(short, lines, segs, at, DEFAULT)}["focal"]
    assert focal.value == pytest.approx(1.25, abs=0.01)
    assert focal.drop > 100 and focal.rss < 1e-6 * focal.rss_file + 1e-9
    assert math.hypot(focal.pose[0] - pose[0], focal.pose[1] - pose[1]) < 0.01
    # A height 0.2 m too low: freeing it finds +0.2 m.
    low = replace(cam, height_m=cam.height_m - 0.2)
    height = {f.name: f for f in calibration_fits(low, lines, segs, at, DEFAULT)}["height"]
    assert height.value == pytest.approx(0.2, abs=0.005)


def test_the_true_calibration_is_not_blamed_and_few_lines_are_not_judged(flat, cam):
    pose = (4.0, 3.0, 30.0)
    lines, segs = _exact_view(flat, cam, pose)
    at = np.array([pose[0], pose[1], math.radians(pose[2])])
    assert miscalibration(cam, lines, segs, at, DEFAULT) == []
    short = replace(cam, fx=cam.fx * 0.8, fy=cam.fy * 0.8)
    assert miscalibration(short, lines, segs, at, DEFAULT)[0].name == "focal"
    few = DEFAULT.verdict.calibration_min_lines - 1
    assert miscalibration(short, lines[:few], segs[:few], at, DEFAULT) == []
    words = doubt(short, lines, segs, at, DEFAULT)
    assert words.startswith("the matched lines fit the map far better with a focal length 1.25 x the camera file's")
    assert words.endswith("check the camera calibration")


def test_the_verdict_refuses_a_pose_whose_lines_blame_the_calibration_last():
    ev = Evidence(score=1e-4, explained=6, searched=12, needed=4, answers=(((1.0, 2.0, 30.0), 6, 1e-4, 1.0),),
                  calibration=Deferred(lambda: "the matched lines fit the map far better with ...: check the "
                                               "camera calibration"))
    v = decide(ev, DEFAULT)
    assert v.status == NOT_LOCALISED and v.reason.endswith("check the camera calibration") and v.score == 1e-4
    assert decide(replace(ev, calibration=Deferred(lambda: "")), DEFAULT)


def _outcomes(linemap, camera, frames, tol=DEFAULT):
    return [matcher.localize(linemap, camera, fr.lines, fr.prior, fr.dt, fr.dyaw, tol) for fr in frames]


@pytest.mark.slow
@pytest.mark.parametrize("scale", [0.8, 1.25])
def test_a_focal_length_20_percent_off_is_refused_with_its_reason(flat, cam, frames, scale):
    """Every answer that matches enough lines to tell a focal length from
    the pose is refused or right. (An answer on 4 lines, 8 residuals for a
    pose and a focal length, cannot tell: docs/benchmarks/calibration.md
    counts those.)"""
    wrong = replace(cam, fx=cam.fx * scale, fy=cam.fy * scale)
    results = _outcomes(flat, wrong, frames)
    blamed = [r for r in results if not r and "check the camera calibration" in r.reason]
    assert len(blamed) >= 4 and all("focal length" in r.reason for r in blamed)
    told = DEFAULT.verdict.calibration_min_lines + 1
    off = [pose_error(r.pose, fr.pose) for r, fr in zip(results, frames) if r and len(r.matches) >= told]
    assert all(dm <= 0.2 for dm, _ in off), off


@pytest.mark.slow
def test_right_cameras_are_answered_as_without_the_check(flat, cam, frames):
    unchecked = replace(DEFAULT, verdict=replace(DEFAULT.verdict, calibration_judged=()))
    for fr, checked, plain in zip(frames, _outcomes(flat, cam, frames), _outcomes(flat, cam, frames, unchecked)):
        assert (checked.ok, checked.reason, checked.pose, checked.matches) == (plain.ok, plain.reason, plain.pose,
                                                                               plain.matches)
        assert checked.ok and pose_error(checked.pose, fr.pose)[0] < 0.2


@pytest.mark.slow
def test_lost_mode_refuses_a_focal_length_twice_off_instead_of_a_place_metres_away(flat, cam):
    """A frame seen at twice the camera file's focal length, localised with
    no prior: the region holding the frame's true segments fits them with
    the focal length freed at a pose metres out of that region (lost mode
    has no prior to bound it: anywhere the robot can stand counts), so the
    calibration is blamed for the whole map, not passed over for a place
    that explains fewer lines (it accepted one 3.8 m off before). The sweep
    is kept to the regions that matter (the truth's, and those of the two
    wrong places it accepted before) to keep the test short."""
    seen = replace(cam, fx=cam.fx * 1.97, fy=cam.fy * 1.97)
    rng = np.random.default_rng([7, 1])
    frame = [make_frame(flat, seen, rng, 1, 1.0, 1.0, clutter=3) for _ in range(7)][-1]
    regions = sorted({int(r) for x, y in (frame.pose[:2], (4.10, 1.83), (2.29, 1.92)) for r in flat.regions_at(x, y)})
    res = matcher.localize_global(flat, cam, frame.lines, regions=regions)
    assert not res and "focal length 2.0" in res.reason and "check the camera calibration" in res.reason, res.reason
