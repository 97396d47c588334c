"""The paper's constraints on hand-worked cases (docs/method.md sections 4-6)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from linemap.camera import Camera, world2cam_rotation
from matcher.search.tree.constraints import (
    binary_constraint,
    line_pieces,
    unary_constraint,
    unary_yaws,
    vertical_bearing,
    vertical_candidates,
    vertical_residual,
    wrap,
)


def camera(pitch_deg: float = 0.0, height: float = 1.0) -> Camera:
    return Camera(640, 480, 900.0, 900.0, 320.0, 240.0, height, pitch_deg)


def project_line(cam: Camera, seg: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    uv, z = cam.project(seg, x, y, yaw)
    assert (z > 0).all()
    return uv[None]


# ---- interpretation plane -------------------------------------------------


def test_plane_normal_is_perpendicular_to_the_segment_in_camera_frame():
    cam = camera(10.0)
    seg = np.array([[3.0, -1.0, 0.0], [3.0, 2.0, 0.0]])
    line = project_line(cam, seg, 0.0, 0.0, 0.2)
    n = cam.interpretation_normals(line)[0]
    R = world2cam_rotation(0.2, cam.pitch)
    C = cam.centre(0.0, 0.0)
    assert abs(n @ (R @ (seg[1] - seg[0]))) < 1e-9
    assert abs(n @ (R @ (seg[0] - C))) < 1e-9


# ---- vertical test ----------------------------------------------------------


def test_vertical_test_level_camera_accepts_vertical_lines_only():
    cam = camera(0.0)
    lines = np.array([[[100.0, 50.0], [100.0, 400.0]], [[100.0, 50.0], [130.0, 400.0]], [[50.0, 200.0], [500.0, 210.0]]])
    n = cam.interpretation_normals(lines)
    # Level camera: images of vertical edges are image columns (n_y = 0).
    assert vertical_residual(cam, n)[0] < 1e-12
    ok = vertical_candidates(cam, n, np.full(3, math.radians(1.0)))
    assert ok.tolist() == [True, False, False]


@pytest.mark.parametrize("pitch", [15.0, -10.0])
def test_vertical_test_pitched_camera(pitch):
    """A pitched camera sees vertical edges converge to the vanishing point
    of z: the exact test holds for them and fails for an image column off
    the middle."""
    cam = camera(pitch, 1.2)
    edge = np.array([[4.0, -1.5, 0.0], [4.0, -1.5, 2.5]])
    line = project_line(cam, edge, 0.0, 0.0, 0.0)
    assert abs(line[0, 0, 0] - line[0, 1, 0]) > 5.0  # not an image column
    n = cam.interpretation_normals(line)
    assert vertical_residual(cam, n)[0] < 1e-12
    column = np.array([[[line[0, 0, 0], 50.0], [line[0, 0, 0], 400.0]]])
    assert vertical_residual(cam, cam.interpretation_normals(column))[0] > 0.01
    # The vanishing point of z lies on the middle column at row cy + fy cot p.
    vp_row = cam.cy + cam.fy / math.tan(math.radians(pitch))
    a, b = line[0]
    u_at_vp = a[0] + (vp_row - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
    assert abs(u_at_vp - cam.cx) < 1e-6


@pytest.mark.parametrize("pitch", [0.0, 12.0])
def test_horizon_corrected_bearing(pitch):
    """tan(alpha) = cos(p) (u_h - cx) / fx gives the edge's bearing to the
    right of the optical axis, whatever the pitch."""
    cam = camera(pitch, 1.2)
    alpha = math.radians(-14.0)  # 14 degrees to the left
    d = 3.0
    # Camera at the origin heading +x: right of the axis is -y.
    p = np.array([d * math.cos(alpha), -d * math.sin(alpha)])
    edge = np.array([[p[0], p[1], 0.0], [p[0], p[1], 2.5]])
    line = project_line(cam, edge, 0.0, 0.0, 0.0)
    assert vertical_bearing(cam, line)[0] == pytest.approx(alpha, abs=1e-9)


# ---- unary constraint -------------------------------------------------------


def test_unary_yaws_hand_worked_level_camera():
    """Level camera, the image row v = 300 (60 px below the centre): its
    plane holds the camera's X axis and the ray (0, 60/900, 1), so
    n = (0, 1, -1/15) normalised. A horizontal world segment along +y has
    R v = (-cos yaw, 0, sin yaw) in camera axes, so n . R v = n_z sin yaw:
    zero at yaw 0 and pi, with slope |n_z| (a near-horizontal plane fixes
    the yaw poorly)."""
    cam = camera(0.0)
    row = np.array([[[0.0, 300.0], [640.0, 300.0]]])
    n = cam.interpretation_normals(row)
    assert np.allclose(np.abs(n[0]), np.array([0.0, 1.0, 1.0 / 15.0]) / math.hypot(1.0, 1.0 / 15.0))
    y1, y2, slope = unary_yaws(n, np.array([[0.0, 1.0, 0.0]]), 0.0)
    sols = sorted(float(v) % math.pi for v in (y1[0, 0], y2[0, 0]))
    assert sols == pytest.approx([0.0, 0.0], abs=1e-9) or sols == pytest.approx([0.0, math.pi], abs=1e-9)
    assert abs(wrap(y1[0, 0] - y2[0, 0])) == pytest.approx(math.pi, abs=1e-9)
    assert slope[0, 0] == pytest.approx(abs(n[0, 2]), abs=1e-12)


def test_unary_yaws_no_solution_for_a_vertical_segment_off_the_plane():
    cam = camera(0.0)
    row = np.array([[[0.0, 300.0], [640.0, 300.0]]])  # not a vertical candidate
    n = cam.interpretation_normals(row)
    y1, _, _ = unary_yaws(n, np.array([[0.0, 0.0, 1.0]]), 0.0)
    assert np.isnan(y1[0, 0])


def test_unary_constraint_accepts_true_pair_and_rejects_wrong_ones():
    cam = camera(8.0, 1.2)
    x, y, yaw = 1.0, 0.5, math.radians(20.0)
    wall = np.array([[5.0, -3.0, 0.0], [5.0, 4.0, 0.0]])  # floor line of the wall x = 5
    line = project_line(cam, wall, x, y, yaw)
    n = cam.interpretation_normals(line)
    eps = np.array([0.01])
    other = np.array([[9.0, -3.0, 0.0], [9.0, 4.0, 0.0]])  # parallel wall 4 m farther
    across = np.array([[-2.0, 6.0, 0.0], [7.0, 6.0, 0.0]])  # perpendicular wall
    segs = np.stack([wall, other, across])
    ok, yaws = unary_constraint(cam, n, eps, segs, (x + 0.1, y - 0.1, yaw + 0.05), 0.3, math.radians(10.0))
    assert ok[:, 0].tolist() == [True, False, False]
    assert yaws[0, 0] == pytest.approx(yaw, abs=0.02)
    # The true pair fails when the prior heading excludes its yaw.
    ok2, _ = unary_constraint(cam, n, eps, segs[:1], (x, y, yaw + 0.5), 0.3, math.radians(10.0))
    assert not ok2[0, 0]


# ---- binary constraint --------------------------------------------------------


def test_binary_constraint_hand_worked():
    """Two corners 2 m apart, camera 2 m in front of their midpoint, heading
    at them: each is 26.57 deg off the axis, seen 53.13 deg apart."""
    Pi, Pk = np.array([[2.0, 1.0]]), np.array([[2.0, -1.0]])
    a = math.atan2(1.0, 2.0)
    alpha_i, alpha_k = np.array([-a]), np.array([a])  # Pi is to the left
    tol = np.array([math.radians(0.5)])
    assert binary_constraint(Pi, Pk, alpha_i, alpha_k, (0.0, 0.0), 0.2, tol)[0]
    # Order swapped in the image: the mirror arc, behind the corners.
    assert not binary_constraint(Pi, Pk, alpha_k, alpha_i, (0.0, 0.0), 0.2, tol)[0]
    # Angle of 30 deg: camera on a larger arc (about 1.7 m farther); a 0.2 m disk misses it.
    b = math.radians(15.0)
    assert not binary_constraint(Pi, Pk, np.array([-b]), np.array([b]), (0.0, 0.0), 0.2, tol)[0]
    # ...which a 2 m disk reaches.
    assert binary_constraint(Pi, Pk, np.array([-b]), np.array([b]), (0.0, 0.0), 2.0, tol)[0]


def test_binary_constraint_closed_form_against_dense_sampling():
    """The closed-form angle range over the disk against the angle sampled
    at 3600 points of its circle (the extremes lie there: the angle is
    harmonic), on random couples, about half of them rejected."""
    rng = np.random.default_rng(5)
    C = 400
    centre = np.array([0.3, -0.2])
    dt = 0.8
    pi = centre + rng.uniform(-6, 6, (C, 2))
    pk = centre + rng.uniform(-6, 6, (C, 2))
    # Bearings as seen from a point near the disk's edge, give or take 9 deg.
    heading = rng.uniform(-np.pi, np.pi, C)
    cam = centre + (dt + rng.uniform(-0.2, 0.2, (C, 1))) * np.stack([np.cos(heading), np.sin(heading)], 1)
    alpha_i = -np.arctan2(pi[:, 1] - cam[:, 1], pi[:, 0] - cam[:, 0]) + rng.uniform(-0.15, 0.15, C)
    alpha_k = -np.arctan2(pk[:, 1] - cam[:, 1], pk[:, 0] - cam[:, 0])
    tol = np.full(C, math.radians(1.0))
    got = binary_constraint(pi, pk, alpha_i, alpha_k, tuple(centre), dt, tol)
    th = np.linspace(0, 2 * np.pi, 3600, endpoint=False)
    ring = centre + dt * np.stack([np.cos(th), np.sin(th)], 1)
    angle = (np.arctan2(pk[:, None, 1] - ring[:, 1], pk[:, None, 0] - ring[:, 0])
             - np.arctan2(pi[:, None, 1] - ring[:, 1], pi[:, None, 0] - ring[:, 0]))
    off = np.abs(wrap(angle - (alpha_i - alpha_k)[:, None])).min(axis=1)
    inside = np.minimum(np.linalg.norm(pi - centre, axis=1), np.linalg.norm(pk - centre, axis=1)) <= dt
    # Sampling misses at most a step's worth of angle: decide only the clear cases.
    clear = inside | (off <= tol - 1e-3) | (off >= tol + 1e-3)
    assert clear.sum() > 0.95 * C
    assert 0.25 * C < got.sum() < 0.75 * C
    assert (got[clear] == (inside | (off <= tol))[clear]).all()


def test_binary_constraint_random_true_couples_always_pass():
    rng = np.random.default_rng(3)
    for _ in range(200):
        cam_xy = rng.uniform(-1, 1, 2)
        yaw = rng.uniform(-math.pi, math.pi)
        pts = cam_xy + rng.uniform(1.5, 6.0, (2, 1)) * np.stack(
            [np.cos(yaw + rng.uniform(-0.3, 0.3, 2)), np.sin(yaw + rng.uniform(-0.3, 0.3, 2))], 1)
        bear = np.arctan2(pts[:, 1] - cam_xy[1], pts[:, 0] - cam_xy[0])
        alpha = wrap(yaw - bear)  # positive to the right
        centre = cam_xy + rng.uniform(-0.2, 0.2, 2)
        assert binary_constraint(pts[:1], pts[1:], alpha[:1], alpha[1:], tuple(centre), 0.3, np.array([1e-3]))[0]


def test_line_pieces_hand_worked():
    """Pieces of one line: collinear (within the planes' noise) and apart
    along it; overlapping or merely parallel lines are not."""
    cam = camera()
    lines = np.array([
        [[100.0, 200.0], [200.0, 200.0]],  # 0
        [[260.0, 200.0], [400.0, 200.0]],  # 1: further along 0's line, 60 px gap
        [[190.0, 200.0], [300.0, 200.0]],  # 2: on the same line, overlaps 0 by 10 px and 1 by 40 px
        [[260.0, 205.0], [400.0, 205.0]],  # 3: parallel to 0, 5 px below
        [[196.0, 200.2], [250.0, 200.2]],  # 4: in the gap, 0.2 px off the line, overlapping 0 by 4 px
    ])
    normals = cam.interpretation_normals(lines)
    eps = np.full(len(lines), math.radians(0.1))
    got = line_pieces(lines, normals, eps, gap_px=8.0)
    want = np.zeros((5, 5), dtype=bool)
    for i, j in [(0, 1), (0, 4), (1, 4)]:
        want[i, j] = want[j, i] = True
    assert (got == want).all()
    # A wider noise bound takes the parallel line in too; an overlap
    # allowance under 4 px drops the couple (0, 4).
    assert line_pieces(lines, normals, np.full(5, math.radians(2.0)), 8.0)[0, 3]
    tight = line_pieces(lines, normals, eps, 2.0)
    assert not tight[0, 4] and tight[0, 1] and tight[1, 4]
    assert line_pieces(lines[:1], normals[:1], eps[:1], 8.0).shape == (1, 1)
