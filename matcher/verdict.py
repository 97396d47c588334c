"""One verdict: is the best pose accepted, is the frame not localised, or
do several poses fit that the evidence cannot tell apart?

Every way of localising gathers what it knows of its best pose in one
:class:`Evidence` record and asks :func:`decide`: a prior's search
(:mod:`matcher.from_prior`), lost mode over the voted places and the
regions (:mod:`matcher.lost`), and next a rig of cameras. The tests, in
this order, each where its evidence is given:

1. a search ran at all (candidates, usable lines, time left);
2. it found a consistent set (a prior's search), or some place or region
   gave an answer (lost mode);
3. the best pose's score E is within ``e_accept`` (method.md section 8):
   :func:`score_accepted`, the one test the strategy
   (:mod:`matcher.search.tree.strategy`) also asks while it chooses its sources;
4. the map segments the pose predicts in view are seen
   (``coverage_min_predicted``, ``coverage_min_share``);
5. it explains clearly more lines than the best answer at another place
   (a rig: ``RigConstants.clear_ratio``), and the lines that clutter
   makes needed (``lines_needed``);
6. no rival explains as many lines and fits about as well at a pose
   elsewhere (:mod:`matcher.ambiguity`); a search that ranked the whole
   prior (:mod:`matcher.search.structure`) gives its runner-up, the best
   pose elsewhere, as a rival however few lines it explains, and a
   refusal then names it beside the best;
7. lost mode: the best answer's own verdict in its search stands;
8. lost mode cut short by the time budget: the best so far explains most
   of the image (``vote_trust_share``), or it is only a candidate;
9. the matched lines do not say the camera file's calibration is wrong
   (:mod:`matcher.stage2.calibration_check`: a focal length, height or
   principal point that fits them far better); last, as it is the dearest
   and judges only a pose that would be accepted.

The verdict carries the failure's reason (the words of the result's JSON,
a contract) and the candidates it names; the results are built from it and
never edited after.
"""

from __future__ import annotations

from dataclasses import dataclass

from matcher import ambiguity
from matcher.result import Deferred
from matcher.tolerances import LostConstants, Tolerances

ACCEPTED, NOT_LOCALISED, AMBIGUOUS = "accepted", "not_localised", "ambiguous"

#: How a search was cut short (:attr:`Evidence.cut`): not at all, by the
#: time budget, by stage 1's node or set budget.
UNCUT, BY_TIME, BY_SEARCH_BUDGET = "", "time", "search"


@dataclass(frozen=True)
class Verdict:
    """``status`` (:data:`ACCEPTED`, :data:`NOT_LOCALISED`, :data:`AMBIGUOUS`),
    the failure's ``reason`` ("" when accepted), the ``candidates`` it names
    (dicts of x, y, yaw_deg, matches, score) and the ``score`` the result
    reports (the best pose's E when it is accepted or refused for it; else
    None); ``miscalibrated``: refused because the best pose's lines say the
    camera file is wrong (lost mode then refuses the whole map, not just
    that piece of it)."""

    status: str
    reason: str = ""
    candidates: tuple = ()
    score: float | None = None
    miscalibrated: bool = False

    def __bool__(self) -> bool:
        return self.status == ACCEPTED

    @classmethod
    def of_result(cls, res) -> Verdict:
        """The verdict a :class:`~matcher.result.LocalizeResult` carries."""
        status = ACCEPTED if res.ok else AMBIGUOUS if res.candidates else NOT_LOCALISED
        return cls(status, res.reason, tuple(res.candidates), res.score)


@dataclass(frozen=True)
class Sweep:
    """Lost mode's search of the map: the voted ``places`` searched, the
    ``regions`` tried of ``of`` in the map; the best answer explains
    ``explained`` of the frame's ``usable`` lines."""

    places: int
    regions: int
    of: int
    explained: int = 0
    usable: int = 0


@dataclass(frozen=True)
class Evidence:
    """What a search knows of its best pose; each field None (or empty)
    where it was not measured, and the test that needs it skipped.

    ``unsearched``: why no search ran ("" when one did).
    ``n_correspondences``: correspondences through the unary tests (a
    prior's search that found no consistent set says how many).
    ``score``: E of the best ranked hypothesis (not finite when stage 2
    dropped every one, ``unscored`` then saying why); None when nothing was
    ranked. ``coverage``: ``(predicted, seen)`` map segments in view at the
    best pose, worked out when read. ``explained``: the lines among the
    ``searched`` ones (the longest, :func:`matcher.frame.searched_lines`)
    that the best pose explains; ``needed``: how many it must
    (:func:`matcher.frame.lines_needed`).
    ``answers``: ``(pose (x, y, yaw_deg), matches, E[, cost])`` of every
    scored answer, best first (the second is the runner-up; the rivals for
    :mod:`matcher.ambiguity`); ``spread``: the best pose's standard
    deviations as :func:`matcher.ambiguity.spread_of` gives them, worked
    out when read (None: not known).
    ``standing``: lost mode, the best answer's own verdict in its search.
    ``sweep``: lost mode's search of the map (:class:`Sweep`).
    ``cut``: how the search was cut short (:data:`UNCUT`, :data:`BY_TIME`,
    :data:`BY_SEARCH_BUDGET`).
    ``clear_ratio``: when set (a rig, whose verification scores answers at
    many places), the best must explain this many times the lines of the
    best answer at another place (:func:`matcher.ambiguity.rival_apart`):
    how many lines a wrong place explains by chance, measured on the frame
    itself instead of a share fixed in advance.
    ``e_accept``: when set (a rig), the acceptance threshold of E in place
    of ``Tolerances.e_accept``: the E the best pose's own matches may reach
    within their noise (:func:`matcher.rig.verify.e_limit`).
    ``calibration``: why the best pose's matched lines say the camera
    file's calibration is wrong ("" when they do not), worked out when read
    (:func:`matcher.stage2.calibration_check.doubt`).
    ``runner_up``: a search that ranked every pose of the prior (the
    structure search), its best pose elsewhere as an answer ``(pose, lines
    explained once verified (0: not verified), E, cost)``: a rival always
    known, named in a refusal."""

    unsearched: str = ""
    n_correspondences: int = 0
    score: float | None = None
    unscored: str = ""
    coverage: Deferred | None = None
    explained: int | None = None
    searched: int = 0
    needed: int = 0
    answers: tuple = ()
    spread: Deferred | None = None
    standing: Verdict | None = None
    sweep: Sweep | None = None
    cut: str = UNCUT
    clear_ratio: float | None = None
    e_accept: float | None = None
    calibration: Deferred | None = None
    runner_up: tuple | None = None


def score_accepted(score: float, tol: Tolerances, limit: float | None = None) -> bool:
    """Is E = ``score`` within the acceptance threshold (method.md
    section 8: ``tol.e_accept``, or ``limit`` when given; not for a NaN)?"""
    return bool(score <= (tol.e_accept if limit is None else limit))


def trusted(explained: int, usable: int, work: LostConstants) -> bool:
    """Does an answer explaining ``explained`` of the frame's ``usable``
    lines explain most of the image (``vote_trust_share``), so that no
    other place could explain much more?"""
    return explained >= work.vote_trust_share * usable


def decide(ev: Evidence, tol: Tolerances) -> Verdict:
    """The verdict on ``ev`` (the module docstring's tests, in order); a
    refusal that names no candidate names the best pose and ``ev.runner_up``
    when it is known."""
    verdict = _decide(ev, tol)
    if verdict.status != NOT_LOCALISED or verdict.candidates or ev.runner_up is None or not ev.answers:
        return verdict
    x, y, yaw = ev.runner_up[0]
    return Verdict(NOT_LOCALISED, f"{verdict.reason}; the best pose elsewhere is ({x:.2f}, {y:.2f}, {yaw:.0f} deg)",
                   tuple(ambiguity.candidates_of([ev.answers[0], ev.runner_up])), verdict.score)


def _decide(ev: Evidence, tol: Tolerances) -> Verdict:
    """:func:`decide` before the runner-up is named."""
    cut = cut_words(ev.cut, tol)
    if ev.unsearched:
        return Verdict(NOT_LOCALISED, ev.unsearched + cut)
    if ev.sweep is not None:
        if not ev.answers:
            return Verdict(NOT_LOCALISED, _nothing_found(ev.sweep, ev.cut, tol))
    elif ev.score is None:
        return Verdict(NOT_LOCALISED, f"no consistent set of {tol.min_matches} or more correspondences "
                                      f"({ev.n_correspondences} correspondences passed the unary tests)" + cut)
    else:
        refused = _refused(ev, tol, cut)
        if refused is not None:
            return refused
    kept = _rivals(ev, tol)
    if len(kept) > 1:
        return Verdict(AMBIGUOUS, ambiguity.reason(kept), tuple(ambiguity.candidates_of(kept)))
    if ev.standing is not None and not ev.standing:
        return ev.standing
    sweep = ev.sweep
    if sweep is not None and ev.cut == BY_TIME and not trusted(sweep.explained, sweep.usable, tol.lost):
        # Cut short, the best so far explains too little to stand for the
        # whole map (a place voted by chance, a look-alike room): a candidate.
        return Verdict(NOT_LOCALISED, f"the time budget of {tol.time_budget_ms:g} ms ran out before the whole map "
                                      f"was searched; the best pose so far explains {sweep.explained} of "
                                      f"{sweep.usable} lines, too few to trust unchecked",
                       tuple(ambiguity.candidates_of([ev.answers[0]])))
    miscalibrated = "" if ev.calibration is None else ev.calibration.get()
    if miscalibrated:
        return Verdict(NOT_LOCALISED, miscalibrated, score=ev.score, miscalibrated=True)
    return Verdict(ACCEPTED, score=ev.score)


def _refused(ev: Evidence, tol: Tolerances, cut: str) -> Verdict | None:
    """Tests 3 to 5 on the best pose alone: its score, its coverage of the
    map in view, the lines it explains; None when it passes them."""
    E, limit = ev.score, tol.e_accept if ev.e_accept is None else ev.e_accept
    if not score_accepted(E, tol, limit):
        finite = E == E and abs(E) != float("inf")
        why = ev.unscored if not finite else f"best score E={E:.3g} is above the acceptance threshold {limit:g}"
        return Verdict(NOT_LOCALISED, why + cut, score=float(E) if finite else None)
    work = tol.verdict
    if ev.coverage is not None:
        predicted, seen = ev.coverage.get()
        if predicted >= work.coverage_min_predicted and seen < work.coverage_min_share * predicted:
            return Verdict(NOT_LOCALISED, f"the best pose predicts {predicted} map segments in view and the image "
                                          f"shows {seen} of them: the lines do not look like the map there")
    if ev.clear_ratio is not None and ev.answers:
        rival = ambiguity.rival_apart(list(ev.answers), work, None if ev.spread is None else ev.spread.get())
        if rival is None or (ev.runner_up is not None and ev.runner_up[1] > rival[1]):
            rival = ev.runner_up
        if rival is not None and ev.answers[0][1] < ev.clear_ratio * rival[1]:
            return Verdict(NOT_LOCALISED, f"the best pose explains {ev.answers[0][1]} lines and a pose elsewhere "
                                          f"{rival[1]}: not {ev.clear_ratio:g} times as many, too few to tell them "
                                          "apart; the candidates name both",
                           tuple(ambiguity.candidates_of([ev.answers[0], rival])), score=ev.score)
    if ev.explained is not None and ev.explained < ev.needed:
        return Verdict(NOT_LOCALISED, f"the best pose explains {ev.explained} of the {ev.searched} longest lines, "
                                      f"fewer than the {ev.needed} that clutter makes needed")
    return None


def _rivals(ev: Evidence, tol: Tolerances) -> list:
    """The answers the best cannot be told from (:func:`matcher.ambiguity.rivals`),
    the best first; looked for only when the runner-up explains as many
    lines (the spread, dear to work out, is read only then)."""
    answers = ev.answers
    if len(answers) < 2 or answers[1][1] != answers[0][1]:
        return list(answers[:1])
    spread = None if ev.spread is None else ev.spread.get()
    return ambiguity.rivals(list(answers), tol.verdict, spread)


def _nothing_found(sweep: Sweep, cut: str, tol: Tolerances) -> str:
    """Lost mode's reason when no place or region gave an answer."""
    spent = f"; the time budget of {tol.time_budget_ms:g} ms ran out" if cut == BY_TIME else ""
    return (f"no region gave an accepted hypothesis ({sweep.places} voted places and {sweep.regions} of {sweep.of} "
            f"regions tried{spent})")


def cut_words(cut: str, tol: Tolerances) -> str:
    """What a failure's reason adds when the search stopped early: the time
    budget spent, or stage 1's node or set budget."""
    if cut == BY_TIME:
        return f" (time budget of {tol.time_budget_ms:g} ms spent; --budget-ms, Tolerances.time_budget_ms)"
    return " (hypothesis search truncated)" if cut == BY_SEARCH_BUDGET else ""
