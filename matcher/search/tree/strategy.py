"""The matcher's strategy: an ordered list of hypothesis sources, stage 2
after each.

The paper's method is one pass: stage 1 (generate hypotheses) then stage 2
(verify them). Three sources of hypotheses stand here, tried in this order,
each when the answer so far calls for it:

1. :class:`TreeSearch`, the interpretation tree of stage 1
   (:func:`matcher.search.tree.generate.generate`): always.
2. :class:`SecondSearch`, the tree again keeping sets one smaller than the
   largest (``match_slack`` 1), when stage 2 doubts the answer: nothing was
   accepted, or the best hypothesis kept fewer matches than the largest set
   had (a clutter line may have padded the largest sets past the true one).
3. :class:`Resection`, poses resected from triples of vertical edges
   (:mod:`matcher.search.tree.resection`), when the tree ran out of budget or
   nothing it found held: where vertical edges leave the position loose the
   tree meets thousands of sets.

A source that adds hypotheses replaces the current ones and stage 2
(:func:`matcher.stage2.rank.verify_hypotheses`) ranks them; the answer that
no later source doubts stands. The time budget stops the sources after the
first (``Deadlines.search``); a source skipped or dropped for want of time
marks the answer as cut short.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from matcher.budget import Deadlines
from matcher.candidates import Candidates
from matcher.frame import ImageLines
from matcher.search.tree.generate import Hypotheses, generate, search_again
from matcher.search.tree.resection import EdgeCorrespondences, vertical_hypotheses
from matcher.stage2.rank import Ranked, verify_hypotheses
from matcher.tolerances import Tolerances
from matcher.verdict import score_accepted


@dataclass(frozen=True)
class Problem:
    """One localisation's fixed inputs: the camera, the frame's image lines,
    the candidates, the prior ``(xe, ye, yaw_e, dt, dyaw)`` (radians), the
    tolerances and the time budget."""

    camera: object
    lines: ImageLines
    cands: Candidates
    prior: tuple
    tol: Tolerances
    deadlines: Deadlines


@dataclass
class Answer:
    """The hypotheses so far (None before the first source), their ranking
    by stage 2 (None while there are none), whether the time budget cut a
    source (``spent``) and each source's milliseconds (``times``)."""

    hyps: Hypotheses | None = None
    ranked: Ranked | None = None
    spent: bool = False
    times: dict = field(default_factory=dict)

    def accepted(self, tol: Tolerances) -> bool:
        """Is the best ranked hypothesis's score accepted
        (:func:`matcher.verdict.score_accepted`)? The strategy looks at the
        score alone: the verdict's other tests judge the final ranking."""
        r = self.ranked
        return r is not None and score_accepted(r.score[r.order[0]], tol)


class TreeSearch:
    """Stage 1: the interpretation tree on the frame's correspondences."""

    name = "generate"
    needs_time = False  # the first source runs whatever the budget

    def applies(self, answer: Answer, tol: Tolerances) -> bool:
        return answer.hyps is None

    def run(self, answer: Answer, problem: Problem) -> Hypotheses | None:
        return generate(problem.cands, problem.camera, problem.lines, problem.prior, problem.tol, problem.deadlines)


class SecondSearch:
    """The tree again, keeping sets one smaller than the largest."""

    name = "second_search"
    needs_time = True

    def applies(self, answer: Answer, tol: Tolerances) -> bool:
        return answer.ranked is not None and tol.match_slack == 0 and doubtful(answer.ranked, answer.hyps, tol)

    def run(self, answer: Answer, problem: Problem) -> Hypotheses | None:
        again = search_again(answer.hyps, replace(problem.tol, match_slack=1))
        if again.counts["out_of_time"]:  # cut short: the first search's sets stand
            answer.spent = True
            return None
        return again


class Resection:
    """Poses resected from triples of vertical edges, with the best few of
    the tree's sets that stage 2 kept."""

    name = "resection"
    needs_time = True

    def applies(self, answer: Answer, tol: Tolerances) -> bool:
        hyps = answer.hyps
        if hyps is None or "resection" in hyps.counts:
            return False
        return hyps.truncated or (answer.ranked is not None and not answer.accepted(tol))

    def run(self, answer: Answer, problem: Problem) -> Hypotheses | None:
        ranked, kept = answer.ranked, problem.tol.stage1.tree_sets_kept
        held = [] if ranked is None else [int(h) for h in ranked.order if np.isfinite(ranked.score[h])][:kept]
        more = with_resection(answer.hyps, held, problem)
        # With nothing ranked yet the resection's (possibly empty) sets stand,
        # its count with them; otherwise only if it found some.
        return more if (more.counts["resection"] or ranked is None) else None


#: The interpretation tree alone, no source after it: lost mode's first
#: sweep of the regions (the second search and the resection cost most
#: where the robot is not) and an attitude band's quick run.
TREE_ALONE = (TreeSearch(),)

#: The strategy: the sources in the order they are tried.
SOURCES = TREE_ALONE + (SecondSearch(), Resection())


def run_strategy(problem: Problem, sources=SOURCES) -> Answer:
    """The answer after each source of ``sources`` that the answer so far
    calls for has run, stage 2 after each that added hypotheses.
    ``times``: the first source's milliseconds under its name, each later
    one's (with its stage 2) under its own, and ``verify`` from the end of
    the first source to the end."""
    answer, tol = Answer(), problem.tol
    t_first = None
    for source in sources:
        if not source.applies(answer, tol):
            continue
        if source.needs_time and not problem.deadlines.may_search():
            answer.spent = True
            continue
        t = time.perf_counter()
        new = source.run(answer, problem)
        t_run = time.perf_counter()
        if new is not None:
            answer.hyps = new
            answer.ranked = (verify_hypotheses(problem.camera, problem.lines, problem.cands, new, problem.prior, tol)
                             if new.sets else None)
        if t_first is None:
            answer.times[source.name] = (t_run - t) * 1e3
            t_first = t_run
        else:
            answer.times[source.name] = (time.perf_counter() - t) * 1e3
    if t_first is not None and answer.ranked is not None:
        answer.times["verify"] = (time.perf_counter() - t_first) * 1e3
    return answer


def with_resection(hyps: Hypotheses, held: list[int], problem: Problem) -> Hypotheses:
    """The sets ``held`` (indices) of ``hyps`` followed by those of
    :mod:`matcher.search.tree.resection` (poses resected from triples of vertical
    edges), at most ``max_hypotheses`` in all; ``counts["resection"]`` says
    how many the resection gave."""
    tol = problem.tol
    counts = dict(hyps.counts)
    counts["resection"] = 0
    inp = hyps.tree_input
    if inp is None:
        return replace(hyps, counts=counts)
    edges = EdgeCorrespondences(problem.cands.reps[hyps.segment, 0, :2], hyps.segment, hyps.line, inp.vertical,
                                inp.compat, problem.lines.alpha, problem.lines.alpha_eps)
    sets, inits = vertical_hypotheses(edges, problem.prior, problem.cands.free, tol, tol.max_hypotheses - len(held),
                                      min_lines=tol.min_matches + 1, deadline=problem.deadlines.search)
    counts["resection"] = len(sets)
    init = hyps.init.reshape(-1, 3)[held]
    return replace(hyps, sets=[hyps.sets[h] for h in held] + sets, init=np.concatenate([init, inits]),
                   counts=counts)


def doubtful(ranked: Ranked, hyps: Hypotheses, tol: Tolerances) -> bool:
    """Nothing accepted, or the best hypothesis kept fewer matches than the
    largest stage-1 set had (and stage 1 was not cut short): a clutter line
    may have padded the largest sets past the true one. One match fewer is
    doubted only when the best also fits loosely (E above ``e_doubt``): a
    clutter line dropped from the true set leaves it fitting as well as
    ever, while the remains of a padded set, whose clutter line took a true
    line's segment, sit at a pose a few centimetres off."""
    if hyps.truncated:  # a second search would run out of budget too
        return False
    best = int(ranked.order[0])
    if not score_accepted(ranked.score[best], tol):
        return True
    short = max(len(x) for x in hyps.sets) - int((ranked.matches.hyp == best).sum())
    return short >= 2 or (short == 1 and ranked.score[best] > tol.e_doubt)
