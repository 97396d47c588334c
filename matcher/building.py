"""The matcher on a building (:class:`linemap.building.Building`): one storey, or every storey.

A building is a map per storey (``matcher.load_map("building.json")``).
With a prior, the robot is on a storey the caller names (``storey=``; a
building of one mapped storey needs no name): :func:`localize_on_storey`
is :func:`matcher.from_prior.localize` on that storey's map. With none,
:func:`search_storeys` runs lost mode (:func:`matcher.lost.localize_global`)
on each storey, lowest first, each with its share of what is left of the
time budget, and judges their answers together with
:func:`matcher.verdict.decide`, as lost mode judges its regions': the
answer that explains the most lines, then the smallest E; answers on two
storeys that fit alike are two places (:func:`matcher.ambiguity.rivals`),
so the same room on two floors seen alike is ambiguous, naming both. The
result names its storey (``LocalizeResult.storey``), each candidate too.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

from linemap.building import Building, Storey
from matcher import ambiguity, from_prior, lost
from matcher.frame import prepare_lines
from matcher.input_validation import check_lines
from matcher.result import Deferred, LocalizeResult, SearchStats, Timings
from matcher.tolerances import Tolerances
from matcher.verdict import BY_TIME, UNCUT, Evidence, Sweep, Verdict, decide


def localize_on_storey(building: Building, camera, lines, prior, dt: float, dyaw: float,
                       tolerances: Tolerances | None = None, storey: str | None = None) -> LocalizeResult:
    """:func:`matcher.from_prior.localize` on the map of ``storey`` (its
    name; None: the building's only mapped storey, else an InputError
    saying to give it); the result names the storey."""
    on = building.storey(storey)
    return replace(from_prior.localize(on.map, camera, lines, prior, dt, dyaw, tolerances), storey=on.name)


@dataclass(frozen=True)
class StoreySearch:
    """Lost mode over a building: the building's ``result``, and the
    regions ``tried`` on each storey (name -> count; a storey the budget
    left no time for: 0), for a caller that goes on where a search stopped."""

    result: LocalizeResult
    tried: dict


@dataclass(frozen=True)
class _Searched:
    """What the storeys' searches gave: each searched storey with its
    result, the frame's usable lines, whether the budget cut a storey's
    search short or left one unsearched, and the call's start
    (``time.perf_counter``)."""

    results: list
    usable: int
    cut_short: bool
    t0: float


def search_storeys(building: Building, camera, lines, tolerances: Tolerances | None = None,
                   first_accepted: bool = False, progress=None, regions: dict | None = None) -> StoreySearch:
    """Lost mode on every mapped storey of ``building``, lowest first, each
    given what is left of ``tolerances.time_budget_ms`` shared among the
    storeys still to search (a storey done early leaves its time to the
    next); the answers judged together (the module docstring).
    ``first_accepted``: stop at the first storey that gives an accepted
    result. ``progress(done, total)`` counts regions over all storeys.
    ``regions``: storey name -> region ids to try in that order (default:
    all, largest first). Image ``lines`` (M, 2, 2) pixels as for
    :func:`matcher.localize_global`; bad input raises InputError before any
    search."""
    t0 = time.perf_counter()
    storeys = building.mapped
    tol = from_prior.validated_types(storeys[0].map, camera, tolerances)
    usable = int(prepare_lines(camera, check_lines(lines, camera, tol), tol).usable.sum())
    total = sum(s.map.n_regions for s in storeys)
    results, done, cut_short = [], 0, False
    for k, on in enumerate(storeys):
        left = tol.time_budget_ms - (time.perf_counter() - t0) * 1e3
        if not left > 0:
            cut_short = True
            break
        share = left / (len(storeys) - k)
        res = lost.localize_global(on.map, camera, lines, replace(tol, time_budget_ms=share), first_accepted,
                                   _offset(progress, done, total), None if regions is None else regions.get(on.name))
        results.append((on, res))
        cut_short |= _cut(res, share, tol)
        done += on.map.n_regions
        if first_accepted and res:
            break
    if progress is not None and done < total:
        progress(total, total)
    tried = {s.name: 0 for s in storeys}
    tried.update({s.name: int(res.time_ms.get("regions_tried", 0)) for s, res in results})
    return StoreySearch(_judged(_Searched(results, usable, cut_short, t0), storeys, tol), tried)


def _cut(res: LocalizeResult, share_ms: float, tol: Tolerances) -> bool:
    """Did the budget cut a storey's search short? Its result says so when
    it has an answer; one with none does not carry it, so a search that
    found nothing in more than the searching part of its share of the
    budget (``SharedConstants.search_share``: the moment its searches
    stop) counts as cut (at worst a search that ended just in time: the
    verdict is then the more careful one)."""
    if res.stage1.out_of_time:
        return True
    return not lost.answers_of(res) and res.time_ms.get("total", 0.0) >= tol.shared.search_share * share_ms


def _offset(progress, done: int, total: int):
    """A storey's ``progress(done, of)`` as the building's, ``done`` regions
    of the storeys before counted."""
    if progress is None:
        return None
    return lambda k, _: progress(done + k, total)


def _judged(searched: _Searched, storeys: tuple[Storey, ...], tol: Tolerances) -> LocalizeResult:
    """The building's answer from its storeys' lost-mode results, as
    :func:`matcher.verdict.decide` judges them together (each answer's pose
    tagged with its storey, so that answers on two storeys are apart)."""
    results = searched.results
    answers = [((pose + (on.name,), m, E), on, res) for on, res in results for pose, m, E in lost.answers_of(res)]
    answers.sort(key=lambda a: (-a[0][1], a[0][2]))  # stable: the lower storey first among equals
    out_of_time = searched.cut_short
    places = sum(int(res.time_ms.get("places_tried", 0)) for _, res in results)
    regions = sum(int(res.time_ms.get("regions_tried", 0)) for _, res in results)
    times = dict(total=(time.perf_counter() - searched.t0) * 1e3, regions_tried=regions, places_tried=places)
    sweep = Sweep(places, regions, sum(s.map.n_regions for s in storeys))
    cut = BY_TIME if out_of_time else UNCUT
    if not answers:
        if results and not (places or regions or out_of_time):
            # Nothing searched anywhere, for the same reason on every
            # storey (too few lines, no regions): that reason.
            first = results[0][1]
            return replace(first, time_ms=replace(first.time_ms, total=times["total"]))
        return LocalizeResult(False, decide(Evidence(sweep=sweep, cut=cut), tol).reason,
                              time_ms=Timings(**times), stage1=SearchStats(out_of_time=out_of_time))
    _, on, best = answers[0]
    spread = Deferred(lambda: ambiguity.spread_of(best.pose_std)) if best else None
    sweep = replace(sweep, explained=len(best.matches), usable=searched.usable)
    verdict = decide(Evidence(answers=tuple(a for a, _, _ in answers), spread=spread, standing=Verdict.of_result(best),
                              sweep=sweep, cut=cut), tol)
    # A verdict that stands from the best storey's own names that storey's poses.
    candidates = [c if "storey" in c else {**c, "storey": on.name} for c in verdict.candidates]
    return replace(best, ok=bool(verdict), reason=verdict.reason, candidates=candidates,
                   time_ms=replace(best.time_ms, **times), stage1=replace(best.stage1, out_of_time=out_of_time),
                   storey=on.name)
