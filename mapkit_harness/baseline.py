"""The baseline the paper sets out to beat: a classic interpretation tree
that computes a pose at every node (:func:`baseline_localize`), run by
``tools/bench_paper.py`` on the same frames as the matcher."""

from __future__ import annotations

import math
import time

import numpy as np

from linemap.camera import Camera
from matcher.search.tree.constraints import wrap


def baseline_localize(linemap, camera: Camera, lines, prior, dt, dyaw, time_limit_s: float = 2.0,
                      min_matches: int = 3, tol_px: float = 6.0):
    """The classic interpretation tree that the paper sets out to beat
    (Grimson's search with a pose check at every node, for line features).

    Depth-first over the candidate model segments (the same region and
    field-of-view selection as ours), each level branching on every unused
    image line and on "unmatched". At every node a pose is computed by
    Gauss-Newton from its parent's pose, on the matched lines' residuals plus
    a weak pull towards the prior (so that nodes with one or two matches,
    which leave the pose free, can be checked too); the node is kept if every
    matched line lies within ``tol_px`` of its segment's projection and the
    pose stays within the prior bounds. A branch is cut when it cannot beat
    the largest interpretation found. Returns ``(pose (x, y, yaw_deg) or
    None, matches, nodes, timed_out)``."""
    from matcher.stage2 import refine as verify
    from matcher.input_validation import check_lines, check_prior
    from linemap.geometry import in_field_of_view
    from matcher.tolerances import DEFAULT

    arr = check_lines(lines, camera, DEFAULT)
    xe, ye, yaw_e, dt, dyaw = check_prior(prior, dt, dyaw)
    ids = linemap.candidate_segments(xe, ye, dt)
    segs = linemap.segments[ids]
    keep = in_field_of_view(segs, camera, (xe, ye, yaw_e), dt, dyaw)
    ids, segs = ids[keep], segs[keep]
    rays = camera.pixel_rays(arr)
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    tol = tol_px / camera.fx
    prior_w = 1e-3  # weak: decides only what the matched lines leave free
    t_end = time.perf_counter() + time_limit_s
    best = {"n": min_matches - 1, "pose": None, "matches": []}
    state = {"nodes": 0, "timed_out": False}
    M = len(arr)

    def pose_for(assign, start):
        si = np.array([i for i, _ in assign])
        lj = np.array([j for _, j in assign])
        p = np.array(start, dtype=float)
        scale = np.array([dt, dt, dyaw])
        terms = verify.MatchTerms(segs[si, 0], segs[si, 1], rays[lj, 0], rays[lj, 1], camera.pitch, camera.height_m)
        for _ in range(4):
            r, J = verify.residuals(p[None], np.zeros(len(si), dtype=np.int64), terms, jacobian=True)
            r, J = r.reshape(-1), J.reshape(-1, 3)
            dp = p - np.array([xe, ye, yaw_e])
            dp[2] = wrap(dp[2])
            rp = prior_w * dp / scale
            Jp = np.diag(prior_w / scale)
            A = J.T @ J + Jp.T @ Jp
            b = J.T @ r + Jp.T @ rp
            p -= np.linalg.solve(A, b)
        r = verify.residuals(p[None], np.zeros(len(si), dtype=np.int64), terms)
        ok = np.abs(r).max() <= tol
        ok &= math.hypot(p[0] - xe, p[1] - ye) <= dt + 0.05
        ok &= abs(float(wrap(p[2] - yaw_e))) <= dyaw + 0.02
        return bool(ok), p

    def rec(level, assign, used, pose):
        if state["timed_out"]:
            return
        if time.perf_counter() > t_end:
            state["timed_out"] = True
            return
        if len(assign) + min(len(ids) - level, M - len(used)) <= best["n"]:
            return
        if level == len(ids):
            best.update(n=len(assign), pose=pose, matches=list(assign))
            return
        for j in range(M):
            if j in used:
                continue
            state["nodes"] += 1
            ok, p = pose_for(assign + [(level, j)], pose)
            if ok:
                rec(level + 1, assign + [(level, j)], used | {j}, p)
        rec(level + 1, assign, used, pose)

    rec(0, [], frozenset(), np.array([xe, ye, yaw_e]))
    if best["pose"] is None:
        return None, [], state["nodes"], state["timed_out"]
    x, y, yaw = best["pose"]
    matches = sorted([int(ids[i]), int(j)] for i, j in best["matches"])
    return (float(x), float(y), float(math.degrees(wrap(yaw)))), matches, state["nodes"], state["timed_out"]
