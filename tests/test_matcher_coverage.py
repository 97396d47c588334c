"""An accepted pose must show the map: a picture of vertical stripes fits a
few vertical edges at many poses, but a pose that would also show floor and
ceiling lines the image lacks is refused, with the reason."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher

ROOT = Path(__file__).resolve().parent.parent


def test_stripes_are_not_a_room_that_shows_its_floor_and_ceiling():
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    cam = matcher.Camera(640, 480, 457.0, 457.0, 320.0, 240.0, 1.2, 0.0)
    img = np.zeros((480, 640), np.uint8)
    for x in range(0, 640, 40):
        img[:, x:x + 20] = 255
    lines = matcher.detect_lines(img, cam)
    x, y = linemap.region_centres()[0]
    assert not matcher.localize(linemap, cam, lines, (float(x), float(y), 0.0), 0.5, 20.0)
    # Every stripe searched (by default stage 1 takes the longest 10
    # vertical lines, and finds no set among them): the coverage test refuses it.
    every = replace(matcher.Tolerances(), search_lines=len(lines), search_vertical_lines=len(lines))
    res = matcher.localize(linemap, cam, lines, (float(x), float(y), 0.0), 0.5, 20.0, tolerances=every)
    assert not res
    assert "map segments in view and the image shows" in res.reason


@pytest.mark.slow
def test_a_true_view_shows_its_map():
    """The simulated frames of the paper's protocol pass (their lines are the
    map's segments in view)."""
    from mapkit_harness.simulate import make_frame, paper_camera

    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    cam = paper_camera(1.2, 0.0)
    rng = np.random.default_rng([9, 1])
    ok = 0
    for _ in range(10):
        fr = make_frame(linemap, cam, rng, 1)
        ok += bool(matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw))
    assert ok >= 9
