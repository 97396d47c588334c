"""Stage 2's slide of loosely fixed poses to where their lines fit
(matcher/stage2/slide.py): the search on a made-up fit count, then the view of
one column's corners on the Barcelona pavilion that it was made for."""

from __future__ import annotations
from pathlib import Path

import numpy as np
import pytest

import matcher
from mapkit.cli import main as mapkit_main
from matcher.stage2 import slide
from mapkit_harness.simulate import make_frame, pose_error

ROOT = Path(__file__).resolve().parents[1]


def _count_where(fits_at):
    """A counter for one hypothesis of three lines: all fit where
    ``fits_at(x, y)`` holds, one otherwise."""

    def count(p):
        return np.where(fits_at(p[..., 0], p[..., 1]), 3.0, 1.0)

    return count


def test_slides_along_the_loose_axis_to_the_nearest_fit():
    # y fixed to 1 m (one standard deviation), x to a millimetre; the lines
    # fit from y = 0.6 on: the pose goes there and no farther, x and the yaw
    # (independent of the position here) unchanged.
    info = np.diag([1e6, 1.0, 1e6])[None]
    poses = np.array([[2.0, 0.0, 0.3]])
    moved, move = slide.slide_poses(poses, info, _count_where(lambda x, y: y >= 0.6), np.array([1.0]))
    assert move.tolist() == [True]
    assert moved[0, 0] == pytest.approx(2.0, abs=1e-9)
    assert moved[0, 2] == pytest.approx(0.3, abs=1e-9)
    assert 0.6 <= moved[0, 1] <= 0.6 + 2 * slide.DEFAULT.stage2.slide_max_m / 2**8 + 1e-9


def test_the_yaw_follows_the_position_as_the_information_says():
    # Yaw and y correlated: the cheapest yaw for a move d in y is
    # -A_yp d / A_yy = -0.5 d.
    info = np.array([[[1e6, 0.0, 0.0], [0.0, 1.0, 5.0], [0.0, 5.0, 10.0]]])
    moved, move = slide.slide_poses(np.zeros((1, 3)), info, _count_where(lambda x, y: y <= -0.4), np.array([1.0]))
    assert move.tolist() == [True]
    assert moved[0, 2] == pytest.approx(-0.5 * moved[0, 1])


def test_a_well_fixed_pose_or_no_better_place_stays():
    count = _count_where(lambda x, y: y >= 0.6)
    tight = np.diag([1e6, 1e6, 1e6])[None]  # a millimetre: no room to slide
    moved, move = slide.slide_poses(np.zeros((1, 3)), tight, count, np.array([1.0]))
    assert not move.any() and np.array_equal(moved, np.zeros((1, 3)))
    loose = np.diag([1e6, 1.0, 1e6])[None]
    nowhere = _count_where(lambda x, y: y >= 10.0)  # beyond the 3 sigma reach
    _, move = slide.slide_poses(np.zeros((1, 3)), loose, nowhere, np.array([1.0]))
    assert not move.any()


@pytest.fixture(scope="module")
def pavilion(tmp_path_factory):
    out = tmp_path_factory.mktemp("pavilion") / "map.lmap"
    options = ["--walls", "Walls", "--walls", "Columns", "--windows", "Crystal"]
    assert mapkit_main(["build", str(ROOT / "tests" / "data" / "barcelona-pavilion.dxf"), "-o", str(out), "-q",
                        *options]) == 0
    return matcher.load_map(out)


@pytest.mark.slow
def test_one_column_seen_from_afar_keeps_its_true_match(pavilion, cam):
    """Seed 0, PEQ 3, frame 32 of tools/bench_paper.py on the pavilion: five
    corners of one column 8 m off and three clutter lines. Least squares
    slid the true hypothesis half a metre back along the bearing, its lines
    stuck out of the column's projection and it was dropped; another column
    won, 0.9 m and 5 degrees off."""
    rng = np.random.default_rng([0, 3])
    frames = [make_frame(pavilion, cam, rng, 3, 1.0, 1.0, clutter=3) for _ in range(33)]
    fr = frames[32]
    res = matcher.localize(pavilion, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
    assert res, res.reason
    assert sorted(map(tuple, res.matches)) == sorted(map(tuple, fr.true_matches()))
    pos, yaw = pose_error(res.pose, fr.pose)
    assert pos < 0.5 and yaw < 3.0
