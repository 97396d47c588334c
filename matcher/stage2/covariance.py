"""Stage 2: how well a hypothesis' matches fix its pose.

The information matrix ``J^T J`` of the noise-weighted residuals and its
inverse, the first-order covariance of the least-squares pose: used to
report the pose's standard deviations, to give a loosely fixed pose more
room at the prior's border, and to slide a loose pose along the directions
its matches leave free (:mod:`matcher.stage2.slide`).
"""

from __future__ import annotations

import math

import numpy as np

from matcher.stage2 import refine
from matcher.stage2.matches import Matches


def pose_std_of(camera, image_lines, segs, ranked, h: int, tol):
    """``(x, y, yaw_deg)`` standard deviations of hypothesis ``h``'s pose
    (metres, degrees; :func:`pose_covariance`), or None where its matches do
    not fix it."""
    cov = pose_covariance(camera, image_lines, segs, ranked.poses[h:h + 1], ranked.matches.of_one(h), tol)[0]
    if not np.isfinite(cov).all():
        return None
    return float(math.sqrt(cov[0, 0])), float(math.sqrt(cov[1, 1])), float(math.degrees(math.sqrt(cov[2, 2])))


def pose_spread(cov: np.ndarray) -> np.ndarray:
    """(H, 2) standard deviations of poses with covariances ``cov`` (H, 3,
    3) (:func:`pose_covariance`): of the position along its worst-fixed
    direction (metres) and of the yaw (radians); inf where not fixed."""
    out = np.full((len(cov), 2), np.inf)
    fixed = np.isfinite(cov).all(axis=(1, 2))
    if fixed.any():
        out[fixed, 0] = np.sqrt(np.maximum(np.linalg.eigvalsh(cov[fixed, :2, :2])[:, 1], 0.0))
        out[fixed, 1] = np.sqrt(np.maximum(cov[fixed, 2, 2], 0.0))
    return out


def pose_covariance(camera, image_lines, segs, poses, m: Matches, tol) -> np.ndarray:
    """(H, 3, 3) per hypothesis the covariance of its least-squares pose
    ``(x, y, yaw)`` (metres, radians) that image noise leaves. First order:
    the inverse of J^T J, J the derivatives of the residuals
    (:func:`matcher.stage2.refine.residuals`) weighted by their noise. Each
    residual (the sine of the angle between an end point's ray and the
    segment's plane, which at the fit is the line's own plane) is first
    turned into pixels across its line: divided by its derivative along the
    line's image normal, ``n . dp / |p|`` with ``n`` the line's
    interpretation-plane normal and ``p`` the end point's ray ``K^-1 (u, v,
    1)`` (a pixel spans less angle off the image centre). Then a line's two
    end points are taken as their mean and half difference: an offset of
    the line moves both ends alike (``line_px``), a turn about its middle
    moves them apart (``line_deg`` over half its length); each bound is
    taken as that of a uniform variable (standard deviation bound /
    sqrt 3). ``m`` the matches (:class:`~matcher.stage2.matches.Matches`,
    their segments indices into ``segs``). A hypothesis whose matches do
    not fix its pose gets inf."""
    A = pose_information(camera, image_lines, segs, poses, m, tol)
    out = np.full(A.shape, np.inf)
    fixed = np.linalg.det(A) > 1e-12 * np.maximum(np.abs(A).max(axis=(1, 2)), 1e-300) ** 3
    if fixed.any():
        out[fixed] = np.linalg.inv(A[fixed])
    return out


def pose_information(camera, image_lines, segs, poses, m: Matches, tol) -> np.ndarray:
    """(H, 3, 3) per hypothesis ``J^T J``, the inverse of
    :func:`pose_covariance` (singular where the matches leave a direction of
    the pose free)."""
    n_h = len(poses)
    A = np.zeros((n_h, 3, 3))
    hyp, local, line_ids = m.hyp, m.local, m.line
    if not len(hyp):
        return A
    lines = image_lines.lines[line_ids]  # (T, 2, 2)
    p = camera.pixel_rays(lines)  # (T, 2, 3)
    p_len = np.linalg.norm(p, axis=2)  # (T, 2)
    rays = p / p_len[..., None]
    terms = refine.MatchTerms(segs[local, 0], segs[local, 1], rays[:, 0], rays[:, 1], camera.pitch, camera.height_m)
    _, J = refine.residuals(poses, hyp, terms, jacobian=True)  # (T, 2, 3)
    d = lines[:, 1] - lines[:, 0]
    length = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    # d(ray)/d(pixel across the line): (-d_v / fx, d_u / fy, 0) / length.
    dp_x, dp_y = -d[:, 1] / (length * camera.fx), d[:, 0] / (length * camera.fy)
    n = image_lines.normals[line_ids]  # (T, 3) unit
    per_px = (n[:, 0] * dp_x + n[:, 1] * dp_y)[:, None] / p_len  # (T, 2)
    per_px = np.where(np.abs(per_px) > 1e-12, per_px, 1e-12)
    Jpx = J / per_px[..., None]  # (T, 2, 3): pixels across the line per unit of pose
    sigma_offset = tol.line_px / math.sqrt(3.0)
    sigma_turn = math.tan(math.radians(tol.line_deg)) * 0.5 * length / math.sqrt(3.0)  # (T,)
    Jw = np.stack([0.5 * (Jpx[:, 0] + Jpx[:, 1]) / sigma_offset,
                   0.5 * (Jpx[:, 0] - Jpx[:, 1]) / sigma_turn[:, None]], axis=1)  # (T, 2, 3)
    np.add.at(A, hyp, np.einsum("tki,tkj->tij", Jw, Jw))
    return A
