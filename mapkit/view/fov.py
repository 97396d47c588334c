"""Which segments a camera may see over a range of positions and headings.

method.md section 3: the union of the retained regions' lists is a superset
of what one frame sees, since the heading is free in the map; the runtime may
drop the segments outside the horizontal field of view for every heading in
``[yaw - dyaw, yaw + dyaw]``. The inspector shows that reduced set. The test
here is conservative (it never drops a segment some pose of the uncertainty
set could see) and exact for a point-like disk.
"""

from __future__ import annotations

import math

import numpy as np


def wrap(angle: np.ndarray | float) -> np.ndarray | float:
    """Angles to (-pi, pi]."""
    return -((-np.asarray(angle) + math.pi) % (2 * math.pi) - math.pi)


def in_horizontal_view(
    segments: np.ndarray, x: float, y: float, dt: float, yaw: float, dyaw: float, half_fov: float
) -> np.ndarray:
    """(N,) bool: True where part of a segment may lie inside the horizontal
    field of view for some camera centre within ``dt`` of (x, y) and some
    heading within ``dyaw`` of ``yaw`` (radians; ``half_fov`` from
    :meth:`linemap.camera.Camera.horizontal_half_fov`).

    Seen from the disk's centre, a segment's points span the arc of bearings
    between its two end points (the shorter one: a straight segment not
    through the centre subtends less than half a turn). Moving the camera by
    at most ``dt`` turns the bearing of a point at distance ``d`` by at most
    ``asin(dt / d)``; ``d`` is at least the segment's distance to the centre,
    so widening the arc by that much covers every camera position.
    """
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    if dyaw + half_fov >= math.pi:
        return np.ones(len(segments), dtype=bool)
    c = np.array([x, y])
    a, b = segments[:, 0, :2] - c, segments[:, 1, :2] - c
    ab = b - a
    denom = np.einsum("ij,ij->i", ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(-np.einsum("ij,ij->i", a, ab) / denom, 0.0, 1.0)
    t = np.where(denom > 0, t, 0.0)
    dist = np.linalg.norm(a + t[:, None] * ab, axis=1)
    b0, b1 = np.arctan2(a[:, 1], a[:, 0]), np.arctan2(b[:, 1], b[:, 0])
    span = wrap(b1 - b0)
    mid = b0 + span / 2
    with np.errstate(divide="ignore"):
        widen = np.arcsin(np.clip(dt / np.maximum(dist, 1e-12), 0.0, 1.0))
    half = np.abs(span) / 2 + widen
    reach = dyaw + half_fov
    close = dist <= max(dt, 1e-9)  # the camera may stand on the segment: anything goes
    return close | (np.abs(wrap(mid - yaw)) <= half + reach)
