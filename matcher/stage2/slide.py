"""Stage 2: loosely fixed poses slid to where their lines fit.

A view of a few vertical edges close together (the corners of one column)
fixes their bearings and hardly the camera's distance or its direction
around them: least squares moves the camera tens of centimetres from the
truth at almost no cost, until the lines stick out beyond their segments'
projected ends and the true hypothesis is thrown out as not fitting. The
image lengths of the lines hold what the bearings do not. So a hypothesis
whose position is loose and some of whose lines do not fit is moved: to
the nearest pose, in the metric of its information matrix, where more of
its lines lie inside their projected segments; and a later least-squares
refit that takes it out again is followed by another slide.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from linemap.geometry import segment_is_vertical
from matcher.stage2.covariance import pose_information
from matcher.stage2.fit import fits
from matcher.stage2.matches import Matches
from matcher.tolerances import DEFAULT, Stage2Constants

#: ``count(p)``: for poses ``p`` (W, N, 3) of W hypotheses, (W, N) how many
#: of each one's lines fit there.
Counter = Callable[[np.ndarray], np.ndarray]


def slide_poses(poses: np.ndarray, info: np.ndarray, count: Counter, now: np.ndarray,
                work: Stage2Constants = DEFAULT.stage2):
    """``(moved (W, 3), move (W,) bool)`` for poses (W, 3) ``(x, y, yaw)``
    with information matrices ``info`` (W, 3, 3) (``J^T J`` of the noise-
    weighted residuals) and ``now`` (W,) lines fitting.

    The yaw is marginalised out (Schur complement) and follows the position
    as the information says (``-A_yy^-1 A_yp d`` for a move ``d``). Where
    the position is loose by at least ``slide_min_loose_m``, a grid along its two
    axes is tried; the grid point with the most lines fitting, then the
    cheapest in the information metric, is the goal if more fit there than
    ``now``, and the pose moves towards it only as far as it takes."""
    W = len(poses)
    a_yy = np.maximum(info[:, 2, 2], 1e-300)
    pos_info = info[:, :2, :2] - info[:, :2, 2, None] * info[:, None, 2, :2] / a_yy[:, None, None]
    lam, vec = np.linalg.eigh(pos_info)  # ascending: column 0 the worst-fixed axis
    sigma = 1.0 / np.sqrt(np.maximum(lam, 1e-300))  # (W, 2) metres
    move = sigma[:, 0] >= work.slide_min_loose_m
    if not move.any():
        return poses, move
    along = work.slide_grid_array[None] * np.minimum(work.slide_sigmas * sigma, work.slide_max_m)[:, None, :]  # (W, G, 2) metres along the axes
    d_xy = np.einsum("wgj,wij->wgi", along, vec)  # (W, G, 2)
    d_yaw = -np.einsum("wi,wgi->wg", info[:, 2, :2], d_xy) / a_yy[:, None]
    delta = np.concatenate([d_xy, d_yaw[..., None]], axis=2)  # (W, G, 3)
    n = count(poses[:, None, :] + delta)  # (W, G)
    # The most lines, then the cheapest move (its cost scaled below one line).
    cost = ((along / sigma[:, None, :]) ** 2).sum(axis=2)
    best = np.argmax(n - 0.5 * cost / np.maximum(cost.max(axis=1, keepdims=True), 1e-300), axis=1)
    target = n[np.arange(W), best]
    move &= target > now
    goal = poses + delta[np.arange(W), best]
    return _nearest_keeping(goal, poses, count, target, work.slide_bisections), move


def _nearest_keeping(good: np.ndarray, towards: np.ndarray, count: Counter, need: np.ndarray,
                     bisections: int) -> np.ndarray:
    """(W, 3) the point of each segment from ``good`` (where ``need`` lines
    fit) to ``towards`` nearest to ``towards`` where as many still fit,
    by bisection (``towards`` itself if they fit there)."""
    way = towards - good
    ok_end = count(towards[:, None])[:, 0] >= need
    lo, hi = np.zeros(len(good)), np.ones(len(good))  # fraction of the way: lo fits, hi not (yet)
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        ok = count((good + mid[:, None] * way)[:, None])[:, 0] >= need
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.where(ok_end[:, None], towards, good + lo[:, None] * way)


def slide_to_fit(camera, image_lines, segs, poses, m: Matches, tol, inl, stuck_out=None):
    """Poses (H, 3), those of loosely fixed hypotheses with a line that does
    not fit (``inl`` (T,) False, per match of ``m``) moved to where more of
    their lines fit (:func:`slide_poses`); and (H,) bool, which moved.
    Tried are the hypotheses with lines enough to be a contender if all
    fitted, matching fewer than ``slide_max_horizontal`` horizontal segments
    and, with ``stuck_out`` (T,) bool, with a line that lies along its
    projected segment but sticks out of it (a line off its segment's line
    says the match is wrong, not the distance)."""
    n_h = len(poses)
    slid = np.zeros(n_h, dtype=bool)
    n_all = np.bincount(m.hyp, minlength=n_h)
    n_fit = np.bincount(m.hyp, inl, minlength=n_h)
    worth = (n_fit < n_all) & (n_all >= max(tol.min_matches, int(n_fit.max(initial=0)) - 1))
    # Bearings are what leave a position loose: two horizontal segments' lines
    # fix it (each puts the camera on a line of the floor at a given yaw).
    work = tol.stage2
    worth &= np.bincount(m.hyp, ~segment_is_vertical(segs[m.local], tol.shared.vertical_axis_deg),
                         minlength=n_h) < work.slide_max_horizontal
    if stuck_out is not None:
        worth &= np.bincount(m.hyp, stuck_out, minlength=n_h) > 0
    cand = np.nonzero(worth)[0]
    if not len(cand):
        return poses, slid
    mine = m.of(cand)
    info = pose_information(camera, image_lines, segs, poses[cand], mine, tol)
    count = _fit_counter(camera, image_lines, segs, mine, tol)
    moved, move = slide_poses(poses[cand], info, count, n_fit[cand], work)
    poses = poses.copy()
    poses[cand[move]] = moved[move]
    slid[cand[move]] = True
    return poses, slid


def _fit_counter(camera, image_lines, segs, mine: Matches, tol):
    """``count(p)``: for poses ``p`` (W, N, 3) of W hypotheses whose
    matches are ``mine`` (numbered 0 to W-1), (W, N) how many of their
    lines fit there, allowing only the end points' noise beyond the
    projected ends (a pose that passes sits where the lines lie inside
    their segments, not at the edge of the plain fit test)."""
    w_of = mine.hyp
    seg_sel, line_sel = segs[mine.local], mine.line

    def count(p: np.ndarray) -> np.ndarray:
        n = p.shape[1]
        good = fits(camera, image_lines, p[w_of].reshape(-1, 3), np.repeat(seg_sel, n, axis=0), np.repeat(line_sel, n),
                    tol, end_px=tol.line_end_px)[0]
        out = np.zeros((len(p), n))
        np.add.at(out, (np.repeat(w_of, n), np.tile(np.arange(n), len(w_of))), good)
        return out

    return count
