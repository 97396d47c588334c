"""Geometry both halves share: angle wrap, vertical segments, the horizontal
field-of-view test and the projection of segments into the image.

Conventions (written down once for the whole project): world frame x, y
horizontal, z up, metres; segments (N, 2, 3); image lines (M, 2, 2) pixels
``(u, v)``, u the column, v the row; poses ``(x, y, yaw)`` with yaw in
radians, counter-clockwise from +x; the camera's rows r, d, f of
method.md section 2 (:func:`linemap.camera.world2cam_rotation`).
"""

from __future__ import annotations

import math

import numpy as np

from linemap.camera import Camera


def wrap(a):
    """Angles to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2 * np.pi)


def world_normals(normals: np.ndarray, yaw: np.ndarray, pitch: float) -> np.ndarray:
    """(..., 3) world directions ``R^T n`` of camera-frame vectors (..., 3)
    (plane normals, rays) at yaws (...), broadcast together, written out from R's rows r, d, f of method.md section 2
    (no (..., 3, 3) rotations: cheaper on these arrays). With ``f_h = n_z
    cos p - n_y sin p``: ``(f_h cos y + n_x sin y, f_h sin y - n_x cos y,
    -n_y cos p - n_z sin p)``."""
    cp, sp = math.cos(pitch), math.sin(pitch)
    c, s = np.cos(yaw), np.sin(yaw)
    nx, ny, nz = normals[..., 0], normals[..., 1], normals[..., 2]
    ahead = nz * cp - ny * sp
    w = np.empty(np.broadcast_shapes(np.shape(yaw), nx.shape) + (3,))
    w[..., 0] = ahead * c + nx * s
    w[..., 1] = ahead * s - nx * c
    w[..., 2] = -ny * cp - nz * sp
    return w


def segment_is_vertical(segments: np.ndarray, axis_deg: float) -> np.ndarray:
    """(N,) bool: the direction of each segment (N, 2, 3) is within
    ``axis_deg`` degrees of the vertical."""
    v = segments[:, 1] - segments[:, 0]
    vz = np.abs(v[:, 2]) / np.maximum(np.linalg.norm(v, axis=1), 1e-12)
    return vz >= math.cos(math.radians(axis_deg))


def in_field_of_view(segments: np.ndarray, camera: Camera, prior, dt: float, dyaw: float) -> np.ndarray:
    """(N,) bool: segments (N, 2, 3) that some heading within ``dyaw``
    (radians) of the prior's yaw and some position within ``dt`` metres of
    its ``(x, y)`` can have within the horizontal field of view.

    From the disk centre a segment covers the bearings between its end
    points; moving within the disk shifts any bearing by at most
    ``asin(dt / distance)``. Segments closer than ``dt`` are kept. The test
    never drops a segment some pose of the set could see."""
    xe, ye, yaw_e = prior
    if dyaw >= math.pi:
        return np.ones(len(segments), dtype=bool)
    c = np.array([xe, ye])
    p0, p1 = segments[:, 0, :2] - c, segments[:, 1, :2] - c
    b0 = wrap(np.arctan2(p0[:, 1], p0[:, 0]) - yaw_e)
    span = wrap(np.arctan2(p1[:, 1], p1[:, 0]) - yaw_e - b0)  # short way: the segment misses c
    lo = np.minimum(b0, b0 + span)
    hi = np.maximum(b0, b0 + span)
    seg = p1 - p0
    L2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-12)
    t = np.clip(-np.einsum("ij,ij->i", p0, seg) / L2, 0.0, 1.0)
    dist = np.linalg.norm(p0 + t[:, None] * seg, axis=1)
    widen = np.arcsin(np.clip(dt / np.maximum(dist, 1e-9), 0.0, 1.0))
    reach = dyaw + camera.horizontal_half_fov() + widen
    ok = np.zeros(len(segments), dtype=bool)
    for shift in (-2 * math.pi, 0.0, 2 * math.pi):
        ok |= (lo + shift <= reach) & (hi + shift >= -reach)
    return ok | (dist <= dt) | (reach >= math.pi)


def project_segments(camera: Camera, poses: np.ndarray, segments: np.ndarray, near_m: float):
    """Project segments (T, 2, 3) at poses (T, 3) ``(x, y, yaw)`` (or one pose
    per leading index of any shape: poses (..., 3), segments (..., 2, 3))
    through the ideal pinhole.

    Returns ``(uv (..., 2, 2) pixels, ok (...))``: the part at least
    ``near_m`` metres in front of the camera (an end point behind that plane
    moves along the segment onto it); ``ok`` False where nothing is.

    The camera coordinates are written out from the rotation's rows r, d, f
    (no (T, 3, 3) matrices: these arrays are short and numpy's per-call
    cost dominates)."""
    c, s = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
    cp, sp = math.cos(camera.pitch), math.sin(camera.pitch)
    dx = segments[..., 0] - poses[..., None, 0]  # (..., 2)
    dy = segments[..., 1] - poses[..., None, 1]
    dz = segments[..., 2] - camera.height_m
    ahead = c * dx + s * dy
    X, Y, Z = s * dx - c * dy, -sp * ahead - cp * dz, cp * ahead - sp * dz
    za, zb = Z[..., 0], Z[..., 1]
    ok = np.maximum(za, zb) >= near_m
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip((near_m - Z) / (Z[..., ::-1] - Z), 0.0, 1.0)  # (..., 2): each end's move towards the other
    cut = Z < near_m
    X = np.where(cut, X + t * (X[..., ::-1] - X), X)
    Y = np.where(cut, Y + t * (Y[..., ::-1] - Y), Y)
    Z = np.maximum(np.where(cut, Z + t * (Z[..., ::-1] - Z), Z), near_m)
    uv = np.empty(X.shape + (2,))
    uv[..., 0] = camera.fx * X / Z + camera.cx
    uv[..., 1] = camera.fy * Y / Z + camera.cy
    return uv, ok


def clip_lines(lines: np.ndarray, box) -> tuple[np.ndarray, np.ndarray]:
    """Image lines (M, 2, 2) cut to ``box`` ``(u_min, u_max, v_min, v_max)``
    pixels (Liang-Barsky), and (M,) bool: the line is finite and some part
    of it (a point at least) is inside. Lines wholly outside come back as
    they were."""
    lines = np.asarray(lines, dtype=np.float64).reshape(-1, 2, 2)
    p0, d = lines[:, 0], lines[:, 1] - lines[:, 0]
    t0, t1 = np.zeros(len(lines)), np.ones(len(lines))
    ok = np.isfinite(lines).all(axis=(1, 2))
    for p, q in ((-d[:, 0], p0[:, 0] - box[0]), (d[:, 0], box[1] - p0[:, 0]),
                 (-d[:, 1], p0[:, 1] - box[2]), (d[:, 1], box[3] - p0[:, 1])):
        parallel = p == 0
        ok &= ~(parallel & (q < 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(parallel, 0.0, q / np.where(parallel, 1.0, p))
        t0 = np.where(~parallel & (p < 0), np.maximum(t0, r), t0)
        t1 = np.where(~parallel & (p > 0), np.minimum(t1, r), t1)
    ok &= t0 <= t1
    out = np.stack([p0 + t0[:, None] * d, p0 + t1[:, None] * d], axis=1)
    return np.where(ok[:, None, None], out, lines), ok
