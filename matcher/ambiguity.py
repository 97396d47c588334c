"""When the evidence does not single out one pose.

A symmetric room shows the same lines from two or four poses; a row of like
rooms, from one pose in each. The matcher then has hypotheses that explain
as many lines and fit about as well, at places far apart, and picking one
would be a guess told as a fact. Such an answer is falsy and names every
pose the evidence cannot tell apart (``LocalizeResult.candidates``).
"""

from __future__ import annotations

import math

from matcher.tolerances import VerdictConstants


def rivals(answers: list[tuple], work: VerdictConstants, spread: tuple[float, float, float] | None = None) -> list:
    """The answers of ``answers`` (each ``(pose (x, y, yaw_deg), matches,
    score E)``, or with a fourth item, the reprojection cost of stage 2's
    ranking; best first) that the first cannot be told from: as many
    matches, E within ``ambiguous_score_ratio`` of its (and the cost, when
    given, within ``ambiguous_cost_ratio``), each at a pose apart from the
    others kept. Apart means farther than ``ambiguous_m`` and
    ``ambiguous_sigmas`` of the best pose's standard deviations ``spread``
    ``(x, y, yaw_deg)`` (metres, degrees; None: not known; see
    :func:`spread_of` for a pose its matches do not fix), or turned more
    than ``ambiguous_deg`` and as many of its yaw's: a pose its lines fix
    loosely (a far column's corners) has near rivals along the loose
    direction, which are the same answer told imprecisely, not another
    place. On a building, a pose's fourth item is its storey: rivals on
    another storey are apart wherever they stand (the same room on two
    floors). The first is always kept: one answer means no ambiguity."""
    best = answers[0]
    reach_m, reach_deg = _reach(work, spread)
    kept = [best]
    for a in answers[1:]:
        if a[1] < best[1] or not a[2] <= work.ambiguous_score_ratio * best[2]:
            continue
        if len(a) > 3 and not a[3] <= work.ambiguous_cost_ratio * best[3]:
            continue
        if all(_apart(a[0], k[0], reach_m, reach_deg) for k in kept):
            kept.append(a)
    return kept


def rival_apart(answers: list[tuple], work: VerdictConstants, spread: tuple[float, float, float] | None = None):
    """The answer of ``answers`` (best first, as :func:`rivals` takes them)
    that explains the most lines at a pose apart from the best's (apart as
    :func:`rivals` says: ``ambiguous_m``, ``ambiguous_deg``, and the
    ``spread``), or None when every other answer is the same place."""
    reach_m, reach_deg = _reach(work, spread)
    apart = [a for a in answers[1:] if _apart(a[0], answers[0][0], reach_m, reach_deg)]
    return max(apart, key=lambda a: a[1]) if apart else None


def _reach(work: VerdictConstants, spread) -> tuple[float, float]:
    """How far (metres, degrees) another answer must be to be another place."""
    reach_m, reach_deg = work.ambiguous_m, work.ambiguous_deg
    if spread is not None:
        reach_m = max(reach_m, work.ambiguous_sigmas * max(spread[0], spread[1]))
        reach_deg = max(reach_deg, work.ambiguous_sigmas * spread[2])
    return reach_m, reach_deg


def spread_of(pose_std) -> tuple[float, float, float]:
    """:func:`rivals`' ``spread`` from a result's ``pose_std``: a pose its
    matches do not fix (None) is loose in position without bound, so only a
    rival turned away from it is another answer."""
    return (math.inf, math.inf, 0.0) if pose_std is None else tuple(pose_std)


def candidates_of(kept: list) -> list[dict]:
    """The result's ``candidates``: dicts of x, y, yaw_deg, matches, score
    (and the storey, on a building: a pose's fourth item)."""
    return [dict(x=a[0][0], y=a[0][1], yaw_deg=a[0][2], matches=int(a[1]), score=float(a[2]),
                 **({"storey": a[0][3]} if len(a[0]) > 3 else {})) for a in kept]


def reason(kept: list) -> str:
    """A failure's reason for ``kept`` poses that cannot be told apart."""
    storeys = {a[0][3] for a in kept if len(a[0]) > 3}
    what = f"like rooms on {len(storeys)} storeys" if len(storeys) > 1 else "a symmetric room or like rooms"
    return (f"{len(kept)} poses fit the lines about equally well (each explains {kept[0][1]} lines: {what}); "
            "the candidates name them")


def _apart(a, b, reach_m: float, reach_deg: float) -> bool:
    """Are poses ``a`` and ``b`` ``(x, y, yaw_deg[, storey])`` different
    places? Poses on two storeys of a building always are."""
    if len(a) > 3 and len(b) > 3 and a[3] != b[3]:
        return True
    dyaw = abs((a[2] - b[2] + 180.0) % 360.0 - 180.0)
    return math.hypot(a[0] - b[0], a[1] - b[1]) > reach_m or dyaw > reach_deg
