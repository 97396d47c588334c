"""The one verdict (matcher/verdict.py): each test of the evidence in its
order, the reasons as the result's JSON gives them, and the strategy's
score test the same as the verdict's."""

from __future__ import annotations

from dataclasses import replace

import pytest

from matcher.result import Deferred
from matcher.tolerances import DEFAULT
from matcher.verdict import (ACCEPTED, AMBIGUOUS, BY_SEARCH_BUDGET, BY_TIME, NOT_LOCALISED, Evidence, Sweep,
                             Verdict, decide, score_accepted)

TOL = DEFAULT


def _never():
    raise AssertionError("read although an earlier test decided")


def _good(**changes) -> Evidence:
    """A best pose that passes every test, with one rival elsewhere that
    explains fewer lines."""
    ev = Evidence(score=1e-4, coverage=Deferred(lambda: (10, 9)), explained=6, searched=12, needed=4,
                  answers=(((1.0, 2.0, 30.0), 6, 1e-4, 1.0), ((5.0, 2.0, 30.0), 5, 1e-4, 1.0)),
                  spread=Deferred(_never))
    return replace(ev, **changes)


def test_a_pose_that_passes_every_test_is_accepted():
    v = decide(_good(), TOL)
    assert v and v.status == ACCEPTED and v.reason == "" and v.score == 1e-4 and v.candidates == ()


def test_nothing_searched_or_found_says_why_and_how_the_search_was_cut():
    v = decide(Evidence(unsearched="no time left to search after preparing 9 lines", cut=BY_TIME), TOL)
    assert not v and v.status == NOT_LOCALISED
    assert v.reason == ("no time left to search after preparing 9 lines (time budget of 30000 ms spent; "
                        "--budget-ms, Tolerances.time_budget_ms)")
    v = decide(Evidence(n_correspondences=7, cut=BY_SEARCH_BUDGET), TOL)
    assert v.reason == ("no consistent set of 3 or more correspondences (7 correspondences passed the unary tests)"
                        " (hypothesis search truncated)")


def test_the_score_is_tested_first_and_reported():
    v = decide(_good(score=5e-3, coverage=Deferred(_never)), TOL)
    assert v.status == NOT_LOCALISED and v.score == 5e-3
    assert v.reason == "best score E=0.005 is above the acceptance threshold 0.002"
    v = decide(_good(score=float("inf"), unscored="no hypothesis kept 3 matches that fit at its pose",
                     coverage=Deferred(_never)), TOL)
    assert v.reason == "no hypothesis kept 3 matches that fit at its pose" and v.score is None
    assert score_accepted(TOL.e_accept, TOL) and not score_accepted(float("nan"), TOL)


def test_a_rig_brings_its_own_score_threshold():
    """A rig's evidence carries its best pose's own threshold (the E its
    matches' noise allows, :func:`matcher.rig.verify.e_limit`): a score
    above the single camera's threshold and within it passes, and a
    refusal names the threshold that refused it."""
    limit = 4.0 * TOL.e_accept
    between = 0.5 * (TOL.e_accept + limit)
    assert not decide(_good(score=between), TOL)
    assert decide(_good(score=between, e_accept=limit), TOL)
    v = decide(_good(score=1.0, e_accept=limit), TOL)
    assert v.reason == f"best score E=1 is above the acceptance threshold {limit:g}"


def test_coverage_then_the_lines_explained():
    v = decide(_good(coverage=Deferred(lambda: (10, 2))), TOL)
    assert v.status == NOT_LOCALISED and v.score is None
    assert v.reason == ("the best pose predicts 10 map segments in view and the image shows 2 of them: the lines do "
                        "not look like the map there")
    assert decide(_good(coverage=Deferred(lambda: (7, 0))), TOL)  # too few predicted to judge
    v = decide(_good(explained=3), TOL)
    assert v.reason == "the best pose explains 3 of the 12 longest lines, fewer than the 4 that clutter makes needed"


def test_a_rival_explaining_as_many_lines_elsewhere_makes_it_ambiguous():
    rival = ((5.0, 2.0, 30.0), 6, 1.5e-4, 1.2)
    v = decide(_good(answers=(_good().answers[0], rival), spread=Deferred(lambda: (0.01, 0.01, 0.1))), TOL)
    assert v.status == AMBIGUOUS and len(v.candidates) == 2
    assert v.reason.startswith("2 poses fit the lines about equally well (each explains 6 lines")
    assert [c["x"] for c in v.candidates] == [1.0, 5.0]
    # Within the best pose's own spread: the same answer told imprecisely.
    near = ((1.2, 2.0, 30.0), 6, 1.5e-4, 1.2)
    assert decide(_good(answers=(_good().answers[0], near), spread=Deferred(lambda: (0.01, 0.01, 0.1))), TOL)


@pytest.mark.parametrize("cut, explained, ok", [(BY_TIME, 3, False), (BY_TIME, 6, True), ("", 3, True)])
def test_lost_mode_cut_short_trusts_only_an_answer_explaining_most_lines(cut, explained, ok):
    answers = (((1.0, 2.0, 30.0), explained, 1e-4),)
    ev = Evidence(answers=answers, standing=Verdict(ACCEPTED, score=1e-4), cut=cut,
                  sweep=Sweep(places=2, regions=3, of=10, explained=explained, usable=10))
    v = decide(ev, TOL)
    assert bool(v) is ok
    if not ok:
        assert v.candidates == ({"x": 1.0, "y": 2.0, "yaw_deg": 30.0, "matches": 3, "score": 1e-4},)
        assert v.reason.endswith("the best pose so far explains 3 of 10 lines, too few to trust unchecked")


def test_lost_mode_keeps_its_best_answers_own_verdict_and_says_what_it_searched():
    own = Verdict(AMBIGUOUS, "2 poses fit ...", ({"x": 1.0},))
    ev = Evidence(answers=(((1.0, 2.0, 30.0), 5, 1e-4),), standing=own, sweep=Sweep(2, 3, 10, 5, 10))
    assert decide(ev, TOL) is own
    v = decide(Evidence(sweep=Sweep(4, 3, 10), cut=BY_TIME), TOL)
    assert v.reason == ("no region gave an accepted hypothesis (4 voted places and 3 of 10 regions tried; the time "
                        "budget of 30000 ms ran out)")

