"""Pose votes of lost mode (matcher/lost_votes.py): sightings put the camera
where it is, and the voted places hold the true pose."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import matcher
from matcher.from_prior import validated_inputs
from matcher.lost_votes import sightings, vote_places
from matcher.tolerances import DEFAULT
from mapkit_harness.simulate import make_frame, pose_error, visible_lines

ROOT = Path(__file__).resolve().parents[1]


def _near(place, pose, metres=0.5, degrees=6.0) -> bool:
    pos, yaw = pose_error((place[0], place[1], math.degrees(place[2])), pose)
    return pos < metres and yaw < degrees


def test_a_floor_line_puts_the_camera_beside_its_segment(cam):
    """One noiseless image line of a horizontal segment: a sighting of it
    has the true heading, and the true position lies on its camera line,
    within its stretch."""
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    pose = (4.0, 3.0, 30.0)
    lines, ids = visible_lines(linemap, cam, pose)
    segs = linemap.segments[ids]
    flat = np.abs(segs[:, 0, 2] - segs[:, 1, 2]) < 1e-6
    assert flat.any()
    one = lines[np.flatnonzero(flat)[:1]]
    _, img = validated_inputs(linemap, cam, one, None)
    s = sightings(linemap, cam, img, DEFAULT)
    mine = s.line == 0
    assert mine.any()
    yaw_err = np.abs(np.remainder(s.yaw[mine] - math.radians(pose[2]) + np.pi, 2 * np.pi) - np.pi)
    xy = np.array(pose[:2])
    off = np.einsum("kc,kc->k", xy - s.base[mine], s.nrm[mine])
    a = np.einsum("kc,kc->k", xy - s.base[mine], s.u[mine])
    hit = (yaw_err < math.radians(0.5)) & (np.abs(off) < 0.02) & (a >= s.a_lo[mine]) & (a <= s.a_hi[mine])
    assert hit.any()


@pytest.mark.slow
def test_the_true_place_is_among_the_voted_ones(cam):
    """Simulated frames (1 px noise, 3 clutter lines): on most, the true
    pose is one of the 12 places the lines vote for."""
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    rng = np.random.default_rng([7, 1])
    found = 0
    for _ in range(12):
        fr = make_frame(linemap, cam, rng, 1, 1.0, 1.0, clutter=3)
        _, img = validated_inputs(linemap, cam, fr.lines, None)
        places = vote_places(linemap, cam, img, DEFAULT, DEFAULT.lost.vote_places)
        assert places.shape[1] == 4 and (np.diff(places[:, 3]) <= 0).all()
        found += any(_near(p, fr.pose) for p in places)
    assert found >= 8


@pytest.mark.slow
def test_clutter_votes_for_no_trusted_place(cam):
    """Random lines alone: lost mode returns no pose."""
    from mapkit_harness.simulate import clutter_lines

    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    rng = np.random.default_rng(5)
    res = matcher.localize_global(linemap, cam, clutter_lines(rng, 8, cam), matcher.Tolerances(time_budget_ms=3000))
    assert not res
