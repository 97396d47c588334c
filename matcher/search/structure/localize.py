"""A rig's frame (a panorama, a ring of cameras, one camera) localised by
the structure search: the ranking's best peaks verified by stage 2 on
every camera, then the one verdict.

    rig frame -> ranking (ranking.py: every place and yaw of the prior)
              -> the best peaks verified on every camera (matcher.rig.verify:
                 the lines that fit at the pose, one robot pose fitted to all),
                 from the peak's slack down to stage 2's own fit bound
              -> the one verdict (matcher.verdict, through matcher.rig.localize's
                 evidence: the best verified pose against the others, the
                 ranking's runner-up among them)

Each peak is verified as a narrow prior of its own
(``SharedConstants.lost_seed_m``, ``lost_seed_deg``, as lost mode's seeds are;
with a prior, its answer must lie inside the robot's prior too), best
first: the best peak and the runner-up elsewhere always, the others while
the verdict refuses the best so far; the best answer is judged against
the others.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from matcher.candidates import select_candidates
from matcher.result import LocalizeResult, Timings
from matcher.rig.frame import RigFrame
from matcher.prior import within_prior
from matcher.rig.joint_fit import camera_matches, refine_robot
from matcher.rig.verify import RigRanked, match_at, verify_seeds
from matcher.search.structure.peaks import Peaks
from matcher.search.structure.ranking import rank_places
from matcher.tolerances import Tolerances
from matcher.verdict import UNCUT, Evidence, decide


def localize_frame(linemap, frame: RigFrame, px: tuple | None, tol: Tolerances, t0: float) -> LocalizeResult:
    """The robot's pose from the prepared rig ``frame`` under the prior
    ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians; None: lost), the call's
    clock started at ``t0`` (module docstring)."""
    from matcher.rig.localize import RunInfo, rig_result

    if frame.usable < tol.min_matches:
        why = (f"only {frame.usable} usable image lines over the frame's {len(frame.views)} camera(s) (need "
               f"{tol.min_matches} of >= {tol.min_line_px:g} px)")
        return LocalizeResult(False, decide(Evidence(unsearched=why), tol).reason,
                              time_ms=Timings(total=(time.perf_counter() - t0) * 1e3))
    ranking = rank_places(linemap, frame.views, px, tol, tol.rig.seeds_per_camera)
    peaks = ranking.peaks
    counts = {"lines": int(sum(len(v.lines.lines) for v in frame.views)), "sets_found": len(peaks.poses),
              "out_of_time": False}
    if not len(peaks.poses):
        why = ("the structure search found no place to score: no point of the map's floor lies within the prior"
               if ranking.places == 0 else "the structure search found no place the frame's lines support")
        return LocalizeResult(False, decide(Evidence(unsearched=why), tol).reason,
                              time_ms=Timings(total=(time.perf_counter() - t0) * 1e3, generate=ranking.ms))
    t_v = time.perf_counter()
    verified, of_peak = [], {}
    for i in range(len(peaks.poses)):
        around = (*peaks.poses[i], tol.shared.lost_seed_m, math.radians(tol.shared.lost_seed_deg))
        found = _verify(linemap, frame, peaks, i, around, tol)
        if found is not None:
            of_peak[i] = len(verified)
            verified.append(found if px is None else _inside(found, px, tol))
        # The best peak, the runner-up elsewhere and the best peak's
        # neighbour (ranking.py) are always verified; the others only while
        # the verdict refuses the best so far.
        if len(verified) >= 3 and _settled(frame, verified, tol):
            break
    times = {"generate": ranking.ms, "verify": (time.perf_counter() - t_v) * 1e3}
    run = RunInfo(t0, times, counts, UNCUT, px)
    if not verified:
        return LocalizeResult(False, decide(Evidence(unsearched="no camera sees a candidate segment from the "
                                                                "structure search's places"), tol).reason,
                              time_ms=Timings(total=(time.perf_counter() - t0) * 1e3, **times))
    cands, ranked, rivals = _best_of(verified)
    runner = _runner_up(peaks, verified, of_peak, ranked, tol)
    return rig_result(frame, cands, ranked, tol, run, rivals=rivals or None, runner_up=runner)


def _runner_up(peaks: Peaks, verified: list, of_peak: dict, ranked: RigRanked, tol: Tolerances) -> tuple | None:
    """The ranking's best pose elsewhere than the best verified pose (farther
    than ``VerdictConstants.ambiguous_m`` or ``ambiguous_deg``) as an answer
    ``(pose_deg, lines, E, cost)``: its peak's verified answer when that
    stayed elsewhere, else the peak itself, no line verified there (0, inf,
    inf); None when every peak is the best's place."""
    if not len(ranked.order) or not np.isfinite(ranked.score[int(ranked.order[0])]):
        return None
    best = ranked.poses[int(ranked.order[0])]
    for i, p in enumerate(peaks.poses):
        if not _apart(p, best, tol):
            continue
        answers = _answers(verified[of_peak[i]][1]) if i in of_peak else []
        far = [a for a in answers if _apart((a[0][0], a[0][1], math.radians(a[0][2])), best, tol)]
        if far:
            return far[0]
        return ((float(p[0]), float(p[1]), math.degrees(math.remainder(float(p[2]), 2 * math.pi))), 0, math.inf,
                math.inf)
    return None


def _apart(p, q, tol: Tolerances) -> bool:
    """Are robot poses ``p`` and ``q`` (x, y, theta radians) different
    answers to the verdict (``ambiguous_m`` or ``ambiguous_deg`` apart)?"""
    turn = abs(math.remainder(float(p[2]) - float(q[2]), 2 * math.pi))
    return math.hypot(p[0] - q[0], p[1] - q[1]) > tol.verdict.ambiguous_m or turn > math.radians(tol.verdict.ambiguous_deg)


def _best_of(verified: list) -> tuple:
    """``(candidates, RigRanked, rivals)``: the verification whose best pose
    ranks first, and the answers of the others."""
    keys = [_best_key(r) for _, r in verified]
    best = min(range(len(verified)), key=lambda i: keys[i])
    rivals = [a for i, (_, r) in enumerate(verified) if i != best for a in _answers(r)]
    return verified[best][0], verified[best][1], rivals


def _settled(frame: RigFrame, verified: list, tol: Tolerances) -> bool:
    """Would the verdict accept the best verified pose so far, against the
    others (the camera files' check left for the final answer)?"""
    from matcher.rig.localize import _evidence

    cands, ranked, rivals = _best_of(verified)
    if not np.isfinite(_best_key(ranked)[2]):
        return False
    return bool(decide(_evidence(frame, cands, ranked, tol, UNCUT, rivals or None, calibration=False)[0], tol))


def _inside(found: tuple, px: tuple, tol: Tolerances) -> tuple:
    """``found`` (candidates, RigRanked) with the poses outside the robot's
    prior ``px`` (radians, with the prior's slack) dropped."""
    cands, ranked = found
    free = next((c.free for c in cands if c is not None), None)
    E = np.where(within_prior(ranked.poses, px, free, tol), ranked.score, np.inf)
    order = np.lexsort((E, ranked.cost, -ranked.n * np.isfinite(E)))
    why = ranked.why or ("" if np.isfinite(E).any() else "no verified pose kept inside the prior bounds")
    return cands, replace(ranked, score=E, order=order, why=why)


def _verify(linemap, frame: RigFrame, peaks: Peaks, i: int, prior: tuple, tol: Tolerances):
    """``(candidates per camera, RigRanked)`` of peak ``i`` verified under
    ``prior`` (a narrow one around it, radians): its lines matched within a
    bound widened to what the peak's slack moves a line by (at the median
    distance of the walls seen from it: a bound made for the nearest wall
    lets most lines take a wrong segment and pulls the pose away) and the
    pose refitted, the bound halved pass by pass down to stage 2's own;
    then stage 2's verification of the peak, the first pass's pose and the
    last's (a narrower pass can lock onto a wrong line near the truth and
    pull the pose off; stage 2 keeps the pose that explains the most
    lines).
    None when no camera has candidates."""
    cands = _frame_candidates(linemap, frame, prior, tol)
    if all(c is None for c in cands):
        return None
    pairs = [(v, c) for v, c in zip(frame.views, cands) if c is not None]
    fx = max(v.camera.fx for v in frame.views)
    gate = fx * (peaks.slack_rad + peaks.slack_m / max(float(peaks.near_m[i]), 1e-3))
    poses = peaks.poses[i:i + 1]
    passes = []
    while gate > tol.stage2.fit_pose_px:
        wide = replace(tol, stage2=replace(tol.stage2, fit_pose_px=gate))
        parts = [camera_matches(v, c.segments, m, wide) for (v, c), m in zip(pairs, match_at(pairs, poses, wide))]
        poses = refine_robot(poses, parts, wide.stage2, robust=True, iterations=tol.stage2.refit_iterations)
        passes.append(poses)
        gate /= 2.0
    return cands, verify_seeds(frame.views, cands, _seeds(peaks.poses[i:i + 1], passes), prior, tol)


def _frame_candidates(linemap, frame: RigFrame, prior: tuple, tol: Tolerances) -> list:
    """Per camera of ``frame`` its candidates under the robot's ``prior``
    (radians; None: none), the regions' visible lists read once per camera
    place (a panorama's views, a ring of cameras at the robot's centre,
    share theirs)."""
    lists: dict[tuple, np.ndarray] = {}
    cands = []
    for v in frame.views:
        px = v.camera_prior(prior)
        ids = lists.get((px[0], px[1], px[3]))
        if ids is None:
            ids = lists[(px[0], px[1], px[3])] = linemap.candidate_segments(px[0], px[1], px[3])
        c = select_candidates(linemap, v.camera, px, tol, candidate_ids=ids)
        cands.append(None if isinstance(c, str) else c)
    return cands


def _best_key(ranked: RigRanked) -> tuple:
    """The ranking key (lines explained most, then cost, then E) of the best
    verified pose of ``ranked``."""
    h = int(ranked.order[0]) if len(ranked.order) else None
    if h is None or not np.isfinite(ranked.score[h]):
        return (1, 0, math.inf, math.inf)
    return (0, -int(ranked.n[h]), float(ranked.cost[h]), float(ranked.score[h]))


def _answers(ranked: RigRanked) -> list:
    """``(pose_deg, matches, E, cost)`` of every verified pose of ``ranked``."""
    out = []
    for h in ranked.order:
        h = int(h)
        if np.isfinite(ranked.score[h]):
            p = ranked.poses[h]
            yaw = math.degrees(math.remainder(float(p[2]), 2 * math.pi))
            out.append(((float(p[0]), float(p[1]), yaw), int(ranked.n[h]), float(ranked.score[h]),
                        float(ranked.cost[h])))
    return out



def _seeds(peak: np.ndarray, passes: list) -> np.ndarray:
    """(S, 3) the seeds stage 2 verifies for one peak (1, 3): the peak
    itself, the first pass's pose (matched within the widest bound) and the
    last's (:func:`_verify`)."""
    return np.vstack([peak, *passes[:1], *passes[-1:]])
