"""A frame's own pitch and roll (matcher/attitude.py): the homography to the
nominal camera, the estimate from vertical lines, frames with a roll of up
to 3 degrees and a pitch up to 2 degrees off the file localised as level
ones, and cameras without the new fields untouched."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher
from matcher import attitude
from matcher.input_validation import check_lines
from matcher.tolerances import DEFAULT

from mapkit_harness.scoring import indistinguishable, is_correct, level_view
from mapkit_harness.simulate import make_frame, paper_camera

MAP = Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"


@pytest.fixture(scope="module")
def flat():
    return matcher.load_map(MAP)


def test_the_homography_moves_a_rolled_and_pitched_view_to_the_nominal_one():
    cam = paper_camera(pitch_deg=4.0)
    real = replace(cam, pitch_deg=5.5, roll_deg=-2.5)
    pts = np.array([[4.0, 1.0, 0.0], [5.0, -2.0, 2.4], [3.0, 0.5, 1.0], [6.0, 2.0, 0.3]])
    seen, _ = real.project(pts, 0.0, 0.0, 0.0)
    want, _ = cam.project(pts, 0.0, 0.0, 0.0)
    att = attitude.Attitude(real.pitch, real.roll, 0.0, 0.0)
    got = attitude.rectify(cam, seen.reshape(2, 2, 2), att).reshape(-1, 2)
    assert np.abs(got - want).max() < 1e-9


def _frames(flat, n, peq, seed, roll=3.0, pitch_error=2.0):
    rng = np.random.default_rng([seed, peq])
    cam = paper_camera()
    return [make_frame(flat, cam, rng, peq, roll_deg=roll, pitch_error_deg=pitch_error) for _ in range(n)]


@pytest.mark.slow
def test_vertical_lines_give_the_roll(flat):
    cam = replace(paper_camera(), pitch_std_deg=1.5, roll_std_deg=2.0)
    err = []
    for fr in _frames(flat, 30, 1, 11):
        est = attitude.from_verticals(cam, check_lines(fr.lines, cam, DEFAULT), DEFAULT)
        err.append(abs(math.degrees(est.roll) - fr.roll_deg))
    assert np.median(err) < 0.4  # the matched segments' fit brings it under 0.3 (below)


@pytest.mark.slow
def test_rolled_and_pitched_frames_localise_as_level_ones(flat):
    cam = replace(paper_camera(), pitch_std_deg=1.5, roll_std_deg=2.0)
    right, pitch_err, roll_err = 0, [], []
    frames = _frames(flat, 10, 2, 3)
    for fr in frames:
        res = matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        truth = {tuple(m) for m in fr.true_matches()}
        right += bool(res.ranked) and is_correct(res.ranked[0][1], truth,
                                                 equivalent=indistinguishable(flat, *level_view(cam, fr)))
        pitch_err.append(abs(res.pitch_deg - fr.pitch_deg))
        roll_err.append(abs(res.roll_deg - fr.roll_deg))
        d = res.to_dict()
        assert d["pitch_deg"] == res.pitch_deg and d["roll_deg"] == res.roll_deg
    assert right >= 9
    assert np.median(pitch_err) < 0.3 and np.median(roll_err) < 0.3


@pytest.mark.slow
def test_a_known_roll_is_one_homography(flat):
    cam = paper_camera()
    for fr in _frames(flat, 4, 3, 5, roll=3.0, pitch_error=0.0):
        known = replace(cam, roll_deg=fr.roll_deg)
        res = matcher.localize(flat, known, fr.lines, fr.prior, fr.dt, fr.dyaw)
        assert res and res.roll_deg == pytest.approx(fr.roll_deg) and res.pitch_deg == 0.0
        moved = attitude.rectify(cam, fr.lines, attitude.Attitude(0.0, math.radians(fr.roll_deg), 0.0, 0.0))
        level = matcher.localize(flat, cam, moved, fr.prior, fr.dt, fr.dyaw)
        assert res.matches == level.matches and np.allclose(res.pose, level.pose, atol=1e-3)


def test_a_camera_without_the_new_fields_takes_the_old_path(flat, monkeypatch):
    def never(*a, **k):
        raise AssertionError("the attitude path ran")

    monkeypatch.setattr(attitude, "localize_with_attitude", never)
    cam = matcher.Camera.from_dict(paper_camera().to_dict())
    fr = _frames(flat, 1, 1, 0, roll=0.0, pitch_error=0.0)[0]
    res = matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    assert res and res.pitch_deg is None and "pitch_deg" not in res.to_dict() and "roll_deg" not in res.to_dict()


def test_one_time_budget_bounds_the_whole_call(flat, monkeypatch):
    """The bands and second runs of an uncertain attitude share the call's
    one budget: with none left after the first band, no other run starts,
    and the first ends not localised, saying why."""
    cam = replace(paper_camera(), pitch_std_deg=1.5, roll_std_deg=2.0)
    fr = _frames(flat, 1, 1, 5)[0]
    runs = []
    real_run = matcher.from_prior.localize_lines

    def counted(*args, **kwargs):
        runs.append(args[6].time_budget_ms)
        return real_run(*args, **kwargs)

    monkeypatch.setattr(matcher.from_prior, "localize_lines", counted)
    tol = replace(matcher.Tolerances(), time_budget_ms=0.0)
    res = matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw, tolerances=tol)
    assert not res and "time budget" in res.reason
    assert runs == [0.0]
    # With a budget, every run gets what the call has left.
    runs.clear()
    matcher.localize(flat, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    assert len(runs) >= 2 and all(b <= DEFAULT.time_budget_ms for b in runs)
    assert all(later < earlier for earlier, later in zip(runs, runs[1:]))
