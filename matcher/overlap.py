"""Model segments against image lines at a known pose: distance and overlap.

Used after stage 2 has a pose: to tell which piece of a group of collinear
segments an image line shows (the constraints, on infinite lines, cannot),
and to add the image lines of visible segments that stage 1 left unmatched.
"""

from __future__ import annotations

import numpy as np

from matcher.camera import Camera
from matcher.camera import world2cam_rotation

#: Segments are cut this far in front of the optical centre before projecting, metres.
_NEAR_M = 0.05


def project_segments(camera: Camera, poses: np.ndarray, segments: np.ndarray):
    """Project segments (T, 2, 3) at poses (T, 3) ``(x, y, yaw)``.

    Returns ``(uv (T, 2, 2) pixels, ok (T,))``: the part in front of the
    camera (``Zc >= 5 cm``); ``ok`` False where nothing is in front."""
    R = world2cam_rotation(poses[:, 2], camera.pitch)
    C = np.stack([poses[:, 0], poses[:, 1], np.full(len(poses), camera.height_m)], axis=1)
    pc = np.einsum("tij,tej->tei", R, segments - C[:, None, :])  # (T, 2, 3)
    za, zb = pc[:, 0, 2], pc[:, 1, 2]
    ok = np.maximum(za, zb) >= _NEAR_M
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip((_NEAR_M - za) / (zb - za), 0.0, 1.0)
    a = np.where((za < _NEAR_M)[:, None], pc[:, 0] + t[:, None] * (pc[:, 1] - pc[:, 0]), pc[:, 0])
    b = np.where((zb < _NEAR_M)[:, None], pc[:, 1] + t[:, None] * (pc[:, 0] - pc[:, 1]), pc[:, 1])
    pts = np.stack([a, b], axis=1)
    z = np.maximum(pts[..., 2], _NEAR_M)
    uv = np.stack([camera.fx * pts[..., 0] / z + camera.cx, camera.fy * pts[..., 1] / z + camera.cy], axis=-1)
    return uv, ok


def distance_and_overlap(camera: Camera, poses: np.ndarray, segments: np.ndarray, lines: np.ndarray):
    """For pairs t of (segment (T, 2, 3), image line (T, 2, 2)) at poses (T, 3):
    ``(dist (T,), overlap (T,))`` in pixels: the larger distance of the line's
    end points to the projected segment's line, and the length along the
    image line shared with the projected segment (negative: a gap)."""
    uv, ok = project_segments(camera, poses, segments)
    p, q = uv[:, 0], uv[:, 1]
    dq = q - p
    lq = np.linalg.norm(dq, axis=1)
    nrm = np.stack([-dq[:, 1], dq[:, 0]], axis=1) / np.maximum(lq, 1e-9)[:, None]
    dist = np.abs(np.einsum("tei,ti->te", lines - p[:, None, :], nrm)).max(axis=1)
    a, b = lines[:, 0], lines[:, 1]
    dl = b - a
    L = np.linalg.norm(dl, axis=1)
    u = dl / np.maximum(L, 1e-9)[:, None]
    s0, s1 = np.einsum("ti,ti->t", p - a, u), np.einsum("ti,ti->t", q - a, u)
    lo, hi = np.minimum(s0, s1), np.maximum(s0, s1)
    overlap = np.minimum(hi, L) - np.maximum(lo, 0.0)
    dist = np.where(ok & (lq > 1e-6), dist, np.inf)
    overlap = np.where(ok, overlap, -np.inf)
    return dist, overlap
