"""Validation at the door: one ``check_*`` per core input type.

Each converts, validates and returns clean arrays; the kernels behind them
trust their input. Errors are :class:`linemap.errors.InputError` (a
``ValueError``) naming the parameter and what would be valid.

Conventions, written once:

- image lines ``(M, 2, 2)`` float pixels: ``lines[j] = [[u1, v1], [u2, v2]]``,
  ``u`` the column, ``v`` the row; ``(M, 4)`` rows ``[u1, v1, u2, v2]`` are
  accepted and reshaped.
- model segments ``(N, 2, 3)`` float world metres.
- a prior is ``(x, y, yaw_deg)``; ``dt`` metres, ``dyaw`` degrees.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.camera import Camera
from linemap.errors import InputError
from linemap.geometry import clip_lines
from matcher.tolerances import Tolerances


def check_lines(lines, camera: Camera, tol: Tolerances) -> np.ndarray:
    """Image lines as a finite ``(M, 2, 2)`` float64 array inside the image.

    End points up to ``tol.image_margin_px`` outside the image are taken as
    they are (noise on lines clipped at the border); a line reaching farther
    out, but no farther than ``tol.image_reach`` of the image's size (an
    undistorted line, a detector's unclipped output), is cut at the image
    border plus that margin, keeping its index. Raises InputError for a
    wrong shape, a non-finite value, more than ``tol.max_lines`` lines, a
    line farther out (lines of another camera) or wholly outside, and a
    zero-length line.
    """
    try:
        arr = np.asarray(lines, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InputError("lines must be numbers: Expected shape (M, 2, 2) or (M, 4)") from None
    if arr.ndim == 2 and arr.shape[1] == 4:
        arr = arr.reshape(-1, 2, 2)
    elif arr.shape == (0,):  # an empty list
        arr = arr.reshape(0, 2, 2)
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise InputError(f"lines: Expected shape (M, 2, 2) or (M, 4), got {arr.shape}")
    if len(arr) > tol.max_lines:
        raise InputError(f"{len(arr)} image lines given, the matcher takes at most {tol.max_lines} "
                         "(Tolerances.max_lines, "
                         "matcher localize --max-lines): keep the longest")
    bad = ~np.isfinite(arr).all(axis=(1, 2))
    if bad.any():
        raise InputError(f"lines[{int(np.argmax(bad))}] is not finite (NaN or inf pixel coordinates)")
    # Outside the image first: a coordinate near the float limit would
    # overflow the length below.
    u0, u1, v0, v1 = camera.ideal_bounds
    m = tol.image_margin_px
    box = (u0 - m, u1 + m, v0 - m, v1 + m)
    reach_u, reach_v = tol.image_reach * (u1 - u0), tol.image_reach * (v1 - v0)
    far = ((arr[..., 0] < u0 - reach_u) | (arr[..., 0] > u1 + reach_u) | (arr[..., 1] < v0 - reach_v)
           | (arr[..., 1] > v1 + reach_v)).any(axis=1)
    if far.any():
        raise InputError(_outside(arr, int(np.argmax(far)), camera, "lies outside"))
    stick_out = ((arr[..., 0] < box[0]) | (arr[..., 0] > box[1]) | (arr[..., 1] < box[2])
                 | (arr[..., 1] > box[3])).any(axis=1)
    if stick_out.any():
        clipped, inside = clip_lines(arr[stick_out], box)
        if not inside.all():
            j = int(np.flatnonzero(stick_out)[np.argmin(inside)])
            raise InputError(_outside(arr, j, camera, "lies wholly outside"))
        arr = arr.copy()
        arr[stick_out] = clipped
    length = np.linalg.norm(arr[:, 1] - arr[:, 0], axis=1)
    zero = length < 1e-6
    if zero.any():
        raise InputError(f"lines[{int(np.argmax(zero))}] has zero length (both end points equal)")
    return arr


def _outside(arr: np.ndarray, j: int, camera: Camera, how: str) -> str:
    """The error for line ``j`` outside the image."""
    u0, u1, v0, v1 = camera.ideal_bounds
    where = (f"u in [0, {camera.width}], v in [0, {camera.height}]" if not camera.distortion else
             f"undistorted: u in [{u0:.1f}, {u1:.1f}], v in [{v0:.1f}, {v1:.1f}]")
    return (f"lines[{j}] = {[float(f'{v:.6g}') for v in arr[j].ravel()]} {how} the "
            f"{camera.width}x{camera.height} image ({where}); were the lines detected with another camera?")


def check_prior(prior, dt, dyaw) -> tuple[float, float, float, float, float]:
    """``(x, y, yaw_rad, dt, dyaw_rad)`` from a prior ``(x, y, yaw_deg)``, ``dt`` m, ``dyaw`` deg."""
    try:
        vals = [float(v) for v in prior]
    except (TypeError, ValueError):
        raise InputError(f"prior must be (x, y, yaw_deg) numbers, got {prior!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise InputError(f"prior must be 3 finite numbers (x, y, yaw_deg), got {prior!r}")
    if max(abs(vals[0]), abs(vals[1])) > 1e6:
        raise InputError(f"prior position ({vals[0]:.6g}, {vals[1]:.6g}) is more than 1000 km out; "
                         "give map coordinates in metres")
    try:
        dt, dyaw = float(dt), float(dyaw)
    except (TypeError, ValueError):
        raise InputError(f"dt and dyaw must be numbers, got {dt!r}, {dyaw!r}") from None
    if not (math.isfinite(dt) and 0.0 < dt <= 100.0):
        raise InputError(f"dt must be in (0, 100] metres, got {dt}")
    if not (math.isfinite(dyaw) and 0.0 < dyaw <= 180.0):
        raise InputError(f"dyaw must be in (0, 180] degrees, got {dyaw}")
    # Any number of turns is the same heading: reduced first, so that a huge
    # angle does not lose its meaning (or overflow) on the way.
    return vals[0], vals[1], math.radians(math.remainder(vals[2], 360.0)), dt, math.radians(dyaw)


def check_segments(segments) -> np.ndarray:
    """Model segments as a finite ``(N, 2, 3)`` float64 array."""
    arr = np.asarray(segments, dtype=np.float64)
    if arr.ndim != 3 or arr.shape[1:] != (2, 3):
        raise InputError(f"segments: Expected shape (N, 2, 3), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError("segments hold non-finite coordinates")
    return arr
