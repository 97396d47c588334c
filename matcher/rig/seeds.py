"""Seed poses of a rig frame: each camera's own search.

Each camera is searched as a single camera is, from its view of the
robot's prior (:meth:`~matcher.rig.frame.CameraView.camera_prior`): its
candidate segments, stage 1's interpretation tree on its lines, stage 2 on
the sets found (:mod:`matcher.search.tree.strategy`). A narrow view rarely decides
alone, but its best few poses, taken to the robot through the mount, are
where the verification on every camera's lines starts
(:mod:`matcher.rig.verify`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from matcher.budget import Deadlines
from matcher.candidates import Candidates, select_candidates
from matcher.frame import too_few_lines
from matcher.rig.frame import CameraView
from matcher.search.tree.strategy import Answer, Problem, run_strategy
from matcher.tolerances import Tolerances


@dataclass(frozen=True)
class CameraSearch:
    """One camera's search: its ``view``, its ``prior`` (radians), its
    candidates (``cands``; None when it has none or too few lines, ``why``
    then saying so) and the strategy's ``answer`` (None: not searched)."""

    view: CameraView
    prior: tuple
    cands: Candidates | None
    why: str = ""
    answer: Answer | None = None


def search_camera(linemap, view: CameraView, px: tuple, tol: Tolerances, deadlines: Deadlines, sources,
                  cands: Candidates | str | None = None) -> CameraSearch:
    """One camera's search under the robot's prior ``px`` ``(xe, ye, yaw_e,
    dt, dyaw)`` (radians) with the strategy's ``sources`` within the call's
    ``deadlines``; ``cands``, its candidates (or the reason it has none)
    when already selected."""
    cpx = view.camera_prior(px)
    if cands is None:
        cands = select_candidates(linemap, view.camera, cpx, tol)
    why = cands if isinstance(cands, str) else too_few_lines(view.lines, tol)
    if why:
        return CameraSearch(view, cpx, None if isinstance(cands, str) else cands, why)
    answer = None
    if deadlines.may_search():
        answer = run_strategy(Problem(view.camera, view.lines, cands, cpx, tol, deadlines), sources)
    return CameraSearch(view, cpx, cands, "" if answer else "no time left to search", answer)


def camera_seeds(search: CameraSearch, tol: Tolerances) -> np.ndarray:
    """(S, 3) robot poses ``(x, y, theta)`` of one camera's search: its best
    ranked poses that kept ``min_matches`` fitting matches
    (``seeds_per_camera`` of them, best first), taken to the robot through
    its mount."""
    ranked = None if search.answer is None else search.answer.ranked
    if ranked is None:
        return np.zeros((0, 3))
    n = np.bincount(ranked.matches.hyp, minlength=len(ranked.order))
    best = [int(h) for h in ranked.order if n[h] >= tol.min_matches][:tol.rig.seeds_per_camera]
    return search.view.mount.robot_poses(ranked.poses[best]).reshape(-1, 3)


def new_poses(poses: np.ndarray, tried: list, tol: Tolerances) -> np.ndarray:
    """The poses (P, 3), near-duplicates once, none near a pose of ``tried``."""
    apart_m, apart_rad = tol.rig.same_seed_m, math.radians(tol.rig.same_seed_deg)
    out = [p for p in distinct_poses(poses, apart_m, apart_rad)
           if not any(math.hypot(p[0] - t[0], p[1] - t[1]) <= apart_m
                      and abs(math.remainder(p[2] - t[2], 2 * math.pi)) <= apart_rad for t in tried)]
    return np.array(out).reshape(-1, 3)


def distinct_poses(poses: np.ndarray, apart_m: float, apart_rad: float) -> np.ndarray:
    """The poses (P, 3) in order, each dropped when an earlier one kept is
    within ``apart_m`` metres and ``apart_rad`` radians."""
    kept: list[np.ndarray] = []
    for p in poses:
        if not any(math.hypot(p[0] - q[0], p[1] - q[1]) <= apart_m
                   and abs(math.remainder(p[2] - q[2], 2 * math.pi)) <= apart_rad for q in kept):
            kept.append(p)
    return np.array(kept).reshape(-1, 3)


def search_counts(searches: list[CameraSearch]) -> dict:
    """Stage 1's counters summed over the cameras (lines, correspondences,
    tree nodes, sets found) and whether the time budget cut any search."""
    out = {"lines": 0, "correspondences": 0, "tree_nodes": 0, "sets_found": 0, "out_of_time": False}
    for s in searches:
        out["lines"] += len(s.view.lines.lines)
        hyps = None if s.answer is None else s.answer.hyps
        if hyps is None:
            continue
        c = hyps.counts
        out["correspondences"] += int(c.get("correspondences", 0))
        out["tree_nodes"] += int(c.get("tree_nodes", 0))
        out["sets_found"] += int(c.get("sets_found", len(hyps.sets)))
        out["out_of_time"] |= bool(c.get("out_of_time") or s.answer.spent)
    return out
