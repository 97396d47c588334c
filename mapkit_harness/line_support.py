"""Which map segments image lines lie along, at a known pose.

The measure of a cut's evidence (tools/bench_pano_cut.py, and the
issue's figures): a map segment is *supported* by a detected line when the
line lies along its projection, within ``SUPPORT_DEG`` degrees and
``SUPPORT_PX`` pixels (both end points from the projected segment's line),
and overlaps at least ``SUPPORT_OVERLAP`` of the projected segment's part
inside the image. :func:`line_matches` gives, per line, the segment it lies
on (the test of a rendered image: the lines are where the map says).
"""

from __future__ import annotations

import math

import numpy as np

from linemap.camera import Camera
from linemap.geometry import clip_lines, project_segments
from matcher.projection import projected_distance_and_overlap

#: A line supports a segment within this many degrees...
SUPPORT_DEG = 2.0
#: ...and pixels...
SUPPORT_PX = 3.0
#: ...overlapping at least this fraction of the segment's projection inside the image.
SUPPORT_OVERLAP = 0.5
#: Segments are cut this far, metres, in front of the camera before projection.
NEAR_M = 0.05


def projected_in_image(camera: Camera, pose, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segments (N, 2, 3) projected at camera pose ``(x, y, yaw)`` (radians)
    and cut to the image: ``(uv (N, 2, 2), ok (N,))``."""
    poses = np.broadcast_to(np.asarray(pose, dtype=float), (len(segments), 3))
    uv, ok = project_segments(camera, poses, np.asarray(segments, dtype=float), NEAR_M)
    uv, inside = clip_lines(uv, (0.0, float(camera.width), 0.0, float(camera.height)))
    return uv, ok & inside


def _pairs(camera: Camera, pose, segments: np.ndarray, lines: np.ndarray):
    """(M, N) distance (pixels), angle (degrees), overlap (pixels) of every
    line against every projected segment, and each segment's length in the image (N,)."""
    uv, ok = projected_in_image(camera, pose, segments)
    M, N = len(lines), len(segments)
    L_uv = np.repeat(uv[None], M, axis=0).reshape(-1, 2, 2)
    L_ok = np.repeat(ok[None], M, axis=0).reshape(-1)
    L_lines = np.repeat(np.asarray(lines, dtype=float), N, axis=0)
    dist, overlap = projected_distance_and_overlap(L_uv, L_ok, L_lines)
    dl, ds = L_lines[:, 1] - L_lines[:, 0], L_uv[:, 1] - L_uv[:, 0]
    cos = np.abs((dl * ds).sum(axis=1)) / np.maximum(np.hypot(*dl.T) * np.hypot(*ds.T), 1e-12)
    angle = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    seg_len = np.where(ok, np.hypot(*(uv[:, 1] - uv[:, 0]).T), 0.0)
    return dist.reshape(M, N), angle.reshape(M, N), overlap.reshape(M, N), seg_len


def supported_segments(camera: Camera, pose, segments: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """Indices of the ``segments`` (N, 2, 3) that ``lines`` (M, 2, 2) support
    (module docstring) from camera pose ``(x, y, yaw)`` (radians)."""
    if not len(lines) or not len(segments):
        return np.zeros(0, dtype=np.int64)
    dist, angle, overlap, seg_len = _pairs(camera, pose, segments, lines)
    ok = (dist <= SUPPORT_PX) & (angle <= SUPPORT_DEG) & (overlap >= SUPPORT_OVERLAP * seg_len[None, :]) \
        & (seg_len[None, :] > 0)
    return np.flatnonzero(ok.any(axis=0))


def line_matches(camera: Camera, pose, segments: np.ndarray, lines: np.ndarray, px: float = 2.0,
                 deg: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """For each line (M, 2, 2): the segment it lies on (within ``deg``
    degrees, both ends within ``px`` pixels of its projection's line, over
    at least half the line's length), -1 if none; and its distance, pixels
    (the best segment's within the angle and overlap, inf if none)."""
    if not len(lines):
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    if not len(segments):
        return np.full(len(lines), -1), np.full(len(lines), math.inf)
    dist, angle, overlap, _ = _pairs(camera, pose, segments, lines)
    length = np.hypot(*(lines[:, 1] - lines[:, 0]).T)
    along = (angle <= deg) & (overlap >= 0.5 * length[:, None])
    d = np.where(along, dist, np.inf)
    best = d.argmin(axis=1)
    best_d = d[np.arange(len(lines)), best]
    return np.where(best_d <= px, best, -1), best_d
