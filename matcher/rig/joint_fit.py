"""One robot pose fitted to the matched lines of every camera of a rig.

Each camera's matches keep the single camera's residuals
(:func:`matcher.stage2.refine.residuals`: the sines of the angles between
its lines' end-point rays and the planes through its centre and the
matched segments), evaluated at that camera's pose
(:meth:`linemap.rig.Mount.camera_poses` of the robot's). The chain rule
through the mount (:meth:`linemap.rig.Mount.jacobian`) gives their
derivatives in the robot's pose, and Gauss-Newton sums every camera's
normal equations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linemap.rig import Mount
from matcher.stage2 import refine
from matcher.stage2.covariance import pose_information
from matcher.stage2.fit import fit_bound_px, unit_rays
from matcher.stage2.matches import Matches
from matcher.tolerances import Stage2Constants


@dataclass(frozen=True)
class CameraMatches:
    """One camera's matches of every hypothesis: its ``mount``, the
    residuals' constants ``terms`` (:class:`~matcher.stage2.refine.MatchTerms`),
    ``hyp`` (T,) each match's hypothesis and ``scale`` (T,) its robust
    scale, radians (its fit bound over the focal length)."""

    mount: Mount
    terms: refine.MatchTerms | None
    hyp: np.ndarray
    scale: np.ndarray


def camera_matches(view, segments: np.ndarray, m: Matches, tol) -> CameraMatches:
    """The :class:`CameraMatches` of ``m`` (segments indices into
    ``segments`` (N, 2, 3)) in the camera ``view``
    (:class:`~matcher.rig.frame.CameraView`)."""
    if not len(m):
        return CameraMatches(view.mount, None, m.hyp, np.zeros(0))
    camera, lines = view.camera, view.lines.lines[m.line]
    rays = unit_rays(camera, lines)
    terms = refine.MatchTerms(segments[m.local, 0], segments[m.local, 1], rays[:, 0], rays[:, 1], camera.pitch,
                              camera.height_m)
    length = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    return CameraMatches(view.mount, terms, m.hyp, fit_bound_px(length, tol) / camera.fx)


def refine_robot(poses: np.ndarray, parts: list[CameraMatches], work: Stage2Constants, robust: bool,
                 iterations: int) -> np.ndarray:
    """Robot poses (H, 3) ``(x, y, theta)`` refitted by Gauss-Newton on the
    matches of every camera (``parts``); with ``robust``, Tukey's biweight
    at each match's scale after ``refine_plain_first`` plain iterations, as
    :func:`matcher.stage2.refine.refine` weighs a single camera's. Every
    camera's matches are one batch, each with its mount's offset."""
    params = np.array(poses, dtype=float)
    H = len(params)
    live = [part for part in parts if part.terms is not None]
    if not live:
        return params
    terms = refine.joined_terms([part.terms for part in live])
    hyp = np.concatenate([part.hyp for part in live])
    scale = np.concatenate([part.scale for part in live])
    mx, my, myaw = (np.concatenate([np.full(len(part.hyp), getattr(part.mount, k)) for part in live])
                    for k in ("x", "y", "yaw"))
    each = np.arange(len(hyp))
    diag_at = np.arange(3)
    for it in range(iterations):
        p = params[hyp]
        c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
        cam = np.stack([p[:, 0] + c * mx - s * my, p[:, 1] + s * mx + c * my, p[:, 2] + myaw], axis=-1)
        r, J = refine.residuals(cam, each, terms, jacobian=True)
        # Through the mount (linemap.rig.Mount.jacobian): the robot's heading
        # also moves the camera's centre.
        J[..., 2] += J[..., 0] * (-s * mx - c * my)[:, None] + J[..., 1] * (c * mx - s * my)[:, None]
        Jw = J
        if robust and it >= work.refine_plain_first:
            u = np.clip(np.abs(r) / (2.0 * scale[:, None]), 0.0, 1.0)
            Jw = J * ((1.0 - u * u) ** 2 + 1e-6)[..., None]
        A, b = np.zeros((H, 3, 3)), np.zeros((H, 3))
        np.add.at(A, hyp, np.einsum("tki,tkj->tij", Jw, J))
        np.add.at(b, hyp, np.einsum("tki,tk->ti", Jw, r))
        diag = A[:, diag_at, diag_at]
        A[:, diag_at, diag_at] = diag + (1e-9 + 1e-6 * diag.sum(axis=1))[:, None]
        step = np.linalg.solve(A, b[..., None])[..., 0]
        params -= step
        if np.abs(step).max() < work.refine_converged and (not robust or it >= work.refine_plain_first):
            break
    return params


def robot_information(views_and_matches, poses: np.ndarray, tol) -> np.ndarray:
    """(H, 3, 3) ``J^T J`` of the robot poses (H, 3) over every camera's
    matches: each camera's information in its own pose
    (:func:`matcher.stage2.covariance.pose_information`) taken to the
    robot's through its mount, ``Jm^T A Jm``. ``views_and_matches``: pairs
    of a :class:`~matcher.rig.frame.CameraView` with its candidate
    segments and :class:`Matches` ``(view, segments, m)``."""
    A = np.zeros((len(poses), 3, 3))
    for view, segments, m in views_and_matches:
        if not len(m):
            continue
        Ac = pose_information(view.camera, view.lines, segments, view.mount.camera_poses(poses), m, tol)
        Jm = view.mount.jacobian(poses[:, 2])
        A += np.einsum("hki,hkl,hlj->hij", Jm, Ac, Jm)
    return A
