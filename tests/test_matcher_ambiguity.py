"""A view the map shows from several poses is not answered with one of
them: the result is falsy, says why, and names the poses (a square room
looks the same every quarter turn)."""

from __future__ import annotations

import math

import pytest

import matcher
from mapkit_harness.simulate import visible_lines
from mapkit_harness.plans import make_box_map


@pytest.fixture(scope="module")
def square_room():
    return make_box_map(6.0, 6.0)


def _view_of_a_corner(room, cam):
    """Lines seen from the room's centre looking at a corner (no noise)."""
    pose = (3.0, 3.0, 45.0)
    lines, ids = visible_lines(room, cam, pose)
    assert len(ids) >= 3
    return pose, lines


def _quarter_turns_named(res, pose):
    yaws = sorted(round(((c["yaw_deg"] - pose[2] + 45.0) % 360.0) // 90.0) for c in res.candidates)
    assert len(res.candidates) >= 2
    assert len(set(yaws)) == len(yaws)  # different poses, not one pose twice
    for c in res.candidates:
        assert math.hypot(c["x"] - pose[0], c["y"] - pose[1]) < 0.1  # the centre, turned
        assert c["matches"] == res.candidates[0]["matches"]


def test_a_symmetric_room_with_a_wide_prior_names_its_twins(square_room):
    cam = matcher.Camera.from_fov(90.0, 640, 480, 1.2, 0.0)
    pose, lines = _view_of_a_corner(square_room, cam)
    res = matcher.localize(square_room, cam, lines, (3.2, 2.9, 0.0), 1.0, 180.0)
    assert not res and res.pose is None
    assert "poses fit the lines about equally well" in res.reason
    _quarter_turns_named(res, pose)
    d = res.to_dict()
    assert d["ok"] is False and len(d["candidates"]) == len(res.candidates)


def test_lost_mode_in_a_symmetric_room_names_its_twins(square_room):
    cam = matcher.Camera.from_fov(90.0, 640, 480, 1.2, 0.0)
    pose, lines = _view_of_a_corner(square_room, cam)
    res = matcher.localize_global(square_room, cam, lines)
    assert not res and "equally well" in res.reason
    _quarter_turns_named(res, pose)


def test_a_narrow_prior_in_the_same_room_decides(square_room):
    """Within a prior that holds one of the twins the answer stands."""
    cam = matcher.Camera.from_fov(90.0, 640, 480, 1.2, 0.0)
    pose, lines = _view_of_a_corner(square_room, cam)
    res = matcher.localize(square_room, cam, lines, (3.1, 2.9, 40.0), 0.3, 20.0)
    assert res, res.reason
    assert not res.candidates
    assert math.hypot(res.pose[0] - pose[0], res.pose[1] - pose[1]) < 0.05
    assert abs(res.pose[2] - pose[2]) < 1.0
