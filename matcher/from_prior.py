"""Localisation from a prior: :func:`localize`.

    lines -> frame (matcher.frame) -> candidates (matcher.candidates)
          -> strategy (matcher.strategy: stage 1 sources, stage 2 after each)
          -> LocalizeResult (matcher.result)

Lost mode, with no prior, is :func:`matcher.lost.localize_global`: this
module's :func:`localize_prepared` once per region.
"""

from __future__ import annotations

import math
import time

import numpy as np

from linemap.camera import Camera
from linemap.errors import InputError
from linemap.geometry import wrap
from linemap.lmap import LineMap
from matcher import ambiguity, attitude
from matcher.budget import NO_LIMIT, Deadlines
from matcher.candidates import Candidates, select_candidates
from matcher.checks import check_lines, check_prior
from matcher.frame import ImageLines, lines_needed, prepare_lines, too_few_lines
from matcher.result import LocalizeResult
from matcher.stage2.covariance import pose_std_of
from matcher.stage2.fit import coverage
from matcher.strategy import SOURCES, Answer, Frame, run_strategy
from matcher.tolerances import DEFAULT, Tolerances


def localize(linemap, camera: Camera, lines, prior, dt: float, dyaw: float, tolerances: Tolerances | None = None):
    """Localise the camera from image ``lines`` (M, 2, 2) or (M, 4) pixels of
    the ideal pinhole (as :func:`matcher.detect_lines` gives them: undistorted
    when the camera has distortion).

    ``prior`` is ``(x, y, yaw_deg)``; the true pose is within ``dt`` metres
    and ``dyaw`` degrees of it. Returns a :class:`LocalizeResult`, falsy with
    a ``reason`` when no hypothesis is accepted. Bad input (shapes, NaN,
    ranges) raises ValueError."""
    t0 = time.perf_counter()
    if attitude.applies(camera):
        # The frame's own pitch and roll (matcher.attitude): the lines moved
        # to the nominal camera, then localised as any.
        tol = checked_types(linemap, camera, tolerances)
        check_prior(prior, dt, dyaw)

        def run(nom, moved, tol_, near, quick=False):
            return localize_lines(linemap, nom, prepare_lines(nom, moved, tol_), prior, dt, dyaw, tol_,
                                  sources=SOURCES[:1] if quick else SOURCES)

        return attitude.localize_with_attitude(camera, lines, tol, linemap.segments, run)
    tol, img = checked_inputs(linemap, camera, lines, tolerances)
    return localize_lines(linemap, camera, img, prior, dt, dyaw, tol, t0)


def localize_lines(linemap, camera: Camera, img: ImageLines, prior, dt, dyaw, tol: Tolerances, t0=None,
                   sources=SOURCES):
    """:func:`localize` on prepared lines ``img`` (the lines moved to the
    nominal camera by :mod:`matcher.attitude` need not lie in the image),
    with the strategy's ``sources``."""
    t0 = time.perf_counter() if t0 is None else t0
    px = check_prior(prior, dt, dyaw)
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms, tol.internals.search_share)
    return localize_prepared(linemap, camera, img, px, tol, t0, deadlines, sources=sources)


def checked_inputs(linemap, camera, lines, tolerances) -> tuple[Tolerances, ImageLines]:
    """ValueError unless the map, camera and tolerances are of their types
    and the lines valid; the tolerances to use and the prepared lines."""
    tol = checked_types(linemap, camera, tolerances)
    return tol, prepare_lines(camera, check_lines(lines, camera, tol), tol)


def checked_types(linemap, camera, tolerances) -> Tolerances:
    """ValueError unless the map, camera and tolerances are of their types;
    the tolerances to use."""
    if not isinstance(linemap, LineMap):
        raise InputError(f"linemap must be a map from matcher.load_map('map.lmap'), got {type(linemap).__name__}")
    if not isinstance(camera, Camera):
        raise InputError(f"camera must be a matcher.Camera (Camera.load('camera.json')), got {type(camera).__name__}")
    if tolerances is not None and not isinstance(tolerances, Tolerances):
        raise InputError(f"tolerances must be a matcher.Tolerances, got {type(tolerances).__name__}")
    return tolerances or DEFAULT


def localize_prepared(linemap, camera: Camera, img: ImageLines, px, tol: Tolerances, t0: float,
                      deadlines: Deadlines = NO_LIMIT, candidate_ids=None, sources=SOURCES) -> LocalizeResult:
    """One prior ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians) on prepared
    lines, within the time budget's ``deadlines``: the candidates
    (:mod:`matcher.candidates`), then the strategy (:mod:`matcher.strategy`),
    then the result. ``candidate_ids``: the segments to consider instead of
    those of the regions the prior disk meets (lost mode: a region's list);
    ``sources`` the strategy's hypothesis sources (:data:`matcher.strategy.SOURCES`)."""
    times: dict[str, float] = {}
    cands = select_candidates(linemap, camera, px, tol, candidate_ids)
    times["select"] = (time.perf_counter() - t0) * 1e3
    reason = cands if isinstance(cands, str) else too_few_lines(img, tol)
    late = not reason and not deadlines.may_search()  # line preparation and selection count too
    if late:
        reason = f"no time left to search after preparing {len(img.lines)} lines" + _cut_short(None, tol, True)
    if reason:
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, reason, time_ms=times, stage1={"out_of_time": True, "tree_nodes": 0} if late else {})
    answer = run_strategy(Frame(camera, img, cands, px, tol, deadlines), sources)
    times.update(answer.times)
    return _result(answer, camera, img, cands, tol, t0, times)


def _result(answer: Answer, camera: Camera, img: ImageLines, cands: Candidates, tol: Tolerances, t0: float,
            times: dict) -> LocalizeResult:
    """The :class:`LocalizeResult` of the strategy's answer: the best ranked
    pose if accepted, else a falsy result with the reason; the ranking,
    stage 1's counters and the times either way."""
    hyps, ranked_h, spent = answer.hyps, answer.ranked, answer.spent
    stage1 = dict(hyps.counts, out_of_time=bool(hyps.counts.get("out_of_time") or spent))
    if ranked_h is None:
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, f"no consistent set of {tol.min_matches} or more correspondences "
                              f"({hyps.n_correspondences} correspondences passed the unary tests)"
                              + _cut_short(hyps, tol, spent), time_ms=times, stage1=stage1)
    E, order, ids, n_h = ranked_h.score, ranked_h.order, cands.ids, len(hyps.sets)

    def matches_of(h):
        sel = ranked_h.hyp == h
        return sorted([int(ids[a]), int(b)] for a, b in zip(ranked_h.local[sel], ranked_h.line[sel]))

    def pose_deg(p):
        return (float(p[0]), float(p[1]), float(math.degrees(wrap(p[2]))))

    ranked = [(float(E[h]), matches_of(h), pose_deg(ranked_h.poses[h])) for h in order]
    best = int(order[0])
    runner = float(E[order[1]]) if n_h > 1 and np.isfinite(E[order[1]]) else None
    times["total"] = (time.perf_counter() - t0) * 1e3
    common = dict(hypotheses=n_h, runner_up_score=runner, time_ms=times, ranked=ranked,
                  sets_found=int(hyps.counts.get("sets_found", n_h)), stage1=stage1)
    if not E[best] <= tol.e_accept:
        why = ranked_h.why if not np.isfinite(E[best]) else (
            f"best score E={E[best]:.3g} is above the acceptance threshold {tol.e_accept:g}")
        res = LocalizeResult(False, why + _cut_short(hyps, tol, spent), **common)
        res.score = float(E[best]) if np.isfinite(E[best]) else None
        return res
    predicted, seen = coverage(camera, ranked_h.poses[best], cands.segments, cands.label,
                               ranked_h.local[ranked_h.hyp == best], cands.walls, tol)
    work = tol.internals
    if predicted >= work.coverage_min_predicted and seen < work.coverage_min_share * predicted:
        return LocalizeResult(False, f"the best pose predicts {predicted} map segments in view and the image shows "
                              f"{seen} of them: the lines do not look like the map there", **common)
    # Counted among the lines searched: the ones added back from the rest
    # (stage 2 judges every line) come with clutter of their own.
    n_best = int(np.unique(ranked_h.line[(ranked_h.hyp == best) & img.searched[ranked_h.line]]).size)
    needed = lines_needed(img, tol)
    if n_best < needed:
        return LocalizeResult(False, f"the best pose explains {n_best} of the {int(img.searched.sum())} longest "
                              f"lines, fewer than the {needed} that clutter makes needed", **common)
    res = LocalizeResult(True, "", pose=pose_deg(ranked_h.poses[best]), score=float(E[best]),
                         matches=matches_of(best), **common)
    # Worked out when first read (a few tenths of a millisecond a robot
    # that only wants the pose does not spend).
    res.pose_std_from(lambda: pose_std_of(camera, img, cands.segments, ranked_h, best, tol))
    n_fin = np.bincount(ranked_h.hyp, minlength=n_h)
    answers = [(pose_deg(ranked_h.poses[h]), int(n_fin[h]), float(E[h]), float(ranked_h.cost[h])) for h in order
               if np.isfinite(E[h])]
    if len(answers) > 1 and answers[1][1] == answers[0][1]:  # a rival explains as many lines: is it elsewhere?
        kept = ambiguity.rivals(answers, tol.internals, ambiguity.spread_of(res.pose_std))
        if len(kept) > 1:
            return LocalizeResult(False, ambiguity.reason(kept), candidates=ambiguity.candidates_of(kept), **common)
    return res


def _cut_short(hyps, tol: Tolerances, spent: bool) -> str:
    """What a failure's reason adds when the search stopped early: the time
    budget spent (by stage 1, or ``spent``: a later step skipped), or
    stage 1's node or set budget."""
    if spent or hyps.counts.get("out_of_time"):
        return f" (time budget of {tol.time_budget_ms:g} ms spent; --budget-ms, Tolerances.time_budget_ms)"
    return " (hypothesis search truncated)" if hyps.truncated else ""
