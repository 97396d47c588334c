"""Stage 2 on a rig: the seed poses verified on every camera's lines.

For each seed robot pose (:mod:`matcher.rig.seeds`), in rounds
(``RigConstants.verify_rounds``):

1. in every camera, at that camera's pose, the lines that fit a visible
   candidate segment (:func:`matcher.stage2.extend.extend_cameras`, the single
   camera's fit and visibility tests, each line once, closest first);
2. one robot pose refitted on all of them (:mod:`matcher.rig.joint_fit`),
   robustly, then plainly after the last round.

The final matches are the lines that fit at the final pose. A pose is kept
when it lies in the prior and the map's free space, its matches number
``min_matches`` or more and fix more than its three numbers; it is scored
with the paper's E over all its matches (each camera's at its own pose)
and ranked, as a single camera's hypotheses are, by lines explained, then
reprojection cost, then E.

Its E is judged against the E the camera's noise model allows its own
matches (:func:`e_limit`: each match with both end points at its fit bound,
:func:`matcher.stage2.fit.fit_bound_px`, from ``line_px``, ``line_deg``, the
pose's ``fit_pose_px`` and the map's ``model_m``), not a threshold fitted to
one data set: the position term of E grows with the distance of the walls
seen (a pose in a large room scores more than one in a corridor for the
same pixel residuals), which a fixed threshold takes for a bad fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linemap.geometry import segment_is_vertical
from matcher.prior import within_prior
from matcher.projection import covered_span
from matcher.rig.joint_fit import camera_matches, refine_robot
from matcher.stage2 import refine
from matcher.stage2.extend import Extension, extend_cameras
from matcher.stage2.fit import fit_bound_px
from matcher.stage2.matches import Matches
from matcher.stage2.rank import reprojection_cost

@dataclass(frozen=True)
class RigRanked:
    """Verified robot poses: ``poses`` (H, 3) ``(x, y, theta)``; per camera
    its ``matches`` (:class:`~matcher.stage2.matches.Matches`, segments
    indices into that camera's candidates); per pose ``n`` (H,) its
    matches over all cameras, ``explained`` (H,) the searched lines among
    them, ``score`` (H,) E (inf when dropped), ``cost`` (H,) the
    reprojection cost, ``order`` (H,) best first; ``why`` the reason when
    none is left; ``e_limit`` (H,) the E the noise model allows each pose's
    matches (:func:`e_limit`, the verdict's acceptance threshold)."""

    poses: np.ndarray
    matches: tuple
    n: np.ndarray
    explained: np.ndarray
    score: np.ndarray
    cost: np.ndarray
    order: np.ndarray
    why: str
    e_limit: np.ndarray


def verify_seeds(views, cands, seeds: np.ndarray, px: tuple, tol) -> RigRanked:
    """The seeds (S, 3) verified on every camera: ``views`` the frame's
    :class:`~matcher.rig.frame.CameraView`, ``cands`` each one's
    :class:`~matcher.candidates.Candidates` (None: none), ``px`` the robot's
    prior ``(xe, ye, yaw_e, dt, dyaw)`` (radians)."""
    poses = np.array(seeds, dtype=float).reshape(-1, 3)
    pairs = [(v, c) for v, c in zip(views, cands) if c is not None]
    for _ in range(tol.rig.verify_rounds):
        parts = [camera_matches(v, c.segments, m, tol) for (v, c), m in zip(pairs, match_at(pairs, poses, tol))]
        poses = refine_robot(poses, parts, tol.stage2, robust=True, iterations=tol.stage2.refine_iterations)
    parts = [camera_matches(v, c.segments, m, tol) for (v, c), m in zip(pairs, match_at(pairs, poses, tol))]
    poses = refine_robot(poses, parts, tol.stage2, robust=False, iterations=tol.stage2.refit_iterations)
    found = match_at(pairs, poses, tol)
    per_view, k = [], 0
    for c in cands:  # back to one entry per camera of the frame
        per_view.append(no_matches() if c is None else found[k])
        k += c is not None
    return _ranked(views, cands, poses, tuple(per_view), px, tol)


def merged(views, cands, a: RigRanked | None, b: RigRanked, px: tuple, tol) -> RigRanked:
    """The verified poses of ``a`` and ``b`` (verifications of other seeds
    under the same prior ``px``), scored and ranked together."""
    if a is None:
        return b
    H = len(a.poses)
    matches = tuple(Matches(np.concatenate([ma.hyp, mb.hyp + H]), np.concatenate([ma.local, mb.local]),
                            np.concatenate([ma.line, mb.line])) for ma, mb in zip(a.matches, b.matches))
    return _ranked(views, cands, np.concatenate([a.poses, b.poses]), matches, px, tol)


def no_matches() -> Matches:
    """No match at all."""
    empty = np.zeros(0, np.int64)
    return Matches(empty, empty, empty)


def match_at(pairs, poses: np.ndarray, tol) -> list[Matches]:
    """Per camera of ``pairs`` (view, candidates): the lines that fit a
    visible candidate at its pose for each robot pose (H, 3), every
    camera's tested in one batch."""
    every = np.arange(len(poses))
    return extend_cameras([Extension(v.camera, v.lines, c.segments, v.mount.camera_poses(poses), no_matches(), every,
                                     c.walls) for v, c in pairs], tol)


def _ranked(views, cands, poses: np.ndarray, matches: tuple, px: tuple, tol) -> RigRanked:
    """Keep, score and rank the verified ``poses`` with their ``matches``
    (one :class:`Matches` per camera): the module docstring's tests."""
    H = len(poses)
    n, fixed, explained = np.zeros(H, int), np.zeros(H), np.zeros(H, int)
    e_sum, lim_sum, cost = np.zeros(H), np.zeros(H), np.zeros(H)
    for v, c, m in zip(views, cands, matches):
        if c is None or not len(m):
            continue
        n += np.bincount(m.hyp, minlength=H)
        vert = segment_is_vertical(c.segments[m.local], tol.shared.vertical_axis_deg)
        fixed += np.bincount(m.hyp, np.where(vert, 1.0, 2.0), minlength=H)
        explained += np.bincount(m.hyp[v.lines.searched[m.line]], minlength=H)
        q = v.mount.camera_poses(poses)
        e_sum += _score(v, c.segments, q, m) * np.bincount(m.hyp, minlength=H)
        lim_sum += e_limit(v, c.segments, q, m, tol) * np.bincount(m.hyp, minlength=H)
        cost += reprojection_cost(v.camera, v.lines, q, m, c.segments, tol, H)
    free = next((c.free for c in cands if c is not None), None)
    alive = (n >= tol.min_matches) & (fixed > 3) & within_prior(poses, px, free, tol)
    E = np.where(alive, e_sum / np.maximum(n, 1), np.inf)
    order = np.lexsort((E, cost, -n * alive))
    keys = {}
    for h in order:  # poses that ended with the same matches are one
        key = tuple(tuple(sorted(zip(m.local[m.hyp == h].tolist(), m.line[m.hyp == h].tolist()))) for m in matches)
        if key in keys and np.isfinite(E[h]):
            E[h] = np.inf
        keys.setdefault(key, h)
    order = np.lexsort((E, cost, -n * np.isfinite(E)))
    why = "" if np.isfinite(E).any() else _why_none(n, fixed, tol)
    return RigRanked(poses, matches, n, explained, E, cost, order, why, lim_sum / np.maximum(n, 1))


def _score(view, segments: np.ndarray, cam_poses: np.ndarray, m: Matches) -> np.ndarray:
    """The paper's E (H,) of one camera's matches at its poses (H, 3), on
    the middle of the part of each segment its line shows (as
    :func:`matcher.stage2.rank` scores a single camera)."""
    lines = view.lines.lines[m.line]
    span = covered_span(view.camera, cam_poses[m.hyp], segments[m.local], lines)
    mid = segments[m.local, 0] + span.mean(axis=1)[:, None] * (segments[m.local, 1] - segments[m.local, 0])
    return refine.score_e(cam_poses, m.hyp, view.lines.normals[m.line], segments[m.local, 0], segments[m.local, 1],
                          view.camera.pitch, view.camera.height_m, mid=mid)


def e_limit(view, segments: np.ndarray, cam_poses: np.ndarray, m: Matches, tol) -> np.ndarray:
    """(H,) the largest E (:func:`_score`) that one camera's matches ``m``
    at its poses (H, 3) reach when each image line's end points lie at its
    fit bound ``b`` (:func:`matcher.stage2.fit.fit_bound_px`, pixels) from
    the projected segment, and the segment is off by the map's ``model_m``.

    An end point ``b`` pixels off, across the line, turns its sight ray out
    of the model segment's plane by the angle ``a_i`` between the line's
    plane and the ray of the end point moved so, so the shown part's end
    points, at distances ``d1``, ``d2`` (metres), lie within ``delta_i =
    sin(a_i) d_i + model_m`` of the line's plane. E's terms are, to first order, the
    middle's distance to the plane ``(delta_1 + delta_2) / 2`` and the
    direction's ``(delta_2 - delta_1) / l`` (``l`` the shown part's
    length; a sine, at most 1): their sum of squares is largest with both
    end points at their bound, on one side of the plane (an offset) or on
    opposite sides (a turn). The larger of the two, averaged per pose as
    E's terms are.
    """
    H = len(cam_poses)
    if not len(m):
        return np.zeros(H)
    lines = view.lines.lines[m.line]
    q, seg = cam_poses[m.hyp], segments[m.local]
    span = covered_span(view.camera, q, seg, lines)
    ends = seg[:, None, 0] + span[..., None] * (seg[:, None, 1] - seg[:, None, 0])  # (T, 2, 3)
    centre = np.stack([q[:, 0], q[:, 1], np.full(len(q), view.camera.height_m)], axis=1)
    d = np.linalg.norm(ends - centre[:, None], axis=2)  # (T, 2)
    shown = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    along = lines[:, 1] - lines[:, 0]
    length = np.maximum(np.linalg.norm(along, axis=1), 1e-9)
    across = np.stack([-along[:, 1], along[:, 0]], axis=1) / length[:, None]
    moved = lines + (fit_bound_px(length, tol)[:, None] * across)[:, None, :]  # (T, 2, 2)
    rays = view.camera.pixel_rays(moved.reshape(-1, 2)).reshape(-1, 2, 3)
    rays /= np.linalg.norm(rays, axis=2, keepdims=True)
    sin_a = np.abs(np.einsum("ti,tki->tk", view.lines.normals[m.line], rays))  # (T, 2)
    delta = sin_a * d + tol.model_m  # (T, 2)
    shown = np.maximum(shown, 1e-9)
    offset = (0.5 * delta.sum(axis=1)) ** 2 + np.minimum(1.0, np.abs(delta[:, 1] - delta[:, 0]) / shown) ** 2
    turn = (0.5 * (delta[:, 1] - delta[:, 0])) ** 2 + np.minimum(1.0, delta.sum(axis=1) / shown) ** 2
    return np.bincount(m.hyp, np.maximum(offset, turn), minlength=H) / np.maximum(np.bincount(m.hyp, minlength=H), 1)


def _why_none(n: np.ndarray, fixed: np.ndarray, tol) -> str:
    """Why no verified pose is left."""
    if not len(n):
        return "no camera's search gave a pose to verify"
    if ((n >= tol.min_matches) & (fixed <= 3)).any() and not ((n >= tol.min_matches) & (fixed > 3)).any():
        return ("the poses left fix the pose exactly (three vertical edges, say), with nothing over to "
                "verify it; more image lines are needed")
    if (n >= tol.min_matches).any():
        return "no verified pose kept inside the prior bounds and the map's free space"
    return f"no pose kept {tol.min_matches} matches that fit on the rig's cameras"
