"""The time budget (Tolerances.time_budget_ms): the searches stop, the
answer says so, and a budget that is never reached changes nothing."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import matcher
from matcher.budget import NO_LIMIT, Deadlines
from matcher.tolerances import DEFAULT
from mapkit_harness.simulate import make_frame

ROOT = Path(__file__).resolve().parents[1]

SEARCH_SHARE = DEFAULT.shared.search_share

#: A budget spent before the search starts.
SPENT = replace(matcher.Tolerances(), time_budget_ms=1e-9)


def test_deadlines_split_the_budget():
    assert Deadlines.from_budget(10.0, math.inf, SEARCH_SHARE) == NO_LIMIT
    d = Deadlines.from_budget(10.0, 100.0, SEARCH_SHARE)
    assert d.search == pytest.approx(10.0 + SEARCH_SHARE * 0.1) and d.checks == pytest.approx(10.1)
    assert NO_LIMIT.may_search() and NO_LIMIT.may_check()
    assert not Deadlines.from_budget(0.0, 1.0, SEARCH_SHARE).may_check()  # perf_counter is far past 1 ms


def test_negative_budget_is_refused():
    with pytest.raises(ValueError, match="time_budget_ms must be >= 0"):
        matcher.Tolerances(time_budget_ms=-1.0)


def test_spent_budget_is_a_reason_not_a_guess(small_map, cam):
    fr = make_frame(small_map, cam, np.random.default_rng([7, 3]), 3)
    res = matcher.localize(small_map, cam, fr.lines, fr.prior, fr.dt, fr.dyaw, SPENT)
    assert not res
    assert "(time budget of 1e-09 ms spent; --budget-ms" in res.reason
    assert res.stage1.out_of_time is True


def test_budget_never_reached_changes_nothing(small_map, cam):
    roomy = replace(matcher.Tolerances(), time_budget_ms=1e7)
    rng = np.random.default_rng([7, 4])
    for _ in range(4):
        fr = make_frame(small_map, cam, rng, 4)
        a = matcher.localize(small_map, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        b = matcher.localize(small_map, cam, fr.lines, fr.prior, fr.dt, fr.dyaw, roomy)
        assert (bool(a), a.pose, a.matches, a.score, a.hypotheses) == (bool(b), b.pose, b.matches, b.score,
                                                                        b.hypotheses)
        assert b.stage1.out_of_time is False


@pytest.mark.slow
def test_budget_stops_a_long_search(cam):
    """A view along the example flat's row of door jambs (seed 0, PEQ 5,
    frame 29 of tools/bench_paper.py): unbudgeted, its tree runs to the node
    budget (about 1900 nodes, over a second here). With 50 ms it stops after
    a few hundred nodes at most, and says so."""
    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    rng = np.random.default_rng([0, 5])
    frames = [make_frame(linemap, cam, rng, 5, 1.0, 1.0, clutter=3) for _ in range(30)]
    fr = frames[29]
    tol = replace(matcher.Tolerances(), time_budget_ms=50.0)
    res = matcher.localize(linemap, cam, fr.lines, fr.prior, fr.dt, fr.dyaw, tol)
    assert res.stage1.out_of_time is True
    assert res.stage1.tree_nodes < 1000
    assert "second_search" not in res.time_ms


def test_pairwise_tests_stop_at_the_search_deadline(small_map, cam):
    """The pairwise tests are stage 1's longest step on a cluttered real view
    (thousands of correspondences, millions of pairs): they stop at the
    search deadline, and stage 1 hands on no sets, truncated and out of time."""
    from matcher.candidates import select_candidates
    from matcher.frame import prepare_lines
    from matcher.search.tree.generate import generate
    from matcher.search.tree.pairwise import pair_compatibility

    fr = make_frame(small_map, cam, np.random.default_rng([7, 5]), 5)
    img = prepare_lines(cam, np.asarray(fr.lines, float), DEFAULT)
    prior = (fr.prior[0], fr.prior[1], math.radians(fr.prior[2]), fr.dt, math.radians(fr.dyaw))
    cands = select_candidates(small_map, cam, prior, DEFAULT)
    past = Deadlines(search=0.0, checks=0.0)
    hyps = generate(cands, cam, img, prior, DEFAULT, past)
    assert hyps.sets == [] and hyps.truncated and hyps.counts["out_of_time"] is True
    assert hyps.tree_input is None and "compatible_pairs" not in hyps.counts
    corr = _correspondences(cands, cam, img, prior)
    assert pair_compatibility(img, corr, prior[3], DEFAULT, past) is None
    assert pair_compatibility(img, corr, prior[3], DEFAULT).shape == (len(corr), len(corr))
    assert generate(cands, cam, img, prior, DEFAULT).sets  # unbudgeted, the same frame has sets


def _correspondences(cands, cam, img, prior):
    from matcher.search.tree.correspondences import find_correspondences

    return find_correspondences(cands.reps, cam, img, prior, DEFAULT, cands.sight, cands.faces, {})


def test_lost_mode_budget_bounds_the_whole_call(small_map, cam):
    fr = make_frame(small_map, cam, np.random.default_rng(3), 1)
    res = matcher.localize_global(small_map, cam, fr.lines, SPENT)
    assert not res
    assert res.reason == (f"no region gave an accepted hypothesis (0 voted places and 0 of {small_map.n_regions} regions tried; "
                          "the time budget of 1e-09 ms ran out)")
    assert res.time_ms["regions_tried"] == 0


def test_lost_mode_tries_the_largest_regions_first(cam, monkeypatch):
    """With no estimate the robot most likely stands on the most floor, and a
    budget spent early has searched the most of it. (The example flat's
    region ids do not follow area; each region's search is replaced by a
    spy that records it; the voted places come first and are not counted.)"""
    import matcher.from_prior as from_prior
    from matcher.result import LocalizeResult

    linemap = matcher.load_map(ROOT / "maps" / "flat.lmap")
    centres, seen = linemap.region_centres(), []

    def spy(linemap, camera, img, px, tol, t0, deadlines, scope):
        if scope.candidate_ids is not None:  # a region's search, not a voted place's
            seen.append(int(np.argmin(np.hypot(*(centres - px[:2]).T))))
        return LocalizeResult(False, "not searched")

    monkeypatch.setattr(from_prior, "localize_prepared", spy)
    fr = make_frame(linemap, cam, np.random.default_rng(3), 1)
    res = matcher.localize_global(linemap, cam, fr.lines)
    assert not res and res.time_ms["regions_tried"] == linemap.n_regions
    areas = linemap.region_areas()
    assert not (np.diff(areas) <= 0).all()  # id order is not area order
    first_pass = seen[:linemap.n_regions]  # (nothing accepted: a second pass runs the whole strategy)
    assert sorted(first_pass) == list(range(linemap.n_regions))
    assert (np.diff(areas[first_pass]) <= 0).all()
