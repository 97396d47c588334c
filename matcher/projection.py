"""Model segments against image lines at a known pose: distance, overlap,
and the part of a segment a line shows.

Used by both stages: stage 1 tests visibility on the part of a segment its
line shows (:class:`ShownSpans`), stage 2 tells which piece of a group of
collinear segments an image line shows (the constraints, on infinite lines,
cannot), fits lines to projected segments and adds the lines of visible
segments that stage 1 left unmatched.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.camera import Camera
from linemap.geometry import project_segments


def distance_and_overlap(camera: Camera, poses: np.ndarray, segments: np.ndarray, lines: np.ndarray, near_m: float):
    """For pairs t of (segment (T, 2, 3), image line (T, 2, 2)) at poses (T, 3),
    segments cut ``near_m`` in front of the camera:
    ``(dist (T,), overlap (T,))`` in pixels: the larger distance of the line's
    end points to the projected segment's line, and the length along the
    image line shared with the projected segment (negative: a gap)."""
    uv, ok = project_segments(camera, poses, segments, near_m)
    return projected_distance_and_overlap(uv, ok, lines)


def projected_distance_and_overlap(uv: np.ndarray, ok: np.ndarray, lines: np.ndarray):
    """:func:`distance_and_overlap` for segments already projected
    (:func:`linemap.geometry.project_segments`' ``uv`` (T, 2, 2) and ``ok`` (T,))."""
    dist = projected_end_distances(uv, ok, lines).max(axis=1)
    dl = lines[:, 1] - lines[:, 0]
    L = np.hypot(dl[:, 0], dl[:, 1])
    ux, uy = dl[:, 0] / np.maximum(L, 1e-9), dl[:, 1] / np.maximum(L, 1e-9)
    # Positions of the projected end points along the image line, from its first end.
    along = (uv[..., 0] - lines[:, None, 0, 0]) * ux[:, None] + (uv[..., 1] - lines[:, None, 0, 1]) * uy[:, None]
    overlap = np.minimum(along.max(axis=1), L) - np.maximum(along.min(axis=1), 0.0)
    overlap = np.where(ok, overlap, -np.inf)
    return dist, overlap


def projected_end_distances(uv: np.ndarray, ok: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """(T, 2) distances, pixels, of each image line's (T, 2, 2) end points to
    the line through its projected segment (``uv`` (T, 2, 2), ``ok`` (T,) as
    :func:`linemap.geometry.project_segments` gives them); inf where nothing is in front."""
    p, q = uv[:, 0], uv[:, 1]
    dq = q - p
    lq = np.hypot(dq[:, 0], dq[:, 1])
    nx, ny = -dq[:, 1] / np.maximum(lq, 1e-9), dq[:, 0] / np.maximum(lq, 1e-9)
    rel = lines - p[:, None, :]  # (T, 2, 2)
    dist = np.abs(rel[..., 0] * nx[:, None] + rel[..., 1] * ny[:, None])
    return np.where((ok & (lq > 1e-6))[:, None], dist, np.inf)


def covered_span(camera: Camera, poses: np.ndarray, segments: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """(T, 2) sorted parameters in [0, 1] along each segment (T, 2, 3) of the
    part its image line (T, 2, 2) shows at poses (T, 3): for each end point
    of the line, the point of the segment's 3D line closest to its sight
    ray, clipped to the segment. A line that shows a sliver of a long
    segment (the rest hidden by a wall or out of the image) covers that
    sliver only: visibility is tested there (:func:`matcher.stage2.fit.visible`). (For many calls
    on the same pairs, :class:`ShownSpans`.)"""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    p, q, dz = _level_rays(camera, lines)  # turned by the yaw below
    dx, dy = c * p - s * q, s * p + c * q
    v = segments[:, 1] - segments[:, 0]  # (T, 3)
    wx, wy = segments[:, 0, 0:1] - poses[:, 0:1], segments[:, 0, 1:2] - poses[:, 1:2]
    wz = segments[:, 0, 2:3] - camera.height_m
    vx, vy, vz = v[:, 0:1], v[:, 1:2], v[:, 2:3]
    a = vx * vx + vy * vy + vz * vz
    b = vx * dx + vy * dy + vz * dz
    c0 = dx * dx + dy * dy + dz * dz
    e = wx * dx + wy * dy + wz * dz
    f = vx * wx + vy * wy + vz * wz
    return _span(a, b, c0, e, f)


def _level_rays(camera: Camera, lines: np.ndarray):
    """``(p, q, r)``, each (T, 2): the world directions of the sight rays of
    lines' (T, 2, 2) end points for a camera at yaw 0 (``X r + Y d + f``
    with the rows r, d, f of method.md section 2); a yaw turns (p, q)."""
    cp, sp = math.cos(camera.pitch), math.sin(camera.pitch)
    X = (lines[..., 0] - camera.cx) / camera.fx  # camera-frame rays (X, Y, 1)
    Y = (lines[..., 1] - camera.cy) / camera.fy
    return cp - sp * Y, -X, -cp * Y - sp


def _span(a, b, c, e, f) -> np.ndarray:
    """(T, 2) sorted parameters in [0, 1] of the points of the lines
    A + t v nearest the rays C + u d: ``t = (b e - c f) / (a c - b^2)`` with
    a = v.v, b = v.d, c = d.d, e = (A - C).d, f = v.(A - C); a ray running
    along its segment gives the middle."""
    den = a * c - b * b
    ok = den > 1e-12 * a * c
    t = np.where(ok, (b * e - c * f) / np.where(ok, den, 1.0), 0.5)
    return np.sort(np.clip(t, 0.0, 1.0), axis=1)


class ShownSpans:
    """:func:`covered_span` of fixed pairs t of (segment (T, 2, 3), image
    line (T, 2, 2)) at any one pose, made fast for the tree's many small
    calls on a few pairs each.

    With the camera centre C = (x, y, h), the sight ray of a line end point
    at yaw ``psi`` has the direction d = Rz(psi) d0 (d0 at yaw 0, the pitch
    applied). The closest point of the segment's line A + t v to the ray is
    t = (b e - c f) / (a c - b^2) with a = v.v, c = d.d (pose-free),
    b = v.d, e = (A - C).d, f = v.(A - C): all three are linear in
    phi = (cos, sin, 1, x cos, x sin, y cos, y sin, x, y), so one matrix
    product per call gives them for every pair and both ends."""

    def __init__(self, camera: Camera, segments: np.ndarray, lines: np.ndarray):
        # Made on the first call: many frames never test visibility in the tree.
        self._inputs = (camera, segments, lines)
        self.coef = None

    def _build(self) -> None:
        camera, segments, lines = self._inputs
        p, q, r = _level_rays(camera, lines)  # d0
        A = segments[:, 0]
        v = segments[:, 1] - A
        ax, ay, az = A[:, 0:1], A[:, 1:2], A[:, 2:3] - camera.height_m
        vx, vy, vz = v[:, 0:1], v[:, 1:2], v[:, 2:3]
        T = len(segments)
        z = np.zeros((T, 2))
        coef = np.empty((T, 5, 9))
        # Rows b (2 ends), e (2 ends), f; columns the terms of phi.
        coef[:, 0:2] = np.stack([vx * p + vy * q, vy * p - vx * q, vz * r, z, z, z, z, z, z], axis=-1)
        coef[:, 2:4] = np.stack([ax * p + ay * q, ay * p - ax * q, az * r, -p, q, -q, -p, z, z], axis=-1)
        zz = np.zeros(T)
        coef[:, 4] = np.stack([zz, zz, (v[:, 0] * A[:, 0] + v[:, 1] * A[:, 1] + v[:, 2] * az[:, 0]), zz, zz, zz, zz,
                               -v[:, 0], -v[:, 1]], axis=-1)
        self.coef = coef
        self.a = (v * v).sum(axis=1)[:, None]  # (T, 1)
        self.c = p * p + q * q + r * r  # (T, 2)

    def at(self, idx: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
        """(S, 2) sorted spans of pairs ``idx`` (S,) at the pose ``(x, y, yaw)``."""
        if self.coef is None:
            self._build()
        c, s = math.cos(yaw), math.sin(yaw)
        m = self.coef[idx] @ np.array([c, s, 1.0, x * c, x * s, y * c, y * s, x, y])  # (S, 5)
        return _span(self.a[idx], m[:, 0:2], self.c[idx], m[:, 2:4], m[:, 4:5])
