"""Camera model in the conventions of docs/method.md section 2.

World: x, y horizontal, z up, metres. Camera: OpenCV pinhole, X right,
Y down, Z forward; pixel ``u`` is the column, ``v`` the row. The camera
centre is ``C = (x, y, h)``; ``yaw`` is the heading of the optical axis on
the floor, counter-clockwise from +x; ``pitch`` is positive looking down;
``roll`` (about the optical axis) is positive when the camera's right side
is down (clockwise seen from behind; the picture turns counter-clockwise),
zero by default. Angles are radians in code and degrees in files.

numpy only: the map builder imports this too (for the vertical field of view).
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from linemap.errors import InputError

REQUIRED_FIELDS = ("width", "height", "fx", "fy", "cx", "cy", "height_m", "pitch_deg")
#: Optional fields of the mounting, degrees, 0 when absent: the roll, and
#: how far the real pitch and roll of a frame may stray from the file's
#: (standard deviations: a camera not mounted exactly, a robot that rocks).
#: 0 says the file is exact.
ATTITUDE_FIELDS = ("roll_deg", "pitch_std_deg", "roll_std_deg")


class CameraError(InputError):
    """A camera description is missing a field or holds an impossible value."""


@contextmanager
def naming_flags(flags: Mapping[str, str | bool | None]):
    """Within it, a CameraError about a camera field that a command-line flag
    set names the flag the user typed instead of the field
    (``{"height_m": "--camera-height"}``: "camera height_m must be above the
    floor ..." becomes "--camera-height must be above the floor ...").
    Fields whose flag is None or False (not given) keep their name."""
    try:
        yield
    except CameraError as exc:
        text = str(exc)
        for name, flag in flags.items():
            if flag:
                text = re.sub(rf"\bcamera {re.escape(name)}\b", flag, text)
        if text == str(exc):
            raise
        raise CameraError(text) from None


@dataclass(frozen=True)
class Camera:
    """A calibrated camera at a known height and pitch.

    ``distortion`` holds OpenCV's coefficients (k1, k2, p1, p2[, k3...]) or is
    empty for an ideal pinhole. ``roll_deg`` is the roll of the mounting;
    ``pitch_std_deg`` and ``roll_std_deg`` how far a frame's own pitch and
    roll may stray from the file's (the matcher then estimates them per
    frame, :mod:`matcher.attitude`); all three 0 by default.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    height_m: float
    pitch_deg: float
    distortion: tuple[float, ...] = field(default=())
    roll_deg: float = 0.0
    pitch_std_deg: float = 0.0
    roll_std_deg: float = 0.0

    def __post_init__(self) -> None:
        check_camera(self)

    # ---- construction -------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict) -> "Camera":
        """Build from the camera.json shape; missing or bad fields raise CameraError."""
        if not isinstance(d, dict):
            raise CameraError("camera description must be a JSON object")
        missing = [k for k in REQUIRED_FIELDS if k not in d]
        if missing:
            raise CameraError(f"camera description lacks {', '.join(missing)} (needs {', '.join(REQUIRED_FIELDS)})")
        vals = {k: _number(f"camera {k}", d[k]) for k in REQUIRED_FIELDS}
        dist = d.get("distortion") or ()
        if not isinstance(dist, (list, tuple)):
            raise CameraError(f"camera distortion must be a list of numbers, got {dist!r}")
        vals["distortion"] = tuple(_number("camera distortion", v) for v in dist)
        for k in ATTITUDE_FIELDS:
            if d.get(k) is not None:
                vals[k] = _number(f"camera {k}", d[k])
        for k in ("width", "height"):
            if math.isfinite(vals[k]) and vals[k] == int(vals[k]):
                vals[k] = int(vals[k])
        return cls(**vals)

    @classmethod
    def load(cls, path: str | Path, height_m: float | None = None, pitch_deg: float | None = None,
             roll_deg: float | None = None) -> "Camera":
        """Read a camera.json, an OpenCV calibration file (YAML, XML, JSON) or a
        ROS camera_info YAML (:mod:`linemap.camera_files`); ``height_m``,
        ``pitch_deg`` and ``roll_deg``, when given, override the file's
        (calibration files usually have none)."""
        from linemap.camera_files import load_camera

        return load_camera(path, height_m, pitch_deg, roll_deg)

    @classmethod
    def from_fov(cls, hfov_deg: float, width: int, height: int, height_m: float, pitch_deg: float) -> "Camera":
        """An ideal pinhole with square pixels and the given horizontal field of view."""
        if not 1.0 <= hfov_deg < 179.0:
            raise CameraError(f"camera hfov_deg (horizontal field of view) must be in [1, 179) degrees, got {hfov_deg}")
        f = (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
        return cls(width, height, f, f, width / 2.0, height / 2.0, height_m, pitch_deg)

    def to_dict(self) -> dict:
        d = {
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "height_m": self.height_m,
            "pitch_deg": self.pitch_deg,
        }
        if self.distortion:
            d["distortion"] = list(self.distortion)
        for k in ATTITUDE_FIELDS:  # only when set: a level, exact camera's file is as it was
            if getattr(self, k):
                d[k] = getattr(self, k)
        return d

    # ---- geometry -------------------------------------------------------
    @property
    def pitch(self) -> float:
        return math.radians(self.pitch_deg)

    @property
    def roll(self) -> float:
        return math.radians(self.roll_deg)

    @property
    def attitude_free(self) -> bool:
        """Do the frames' pitch and roll stray from the file's (a standard deviation above 0)?"""
        return self.pitch_std_deg > 0.0 or self.roll_std_deg > 0.0

    @property
    def K(self) -> np.ndarray:
        """(3, 3) intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def world2cam(self, yaw: float) -> np.ndarray:
        """(3, 3) rotation R with rows (right, down, forward) in world coordinates."""
        return world2cam_rotation(yaw, self.pitch, self.roll)

    def centre(self, x: float, y: float) -> np.ndarray:
        return np.array([x, y, self.height_m])

    def project(self, points: np.ndarray, x: float, y: float, yaw: float) -> tuple[np.ndarray, np.ndarray]:
        """Project world points (..., 3) for the camera at pose (x, y, yaw).

        Returns pixels (..., 2) as (u, v) and depth Zc (...,); points with
        Zc <= 0 are behind the camera and their pixels are meaningless.
        """
        R = self.world2cam(yaw)
        pc = (np.asarray(points, dtype=float) - self.centre(x, y)) @ R.T
        z = pc[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = np.stack([self.fx * pc[..., 0] / z + self.cx, self.fy * pc[..., 1] / z + self.cy], axis=-1)
        return uv, z

    def pixel_rays(self, uv: np.ndarray) -> np.ndarray:
        """Rays K^-1 [u, v, 1] (..., 3) in camera coordinates (not normalised)."""
        uv = np.asarray(uv, dtype=float)
        return np.stack([(uv[..., 0] - self.cx) / self.fx, (uv[..., 1] - self.cy) / self.fy, np.ones(uv.shape[:-1])], axis=-1)

    def interpretation_normals(self, lines: np.ndarray) -> np.ndarray:
        """Unit normals (M, 3), camera frame, of the planes through the optical
        centre and image lines (M, 2, 2) pixels (method.md section 4).

        The sign is arbitrary (every use squares it or takes its absolute value).
        Lines must be undistorted (see :meth:`undistort_pixels`)."""
        rays = self.pixel_rays(np.asarray(lines, dtype=float))
        n = np.cross(rays[:, 0], rays[:, 1])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def undistort_pixels(self, uv: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of the real (distorted) camera -> pixels of the ideal
        pinhole with the same K. Identity when there is no distortion."""
        uv = np.asarray(uv, dtype=float)
        if not self.distortion or uv.size == 0:
            return uv.copy()
        import cv2  # only needed with distortion; keeps this module numpy-only otherwise

        pts = uv.reshape(-1, 1, 2).astype(np.float64)
        out = cv2.undistortPoints(pts, self.K, np.asarray(self.distortion, dtype=np.float64), P=self.K)
        return out.reshape(uv.shape)

    def elevation_range(self) -> tuple[float, float]:
        """(lowest, highest) elevation angle, radians, that any pixel looks at.

        Elevation is measured from the horizontal plane, positive upwards. The
        extremes of a pinhole's view cone lie on the image border, so the
        border is sampled densely (corners included); the heading is free, so
        these bounds are all the vertical field of view says about visibility.
        """
        w, h = self.width, self.height
        t = np.linspace(0.0, 1.0, 257)
        border = np.concatenate(
            [
                np.stack([t * w, np.zeros_like(t)], 1),
                np.stack([t * w, np.full_like(t, h)], 1),
                np.stack([np.zeros_like(t), t * h], 1),
                np.stack([np.full_like(t, w), t * h], 1),
                [[self.cx, 0.0], [self.cx, h]],
            ]
        )
        rays = self.pixel_rays(border)
        # World direction of a camera ray: R^T ray; its z component is d_z*Y + f_z*Z
        # (and r_z*X with a roll).
        p = self.pitch
        if self.roll_deg:
            z = rays @ self.world2cam(0.0)[:, 2]
        else:
            z = -math.cos(p) * rays[:, 1] - math.sin(p) * rays[:, 2]
        elev = np.arcsin(z / np.linalg.norm(rays, axis=1))
        return float(elev.min()), float(elev.max())

    def horizontal_half_fov(self) -> float:
        """Largest horizontal angle, radians, between the optical axis's heading and
        the heading of any pixel's ray (used to drop segments out of view)."""
        return self._half_fov

    @cached_property
    def ideal_bounds(self) -> tuple[float, float, float, float]:
        """``(u_min, u_max, v_min, v_max)``: where the image's pixels land on
        the ideal pinhole (the frame of the lines :func:`matcher.localize`
        takes). The image itself without distortion; with it, the box around
        the undistorted border as well (barrel distortion moves the corners
        outwards). Computed once per camera (it is immutable)."""
        w, h = float(self.width), float(self.height)
        if not self.distortion:
            return 0.0, w, 0.0, h
        t = np.linspace(0.0, 1.0, 65)
        zero, one = np.zeros_like(t), np.ones_like(t)
        border = np.concatenate([np.stack([t * w, zero], 1), np.stack([t * w, one * h], 1),
                                 np.stack([zero, t * h], 1), np.stack([one * w, t * h], 1)])
        ideal = self.undistort_pixels(border)
        lo, hi = ideal.min(axis=0), ideal.max(axis=0)
        return min(0.0, float(lo[0])), max(w, float(hi[0])), min(0.0, float(lo[1])), max(h, float(hi[1]))

    @cached_property
    def _half_fov(self) -> float:
        """:meth:`horizontal_half_fov`, computed once per camera (it is immutable)."""
        w, h = self.width, self.height
        t = np.linspace(0.0, 1.0, 129)
        border = np.concatenate([np.stack([np.zeros_like(t), t * h], 1), np.stack([np.full_like(t, w), t * h], 1)])
        R = self.world2cam(0.0)  # yaw 0: the optical axis heads along +x
        d = self.pixel_rays(border) @ R  # world directions (R^T ray)
        return float(np.abs(np.arctan2(d[:, 1], d[:, 0])).max())


def world2cam_rotation(yaw, pitch: float, roll: float = 0.0) -> np.ndarray:
    """World-to-camera rotation(s), rows r, d, f of method.md section 2.

    ``yaw`` a scalar gives (3, 3); an array of yaws (...,) gives (..., 3, 3).
    A ``roll`` (radians, the camera's right side down) turns the rows r and
    d about f: ``roll_rotation(roll) @ R``."""
    cy_, sy_ = np.cos(yaw), np.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    z = np.zeros_like(cy_)
    r = np.stack([sy_, -cy_, z], -1)
    d = np.stack([-sp * cy_, -sp * sy_, z - cp], -1)
    f = np.stack([cp * cy_, cp * sy_, z - sp], -1)
    R = np.stack([r, d, f], -2)
    return roll_rotation(roll) @ R if roll else R


def roll_rotation(roll: float) -> np.ndarray:
    """(3, 3) turn of the camera frame about its optical axis by ``roll``
    radians (the right side down): the rows r, d become
    ``cos*r + sin*d`` and ``-sin*r + cos*d``."""
    c, s = math.cos(roll), math.sin(roll)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _number(what: str, v) -> float:
    """``v`` as a float if it is a real number (not a bool, not a string);
    else CameraError naming ``what``."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        raise CameraError(f"{what} must be a number, got {v!r}")
    try:
        return float(v)
    except OverflowError:
        raise CameraError(f"{what} is out of range, got {v!r}") from None


def check_camera(cam: Camera) -> None:
    """Validate a camera; raise CameraError naming the field and its valid range."""
    vals = {k: _number(f"camera {k}", getattr(cam, k)) for k in REQUIRED_FIELDS}
    for k, v in vals.items():
        if not math.isfinite(v):
            raise CameraError(f"camera {k} must be finite, got {v}")
    if vals["width"] != int(vals["width"]) or vals["height"] != int(vals["height"]):
        raise CameraError(f"camera width and height must be whole pixels, got {cam.width}x{cam.height}")
    if not isinstance(cam.distortion, tuple):
        raise CameraError(f"camera distortion must be a tuple of numbers, got {cam.distortion!r}")
    for v in cam.distortion:
        _number("camera distortion", v)
    if cam.width <= 0 or cam.height <= 0:
        raise CameraError(f"camera width and height must be positive pixels, got {cam.width}x{cam.height}")
    if cam.fx <= 0 or cam.fy <= 0:
        raise CameraError(f"camera fx and fy must be positive, got {cam.fx}, {cam.fy}")
    if cam.height_m <= 0:
        raise CameraError(f"camera height_m must be above the floor (> 0 m), got {cam.height_m}")
    if not -89.0 <= cam.pitch_deg <= 89.0:
        raise CameraError(f"camera pitch_deg must be in [-89, 89] (positive looks down), got {cam.pitch_deg}")
    for k in ATTITUDE_FIELDS:
        v = _number(f"camera {k}", getattr(cam, k))
        if not math.isfinite(v):
            raise CameraError(f"camera {k} must be finite, got {v}")
    # Beyond these the picture is not of a camera looking ahead upright (and
    # the correction's homography bends lines far from the centre away).
    if not -45.0 <= cam.roll_deg <= 45.0:
        raise CameraError(f"camera roll_deg must be in [-45, 45] (positive: the right side down), got {cam.roll_deg}")
    for k in ("pitch_std_deg", "roll_std_deg"):
        if not 0.0 <= getattr(cam, k) <= 10.0:
            raise CameraError(f"camera {k} must be in [0, 10] degrees (0: the file's value is exact), "
                              f"got {getattr(cam, k)}")
    if any(not math.isfinite(v) for v in cam.distortion):
        raise CameraError("camera distortion coefficients must be finite")
    if cam.distortion and len(cam.distortion) not in (4, 5, 8, 12, 14):
        raise CameraError(f"camera distortion takes 4, 5, 8, 12 or 14 OpenCV coefficients, got {len(cam.distortion)}")
