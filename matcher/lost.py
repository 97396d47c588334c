"""Lost mode (method.md section 3): localisation with no prior.

The places the image's lines vote for (:mod:`matcher.lost_votes`), each a
narrow prior; then, when none explains most of the image, one prior per
region of the map (its centre, ``dt`` its radius, any heading, the region's
own visible list); each searched as
:func:`matcher.from_prior.localize_prepared` searches a prior.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from linemap.building import Building
from linemap.camera import Camera
from matcher import ambiguity, attitude, from_prior
from matcher.budget import Deadlines
from matcher.frame import prepare_lines, too_few_lines
from matcher.lost_votes import vote_places
from matcher.result import Deferred, LocalizeResult, Timings
from matcher.search import default_search, search_of
from matcher.search.tree.strategy import SOURCES, TREE_ALONE
from matcher.tolerances import Tolerances
from matcher.verdict import BY_TIME, UNCUT, Evidence, Sweep, Verdict, decide, trusted


def localize_global(linemap, camera: Camera, lines, tolerances: Tolerances | None = None,
                    first_accepted: bool = False, progress=None, regions=None):
    """Lost mode (method.md section 3): first the places the frame's lines
    vote for (:mod:`matcher.lost_votes`), each a narrow prior; then, unless
    one of them explains most of the image (``LostConstants.vote_trust_share``
    of the usable lines), one prior per region (its centre, ``dt`` its
    radius, any heading, the region's own visible list), looking only for
    answers that could beat the voted ones.

    Regions are tried largest first. With ``first_accepted`` the search
    stops at the first region that gives an accepted hypothesis (the
    paper's loop).
    Otherwise every region is tried and the accepted result that explains
    the most lines wins, then the smallest E: a wrong room can hold a few
    lines that fit well, the right one explains more of the image. So once
    a region has given an answer, the later regions' trees look only for
    sets that could beat it (at least its matches less one: stage 2 adds a
    line or so). The regions are first searched with the tree alone
    (:data:`~matcher.search.tree.strategy.TREE_ALONE`); only when none gives an answer
    does a second pass run the whole strategy (second search, resection),
    which costs most on the many regions where the robot is not.
    ``time_ms['total']`` covers all tries (the other entries are the winning
    region's); ``time_ms['places_tried']`` and ``time_ms['regions_tried']`` count them. ``progress``, if
    given, is called as ``progress(done, total)`` as the regions are done,
    last with ``done == total``. The tolerances' ``time_budget_ms`` bounds
    the whole call: regions are tried until it is spent. ``regions``: the
    region ids to try, in that order (default: all, largest first; a caller
    whose budget covers part of the map each call passes the rest next).
    Returns a falsy result if no region gives one.

    On a building (:class:`linemap.building.Building`), every storey is
    searched and the result names its storey
    (:func:`matcher.building.search_storeys`; ``regions`` then maps a
    storey's name to its region ids).

    ``tolerances.search == "structure"`` ranks the whole floor at once
    instead (:mod:`matcher.search.structure`, as a one-camera rig; None:
    the default, :func:`matcher.search.default_search`)."""
    if default_search(search_of(tolerances)) == "structure" and not isinstance(linemap, Building):
        from linemap.rig import Rig
        from matcher.rig.localize import localize_rig_global

        return localize_rig_global(linemap, Rig.single(camera), [lines], tolerances)
    if isinstance(linemap, Building):
        from matcher.building import search_storeys

        return search_storeys(linemap, camera, lines, tolerances, first_accepted, progress, regions).result
    t0 = time.perf_counter()
    if attitude.applies(camera):
        # The frame's own pitch and roll (matcher.attitude); the second run,
        # on the lines moved with the attitude the first answer gave, is a
        # narrow prior around that answer.
        tol = from_prior.validated_types(linemap, camera, tolerances)
        return attitude.localize_with_attitude(camera, lines, tol, Lost(linemap, first_accepted, progress, regions),
                                               attitude.RerunPolicy(around_answer=True))
    tol, image_lines = from_prior.validated_inputs(linemap, camera, lines, tolerances)
    return _localize_global(linemap, camera, image_lines, tol, t0, first_accepted, progress, regions)


@dataclass(frozen=True)
class Lost:
    """:func:`localize_global`'s search of a levelled frame
    (:class:`matcher.attitude.Localiser`) on ``linemap``: the whole map, or
    a narrow prior around a first answer (``run.near``). A quick run (an
    attitude band's) needs a few hypotheses near the truth, not the best
    region: it stops at the first accepted one."""

    linemap: object
    first_accepted: bool = False
    progress: object = None
    regions: object = None

    @property
    def segments(self) -> np.ndarray:
        return self.linemap.segments

    def localize_levelled(self, camera: Camera, lines: np.ndarray, run: attitude.Run) -> LocalizeResult:
        image_lines = prepare_lines(camera, lines, run.tol)
        if run.near is None:
            return _localize_global(self.linemap, camera, image_lines, run.tol, time.perf_counter(),
                                    self.first_accepted or run.quick, self.progress, self.regions)
        x, y, yaw_deg, dt, dyaw = run.near
        return from_prior.localize_lines(self.linemap, camera, image_lines, (x, y, yaw_deg), dt, dyaw, run.tol)


def _localize_global(linemap, camera: Camera, image_lines, tol: Tolerances, t0: float, first_accepted: bool, progress,
                     regions) -> LocalizeResult:
    """:func:`localize_global` on prepared lines ``image_lines``."""
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms, tol.shared.search_share)
    # The same for every region:
    unsearched = "the map has no regions" if linemap.n_regions == 0 else too_few_lines(image_lines, tol)
    if unsearched:
        total = 0.0 if linemap.n_regions == 0 else (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, decide(Evidence(unsearched=unsearched), tol).reason,
                              time_ms=Timings(total=total, regions_tried=0))
    # The robot is stopped: the whole strategy gets a larger search budget
    # per region than when tracking.
    factor = tol.lost.lost_budget_factor
    wide = replace(tol, max_nodes=tol.max_nodes * factor, max_sets=tol.max_sets * factor)
    search = _RegionSearch(linemap, camera, image_lines, deadlines, progress)
    # The places the frame's lines vote for first (a few narrow priors,
    # milliseconds each); the sweep of every region only when none holds.
    voted = search.run_voted(tol) or search.run_voted(wide, SOURCES)
    best = max((a[1] for res in voted.values() for a in answers_of(res)), default=0)
    if voted and (first_accepted or trusted(best, int(image_lines.usable.sum()), tol.lost)):
        # A voted place explains most of the image: no region can explain
        # much more, the sweep is not needed.
        if progress is not None:
            progress(linemap.n_regions, linemap.n_regions)
        return _decide(voted, search, tol, (time.perf_counter() - t0) * 1e3)
    # Largest region first: with no estimate, the robot stands most likely
    # on the most floor, and a budget spent early has searched the most.
    order = np.argsort(-linemap.region_areas(), kind="stable").tolist() if regions is None else [
        int(r) for r in regions if 0 <= int(r) < linemap.n_regions]
    found = search.run(order, TREE_ALONE, tol, first_accepted, best)
    found.update(voted)
    if found and not first_accepted:
        # The whole strategy where the tree's answers contend: a view the
        # second search or the resection completes gets its other lines back.
        keys = _contenders(found)
        found.update(search.run([k for k in keys if not isinstance(k, tuple)], SOURCES, wide))
        found.update(search.run_voted(wide, SOURCES, [k for k in keys if isinstance(k, tuple)]))
    elif not found:
        found = search.run(order, SOURCES, wide, first_accepted)
    if progress is not None:
        progress(linemap.n_regions, linemap.n_regions)
    return _decide(found, search, tol, (time.perf_counter() - t0) * 1e3)


class _RegionSearch:
    """Searches of lost mode, one per region, sharing the frame's lines, the
    call's time budget and what has been searched."""

    def __init__(self, linemap, camera, image_lines, deadlines, progress) -> None:
        self.linemap, self.camera, self.image_lines = linemap, camera, image_lines
        self.deadlines, self.progress = deadlines, progress
        self.centres, self.radii = linemap.region_centres(), linemap.region_radii()
        self.tried: set[int] = set()
        #: Answers refused because their lines say the camera file is wrong
        #: (:attr:`~matcher.result.LocalizeResult.miscalibrated`).
        self.miscalibrated: list[LocalizeResult] = []
        self.out_of_time = False
        self.places = None  # the voted places (n, 4), once worked out
        self.voted: set[int] = set()  # the voted places searched

    def run_voted(self, tol: Tolerances, sources=TREE_ALONE, only: list | None = None) -> dict:
        """Key ``("vote", k)`` -> accepted result (or one naming look-alike
        poses) of the places the lines vote for
        (:func:`~matcher.lost_votes.vote_places`), each a narrow prior searched
        with the strategy's ``sources``; ``only``: just those keys again."""
        work = tol.lost
        if not self.deadlines.may_search():
            self.out_of_time = True
            return {}
        if self.places is None:
            self.places = vote_places(self.linemap, self.camera, self.image_lines, tol, work.vote_places)
        found: dict = {}
        dt, dyaw = work.vote_prior_m, math.radians(work.vote_prior_deg)
        for k, (x, y, yaw, _) in enumerate(self.places):
            if only is not None and ("vote", k) not in only:
                continue
            if not self.deadlines.may_search():
                self.out_of_time = True
                break
            res = from_prior.localize_prepared(self.linemap, self.camera, self.image_lines, (x, y, yaw, dt, dyaw), tol,
                                               time.perf_counter(), self.deadlines,
                                               from_prior.Scope(sources, whole_map=True))
            self.voted.add(k)
            self.out_of_time |= bool(res.stage1.out_of_time)
            if res or res.candidates:
                found[("vote", k)] = res
            elif res.miscalibrated:
                self.miscalibrated.append(res)
        return found

    def run(self, regions: list[int], sources, tol: Tolerances, first_accepted: bool = False, best: int = 0) -> dict:
        """Region id -> accepted result, for ``regions`` in order, each with
        the strategy's ``sources`` and tolerances ``tol``. Once a region has given an answer, the
        later ones look only for sets that could beat it (its matches less
        one: stage 2 may add a line)."""
        found: dict[int, LocalizeResult] = {}
        for done, r in enumerate(regions):
            if self.progress is not None and done:
                self.progress(done, len(regions))
            if not self.deadlines.may_search():
                self.out_of_time = True
                break
            cx, cy = (float(v) for v in self.centres[r])
            dt = float(self.radii[r])
            if not (math.isfinite(cx) and math.isfinite(cy) and dt > 0):
                continue
            self.tried.add(r)
            tol_r = replace(tol, min_matches=max(tol.min_matches, best - 1)) if best else tol
            res = from_prior.localize_prepared(self.linemap, self.camera, self.image_lines,
                                               (cx, cy, 0.0, min(dt, 100.0), math.pi), tol_r, time.perf_counter(),
                                               self.deadlines,
                                               from_prior.Scope(sources, self.linemap.region_list(r), whole_map=True))
            self.out_of_time |= bool(res.stage1.out_of_time)
            if res.miscalibrated:
                self.miscalibrated.append(res)
            if res or res.candidates:  # accepted, or poses the region cannot tell apart
                found[r] = res
                best = max(best, max([len(res.matches)] + [c["matches"] for c in res.candidates]))
                if first_accepted and res:
                    break
        return found


def _decide(found: dict, search: _RegionSearch, tol: Tolerances, total_ms: float) -> LocalizeResult:
    """The answer of lost mode from the places' and regions' results (each
    accepted or naming poses its search could not tell apart): the one that
    explains the most lines, then the smallest E, as
    :func:`matcher.verdict.decide` judges it: falsy, naming them, when
    others that explain as many lines at a pose elsewhere fit about as well
    (:mod:`matcher.ambiguity`: a symmetric room, a row of like rooms), or
    when the time budget cut the search before one explained most of the
    image."""
    tried, places = len(search.tried), len(search.voted)
    times = dict(total=total_ms, regions_tried=tried, places_tried=places)
    cut = BY_TIME if search.out_of_time else UNCUT
    blamed = _calibration_blamed(found, search.miscalibrated)
    if blamed is not None:
        return replace(blamed, time_ms=replace(blamed.time_ms, **times))
    sweep = Sweep(places, tried, search.linemap.n_regions)
    if not found:
        return LocalizeResult(False, decide(Evidence(sweep=sweep, cut=cut), tol).reason, time_ms=Timings(**times))
    # Every answer: each region's pose, or the poses it could not tell apart.
    answers = sorted(((c, res) for res in found.values() for c in answers_of(res)), key=lambda a: (-a[0][1], a[0][2]))
    best = answers[0][1]
    spread = Deferred(lambda: ambiguity.spread_of(best.pose_std)) if best else None
    sweep = replace(sweep, explained=len(best.matches), usable=int(search.image_lines.usable.sum()))
    verdict = decide(Evidence(answers=tuple(a for a, _ in answers), spread=spread, standing=Verdict.of_result(best),
                              sweep=sweep, cut=cut), tol)
    # The best of the regions searched, not of all: the result says so.
    return replace(best, ok=bool(verdict), reason=verdict.reason, candidates=list(verdict.candidates),
                   time_ms=replace(best.time_ms, **times), stage1=replace(best.stage1, out_of_time=search.out_of_time))


def _calibration_blamed(found: dict, miscalibrated: list) -> LocalizeResult | None:
    """Lost mode's refusal when an answer refused for the camera file's
    calibration explains at least as many lines as every answer found: lost
    mode has no prior, so the place whose lines say the calibration is
    wrong is not one piece of the map to pass over for a place that
    explains fewer (a wrong focal length fits a few lines somewhere else
    too). Explaining more, its reason stands; as many, the two cannot be
    told apart and the candidates name both. None when an answer explains
    more, or none was refused for it."""
    if not miscalibrated:
        return None
    doubt = max(miscalibrated, key=lambda res: len(res.ranked[0][1]) if res.ranked else 0)
    explained = len(doubt.ranked[0][1]) if doubt.ranked else 0
    answers = sorted((a for res in found.values() for a in answers_of(res)), key=lambda a: (-a[1], a[2]))
    if explained == 0 or (answers and answers[0][1] > explained):
        return None
    if not answers or answers[0][1] < explained:
        return doubt
    E, pose = doubt.ranked[0][0], doubt.ranked[0][2]
    rivals = [answers[0], (pose, explained, E)]
    return replace(doubt, candidates=list(ambiguity.candidates_of(rivals)),
                   reason=f"a pose explains {explained} lines as well as the pose {pose[0]:.2f}, {pose[1]:.2f}, "
                          f"{pose[2]:.1f} deg whose lines say the calibration is wrong ({doubt.reason}); the "
                          "candidates name both")


def _contenders(found: dict) -> list:
    """The keys of ``found`` whose answers explain at least the most lines
    of any less one (stage 2 may add a line to a set the tree found)."""
    most = {k: max(a[1] for a in answers_of(res)) for k, res in found.items()}
    top = max(most.values())
    return [k for k in found if most[k] >= top - 1]


def answers_of(res: LocalizeResult) -> list:
    """``(pose, matches, score)`` of a region's accepted answer, or of each
    pose it could not tell apart."""
    if res:
        return [(res.pose, len(res.matches), res.score)]
    return [((c["x"], c["y"], c["yaw_deg"]), c["matches"], c["score"]) for c in res.candidates]

