"""Localisation from a prior: :func:`localize`.

    lines -> frame (matcher.frame) -> candidates (matcher.candidates)
          -> strategy (matcher.search.tree.strategy: stage 1 sources, stage 2 after each)
          -> LocalizeResult (matcher.result)

Lost mode, with no prior, is :func:`matcher.lost.localize_global`: this
module's :func:`localize_prepared` once per region.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from linemap.building import Building
from linemap.camera import Camera
from linemap.errors import InputError
from linemap.geometry import wrap
from linemap.lmap import LineMap
from linemap.rig import Rig
from matcher import ambiguity, attitude
from matcher.budget import NO_LIMIT, Deadlines
from matcher.candidates import select_candidates
from matcher.input_validation import check_lines, check_prior
from matcher.frame import ImageLines, lines_needed, prepare_lines, too_few_lines
from matcher.result import Deferred, LocalizeResult, SearchStats, Timings
from matcher.search import default_search, search_of
from matcher.stage2.calibration_check import Where
from matcher.stage2.calibration_check import doubt as calibration_doubt
from matcher.stage2.covariance import pose_std_of
from matcher.stage2.fit import coverage as coverage_of
from matcher.search.tree.strategy import SOURCES, TREE_ALONE, Answer, Problem, run_strategy
from matcher.tolerances import DEFAULT, Tolerances
from matcher.verdict import BY_SEARCH_BUDGET, BY_TIME, UNCUT, Evidence, decide


def localize(linemap, camera: Camera, lines, prior, dt: float, dyaw: float, tolerances: Tolerances | None = None,
             storey: str | None = None):
    """Localise the camera from image ``lines`` (M, 2, 2) or (M, 4) pixels of
    the ideal pinhole (as :func:`matcher.detect_lines` gives them: undistorted
    when the camera has distortion).

    ``prior`` is ``(x, y, yaw_deg)``; the true pose is within ``dt`` metres
    and ``dyaw`` degrees of it. ``linemap`` a map, or a building
    (:class:`linemap.building.Building`) with the prior's ``storey`` named
    (:func:`matcher.building.localize_on_storey`). Returns a
    :class:`LocalizeResult`, falsy with a ``reason`` when no hypothesis is
    accepted. ``tolerances.search`` chooses how places are ranked
    (``"tree"``, the paper's interpretation tree, or ``"structure"``,
    :mod:`matcher.search.structure`, run as a one-camera rig; None: the
    default, :func:`matcher.search.default_search`). Bad input (shapes,
    NaN, ranges) raises ValueError."""
    t0 = time.perf_counter()
    if default_search(search_of(tolerances)) == "structure" and not isinstance(linemap, Building):
        from matcher.rig.localize import localize_rig

        return localize_rig(linemap, Rig.single(camera), [lines], prior, dt, dyaw, tolerances)
    if isinstance(linemap, Building):
        from matcher.building import localize_on_storey

        return localize_on_storey(linemap, camera, lines, prior, dt, dyaw, tolerances, storey)
    if storey is not None:
        raise InputError(f"storey={storey!r} names a storey of a building; this map is one floor (a .lmap): "
                         "drop the storey, or load the building's manifest (building.json)")
    if attitude.applies(camera):
        # The frame's own pitch and roll (matcher.attitude): the lines moved
        # to the nominal camera, then localised as any.
        tol = validated_types(linemap, camera, tolerances)
        check_prior(prior, dt, dyaw)
        return attitude.localize_with_attitude(camera, lines, tol, FromPrior(linemap, prior, dt, dyaw))
    tol, image_lines = validated_inputs(linemap, camera, lines, tolerances)
    return _localize_checked(linemap, camera, image_lines, check_prior(prior, dt, dyaw), tol, t0)


@dataclass(frozen=True)
class FromPrior:
    """:func:`localize`'s search of a levelled frame (:class:`matcher.attitude.Localiser`):
    the ``prior`` ``(x, y, yaw_deg)`` within ``dt`` metres and ``dyaw``
    degrees on ``linemap``; a quick run (an attitude band's) with the
    interpretation tree alone."""

    linemap: LineMap
    prior: tuple
    dt: float
    dyaw: float

    @property
    def segments(self) -> np.ndarray:
        return self.linemap.segments

    def localize_levelled(self, camera: Camera, lines: np.ndarray, run: attitude.Run) -> LocalizeResult:
        return localize_lines(self.linemap, camera, prepare_lines(camera, lines, run.tol), self.prior, self.dt,
                              self.dyaw, run.tol, sources=TREE_ALONE if run.quick else SOURCES)


def localize_lines(linemap, camera: Camera, image_lines: ImageLines, prior, dt, dyaw, tol: Tolerances, sources=SOURCES):
    """:func:`localize` on prepared lines ``image_lines`` (the lines moved to the
    nominal camera by :mod:`matcher.attitude` need not lie in the image),
    with the strategy's ``sources``."""
    t0 = time.perf_counter()
    return _localize_checked(linemap, camera, image_lines, check_prior(prior, dt, dyaw), tol, t0, sources)


def _localize_checked(linemap, camera: Camera, image_lines: ImageLines, px, tol: Tolerances, t0: float,
                      sources=SOURCES):
    """:func:`localize_prepared` on the checked prior ``px`` with the time
    budget of ``tol`` counted from ``t0``."""
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms, tol.shared.search_share)
    return localize_prepared(linemap, camera, image_lines, px, tol, t0, deadlines, Scope(sources))


def validated_inputs(linemap, camera, lines, tolerances) -> tuple[Tolerances, ImageLines]:
    """ValueError unless the map, camera and tolerances are of their types
    and the lines valid; the tolerances to use and the prepared lines."""
    tol = validated_types(linemap, camera, tolerances)
    return tol, prepare_lines(camera, check_lines(lines, camera, tol), tol)


def validated_types(linemap, camera, tolerances) -> Tolerances:
    """ValueError unless the map, camera and tolerances are of their types;
    the tolerances to use."""
    if not isinstance(linemap, LineMap):
        raise InputError(f"linemap must be a map from matcher.load_map('map.lmap'), got {type(linemap).__name__}")
    if not isinstance(camera, Camera):
        raise InputError(f"camera must be a matcher.Camera (Camera.load('camera.json')), got {type(camera).__name__}")
    if tolerances is not None and not isinstance(tolerances, Tolerances):
        raise InputError(f"tolerances must be a matcher.Tolerances, got {type(tolerances).__name__}")
    return tolerances or DEFAULT


@dataclass(frozen=True)
class Scope:
    """What one search covers: the strategy's hypothesis ``sources``
    (:data:`matcher.search.tree.strategy.SOURCES`) and ``candidate_ids``, the segments
    to consider instead of those of the regions the prior disk meets (lost
    mode: a region's list; None: those). ``whole_map``: the prior is one
    piece of lost mode's search of the whole map, not a bound on where the
    robot is: the calibration check may find the pose anywhere the robot
    can stand (a wrong focal length moves the pose metres, out of the piece)."""

    sources: tuple = SOURCES
    candidate_ids: np.ndarray | None = None
    whole_map: bool = False


def localize_prepared(linemap, camera: Camera, image_lines: ImageLines, px, tol: Tolerances, t0: float,
                      deadlines: Deadlines = NO_LIMIT, scope: Scope = Scope()) -> LocalizeResult:
    """One prior ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians) on prepared
    lines, within the time budget's ``deadlines`` (``t0`` the start of the
    call's clock): the candidates (:mod:`matcher.candidates`), then the
    strategy (:mod:`matcher.search.tree.strategy`), then the verdict
    (:mod:`matcher.verdict`) and the result; ``scope`` what it covers."""
    times: dict[str, float] = {}
    cands = select_candidates(linemap, camera, px, tol, scope.candidate_ids)
    times["select"] = (time.perf_counter() - t0) * 1e3
    reason = cands if isinstance(cands, str) else too_few_lines(image_lines, tol)
    late = not reason and not deadlines.may_search()  # line preparation and selection count too
    if late:
        reason = f"no time left to search after preparing {len(image_lines.lines)} lines"
    if reason:
        verdict = decide(Evidence(unsearched=reason, cut=BY_TIME if late else UNCUT), tol)
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, verdict.reason, time_ms=Timings(**times),
                              stage1=SearchStats(out_of_time=True, tree_nodes=0) if late else SearchStats())
    problem = Problem(camera, image_lines, cands, px, tol, deadlines)
    answer = run_strategy(problem, scope.sources)
    times.update(answer.times)
    return _result(answer, problem, t0, times, linemap if scope.whole_map else None)


def _result(answer: Answer, problem: Problem, t0: float, times: dict, whole_map=None) -> LocalizeResult:
    """The :class:`LocalizeResult` of the strategy's answer as
    :func:`matcher.verdict.decide` judges it: the best ranked pose if
    accepted, else a falsy result with the reason (and the poses it cannot
    tell apart); the ranking, stage 1's counters and the times either way.
    ``whole_map``: the map, when the prior is a piece of lost mode's search
    (:class:`Scope`)."""
    hyps, ranked_h, tol = answer.hyps, answer.ranked, problem.tol
    cut = BY_TIME if (answer.spent or hyps.counts.get("out_of_time")) else BY_SEARCH_BUDGET if hyps.truncated else UNCUT
    stage1 = SearchStats(**dict(hyps.counts, out_of_time=bool(hyps.counts.get("out_of_time") or answer.spent)))
    if ranked_h is None:
        verdict = decide(Evidence(n_correspondences=hyps.n_correspondences, cut=cut), tol)
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, verdict.reason, time_ms=Timings(**times), stage1=stage1)
    E, order, ids, n_h = ranked_h.score, ranked_h.order, problem.cands.ids, len(hyps.sets)

    def matches_of(h):
        mine = ranked_h.matches.of_one(h)
        return sorted([int(ids[a]), int(b)] for a, b in zip(mine.local, mine.line))

    def pose_deg(p):
        return (float(p[0]), float(p[1]), float(math.degrees(wrap(p[2]))))

    ranked = [(float(E[h]), matches_of(h), pose_deg(ranked_h.poses[h])) for h in order]
    best = int(order[0])
    runner = float(E[order[1]]) if n_h > 1 and np.isfinite(E[order[1]]) else None
    # Worked out when first read (a few tenths of a millisecond a robot
    # that only wants the pose does not spend).
    pose_std = Deferred(lambda: pose_std_of(problem.camera, problem.lines, problem.cands.segments, ranked_h, best,
                                            tol))
    verdict = decide(_evidence(ranked_h, ranked, problem, cut, pose_std, whole_map), tol)
    times["total"] = (time.perf_counter() - t0) * 1e3
    common = dict(hypotheses=n_h, runner_up_score=runner, time_ms=Timings(**times), ranked=ranked,
                  sets_found=int(hyps.counts.get("sets_found", n_h)), stage1=stage1)
    if not verdict:
        return LocalizeResult(False, verdict.reason, score=verdict.score, candidates=list(verdict.candidates),
                              miscalibrated=verdict.miscalibrated, **common)
    return LocalizeResult(True, "", pose=ranked[0][2], score=verdict.score, matches=ranked[0][1], _pose_std=pose_std,
                          **common)


def sees_all(linemap, ids: np.ndarray):
    """``(x, y, r) -> bool``: do the map's regions within ``r`` of ``(x, y)``
    (metres) list every segment of ``ids`` as visible?"""
    def sees(x: float, y: float, r: float) -> bool:
        regions = linemap.regions_near(x, y, r)
        if len(regions) == 0:
            return False
        return bool(np.isin(ids, linemap.segments_for_regions(regions)).all())

    return sees


def _evidence(ranked_h, ranked: list, problem: Problem, cut: str, pose_std: Deferred,
              whole_map=None) -> Evidence:
    """The :class:`~matcher.verdict.Evidence` of stage 2's ranking
    ``ranked_h`` (``ranked``: its hypotheses' E, matches and poses in
    degrees, best first) on its best hypothesis; ``cut``, how the search
    was cut short; ``pose_std``, the best pose's standard deviations;
    ``whole_map``: the map, when the prior is a piece of lost mode's search (:class:`Scope`)."""
    camera, image_lines, cands, tol = problem.camera, problem.lines, problem.cands, problem.tol
    best = int(ranked_h.order[0])
    mine = ranked_h.matches.of_one(best)
    coverage = Deferred(lambda: coverage_of(camera, ranked_h.poses[best], cands.segments, cands.label, mine.local,
                                            cands.walls, tol))
    # Counted among the lines searched: the ones added back from the rest
    # (stage 2 judges every line) come with clutter of their own.
    explained = int(np.unique(mine.line[image_lines.searched[mine.line]]).size)
    n_fin = np.bincount(ranked_h.matches.hyp, minlength=len(ranked_h.order))
    answers = tuple((pose, int(n_fin[h]), E, float(ranked_h.cost[h])) for (E, _, pose), h in zip(ranked, ranked_h.order)
                    if math.isfinite(E))
    # Where the pose with a calibration freed may lie: within a prior's
    # bounds, or in lost mode anywhere the robot can stand and see the
    # matched segments.
    where = Where(problem.prior) if whole_map is None else Where(None, cands.free,
                                                                   sees_all(whole_map, cands.ids[mine.local]))
    calibration = Deferred(lambda: calibration_doubt(camera, image_lines.lines[mine.line], cands.segments[mine.local],
                                                     ranked_h.poses[best], tol, where))
    return Evidence(score=float(ranked_h.score[best]), unscored=ranked_h.why, coverage=coverage, explained=explained,
                    searched=int(image_lines.searched.sum()), needed=lines_needed(image_lines, tol), answers=answers,
                    spread=Deferred(lambda: ambiguity.spread_of(pose_std.get())), cut=cut, calibration=calibration)
