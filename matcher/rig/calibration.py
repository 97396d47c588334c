"""A rig's calibration check: do a camera's matched lines say its camera
file is wrong?

The single camera's check (:mod:`matcher.stage2.calibration_check`) run on
each camera of the rig in turn, on that camera's own matches, at its pose
on the robot's best pose, within the robot's prior carried to the camera
(:meth:`~matcher.rig.frame.CameraView.camera_prior`).
A rig whose camera files are all off (a focal length 20 % short in a
shared model, a wrong camera height) moves the robot's pose to make up
for it, as one camera does; a rig with one wrong camera file makes the
joint fit pull between its cameras. Either way each camera's own lines fit
far better with its focal length or height freed, and the check, on the
accepted answer only, names the camera and the parameter.

Judged per camera, not jointly: the joint fit with one camera's
parameter free would be stronger (the other cameras hold the pose), but
the per-camera fit is the single camera's, whose thresholds were chosen
and held out on its own benchmark (tools/bench_calibration.py); a camera
with fewer than ``calibration_min_lines`` matches is not judged.
"""

from __future__ import annotations

import numpy as np

from matcher.stage2.calibration_check import doubt


def rig_doubt(per_camera, robot_pose: np.ndarray, tol, px: tuple | None) -> str:
    """Why the matched lines of a rig's cameras say a camera file is wrong,
    "" when none does. ``per_camera``: one ``(view, lines, segments)`` per
    camera with matches (its :class:`~matcher.rig.frame.CameraView`, its
    matched pixel lines (T, 2, 2) and map segments (T, 2, 3)); ``robot_pose``
    (3,) ``(x, y, yaw)`` radians; ``px`` the robot's prior (None in lost
    mode). Every camera is judged; the reason names each one blamed and
    the first one's parameters."""
    blamed = []
    for view, lines, segments in per_camera:
        prior = None if px is None else view.camera_prior(px)
        why = doubt(view.camera, lines, segments, view.mount.camera_poses(robot_pose), tol, prior)
        if why:
            blamed.append((view.name, why))
    if not blamed:
        return ""
    name, why = blamed[0]
    others = "".join(f"; so do camera {n}'s" for n, _ in blamed[1:])
    return f"camera {name}: {why}{others}"
