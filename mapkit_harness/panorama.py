"""Perspective views cut from an upright equirectangular panorama, and their poses.

A ZInD panorama (:class:`mapkit.importers.zind.annotations.ZindPano`) is a
``W x W/2`` equirectangular image taken at a known place of the floor plan;
a pinhole :class:`linemap.camera.Camera` at that place, at the panorama's
camera height, looking along a world heading ``yaw`` and pitched down by
the camera's pitch, sees what :func:`cut_view` resamples from it. The view's
true pose is then ``(pano.position, yaw)``: nothing else to estimate.

Used by ``tools/bench_real.py``; tested on a box room drawn into an
equirectangular image (``tests/test_panorama_views.py``). ZInD spreads the
full turn over ``W - 1`` columns (:meth:`ZindPano.pixel_of`), the matcher's
own cut (:mod:`matcher.panorama`) over ``W``: a ZInD panorama of plan
rotation ``r`` is the matcher's panorama at robot heading ``-90 - r``, and
the two cuts sample it within half a pixel of each other
(``tests/test_panorama.py``). This one stays ZInD's, so the benchmark's
views are as they were.
"""

from __future__ import annotations

import cv2
import numpy as np

from linemap.camera import Camera


def view_directions(camera: Camera, yaw: float) -> np.ndarray:
    """(H, W, 3) world direction of each pixel centre of ``camera`` looking
    along heading ``yaw`` (radians, counter-clockwise from +x)."""
    u, v = np.meshgrid(np.arange(camera.width, dtype=float), np.arange(camera.height, dtype=float))
    rays = camera.pixel_rays(np.stack([u, v], axis=-1))  # camera frame (right, down, forward)
    return rays @ camera.world2cam(yaw)  # R's rows are the camera axes in world: R^T ray


def cut_view(panorama: np.ndarray, pano, camera: Camera, yaw: float) -> np.ndarray:
    """The ``camera`` image at heading ``yaw`` (radians) resampled from the
    equirectangular ``panorama`` (H, 2H[, 3]) taken by ``pano`` (a ZindPano:
    ``local_directions`` and ``pixel_of``). Bilinear; wraps around the seam."""
    h, w = panorama.shape[:2]
    if w != 2 * h:
        raise ValueError(f"an equirectangular panorama is twice as wide as high, got {w}x{h}")
    dirs = view_directions(camera, yaw).reshape(-1, 3)
    uv = pano.pixel_of(pano.local_directions(dirs), w).reshape(camera.height, camera.width, 2).astype(np.float32)
    # ZInD's columns span the full turn over width - 1 pixels: map onto w columns with wrap.
    return cv2.remap(panorama, uv[..., 0], uv[..., 1], interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)


def view_pose(pano, yaw_deg: float) -> tuple[float, float, float]:
    """The true pose (x, y, yaw_deg) of a view cut from ``pano`` at heading ``yaw_deg``."""
    return float(pano.position[0]), float(pano.position[1]), float((yaw_deg + 180.0) % 360.0 - 180.0)

