"""The model as the camera would see it: projected segments drawn into an image.

Segments are cut at the camera's near plane and projected through the ideal
pinhole by :func:`linemap.geometry.project_segments`, the projection the
matcher uses (lens distortion is not drawn), then clipped to the image
rectangle. Image lines are (M, 2, 2) pixel end points (u column, v row).
"""

from __future__ import annotations

import numpy as np

from linemap.camera import Camera
from linemap.geometry import clip_lines, project_segments as project_at_poses

#: Points nearer than this (metres, along the optical axis) are behind the image.
NEAR_PLANE_M = 0.05


def clip_to_image(lines: np.ndarray, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """(M, 2, 2) pixel lines clipped to [0, width] x [0, height]
    (:func:`linemap.geometry.clip_lines`).

    Returns (clipped lines (K, 2, 2), indices (K,) of the kept input lines).
    """
    out, ok = clip_lines(lines, (0.0, width, 0.0, height))
    return out[ok], np.nonzero(ok)[0]


def project_segments(
    camera: Camera, segments: np.ndarray, x: float, y: float, yaw: float
) -> tuple[np.ndarray, np.ndarray]:
    """Image lines (K, 2, 2) of the visible parts of world segments (N, 2, 3)
    for the camera at (x, y, yaw radians), with their indices (K,) into ``segments``.

    Occlusion is not modelled: a segment behind a wall is drawn too (the map's
    lists already say what is visible from where).
    """
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    uv, ok = project_at_poses(camera, np.array([[x, y, yaw]], dtype=np.float64), segments, NEAR_PLANE_M)
    idx = np.nonzero(ok)[0]
    lines, kept = clip_to_image(uv[idx], camera.width, camera.height)
    return lines, idx[kept]


def blank_image(camera: Camera, shade: int = 245) -> np.ndarray:
    """(height, width, 3) uint8 light-grey canvas with the image centre marked."""
    img = np.full((camera.height, camera.width, 3), shade, dtype=np.uint8)
    cx, cy = int(round(camera.cx)), int(round(camera.cy))
    img[max(cy, 0) : cy + 1, :] = np.minimum(img[max(cy, 0) : cy + 1, :], 225)
    img[:, max(cx, 0) : cx + 1] = np.minimum(img[:, max(cx, 0) : cx + 1], 225)
    return img


def draw_lines(image: np.ndarray, lines: np.ndarray, colours, thickness: int = 2) -> np.ndarray:
    """Draw (K, 2, 2) pixel lines into ``image`` (in place, returned).

    ``colours`` is one RGB triple or (K, 3). Anti-aliased OpenCV lines.
    """
    import cv2  # a core dependency of the project (the matcher detects lines with it)

    lines = np.asarray(lines, dtype=np.float64).reshape(-1, 2, 2)
    cols = np.broadcast_to(np.asarray(colours, dtype=np.int64).reshape(-1, 3), (len(lines), 3))
    shift = 4  # sub-pixel precision: 1/16 pixel
    pts = np.round(lines * (1 << shift)).astype(np.int64)
    for (a, b), c in zip(pts, cols):
        cv2.line(image, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), tuple(int(v) for v in c), thickness,
                 cv2.LINE_AA, shift)
    return image


def render_segments(
    camera: Camera, segments: np.ndarray, colours: np.ndarray, x: float, y: float, yaw: float,
    image: np.ndarray | None = None, thickness: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """Draw world segments (N, 2, 3) with per-segment ``colours`` (N, 3) as the
    camera at (x, y, yaw) sees them. Returns (image, indices of drawn segments)."""
    img = blank_image(camera) if image is None else image
    lines, idx = project_segments(camera, segments, x, y, yaw)
    cols = np.asarray(colours).reshape(-1, 3)
    draw_lines(img, lines, cols[idx] if len(cols) == len(segments) else cols, thickness)
    return img, idx
