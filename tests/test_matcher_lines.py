"""Line detection with LSD on images drawn by the test."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import matcher
from linemap.camera import Camera
from matcher.lines import merge_collinear


def _angle(line):
    d = line[1] - line[0]
    return np.degrees(np.arctan2(d[1], d[0])) % 180.0


def _match(found, a, b, tol_px=3.0):
    """The found line close to the segment a-b (both end points, either order)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    for ln in found:
        if (np.linalg.norm(ln[0] - a) < tol_px and np.linalg.norm(ln[1] - b) < tol_px) or (
            np.linalg.norm(ln[0] - b) < tol_px and np.linalg.norm(ln[1] - a) < tol_px
        ):
            return ln
    return None


def test_lsd_finds_drawn_lines_as_single_lines():
    img = np.full((480, 640), 40, np.uint8)
    drawn = [((100, 60), (100, 420)), ((150, 400), (560, 330)), ((300, 100), (520, 110))]
    for a, b in drawn:
        cv2.line(img, a, b, 220, 2)
    found = matcher.detect_lines(img)
    assert found.shape[1:] == (2, 2)
    # Each stroke gives one line (its two LSD edges merged), end points within 3 px.
    for a, b in drawn:
        assert _match(found, a, b) is not None, (a, b, found.round(1).tolist())
    assert len(found) == len(drawn)


def test_colour_image_and_float_image():
    img = np.zeros((480, 640, 3), np.uint8)
    cv2.line(img, (50, 50), (50, 400), (0, 200, 255), 2)
    assert _match(matcher.detect_lines(img), (50, 50), (50, 400)) is not None
    f = img[..., 1].astype(np.float32) / 255.0
    assert _match(matcher.detect_lines(f), (50, 50), (50, 400)) is not None


def test_sixteen_bit_and_other_types_give_the_same_lines():
    img = np.full((240, 320), 200, np.uint8)
    cv2.rectangle(img, (60, 50), (250, 190), 40, -1)
    ref = matcher.detect_lines(img)
    assert len(ref) == 4
    bgr = np.dstack([img] * 3)
    for other in (img.astype(np.uint16) * 257, img.astype(np.float64) * 257, bgr / 255.0, bgr.astype(np.int64),
                  img > 100):
        found = matcher.detect_lines(other)
        assert len(found) == 4 and all(_match(found, *ln) is not None for ln in ref), other.dtype


@pytest.mark.parametrize("bad, msg", [(np.zeros((0, 640), np.uint8), "image is empty"),
                                      (np.full((4, 4), "a"), "image must hold numbers")])
def test_unusable_images_are_rejected(bad, msg):
    with pytest.raises(ValueError, match=msg):
        matcher.detect_lines(bad)


@pytest.mark.parametrize("kwargs, msg", [({"min_length": -1.0}, "min_length must be a number"),
                                         ({"min_length": "15"}, "min_length must be a number"),
                                         ({"camera": {"width": 640}}, "camera must be a matcher.Camera")])
def test_bad_arguments_are_rejected(kwargs, msg):
    with pytest.raises(ValueError, match=msg):
        matcher.detect_lines(np.zeros((480, 640), np.uint8), **kwargs)


def test_lines_of_a_distorted_image_are_accepted_by_localize():
    """Barrel distortion moves the image corners outwards on the ideal
    pinhole: lines along the border, undistorted, lie beyond the image and
    must still pass localize's input check."""
    from matcher.input_validation import check_lines

    cam = Camera(640, 480, 900.0, 900.0, 320.0, 240.0, 1.2, 0.0, (-0.3, 0.1, 0.0, 0.0))
    img = np.full((480, 640), 200, np.uint8)
    cv2.rectangle(img, (8, 8), (632, 472), 40, -1)
    found = matcher.detect_lines(img, cam)
    u0, u1, v0, v1 = cam.ideal_bounds
    assert u0 < -5 and u1 > 645 and v0 < -5 and v1 > 485
    assert (found[..., 0].min() < 0) and len(check_lines(found, cam, matcher.Tolerances())) == len(found)
    cut = check_lines([[u0 - 20, 240.0, 320.0, 240.0]], cam, matcher.Tolerances())  # a little out: cut
    assert cut[0, 0, 0] == pytest.approx(u0 - 5.0)
    with pytest.raises(ValueError, match="undistorted: u in"):  # far out: another camera's line
        check_lines([[u0 - 0.3 * (u1 - u0), 240.0, 320.0, 240.0]], cam, matcher.Tolerances())


def test_minimum_length_drops_short_lines():
    img = np.zeros((480, 640), np.uint8)
    cv2.line(img, (100, 100), (108, 100), 255, 2)  # 8 px
    cv2.line(img, (100, 300), (400, 300), 255, 2)
    found = matcher.detect_lines(img, min_length=15)
    assert len(found) == 1 and _match(found, (100, 300), (400, 300)) is not None


def test_collinear_fragments_merge():
    frags = np.array([[[0, 0], [100, 1]], [[105, 1.1], [200, 2]], [[0, 50], [100, 50]]], float)
    merged = merge_collinear(frags)
    assert len(merged) == 2
    long = max(merged, key=lambda ln: np.linalg.norm(ln[1] - ln[0]))
    assert np.linalg.norm(long[1] - long[0]) == pytest.approx(200.0, abs=0.5)


def test_distortion_is_removed_from_end_points():
    """A straight world line drawn through a distorted camera comes out
    straight after undistortion of the detected end points."""
    cam = Camera(640, 480, 500.0, 500.0, 320.0, 240.0, 1.2, 0.0, (-0.2, 0.03, 0.0, 0.0))
    # Ideal pixels of a line, distorted for drawing.
    ideal = np.array([[120.0, 100.0], [520.0, 140.0]])
    t = np.linspace(0, 1, 200)[:, None]
    pts = ideal[0] + t * (ideal[1] - ideal[0])
    norm = (pts - [cam.cx, cam.cy]) / cam.fx
    obj = np.concatenate([norm, np.ones((len(norm), 1))], 1)
    dist, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), cam.K, np.array(cam.distortion))
    dist = dist.reshape(-1, 2)
    img = np.zeros((480, 640), np.uint8)
    cv2.polylines(img, [np.round(dist).astype(np.int32)], False, 255, 2)
    found = matcher.detect_lines(img, cam, min_length=100)
    assert len(found)
    best = max(found, key=lambda ln: np.linalg.norm(ln[1] - ln[0]))
    # The undistorted line lies on the ideal one (within 2 px at both ends).
    d = ideal[1] - ideal[0]
    nrm = np.array([-d[1], d[0]]) / np.linalg.norm(d)
    assert np.abs((best - ideal[0]) @ nrm).max() < 2.0


def test_camera_size_must_match_image():
    cam = Camera(320, 240, 300.0, 300.0, 160.0, 120.0, 1.2, 0.0)
    with pytest.raises(ValueError, match="image is 640x480 but the camera is 320x240"):
        matcher.detect_lines(np.zeros((480, 640), np.uint8), cam)


def test_bad_image_shape():
    with pytest.raises(ValueError, match=r"Expected shape \(H, W\)"):
        matcher.detect_lines(np.zeros((4, 5, 6, 7)))


def test_a_real_photograph():
    """LSD on a real photograph (tests/data/rocket.jpg, public domain): the
    launch tower's long straight edges come out whole, every line inside
    the image and at least the minimum length. (Its time is printed by
    tools/bench_lines.py, not asserted here.)"""
    from pathlib import Path

    img = cv2.imread(str(Path(__file__).parent / "data" / "rocket.jpg"))
    assert img is not None and img.shape == (427, 640, 3)
    found = matcher.detect_lines(img)
    assert 80 <= len(found) <= 400
    # (A merged line spans its parts' projections on their mean direction: a
    # few pixels past the border at most, within localize's margin.)
    assert (found[..., 0] >= -5).all() and (found[..., 0] <= 645).all()
    assert (found[..., 1] >= -5).all() and (found[..., 1] <= 432).all()
    # The lines pass the matcher's input check as they are.
    from matcher.input_validation import check_lines
    cam = matcher.Camera.from_fov(60.0, 640, 427, 1.2, 0.0)
    assert (check_lines(found, cam, matcher.Tolerances()) == found).all()
    length = np.linalg.norm(found[:, 1] - found[:, 0], axis=1)
    assert length.min() >= 15.0
    tilt = np.degrees(np.arctan2(np.abs(found[:, 1, 0] - found[:, 0, 0]), np.abs(found[:, 1, 1] - found[:, 0, 1])))
    assert ((length > 100) & (tilt < 5)).sum() >= 5  # the tower's uprights


def test_merging_leaves_no_mergeable_pair():
    """After merging, no two lines pass the merge test (checked against all
    pairs), on fragments of random lines broken at random gaps."""
    import math

    from matcher.lines import _mergeable_pairs
    from matcher.tolerances import DETECTION

    rng = np.random.default_rng(5)
    frags = []
    for _ in range(40):
        a = rng.uniform(0, 600, 2)
        ang = rng.uniform(0, math.pi)
        u = np.array([math.cos(ang), math.sin(ang)])
        s = 0.0
        while s < 150:
            ln = rng.uniform(5, 40)
            frags.append([a + s * u + rng.normal(0, 0.3, 2), a + (s + ln) * u + rng.normal(0, 0.3, 2)])
            s += ln + rng.uniform(0, 12)
    merged = merge_collinear(np.array(frags))
    assert len(merged) < len(frags)
    # Brute force: every pair, the same test.
    n = len(merged)
    i, j = np.triu_indices(n, 1)
    d = merged[:, 1] - merged[:, 0]
    L = np.hypot(d[:, 0], d[:, 1])
    u = d / L[:, None]
    nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
    par = np.abs((u[i] * u[j]).sum(axis=1)) >= math.cos(math.radians(DETECTION.merge_angle_deg))

    def off_gap(p, q):
        rel = merged[q] - merged[p][:, None, 0]
        off = np.abs(np.einsum("pek,pk->pe", rel, nrm[p])).max(axis=1)
        s_ = np.einsum("pek,pk->pe", rel, u[p])
        return off, np.maximum(s_.min(axis=1) - L[p], -s_.max(axis=1))

    o1, g1 = off_gap(i, j)
    o2, _ = off_gap(j, i)
    left = par & (o1 <= DETECTION.merge_offset_px) & (o2 <= DETECTION.merge_offset_px) & (g1 <= DETECTION.merge_gap_px)
    assert not left.any()
    assert len(_mergeable_pairs(merged, DETECTION)[0]) == 0
