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

from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from linemap.camera import Camera
from linemap.errors import InputError
from matcher.tolerances import DETECTION, LineDetection



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
        raise InputError(f"image: Expected shape (H, W), (H, W, 3) or (H, W, 4), got {np.asarray(image).shape}")
    if img.size == 0:
        raise InputError(f"image is empty (shape {np.asarray(image).shape})")
    if not (img.dtype == np.bool_ or np.issubdtype(img.dtype, np.integer) or np.issubdtype(img.dtype, np.floating)):
        raise InputError(f"image must hold numbers, got dtype {img.dtype}")
    if img.dtype != np.uint8:
        f = img.astype(np.float64)
        if not np.isfinite(f).all():
            raise InputError("image holds non-finite values")
        top = float(f.max())
        if np.issubdtype(img.dtype, np.integer):
            scale = 255.0 / float(np.iinfo(img.dtype).max) if top > 255.0 else 1.0
        else:
            scale = 255.0 if top <= 1.0 else (255.0 / top if top > 255.0 else 1.0)
        img = np.clip(f * scale, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(img)


def merge_collinear(lines: np.ndarray, settings: LineDetection = DETECTION) -> np.ndarray:
    """Merge collinear fragments of lines (M, 2, 2) until none is left; each
    merged line spans the extreme projections of its parts on their
    length-weighted mean direction.

    Two fragments merge when their directions differ by less than
    ``merge_angle_deg``, each one's end points lie within
    ``merge_offset_px`` of the other's line and the gap between them along
    it is at most ``merge_gap_px``. Candidate pairs come from a k-d tree of
    points sampled along the lines (fragments that can merge come that
    close somewhere), the exact test runs on those pairs only, and every
    connected group merges at once; rounds repeat while anything merges (a
    merged line may reach another fragment). Time grows with the number of
    fragments, not its square."""
    lines = np.asarray(lines, dtype=np.float64).reshape(-1, 2, 2)
    while len(lines) > 1:
        i, j = _mergeable_pairs(lines, settings)
        if not len(i):
            break
        n = len(lines)
        graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
        count, label = connected_components(graph, directed=False)
        if count == n:
            break
        order = np.argsort(label, kind="stable")
        starts = np.flatnonzero(np.r_[True, np.diff(label[order]) != 0])
        groups = np.split(order, starts[1:])
        lines = np.stack([lines[g[0]] if len(g) == 1 else _span(lines[g]) for g in groups])
    return lines


def _mergeable_pairs(lines: np.ndarray, settings: LineDetection) -> tuple[np.ndarray, np.ndarray]:
    """``(i, j)`` (P,) index pairs, i < j, of lines (M, 2, 2) that pass the
    merge test of :func:`merge_collinear`."""
    d = lines[:, 1] - lines[:, 0]
    L = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    # Points every `step` pixels along each line (both ends included): two
    # fragments that may merge have points within `reach` of each other.
    step = settings.merge_sample_px
    n_pts = np.ceil(L / step).astype(np.int64) + 1
    owner = np.repeat(np.arange(len(lines)), n_pts)
    t = (np.arange(len(owner)) - np.repeat(np.cumsum(n_pts) - n_pts, n_pts)) / np.repeat(n_pts - 1, n_pts)
    pts = lines[owner, 0] + t[:, None] * d[owner]
    reach = math.hypot(max(settings.merge_gap_px, settings.merge_offset_px), settings.merge_offset_px) + step
    pairs = cKDTree(pts).query_pairs(reach, output_type="ndarray")
    a, b = owner[pairs[:, 0]], owner[pairs[:, 1]]
    keep = a != b
    a, b = np.minimum(a[keep], b[keep]), np.maximum(a[keep], b[keep])
    if not len(a):
        return a, b
    ab = np.unique(a * len(lines) + b)
    i, j = np.divmod(ab, len(lines))
    u = d / L[:, None]
    nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
    par = np.abs((u[i] * u[j]).sum(axis=1)) >= math.cos(math.radians(settings.merge_angle_deg))

    def off_and_gap(p, q):
        """Offset of q's end points from p's line, and q's gap along p."""
        rel = lines[q] - lines[p][:, None, 0]  # (P, 2, 2)
        off = np.abs(np.einsum("pek,pk->pe", rel, nrm[p])).max(axis=1)
        s_ = np.einsum("pek,pk->pe", rel, u[p])
        return off, np.maximum(s_.min(axis=1) - L[p], -s_.max(axis=1))

    off_ij, gap_ij = off_and_gap(i, j)
    off_ji, _ = off_and_gap(j, i)
    ok = par & (off_ij <= settings.merge_offset_px) & (off_ji <= settings.merge_offset_px) & (
        gap_ij <= settings.merge_gap_px)
    return i[ok], j[ok]


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


def detect_lines(image, camera=None, min_length: float | None = None, merge: bool = True,
                 settings: LineDetection = DETECTION) -> np.ndarray:
    """Lines (M, 2, 2) pixels of ``image`` (see module docstring).

    ``camera``: a :class:`matcher.Camera`; with distortion coefficients the
    end points are undistorted; its size must match the image's.
    ``min_length`` (pixels) overrides ``settings.min_length_px``; fragments
    too short to reach it even merged at full gaps are dropped before the
    merge (LSD gives many)."""
    if min_length is None:
        min_length = settings.min_length_px
    if isinstance(min_length, bool) or not isinstance(min_length, numbers.Real) or not (
            math.isfinite(min_length) and min_length >= 0):
        raise InputError(f"min_length must be a number of pixels >= 0, got {min_length!r}")
    if camera is not None and not isinstance(camera, Camera):
        raise InputError(f"camera must be a matcher.Camera (Camera.load('camera.json')), got {type(camera).__name__}")
    grey = to_grey(image)
    if camera is not None and (grey.shape[1], grey.shape[0]) != (camera.width, camera.height):
        raise InputError(
            f"image is {grey.shape[1]}x{grey.shape[0]} but the camera is {camera.width}x{camera.height}"
        )
    if grey.size > settings.max_image_pixels:
        raise InputError(f"image is {grey.shape[1]}x{grey.shape[0]}, over {settings.max_image_pixels:.0f} pixels "
                         "(LineDetection.max_image_pixels); scale it down first")
    lsd = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD)
    found = lsd.detect(grey)[0]
    lines = np.zeros((0, 2, 2)) if found is None else found.reshape(-1, 2, 2).astype(np.float64)
    if merge and len(lines) > 1:
        lines = lines[np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1) >= settings.merge_keep_px]
        lines = merge_collinear(lines, settings)
    if camera is not None and camera.distortion:
        lines = camera.undistort_pixels(lines)
    keep = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1) >= min_length
    return lines[keep]
