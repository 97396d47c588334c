"""Cluttered frames: stage 1 searches with the longest lines only, stage 2
judges them all, and a pose must explain more lines the more lines the
frame has (clutter fits a few lines anywhere)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher
from matcher.frame import lines_needed, prepare_lines
from mapkit_harness.simulate import make_frame, paper_camera, pose_error

ROOT = Path(__file__).resolve().parent.parent


def _short_clutter(rng, n, camera, length_px=(16.0, 30.0)):
    """``n`` random lines (n, 2, 2) inside the image, ``length_px`` pixels long."""
    out = []
    while len(out) < n:
        a = rng.uniform((5, 5), (camera.width - 5, camera.height - 5))
        t = rng.uniform(0, 2 * math.pi)
        b = a + rng.uniform(*length_px) * np.array([math.cos(t), math.sin(t)])
        if 5 <= b[0] <= camera.width - 5 and 5 <= b[1] <= camera.height - 5:
            out.append((a, b))
    return np.array(out)


def test_stage1_searches_the_longest_lines_and_few_vertical_ones():
    cam = paper_camera()
    tol = matcher.Tolerances()
    rng = np.random.default_rng(3)
    horizontal = np.stack([rng.uniform(100, 200, (40, 2)), rng.uniform(250, 300, (40, 2))], 1)  # 50 to 200 px
    horizontal[:, :, 1] = horizontal[:, :, 0] * 0.2 + 50  # slanted: not vertical candidates
    horizontal[:, 1, 1] += 5
    vertical = np.stack([np.stack([np.linspace(30, 600, 20), np.full(20, 40.0)], 1),
                         np.stack([np.linspace(30, 600, 20), np.linspace(200, 440, 20)], 1)], 1)
    lines = np.concatenate([horizontal, vertical])  # the vertical ones 160 to 400 px: the longest
    img = prepare_lines(cam, lines, tol)
    assert img.usable.sum() == 60
    assert img.searched.sum() == tol.search_lines
    assert (img.searched & img.vertical).sum() == tol.search_vertical_lines
    length = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    # The vertical ones kept are the longest vertical ones.
    v = np.nonzero(img.vertical)[0]
    kept = v[img.searched[v]]
    assert length[kept].min() >= np.sort(length[v])[-tol.search_vertical_lines]
    # A frame with few lines searches them all.
    few = prepare_lines(cam, lines[:8], tol)
    assert (few.searched == few.usable).all()


def test_lines_needed_grows_with_the_lines_searched():
    cam = paper_camera()
    tol = matcher.Tolerances()
    rng = np.random.default_rng(5)
    small = prepare_lines(cam, _short_clutter(rng, 6, cam), tol)
    large = prepare_lines(cam, _short_clutter(rng, 60, cam), tol)
    assert lines_needed(small, tol) == tol.min_matches
    share = tol.verdict.chance_fit_share
    assert lines_needed(large, tol) == tol.min_matches + int(share * tol.search_lines)


@pytest.mark.slow
def test_short_clutter_changes_nothing():
    """Fifty short clutter lines: stage 1 searches the longest 25 (the map's
    own lines among them), stage 2 judges every line, and the answer is the
    one the frame gives alone, with no clutter line matched."""
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    cam = paper_camera()
    rng = np.random.default_rng([25, 1])
    for _ in range(6):
        fr = make_frame(linemap, cam, rng, 1, clutter=0, min_seen=7, max_seen=9)
        alone = matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        res = matcher.localize(linemap, cam, np.concatenate([fr.lines, _short_clutter(rng, 50, cam)]), fr.prior,
                               fr.dt, fr.dyaw)
        assert bool(res) == bool(alone)
        if alone:
            assert pose_error(res.pose, alone.pose)[0] < 1e-3
            assert all(line < len(fr.lines) for _, line in res.matches)


@pytest.mark.slow
def test_a_pose_explaining_few_of_many_lines_is_refused_with_its_reason():
    """A view of four map lines among long clutter lines: a pose that
    explains four of 25 lines could be chance, so it is not accepted."""
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    cam = paper_camera()
    rng = np.random.default_rng([25, 2])
    # Without the clutter rule the true pose would be accepted: the frame
    # alone localises.
    while True:
        fr = make_frame(linemap, cam, rng, 1, clutter=0, min_seen=4, max_seen=4)
        if matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw):
            break
    longest = np.linalg.norm(fr.lines[:, 1] - fr.lines[:, 0], axis=1).max()
    clutter = _short_clutter(rng, 30, cam, (longest + 10, longest + 60))
    tol = replace(matcher.Tolerances(), search_lines=34)  # every line searched: the true ones too
    res = matcher.localize(linemap, cam, np.concatenate([fr.lines, clutter]), fr.prior, fr.dt, fr.dyaw,
                           tolerances=tol)
    assert not res
    assert "that clutter makes needed" in res.reason
