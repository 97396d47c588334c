"""A rig's frame localised: :func:`localize_rig` from a prior,
:func:`localize_rig_global` without one.

    lines per camera -> rig frame (matcher.rig.frame)
        -> each camera's search, seed poses (matcher.rig.seeds)
        -> verification on every camera (matcher.rig.verify)
        -> the one verdict (matcher.verdict) -> LocalizeResult of the robot

The one-camera rig (one camera at the robot's centre) is localised by the
single-camera entry points themselves: its results are theirs, bit for bit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from linemap.errors import InputError
from linemap.geometry import project_segments, wrap
from matcher import ambiguity
from matcher.budget import Deadlines
from matcher.candidates import select_candidates
from matcher.from_prior import localize, validated_types
from matcher.input_validation import check_prior
from matcher.lost import _localize_global, localize_global
from matcher.projection import projected_end_distances
from matcher.result import Deferred, LocalizeResult, SearchStats, Timings
from matcher.rig.calibration import focal_doubted, focal_profile, rig_doubt
from matcher.rig.frame import RigFrame, check_rig, prepare_rig_frame
from matcher.rig.joint_fit import robot_information
from matcher.rig.seeds import camera_seeds, new_poses, search_camera, search_counts
from matcher.rig.verify import RigRanked, merged, verify_seeds
from matcher.search import default_search, search_of
from matcher.search.structure.localize import localize_frame
from matcher.stage2.fit import coverage_in_sight
from matcher.search.tree.strategy import SOURCES, TREE_ALONE
from matcher.tolerances import Tolerances
from matcher.verdict import BY_TIME, UNCUT, Evidence, decide, trusted


def localize_rig(linemap, rig, lines, prior, dt: float, dyaw: float, tolerances: Tolerances | None = None):
    """Localise the robot carrying ``rig`` (:class:`~linemap.rig.Rig`) from
    ``lines``, a list with one (M_c, 2, 2) or (M_c, 4) array of pixel lines
    per camera (ideal pinhole, in the rig's order), under the robot's
    ``prior`` ``(x, y, yaw_deg)`` within ``dt`` metres and ``dyaw``
    degrees. Returns a :class:`LocalizeResult` of the robot's pose; its
    ``cameras`` name each camera's matches. ``tolerances.search``:
    ``"tree"`` (each camera's interpretation tree seeds the verification)
    or ``"structure"`` (:mod:`matcher.search.structure`); None: the default
    (:func:`matcher.search.default_search`). Bad input raises InputError."""
    t0 = time.perf_counter()
    rig = check_rig(rig)
    if default_search(search_of(tolerances), rig) == "structure":
        tol = validated_types(linemap, rig[0].camera, tolerances)
        px = check_prior(prior, dt, dyaw)
        return localize_frame(linemap, prepare_rig_frame(rig, lines, tol), px, tol, t0)
    if rig.is_single:
        return localize(linemap, rig[0].camera, _single_lines(rig, lines), prior, dt, dyaw, tolerances)
    tol = validated_types(linemap, rig[0].camera, tolerances)
    px = check_prior(prior, dt, dyaw)
    frame = prepare_rig_frame(rig, lines, tol)
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms, tol.shared.search_share)
    found = _prior_search(linemap, frame, px, tol, deadlines)
    counts = search_counts(found.searches)
    if all(s.answer is None for s in found.searches):  # no camera could be searched: each one's reason
        return _unsearched("; ".join(f"{s.view.name}: {s.why}" for s in found.searches), tol, t0)
    cut = BY_TIME if counts["out_of_time"] else UNCUT
    times = {"generate": found.search_ms, "verify": found.verify_ms}
    if found.ranked is None:
        verdict = decide(Evidence(n_correspondences=counts["correspondences"], cut=cut), tol)
        return LocalizeResult(False, verdict.reason, time_ms=Timings(total=(time.perf_counter() - t0) * 1e3, **times),
                              stage1=SearchStats(**counts))
    return rig_result(frame, found.cands, found.ranked, tol, RunInfo(t0, times, counts, cut, px))


@dataclass
class PriorFound:
    """A prior's search so far: each camera's latest ``searches`` (rig
    order), its candidates ``cands``, the verified poses ``ranked`` (None:
    none yet), the seeds ``tried``, the milliseconds of the searches and of
    the verifications."""

    searches: list
    cands: list
    ranked: RigRanked | None = None
    tried: list = field(default_factory=list)
    search_ms: float = 0.0
    verify_ms: float = 0.0
    #: (H,) per verified pose of ``ranked``, the camera whose seed it is.
    proposed_by: list = field(default_factory=list)


def _prior_search(linemap, frame: RigFrame, px: tuple, tol: Tolerances, deadlines: Deadlines) -> PriorFound:
    """The cameras searched, those with the most usable lines first, each
    one's new seeds verified on every camera as they come: first every
    camera with the interpretation tree alone
    (:data:`~matcher.search.tree.strategy.TREE_ALONE`), then, only if none of their
    seeds verified, with the whole strategy. The search stops before the
    other cameras' trees once it is settled (:func:`_settled`: the verdict
    accepts a pose that the seeds of ``RigConstants.settled_cameras``
    cameras verified to). (Stopping at the first pose that explains most of
    the frame would not do: a look-alike a few centimetres off, a jamb's
    near face for its far one, explains most of the frame too.)"""
    searches = [search_camera(linemap, v, px, tol, deadlines, ()) for v in frame.views]  # candidates only
    found = PriorFound(searches, [s.cands for s in searches])
    order = sorted(range(len(frame.views)), key=lambda i: -int(frame.views[i].lines.usable.sum()))
    for sources in (TREE_ALONE, SOURCES):
        for i in order:
            t = time.perf_counter()
            found.searches[i] = search_camera(linemap, frame.views[i], px, tol, deadlines, sources,
                                              found.cands[i] if found.cands[i] is not None else searches[i].why)
            seeds = new_poses(camera_seeds(found.searches[i], tol), found.tried, tol)
            t_v = time.perf_counter()
            found.search_ms += (t_v - t) * 1e3
            if len(seeds):
                found.tried += list(seeds)
                found.proposed_by += [i] * len(seeds)
                found.ranked = merged(frame.views, found.cands, found.ranked,
                                      verify_seeds(frame.views, found.cands, seeds, px, tol), px, tol)
            settled = len(seeds) and _settled(frame, found, tol)
            found.verify_ms += (time.perf_counter() - t_v) * 1e3
            if settled:
                return found
        if found.ranked is not None and np.isfinite(found.ranked.score).any():
            return found  # the tree's seeds gave verified poses: the verdict judges them
    return found


def _settled(frame: RigFrame, found: PriorFound, tol: Tolerances) -> bool:
    """Whether the verdict accepts the best verified pose so far and the
    seeds of ``RigConstants.settled_cameras`` cameras (or more) verified to
    it, within ``settled_m`` and ``settled_deg``: the other cameras' trees
    are not searched then."""
    ranked = found.ranked
    if ranked is None or confirmed_by(ranked, found.proposed_by, tol) < tol.rig.settled_cameras:
        return False
    # The calibration is judged once, on the final answer (rig_result).
    return bool(decide(_evidence(frame, found.cands, ranked, tol, UNCUT, calibration=False)[0], tol))


def confirmed_by(ranked: RigRanked, proposed_by, tol: Tolerances) -> int:
    """How many cameras' seeds (``proposed_by`` (H,): the camera of each of
    ``ranked``'s poses) were verified to within ``RigConstants.settled_m``
    and ``settled_deg`` of the best verified pose; 0 when none is left."""
    if not len(ranked.order) or not np.isfinite(ranked.score[ranked.order[0]]):
        return 0
    d = ranked.poses - ranked.poses[int(ranked.order[0])]
    near = ((np.hypot(d[:, 0], d[:, 1]) <= tol.rig.settled_m)
            & (np.abs(np.remainder(d[:, 2] + math.pi, 2 * math.pi) - math.pi) <= math.radians(tol.rig.settled_deg)))
    return len({int(proposed_by[h]) for h in near.nonzero()[0]})


def localize_rig_global(linemap, rig, lines, tolerances: Tolerances | None = None):
    """Lost mode on a rig's frame: each camera's lost search
    (:func:`matcher.localize_global`, a share of the time budget each)
    gives seed poses; each seed, a narrow prior around it
    (``SharedConstants.lost_seed_m``, ``lost_seed_deg``), is verified on every
    camera's lines, and the best verified pose is judged by the one verdict
    against all the others (a look-alike place that fits as well is named
    as a candidate, the result then falsy). ``tolerances.search`` as
    :func:`localize_rig` reads it (structure: the whole floor ranked at
    once)."""
    t0 = time.perf_counter()
    rig = check_rig(rig)
    if default_search(search_of(tolerances), rig, lost=True) == "structure":
        tol = validated_types(linemap, rig[0].camera, tolerances)
        return localize_frame(linemap, prepare_rig_frame(rig, lines, tol), None, tol, t0)
    if rig.is_single:
        return localize_global(linemap, rig[0].camera, _single_lines(rig, lines), tolerances)
    tol = validated_types(linemap, rig[0].camera, tolerances)
    frame = prepare_rig_frame(rig, lines, tol)
    found = _lost_search(linemap, frame, tol, t0)
    times = {"generate": found.search_ms, "verify": found.verify_ms}
    run = RunInfo(t0, times, found.counts, found.cut)
    if found.best is None:
        reason = "no camera's lost search gave a pose to verify"
        if found.cut != UNCUT:
            reason += f"; the time budget of {tol.time_budget_ms:g} ms ran out"
        return LocalizeResult(False, decide(Evidence(unsearched=reason), tol).reason,
                              time_ms=Timings(total=(time.perf_counter() - t0) * 1e3, **times),
                              stage1=SearchStats(**found.counts))
    cands, ranked = found.best
    return rig_result(frame, cands, ranked, tol, run, rivals=found.answers)


class RunInfo:
    """A call's clock start ``t0``, its step ``times`` (ms), stage 1's
    ``counts``, how the search was ``cut`` and the robot's prior ``px``
    ``(xe, ye, yaw_e, dt, dyaw)`` radians (None: lost mode)."""

    def __init__(self, t0: float, times: dict, counts: dict, cut: str, px: tuple | None = None) -> None:
        self.t0, self.times, self.counts, self.cut, self.px = t0, times, counts, cut, px


def rig_result(frame: RigFrame, cands: list, ranked: RigRanked, tol: Tolerances, run: RunInfo,
               rivals: list | None = None, runner_up: tuple | None = None) -> LocalizeResult:
    """The :class:`LocalizeResult` of the verified poses as the verdict
    judges them: the best robot pose if accepted (with each camera's
    matches), else a falsy result with the reason and candidates.
    ``rivals``: every answer of the other verifications (lost mode's other
    seeds), ``(pose_deg, matches, E, cost)``, for the ambiguity test;
    ``runner_up`` the ranking's best pose elsewhere
    (:attr:`matcher.verdict.Evidence.runner_up`)."""
    E, order = ranked.score, ranked.order
    best = int(order[0]) if len(order) else None
    finite = [int(h) for h in order if np.isfinite(E[h])]
    ev, pose_std = _evidence(frame, cands, ranked, tol, run.cut, rivals, px=run.px)
    if runner_up is not None:
        ev = replace(ev, runner_up=runner_up)
    verdict = decide(ev, tol)
    times = dict(run.times, total=(time.perf_counter() - run.t0) * 1e3)
    listed = [(float(E[h]), _all_matches(frame, cands, ranked, h), _pose_deg(ranked.poses[h])) for h in finite]
    common = dict(hypotheses=len(ranked.poses), time_ms=Timings(**times), ranked=listed, sets_found=len(finite),
                  stage1=SearchStats(**run.counts),
                  runner_up_score=float(E[finite[1]]) if len(finite) > 1 else None)
    if not verdict:
        return LocalizeResult(False, verdict.reason, score=verdict.score, candidates=list(verdict.candidates),
                              **common)
    return LocalizeResult(True, "", pose=_pose_deg(ranked.poses[best]), score=verdict.score,
                          matches=listed[0][1], cameras=_per_camera(frame, cands, ranked, best, tol), _pose_std=pose_std,
                          **common)


def _evidence(frame: RigFrame, cands: list, ranked: RigRanked, tol: Tolerances, cut: str,
              rivals: list | None = None, px: tuple | None = None, calibration: bool = True) -> tuple:
    """``(Evidence, pose_std)`` of the verified poses for the verdict (the
    best's pose standard deviations deferred; None when no pose is left);
    ``rivals`` as :func:`rig_result` takes them; with ``calibration``, the
    cameras' calibration judged within the robot's prior ``px`` (None:
    lost mode, no bounds)."""
    E, order = ranked.score, ranked.order
    best = int(order[0]) if len(order) else None
    finite = [int(h) for h in order if np.isfinite(E[h])]
    answers = [(_pose_deg(ranked.poses[h]), int(ranked.n[h]), float(E[h]), float(ranked.cost[h])) for h in finite]
    if rivals and answers:  # the best stays first; the others by the ranking's keys
        rest = sorted([a for a in rivals if a[0] != answers[0][0]] + answers[1:], key=lambda a: (-a[1], a[3], a[2]))
        answers = answers[:1] + rest
    answers = tuple(answers)
    if not finite:
        return Evidence(score=math.inf, unscored=ranked.why or "no verified pose", cut=cut), None
    pose_std = Deferred(lambda: _pose_std(frame, cands, ranked, best, tol))
    return Evidence(score=float(E[best]), coverage=Deferred(lambda: _coverage(frame, cands, ranked, best, tol)),
                    explained=int(ranked.explained[best]), searched=frame.searched,
                    needed=rig_lines_needed(frame.searched, tol),
                    answers=answers, spread=Deferred(lambda: ambiguity.spread_of(pose_std.get())), cut=cut,
                    clear_ratio=tol.rig.clear_ratio, e_accept=float(ranked.e_limit[best]),
                    calibration=Deferred(lambda: _calibration(frame, cands, ranked, best, tol, px)) if calibration
                    else None), pose_std


def rig_lines_needed(searched: int, tol: Tolerances) -> int:
    """How many of a rig frame's ``searched`` lines (all cameras) its best
    pose must explain: ``min_matches`` and ``RigConstants.explained_min_share``
    of them, whatever the other places (the clear-ratio test measures chance
    fits against them; where none was verified it has nothing to compare
    with, and this floor is what holds)."""
    return max(tol.min_matches, math.ceil(tol.rig.explained_min_share * searched))


def _single_lines(rig, lines):
    """The one camera's lines of a one-camera rig's frame."""
    if isinstance(lines, np.ndarray) or not isinstance(lines, (list, tuple)) or len(lines) != 1:
        raise InputError(f"a rig frame's lines must be a list with one array of lines per camera "
                         f"({len(rig)} camera: {rig.names[0]})")
    return lines[0]


def _unsearched(reason: str, tol: Tolerances, t0: float) -> LocalizeResult:
    verdict = decide(Evidence(unsearched=reason), tol)
    return LocalizeResult(False, verdict.reason, time_ms=Timings(total=(time.perf_counter() - t0) * 1e3))


def _pose_deg(p) -> tuple[float, float, float]:
    return float(p[0]), float(p[1]), float(math.degrees(wrap(p[2])))


def _all_matches(frame: RigFrame, cands: list, ranked: RigRanked, h: int) -> list[list[int]]:
    """Pose ``h``'s matches over all cameras ``[[segment_id, line], ...]``,
    lines counted through the cameras' lists in the rig's order."""
    out = []
    for v, c, m in zip(frame.views, cands, ranked.matches):
        sel = m.hyp == h
        out += [[int(c.ids[a]), int(b) + v.offset] for a, b in zip(m.local[sel], m.line[sel])]
    return sorted(out)


def _per_camera(frame: RigFrame, cands: list, ranked: RigRanked, h: int, tol: Tolerances) -> list[dict]:
    """Each camera's matches of pose ``h`` and their RMS end-point distance, pixels."""
    out = []
    for v, c, m in zip(frame.views, cands, ranked.matches):
        sel = m.hyp == h
        pairs = sorted([int(c.ids[a]), int(b)] for a, b in zip(m.local[sel], m.line[sel])) if c is not None else []
        rms = None
        if pairs:
            q = v.mount.camera_poses(np.repeat(ranked.poses[h:h + 1], int(sel.sum()), axis=0))
            d = projected_end_distances(*project_segments(v.camera, q, c.segments[m.local[sel]], tol.stage2.near_plane_m),
                                        v.lines.lines[m.line[sel]])
            rms = float(np.sqrt(np.mean(d**2)))
        out.append({"name": v.name, "matches": pairs, "rms_px": rms})
    return out


def _coverage(frame: RigFrame, cands: list, ranked: RigRanked, h: int, tol: Tolerances) -> tuple[int, int]:
    """``(predicted, seen)`` map segments in view of the rig's cameras at
    pose ``h`` (:func:`matcher.stage2.fit.coverage_in_sight` of each), each
    counted once however many cameras see it: a pose must be supported
    around the robot, not by one camera's clutter; and the views of a
    panorama overlap (a segment in two views and matched by a line of one
    of them is seen, not half seen)."""
    predicted, seen = set(), set()
    for v, c, m in zip(frame.views, cands, ranked.matches):
        if c is None:
            continue
        q = v.mount.camera_poses(ranked.poses[h])
        idx, held = coverage_in_sight(v.camera, q, c.segments, c.label, m.local[m.hyp == h], c.walls, tol)
        predicted.update(c.ids[idx].tolist())
        seen.update(c.ids[idx[held]].tolist())
    return len(predicted), len(seen)


def _calibration(frame: RigFrame, cands: list, ranked: RigRanked, h: int, tol: Tolerances, px: tuple | None) -> str:
    """Why pose ``h``'s matches say a camera file is wrong
    (:func:`matcher.rig.calibration.rig_doubt`), "" when they do not."""
    per_camera = []
    for v, c, m in zip(frame.views, cands, ranked.matches):
        sel = m.hyp == h
        if c is not None and sel.any():
            per_camera.append((v, v.lines.lines[m.line[sel]], c.segments[m.local[sel]]))
    why = rig_doubt(per_camera, ranked.poses[h], tol, px)
    if why or len(frame.views) == 1 or not focal_doubted(per_camera, ranked.poses[h], tol):
        return why
    # The focal profile (matcher.rig.calibration): the same checks where the
    # scale that explains the most lines puts the pose, when not the files'.
    around = px if px is not None else (*ranked.poses[h], tol.shared.lost_seed_m, math.radians(tol.shared.lost_seed_deg))
    scale, pose, at_scale = focal_profile(frame.views, cands, ranked.poses[h], around, tol, per_camera)
    return "" if scale == 1.0 else rig_doubt(at_scale, pose, tol, px)


def _pose_std(frame: RigFrame, cands: list, ranked: RigRanked, h: int, tol: Tolerances):
    """``(x, y, yaw_deg)`` standard deviations of pose ``h`` over every
    camera's matches, or None where they do not fix it."""
    triples = [(v, c.segments, m.of_one(h)) for v, c, m in zip(frame.views, cands, ranked.matches) if c is not None]
    A = robot_information(triples, ranked.poses[h:h + 1], tol)[0]
    if np.linalg.det(A) <= 1e-12 * max(float(np.abs(A).max()), 1e-300) ** 3:
        return None
    cov = np.linalg.inv(A)
    return float(math.sqrt(cov[0, 0])), float(math.sqrt(cov[1, 1])), float(math.degrees(math.sqrt(cov[2, 2])))


def _candidates(linemap, view, px: tuple, tol: Tolerances):
    """A camera's candidates under the robot's prior ``px``, None when none."""
    cands = select_candidates(linemap, view.camera, view.camera_prior(px), tol)
    return None if isinstance(cands, str) else cands


@dataclass
class LostFound:
    """Lost mode's search so far: the ``best`` verification ``(candidates,
    ranked)`` (None: none), every verified ``answers`` (for the rivals),
    stage 1's ``counts``, how the search was ``cut``, the milliseconds of
    the cameras' searches and of the verifications."""

    best: tuple | None = None
    answers: list = field(default_factory=list)
    counts: dict = field(default_factory=lambda: {"out_of_time": False})
    cut: str = UNCUT
    search_ms: float = 0.0
    verify_ms: float = 0.0


def _lost_search(linemap, frame: RigFrame, tol: Tolerances, t0: float) -> LostFound:
    """Each camera's lost search, the cameras with the most usable lines
    first, with its share of the budget left; its answers' robot poses
    (``seeds_per_camera`` of its ranked answers and its candidates) each
    verified on every camera as a narrow prior. Stops once the best
    verified pose explains most of the frame's usable lines
    (``LostConstants.vote_trust_share``): no other camera's seeds could
    explain much more."""
    found, tried = LostFound(), []
    found.counts["lines"] = int(sum(len(v.lines.lines) for v in frame.views))
    order = sorted(range(len(frame.views)), key=lambda i: -int(frame.views[i].lines.usable.sum()))
    # First each camera's quick search (its first accepted answer), then,
    # if no seed explained most of the frame, each camera's whole one.
    for quick in (True, False):
        for k, i in enumerate(order):
            left = tol.time_budget_ms - (time.perf_counter() - t0) * 1e3
            if left <= 0:
                found.cut = BY_TIME
                return found
            share = left / (len(order) * (2 if quick else 1) - k) if math.isfinite(left) else left
            tried += list(_lost_camera(linemap, frame, frame.views[i], replace(tol, time_budget_ms=share), quick,
                                       found, tried))
            best = found.best
            if best is not None and trusted(int(best[1].n[best[1].order[0]]), frame.usable, tol.lost):
                return found
    return found


def _lost_camera(linemap, frame: RigFrame, view, tol: Tolerances, quick: bool, found: LostFound,
                 tried: list) -> np.ndarray:
    """One camera's lost search (``quick``: to its first accepted answer)
    and its seeds (none near one ``tried``) verified into ``found``;
    returns the seeds."""
    t = time.perf_counter()
    res = _localize_global(linemap, view.camera, view.lines, tol, t, quick, None, None)
    found.counts["out_of_time"] |= bool(res.stage1.out_of_time)
    seeds = _seeds_of(res, view, tol, tried)
    t_v = time.perf_counter()
    found.search_ms += (t_v - t) * 1e3
    for seed in seeds:
        _verify_lost_seed(linemap, frame, seed, tol, found)
    found.verify_ms += (time.perf_counter() - t_v) * 1e3
    return seeds


def _seeds_of(res: LocalizeResult, view, tol: Tolerances, tried: list) -> np.ndarray:
    """(S, 3) robot poses of a camera's lost result: its best ranked
    answers and its candidates, each once and none near a seed ``tried``."""
    poses = [r[2] for r in res.ranked[:tol.rig.seeds_per_camera]]
    poses += [(c["x"], c["y"], c["yaw_deg"]) for c in res.candidates]
    if not poses:
        return np.zeros((0, 3))
    q = np.array([(x, y, math.radians(yaw)) for x, y, yaw in poses])
    return new_poses(view.mount.robot_poses(q), tried, tol)


def _verify_lost_seed(linemap, frame: RigFrame, seed: np.ndarray, tol: Tolerances, found: LostFound) -> None:
    """One seed verified on every camera under a narrow prior around it;
    ``found`` keeps the better verification and every answer."""
    px = (float(seed[0]), float(seed[1]), float(seed[2]), tol.shared.lost_seed_m, math.radians(tol.shared.lost_seed_deg))
    cands = [_candidates(linemap, v, px, tol) for v in frame.views]
    ranked = verify_seeds(frame.views, cands, seed[None], px, tol)
    answers = [(_pose_deg(ranked.poses[h]), int(ranked.n[h]), float(ranked.score[h]), float(ranked.cost[h]))
               for h in ranked.order if np.isfinite(ranked.score[h])]
    found.answers += answers
    if answers and (found.best is None or _key(ranked) < _key(found.best[1])):
        found.best = (cands, ranked)


def _key(ranked: RigRanked) -> tuple:
    h = int(ranked.order[0])
    ok = bool(np.isfinite(ranked.score[h]))
    return (not ok, -int(ranked.n[h]) if ok else 0, float(ranked.cost[h]) if ok else math.inf,
            float(ranked.score[h]))

