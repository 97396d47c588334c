"""Validation at the door: one ``check_*`` per core input type.

Each converts, validates and returns clean arrays; the kernels behind them
trust their input. Errors are ``ValueError`` naming the parameter and what
would be valid.

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
from matcher.tolerances import Tolerances


def check_lines(lines, camera: Camera, tol: Tolerances) -> np.ndarray:
    """Image lines as a finite ``(M, 2, 2)`` float64 array inside the image.

    Raises ValueError for a wrong shape, a non-finite value, a zero-length
    line or an end point outside the image (beyond ``tol.image_margin_px``).
    """
    try:
        arr = np.asarray(lines, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError("lines must be numbers: Expected shape (M, 2, 2) or (M, 4)") from None
    if arr.ndim == 2 and arr.shape[1] == 4:
        arr = arr.reshape(-1, 2, 2)
    elif arr.shape == (0,):  # an empty list
        arr = arr.reshape(0, 2, 2)
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise ValueError(f"lines: Expected shape (M, 2, 2) or (M, 4), got {arr.shape}")
    bad = ~np.isfinite(arr).all(axis=(1, 2))
    if bad.any():
        raise ValueError(f"lines[{int(np.argmax(bad))}] is not finite (NaN or inf pixel coordinates)")
    # Outside the image first: a coordinate near the float limit would
    # overflow the length below.
    u0, u1, v0, v1 = camera.ideal_bounds
    m = tol.image_margin_px
    out = (
        (arr[..., 0] < u0 - m).any(axis=1)
        | (arr[..., 0] > u1 + m).any(axis=1)
        | (arr[..., 1] < v0 - m).any(axis=1)
        | (arr[..., 1] > v1 + m).any(axis=1)
    )
    if out.any():
        j = int(np.argmax(out))
        where = (f"u in [0, {camera.width}], v in [0, {camera.height}]" if not camera.distortion else
                 f"undistorted: u in [{u0:.1f}, {u1:.1f}], v in [{v0:.1f}, {v1:.1f}]")
        raise ValueError(
            f"lines[{j}] = {[float(f'{v:.6g}') for v in arr[j].ravel()]} lies outside the "
            f"{camera.width}x{camera.height} image ({where}); were the lines detected with another camera?"
        )
    length = np.linalg.norm(arr[:, 1] - arr[:, 0], axis=1)
    zero = length < 1e-6
    if zero.any():
        raise ValueError(f"lines[{int(np.argmax(zero))}] has zero length (both end points equal)")
    return arr


def check_prior(prior, dt, dyaw) -> tuple[float, float, float, float, float]:
    """``(x, y, yaw_rad, dt, dyaw_rad)`` from a prior ``(x, y, yaw_deg)``, ``dt`` m, ``dyaw`` deg."""
    try:
        vals = [float(v) for v in prior]
    except (TypeError, ValueError):
        raise ValueError(f"prior must be (x, y, yaw_deg) numbers, got {prior!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise ValueError(f"prior must be 3 finite numbers (x, y, yaw_deg), got {prior!r}")
    if max(abs(vals[0]), abs(vals[1])) > 1e6:
        raise ValueError(f"prior position ({vals[0]:.6g}, {vals[1]:.6g}) is more than 1000 km out; "
                         "give map coordinates in metres")
    try:
        dt, dyaw = float(dt), float(dyaw)
    except (TypeError, ValueError):
        raise ValueError(f"dt and dyaw must be numbers, got {dt!r}, {dyaw!r}") from None
    if not (math.isfinite(dt) and 0.0 < dt <= 100.0):
        raise ValueError(f"dt must be in (0, 100] metres, got {dt}")
    if not (math.isfinite(dyaw) and 0.0 < dyaw <= 180.0):
        raise ValueError(f"dyaw must be in (0, 180] degrees, got {dyaw}")
    # Any number of turns is the same heading: reduced first, so that a huge
    # angle does not lose its meaning (or overflow) on the way.
    return vals[0], vals[1], math.radians(math.remainder(vals[2], 360.0)), dt, math.radians(dyaw)


def check_segments(segments) -> np.ndarray:
    """Model segments as a finite ``(N, 2, 3)`` float64 array."""
    arr = np.asarray(segments, dtype=np.float64)
    if arr.ndim != 3 or arr.shape[1:] != (2, 3):
        raise ValueError(f"segments: Expected shape (N, 2, 3), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError("segments hold non-finite coordinates")
    return arr
