"""A rig's calibration check: do its cameras' matched lines say the camera
files are wrong?

The single camera's check (:mod:`matcher.stage2.calibration_check`) asked
of a rig twice, on the robot's best pose:

1. **Every camera alike**: the robot's pose fitted again on all cameras'
   matches, each through its mount, with one calibration parameter free
   and shared by all (a focal length scale, a height offset, a principal
   point row offset): the rig of one camera model whose file is wrong (a
   panorama's cut views, a rig of identical cameras with one file). A
   focal length 20 % short moves the robot half a metre to make up for it,
   as it moves one camera; one camera's few matches do not show it, all
   the cameras' together do.
2. **Each camera on its own**: the same fit with one calibration
   parameter free for that camera alone, the robot's pose fitted on every
   camera's matches: one camera of the rig whose file is wrong. The pose
   is the robot's, fixed by all the cameras through their mounts, not the
   camera's own: a camera's few lines (a panorama's view holds 6 to 20)
   fitted with its pose and a focal length free leave the four nearly
   undetermined, and the map's own error (decimetres on a plan drawn from
   annotations) is then taken up by a focal length 1.1 to 2.7 times the
   file's, at a camera pose metres away; pinned by the others, a right
   camera's lines have nothing left over for the focal length to explain.

Both are asked at the accepted pose and, when it differs, at the pose of
the rig's **focal profile** (:func:`focal_profile`): the accepted pose
verified again with every camera's focal length scaled by each of
``calibration_focal_grid`` (lines matched anew, the pose refitted, as
:mod:`matcher.rig.verify` does), the scale whose verification explains
the most lines (then the least reprojection cost) kept. A wrong focal
length's answer is a local optimum of the pose and the focal length
together: at it the lines reject the file strongly (chi-square drops of
35 to 223) but the fit with the focal length free stays in the answer's
basin and estimates the focal length 1 to 4 % off when it is 10 % off,
under ``calibration_min_focal``; re-matching there does not leave the
basin. The profile's scales start the fit in the other basins. The scale must explain ``RigConstants.clear_ratio``
times the lines the files' does (a rival calibration judged as a rival
place is), or the checks are not asked again.

The thresholds are the single camera's (``VerdictConstants``), chosen and
held out on its own benchmark; ``python tools/bench_calibration.py
--cameras 4`` measures the rig's. Run on the accepted answer only.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import replace

import numpy as np

from matcher.frame import prepare_lines
from matcher.rig.frame import CameraView
from matcher.rig.verify import verify_seeds
from matcher.stage2.calibration_check import PARAMETERS, MatchedLines, blamed_parameters, fit, screened


class RigMatchedLines:
    """The rig's matches at one robot pose, for the calibration fits: each
    camera's :class:`~matcher.stage2.calibration_check.MatchedLines` and
    its mount; the residuals of all cameras at the camera poses of a robot
    pose, their derivatives in the robot's pose through each mount, a
    calibration change applied to every camera alike."""

    def __init__(self, per_camera, tol) -> None:
        self.parts = [(MatchedLines(view.camera, lines, segments, tol), view.mount)
                      for view, lines, segments in per_camera]
        self.only = None  # every camera's calibration changes alike (:meth:`only_camera`: one's)

    def __len__(self) -> int:
        return sum(len(data) for data, _ in self.parts)

    def only_camera(self, c: int) -> RigMatchedLines:
        """The same matches with camera ``c``'s calibration alone free."""
        alone = copy.copy(self)
        alone.only = c
        return alone

    def weighted(self, pose: np.ndarray, calib: np.ndarray, jacobian: bool = False):
        """(2T,) noise-weighted residuals of every camera at robot ``pose``
        (3,) and calibration ``calib`` (4,), and with ``jacobian`` their
        (2T, 3) derivatives in the robot's pose. With ``only`` (an index
        into the cameras) the calibration change is that camera's alone,
        the others at their files'."""
        file = np.array([1.0, 0.0, 0.0, 0.0])
        out = [data.weighted(mount.camera_poses(pose), calib if self.only in (None, c) else file, jacobian)
               for c, (data, mount) in enumerate(self.parts)]
        if not jacobian:
            return np.concatenate(out)
        J = [Jc @ mount.jacobian(pose[2]) for (_, Jc), (_, mount) in zip(out, self.parts)]
        return np.concatenate([r for r, _ in out]), np.concatenate(J)


def rig_doubt(per_camera, robot_pose: np.ndarray, tol, px: tuple | None) -> str:
    """Why the matched lines of a rig's cameras say the camera files are
    wrong, "" when they do not. ``per_camera``: one ``(view, lines,
    segments)`` per camera with matches (its
    :class:`~matcher.rig.frame.CameraView`, its matched pixel lines (T, 2,
    2) and map segments (T, 2, 3)); ``robot_pose`` (3,) ``(x, y, yaw)``
    radians; ``px`` the robot's prior (None in lost mode)."""
    if not per_camera:
        return ""
    lowest = min((view.camera for view, _, _ in per_camera), key=lambda c: (c.height_m, c.height))
    every = RigMatchedLines(per_camera, tol)
    # With no parameter free the fit is the same whichever camera's may
    # change: fitted once, when a first check needs it.
    at_file = functools.cache(lambda: fit(every, robot_pose, None, tol.verdict))
    alike = blamed_parameters(every, lowest, robot_pose, tol, px, at_file)
    if alike:
        f, name = alike[0], per_camera[0][0].name
        x, y, yaw = f.pose
        return (f"the matched lines of every camera fit the map far better with {f.off_by(per_camera[0][0].camera)} "
                f"for camera {name}, alike in every camera's file (the pose would be {x:.2f}, {y:.2f}, {yaw:.1f} "
                f"deg), than with the camera files' calibration: check the camera calibration")
    if len(per_camera) == 1:  # one camera: "every camera alike" was its check
        return ""
    blamed = []
    for c, (view, lines, _) in enumerate(per_camera):
        if len(lines) < tol.verdict.calibration_min_lines:  # too few residuals to tell a calibration from noise
            continue
        alone = blamed_parameters(every.only_camera(c), view.camera, robot_pose, tol, px, at_file)
        if alone:
            blamed.append((view, alone[0]))
    if not blamed:
        return ""
    (view, f), others = blamed[0], "".join(f"; so do camera {v.name}'s" for v, _ in blamed[1:])
    x, y, yaw = f.pose
    return (f"camera {view.name}: the matched lines fit the map far better with {f.off_by(view.camera)} "
            f"for that camera alone (the robot's pose would be {x:.2f}, {y:.2f}, {yaw:.1f} deg) than with its camera "
            f"file's calibration: check the camera calibration{others}")


def focal_profile(views, cands, pose: np.ndarray, prior: tuple, tol, per_camera=()):
    """The rig's focal profile about the accepted robot ``pose`` (3,): for
    each scale of ``calibration_focal_grid`` (and 1, the files'), every
    camera's focal length scaled by it, ``pose`` verified again on every
    camera (:func:`matcher.rig.verify.verify_seeds`: lines matched anew, the
    pose refitted; seeded at ``pose`` and, given the answer's matches
    ``per_camera`` as :func:`rig_doubt` takes them, where they put the robot
    at that scale) within ``prior`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians).
    ``views`` the frame's :class:`~matcher.rig.frame.CameraView`, ``cands``
    each one's candidates (None: none). Returns ``(scale, pose (3,),
    per_camera)`` of the scale whose verification explains the most lines
    (then has the least reprojection cost), its ``per_camera`` matches as
    :func:`rig_doubt` takes them (the files' views: the lines and segments
    are the same whatever the scale); the files' scale (1, the pose, no
    matches) unless that scale explains ``RigConstants.clear_ratio`` times
    the lines the files' does: a rival calibration must be clearly better,
    as a rival place must (on ZInD panoramas, whose cut views' focal
    lengths are exact, the map's error lets a scale 0.91 or 1.1 explain up
    to 1.1 times the files' lines; a file 10 % off explains 0.67 times
    the lines the true scale does)."""
    best, at_file = None, 0
    for scale in (1.0, *(float(s) for s in tol.verdict.calibration_focal_grid)):
        scaled = [_scaled(v, scale, tol) for v in views]
        seeds = [pose]
        if per_camera and scale != 1.0:  # the answer's matches refitted at that scale: where they put the robot
            made = {id(v): w for v, w in zip(views, scaled)}  # the answer's cameras are the frame's
            at = RigMatchedLines([(made.get(id(v)) or _scaled(v, scale, tol), lines, segs)
                                  for v, lines, segs in per_camera], tol)
            seeds.append(fit(at, pose, None, tol.verdict)[0])
        ranked = verify_seeds(scaled, cands, np.array(seeds), prior, tol)
        h = int(ranked.order[0])
        if not np.isfinite(ranked.score[h]):
            continue
        key = (-int(ranked.n[h]), float(ranked.cost[h]))
        if scale == 1.0:
            at_file = int(ranked.n[h])
        if best is None or key < best[0]:
            best = (key, scale, ranked, h)
    if best is None or -best[0][0] < tol.rig.clear_ratio * at_file:
        return 1.0, np.asarray(pose, dtype=float), []
    _, scale, ranked, h = best
    per_camera = []
    for v, c, m in zip(views, cands, ranked.matches):
        sel = m.hyp == h
        if c is not None and sel.any():
            per_camera.append((v, v.lines.lines[m.line[sel]], c.segments[m.local[sel]]))
    return scale, ranked.poses[h], per_camera


def _scaled(view: CameraView, scale: float, tol) -> CameraView:
    """``view`` with its camera's focal length (fx and fy) scaled by ``scale``,
    its lines prepared again for that camera."""
    if scale == 1.0:
        return view
    camera = replace(view.camera, fx=view.camera.fx * scale, fy=view.camera.fy * scale)
    return CameraView(view.name, camera, view.mount, prepare_lines(camera, view.lines.lines, tol), view.offset)


def focal_doubted(per_camera, robot_pose: np.ndarray, tol) -> bool:
    """Do the answer's matches (``per_camera`` as :func:`rig_doubt` takes
    them) at ``robot_pose`` (3,) reject the files' focal length, to first
    order (:func:`~matcher.stage2.calibration_check.screened`, every
    camera's alike), by the share of the least drop that earns a full fit
    (``calibration_screen_share``)? Only then is the focal profile worth
    its verifications: a right file's lines rarely do."""
    work = tol.verdict
    focal = PARAMETERS.index("focal")
    if not per_camera or focal not in tuple(int(k) for k in work.calibration_judged):
        return False
    drop = screened(RigMatchedLines(per_camera, tol), np.asarray(robot_pose, dtype=float), [focal], work)[0]
    return bool(drop >= work.calibration_screen_share * work.calibration_min_drop)
