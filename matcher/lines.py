"""Straight image lines from a picture: OpenCV's LSD, cleaned for matching.

``detect_lines(image, camera=None)`` returns lines (M, 2, 2) in pixels
``[[u1, v1], [u2, v2]]``: grey conversion, LSD, merging of collinear
fragments (LSD splits a line at noise and gives both edges of a thin
stroke), a minimum length, and, if the camera has distortion, end points
moved to the ideal pinhole (the form :func:`matcher.localize` expects).
"""

from __future__ import annotations

import math
import numbers

import cv2
import numpy as np

from linemap.camera import Camera

#: Lines shorter than this many pixels are dropped: their orientation is
#: too uncertain for the constraints (same default as ``Tolerances.min_line_px``).
MIN_LENGTH_PX = 15.0
#: Fragments merge when their directions differ by less than this many
#: degrees (LSD's own angle tolerance is 22.5 degrees per pixel, its lines
#: are good to about a degree)...
MERGE_ANGLE_DEG = 2.0
#: ...each one's end points lie within this many pixels of the other's line
#: (both edges of a stroke up to about 4 px wide)...
MERGE_OFFSET_PX = 4.0
#: ...and the gap between them along the line is under this many pixels.
MERGE_GAP_PX = 10.0


def to_grey(image: np.ndarray) -> np.ndarray:
    """(H, W) uint8 grey image from a grey, BGR or BGRA array.

    8-bit images are taken as they are. Other integer images whose values
    exceed 255 (16-bit ones) are scaled by their type's range; booleans and
    floats in [0, 1] by 255; floats beyond 255 by their maximum."""
    img = np.asarray(image)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    if img.ndim == 3 and img.shape[2] in (3, 4):
        if img.dtype not in (np.uint8, np.uint16, np.float32):  # the types cvtColor takes
            img = img.astype(np.float32)
        img = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    if img.ndim != 2:
        raise ValueError(f"image: Expected shape (H, W), (H, W, 3) or (H, W, 4), got {np.asarray(image).shape}")
    if img.size == 0:
        raise ValueError(f"image is empty (shape {np.asarray(image).shape})")
    if not (img.dtype == np.bool_ or np.issubdtype(img.dtype, np.integer) or np.issubdtype(img.dtype, np.floating)):
        raise ValueError(f"image must hold numbers, got dtype {img.dtype}")
    if img.dtype != np.uint8:
        f = img.astype(np.float64)
        if not np.isfinite(f).all():
            raise ValueError("image holds non-finite values")
        top = float(f.max())
        if np.issubdtype(img.dtype, np.integer):
            scale = 255.0 / float(np.iinfo(img.dtype).max) if top > 255.0 else 1.0
        else:
            scale = 255.0 if top <= 1.0 else (255.0 / top if top > 255.0 else 1.0)
        img = np.clip(f * scale, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(img)


def merge_collinear(lines: np.ndarray) -> np.ndarray:
    """Merge collinear fragments of lines (M, 2, 2) until none is left; each
    merged line spans the extreme projections of its parts on their
    length-weighted mean direction."""
    lines = np.asarray(lines, dtype=np.float64).reshape(-1, 2, 2)
    cos_tol = math.cos(math.radians(MERGE_ANGLE_DEG))
    changed = True
    while changed and len(lines) > 1:
        changed = False
        d = lines[:, 1] - lines[:, 0]
        L = np.linalg.norm(d, axis=1)
        u = d / L[:, None]
        nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
        par = np.abs(u @ u.T) >= cos_tol
        # Offset of j's end points from i's line, and gap along i's direction.
        rel = lines[None, :, :, :] - lines[:, None, None, 0, :]  # (i, j, 2, 2)
        off = np.abs(np.einsum("ijek,ik->ije", rel, nrm)).max(axis=2)
        s = np.einsum("ijek,ik->ije", rel, u)
        gap = np.maximum(s.min(axis=2) - L[:, None], -s.max(axis=2))
        close = par & (off <= MERGE_OFFSET_PX) & (off.T <= MERGE_OFFSET_PX) & (gap <= MERGE_GAP_PX)
        np.fill_diagonal(close, False)
        if not close.any():
            break
        i, j = np.unravel_index(int(np.argmax(close)), close.shape)
        merged = _span(lines[[i, j]])
        lines = np.concatenate([np.delete(lines, [i, j], axis=0), merged[None]])
        changed = True
    return lines


def _span(parts: np.ndarray) -> np.ndarray:
    """One line (2, 2) through parts (k, 2, 2), over their whole extent."""
    d = parts[:, 1] - parts[:, 0]
    w = np.linalg.norm(d, axis=1)
    ref = d[np.argmax(w)]
    d = np.where((d @ ref)[:, None] < 0, -d, d)  # orient alike before averaging
    u = d.sum(axis=0)
    u /= np.linalg.norm(u)
    pts = parts.reshape(-1, 2)
    c = (0.5 * (parts[:, 0] + parts[:, 1]) * w[:, None]).sum(axis=0) / w.sum()
    s = (pts - c) @ u
    return np.array([c + s.min() * u, c + s.max() * u])


def detect_lines(image, camera=None, min_length: float = MIN_LENGTH_PX, merge: bool = True) -> np.ndarray:
    """Lines (M, 2, 2) pixels of ``image`` (see module docstring).

    ``camera``: a :class:`matcher.Camera`; with distortion coefficients the
    end points are undistorted; its size must match the image's."""
    if isinstance(min_length, bool) or not isinstance(min_length, numbers.Real) or not (
            math.isfinite(min_length) and min_length >= 0):
        raise ValueError(f"min_length must be a number of pixels >= 0, got {min_length!r}")
    if camera is not None and not isinstance(camera, Camera):
        raise ValueError(f"camera must be a matcher.Camera (Camera.load('camera.json')), got {type(camera).__name__}")
    grey = to_grey(image)
    if camera is not None and (grey.shape[1], grey.shape[0]) != (camera.width, camera.height):
        raise ValueError(
            f"image is {grey.shape[1]}x{grey.shape[0]} but the camera is {camera.width}x{camera.height}"
        )
    lsd = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD)
    found = lsd.detect(grey)[0]
    lines = np.zeros((0, 2, 2)) if found is None else found.reshape(-1, 2, 2).astype(np.float64)
    if merge and len(lines) > 1:
        lines = merge_collinear(lines)
    if camera is not None and camera.distortion:
        lines = camera.undistort_pixels(lines)
    keep = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1) >= min_length
    return lines[keep]
