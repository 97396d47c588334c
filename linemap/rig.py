"""A camera rig: several calibrated cameras fixed on one robot.

Each camera is the usual :class:`~linemap.camera.Camera` (its intrinsics,
its own height above the floor, pitch and roll) plus where it sits on the
robot: ``x`` forward and ``y`` left of the robot's centre, metres, and
``yaw_deg`` its heading relative to the robot's heading (counter-clockwise
seen from above, like every yaw here). The robot's pose ``(X, Y, theta)``
puts camera c at

    position = (X, Y) + Rz(theta) (x_c, y_c),   heading = theta + yaw_c,

at its own height. A single camera is the one-camera rig with its mount at
the robot's centre (:meth:`Rig.single`): everything that localises one
camera localises it as before.

numpy only (the map builder and the inspector may import it too).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera, CameraError


@dataclass(frozen=True)
class Mount:
    """Where a camera sits on the robot: ``x`` forward, ``y`` left of the
    robot's centre, metres; ``yaw_deg`` its heading relative to the robot's,
    degrees, counter-clockwise seen from above. Its height, pitch and roll
    are its :class:`~linemap.camera.Camera`'s."""

    x: float = 0.0
    y: float = 0.0
    yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "yaw_deg"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise CameraError(f"camera mount {name} must be a finite number, got {v!r}")
        if abs(self.x) > 100.0 or abs(self.y) > 100.0:
            raise CameraError(f"camera mount ({self.x:g}, {self.y:g}) m is more than 100 m from the robot's centre; "
                              "mount positions are in metres")

    @property
    def yaw(self) -> float:
        """The heading offset, radians."""
        return math.radians(self.yaw_deg)

    @property
    def at_centre(self) -> bool:
        """Is the camera at the robot's centre, looking along its heading?"""
        return self.x == 0.0 and self.y == 0.0 and self.yaw_deg == 0.0

    def camera_poses(self, robot_poses: np.ndarray) -> np.ndarray:
        """(..., 3) camera poses ``(x, y, yaw)`` (radians) of robot poses
        (..., 3) ``(X, Y, theta)``."""
        p = np.asarray(robot_poses, dtype=float)
        c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
        out = np.empty(p.shape)  # filled in place: a rig's verification asks this thousands of times a call
        out[..., 0] = p[..., 0] + c * self.x - s * self.y
        out[..., 1] = p[..., 1] + s * self.x + c * self.y
        out[..., 2] = p[..., 2] + self.yaw
        return out

    def robot_poses(self, camera_poses: np.ndarray) -> np.ndarray:
        """(..., 3) robot poses of camera poses (..., 3): the inverse of
        :meth:`camera_poses`."""
        q = np.asarray(camera_poses, dtype=float)
        theta = q[..., 2] - self.yaw
        c, s = np.cos(theta), np.sin(theta)
        return np.stack([q[..., 0] - c * self.x + s * self.y, q[..., 1] - s * self.x - c * self.y, theta], axis=-1)

    def jacobian(self, theta: np.ndarray) -> np.ndarray:
        """(..., 3, 3) derivative of the camera pose with respect to the robot
        pose at robot headings ``theta`` (...,) radians."""
        theta = np.asarray(theta, dtype=float)
        c, s = np.cos(theta), np.sin(theta)
        J = np.zeros(theta.shape + (3, 3))
        J[..., 0, 0] = J[..., 1, 1] = J[..., 2, 2] = 1.0
        J[..., 0, 2] = -s * self.x - c * self.y
        J[..., 1, 2] = c * self.x - s * self.y
        return J


@dataclass(frozen=True)
class RigCamera:
    """One camera of a rig: its ``name`` (as its frames and results call
    it), its ``camera`` model and its ``mount`` on the robot; ``topic``, if
    known, the image topic its frames come on (a rig file's ``topic``, a
    Kalibr camchain's ``rostopic``), else empty."""

    name: str
    camera: Camera
    mount: Mount = Mount()
    topic: str = ""


@dataclass(frozen=True)
class Rig:
    """The cameras of one robot, in order (frames give one list of lines per
    camera, in this order)."""

    cameras: tuple[RigCamera, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.cameras, tuple) or not self.cameras:
            raise CameraError("a rig needs at least one camera")
        for rc in self.cameras:
            if not isinstance(rc, RigCamera):
                raise CameraError(f"rig cameras must be RigCamera, got {type(rc).__name__}")
        names = [rc.name for rc in self.cameras]
        if len(set(names)) != len(names):
            raise CameraError(f"rig camera names must differ, got {names}")

    @classmethod
    def single(cls, camera: Camera, name: str = "cam0") -> "Rig":
        """The one-camera rig: ``camera`` at the robot's centre."""
        return cls((RigCamera(name, camera),))

    def __len__(self) -> int:
        return len(self.cameras)

    def __iter__(self):
        return iter(self.cameras)

    def __getitem__(self, i: int) -> RigCamera:
        return self.cameras[i]

    @property
    def names(self) -> list[str]:
        return [rc.name for rc in self.cameras]

    @property
    def is_single(self) -> bool:
        """One camera at the robot's centre: localised as a single camera."""
        return len(self.cameras) == 1 and self.cameras[0].mount.at_centre

    @property
    def reach_m(self) -> float:
        """The farthest a camera sits from the robot's centre, metres."""
        return max(math.hypot(rc.mount.x, rc.mount.y) for rc in self.cameras)
