"""Loosely fixed poses slid to where their lines fit (stage 2).

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

#: A pose is slid only if its position is loose by at least this much,
#: metres (one standard deviation along its worst-fixed axis): a pose fixed
#: better has no room to slide.
MIN_LOOSE_M = 0.05
#: Positions are tried within this many standard deviations along both axes
#: of the position, and at most this far, metres (a direction the matches
#: leave free has no standard deviation).
SIGMAS = 3.0
MAX_M = 2.0
#: The positions tried: a grid of fractions of that range along the two
#: axes; then this many bisections towards the best.
_GRID = np.stack(np.meshgrid(np.linspace(-1, 1, 15), np.linspace(-1, 1, 15), indexing="ij"), -1).reshape(-1, 2)
_BISECTIONS = 8

#: ``count(p)``: for poses ``p`` (W, N, 3) of W hypotheses, (W, N) how many
#: of each one's lines fit there.
Counter = Callable[[np.ndarray], np.ndarray]


def slide_to_fit(poses: np.ndarray, info: np.ndarray, count: Counter, now: np.ndarray):
    """``(moved (W, 3), move (W,) bool)`` for poses (W, 3) ``(x, y, yaw)``
    with information matrices ``info`` (W, 3, 3) (``J^T J`` of the noise-
    weighted residuals) and ``now`` (W,) lines fitting.

    The yaw is marginalised out (Schur complement) and follows the position
    as the information says (``-A_yy^-1 A_yp d`` for a move ``d``). Where
    the position is loose by at least MIN_LOOSE_M, a grid along its two
    axes is tried; the grid point with the most lines fitting, then the
    cheapest in the information metric, is the goal if more fit there than
    ``now``, and the pose moves towards it only as far as it takes."""
    W = len(poses)
    a_yy = np.maximum(info[:, 2, 2], 1e-300)
    pos_info = info[:, :2, :2] - info[:, :2, 2, None] * info[:, None, 2, :2] / a_yy[:, None, None]
    lam, vec = np.linalg.eigh(pos_info)  # ascending: column 0 the worst-fixed axis
    sigma = 1.0 / np.sqrt(np.maximum(lam, 1e-300))  # (W, 2) metres
    move = sigma[:, 0] >= MIN_LOOSE_M
    if not move.any():
        return poses, move
    along = _GRID[None] * np.minimum(SIGMAS * sigma, MAX_M)[:, None, :]  # (W, G, 2) metres along the axes
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
    return _nearest_keeping(goal, poses, count, target), move


def _nearest_keeping(good: np.ndarray, towards: np.ndarray, count: Counter, need: np.ndarray) -> np.ndarray:
    """(W, 3) the point of each segment from ``good`` (where ``need`` lines
    fit) to ``towards`` nearest to ``towards`` where as many still fit,
    by bisection (``towards`` itself if they fit there)."""
    way = towards - good
    ok_end = count(towards[:, None])[:, 0] >= need
    lo, hi = np.zeros(len(good)), np.ones(len(good))  # fraction of the way: lo fits, hi not (yet)
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        ok = count((good + mid[:, None] * way)[:, None])[:, 0] >= need
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.where(ok_end[:, None], towards, good + lo[:, None] * way)
