"""A rig frame: one camera's lines per camera of a rig, each prepared as
the single-camera matcher prepares a frame, with that camera's view of the
robot's prior.

A camera whose file gives a roll has its lines moved to the levelled
camera (:func:`matcher.attitude.levelled`, one homography): stage 1 and
stage 2 work on levelled cameras. A rig camera's pitch and roll are the
file's: the per-frame attitude estimate of :mod:`matcher.attitude` is the
single camera's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera
from linemap.errors import InputError
from linemap.rig import Mount, Rig, RigCamera
from matcher import attitude
from matcher.frame import ImageLines, prepare_lines
from matcher.input_validation import check_lines
from matcher.tolerances import Tolerances


@dataclass(frozen=True)
class CameraView:
    """One rig camera in one frame: its ``name``, its levelled ``camera``,
    its ``mount`` on the robot, its prepared ``lines``, and ``offset``, the
    index its first line has among the frame's lines of all cameras (the
    rig result's ``matches`` count lines that way)."""

    name: str
    camera: Camera
    mount: Mount
    lines: ImageLines
    offset: int

    def camera_prior(self, px: tuple) -> tuple:
        """This camera's prior ``(xe, ye, yaw_e, dt, dyaw)`` (radians) of the
        robot's prior ``px``: the camera's place at the prior heading, the
        disk widened by the most the mount's offset moves over the heading
        interval (a chord of its circle), the headings turned by its yaw."""
        xe, ye, yaw_e, dt, dyaw = px
        q = self.mount.camera_poses(np.array([xe, ye, yaw_e]))
        lever = math.hypot(self.mount.x, self.mount.y)
        chord = 2.0 * lever * math.sin(0.5 * min(dyaw, math.pi))
        return float(q[0]), float(q[1]), float(q[2]), dt + chord, dyaw


@dataclass(frozen=True)
class RigFrame:
    """The frame's cameras (:class:`CameraView`, in the rig's order)."""

    views: tuple[CameraView, ...]

    @property
    def searched(self) -> int:
        """Lines stage 1 searches with, over all cameras."""
        return int(sum(int(v.lines.searched.sum()) for v in self.views))

    @property
    def usable(self) -> int:
        """Usable lines over all cameras."""
        return int(sum(int(v.lines.usable.sum()) for v in self.views))


def check_rig(rig) -> Rig:
    """InputError unless ``rig`` is a :class:`~linemap.rig.Rig`."""
    if not isinstance(rig, Rig):
        raise InputError(f"rig must be a matcher.Rig (matcher.load_rig('rig.json')), got {type(rig).__name__}")
    return rig


def prepare_rig_frame(rig: Rig, lines_per_camera, tol: Tolerances) -> RigFrame:
    """The frame of ``lines_per_camera`` (a list, one (M_c, 2, 2) or (M_c, 4)
    pixel array per rig camera, in the rig's order): each checked as a
    single camera's lines are (an InputError names the camera), levelled
    and prepared."""
    if isinstance(lines_per_camera, np.ndarray) or not isinstance(lines_per_camera, (list, tuple)):
        raise InputError("a rig frame's lines must be a list with one array of lines per camera "
                         f"({len(rig)} cameras: {', '.join(rig.names)})")
    if len(lines_per_camera) != len(rig):
        raise InputError(f"the rig has {len(rig)} cameras ({', '.join(rig.names)}) and the frame gives lines for "
                         f"{len(lines_per_camera)}; give one list of lines per camera, in the rig's order")
    views, offset = [], 0
    for rc, raw in zip(rig.cameras, lines_per_camera):
        views.append(_view(rc, raw, tol, offset))
        offset += len(views[-1].lines.lines)
    return RigFrame(tuple(views))


def _view(rc: RigCamera, raw, tol: Tolerances, offset: int) -> CameraView:
    """One camera's :class:`CameraView` of its raw lines."""
    try:
        arr = check_lines(raw, rc.camera, tol)
    except InputError as exc:
        raise InputError(f"camera {rc.name}: {exc}") from None
    camera = rc.camera
    if camera.roll_deg or camera.attitude_free:
        camera, arr = attitude.levelled(camera, arr, attitude.of_file(camera))
    return CameraView(rc.name, camera, rc.mount, prepare_lines(camera, arr, tol), offset)
