"""Stage 2: the lines a hypothesis left unmatched that fit visible segments
at its pose, added back (a hypothesis that lost a true line to a clutter
line in stage 1 gets it back; a line broken in pieces is explained whole).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linemap.geometry import project_segments
from matcher.stage2.fit import fit_bound_px, fits_lines, sight_points, visible_points
from matcher.stage2.matches import Matches


def extend_all(camera, image_lines, segs, poses, m: Matches, hyps, tol, walls) -> Matches:
    """For each hypothesis h of ``hyps``: the (segment, line) pairs that fit
    at its pose ``poses[h]`` among its unmatched usable lines (see
    :func:`fits`; the segment visible too), closest first, each line once.
    A segment takes a further line only where that line shows another part
    of it than its lines so far (they overlap by at most the end-point
    noise): a detector breaks a line where its contrast fades or something
    stands in front, and the pieces are all explained by the one segment,
    while one-to-one matching would leave all but one unexplained (and a
    wrong pose that spreads the pieces over several segments would explain
    more lines). All hypotheses' pairs are tested in one batch. Returns
    the pairs to add; ``m`` the matches so far."""
    return extend_cameras([Extension(camera, image_lines, segs, poses, m, hyps, walls)], tol)[0]


@dataclass(frozen=True)
class Extension:
    """One camera's part of :func:`extend_cameras`: :func:`extend_all`'s
    arguments."""

    camera: object
    image_lines: object
    segs: np.ndarray
    poses: np.ndarray
    m: Matches
    hyps: np.ndarray
    walls: object


def extend_cameras(parts: list[Extension], tol) -> list[Matches]:
    """:func:`extend_all` of several cameras (a rig's, each at its own
    poses): the pairs to add, one :class:`Matches` per part. The fit and
    sight tests of every camera's pairs run as one batch (the cameras of a
    rig share the map's walls): a rig's verification asks this for all its
    cameras at once, over and over."""
    empty = Matches(*(np.zeros(0, dtype=np.int64),) * 3)
    pairs = [_candidate_pairs(part, tol) for part in parts]
    live = [k for k, p in enumerate(pairs) if p is not None]
    if not live:
        return [empty] * len(parts)
    lines = [parts[k].image_lines.lines[pairs[k].li] for k in live]
    ok, dist = fits_lines(np.concatenate(lines), np.concatenate([pairs[k].uv[pairs[k].pc, pairs[k].si] for k in live]),
                          np.concatenate([pairs[k].in_front[pairs[k].pc, pairs[k].si] for k in live]), tol)
    bounds = np.cumsum([0] + [len(x) for x in lines])
    seen = [np.nonzero(ok[a:b])[0] for a, b in zip(bounds[:-1], bounds[1:])]
    shown = [sight_points(parts[k].camera, parts[k].poses[pairs[k].ph[s]], parts[k].segs[pairs[k].si[s]], x[s],
                          tol.stage2) for k, s, x in zip(live, seen, lines)]
    clear = visible_points(shown, [parts[k].walls for k in live], tol.stage2, tol.shared)
    out = [empty] * len(parts)
    for k, a, b, s, c in zip(live, bounds[:-1], bounds[1:], seen, clear):
        keep = ok[a:b]
        keep[s] = c
        out[k] = _closest_first(parts[k], pairs[k], keep, dist[a:b], tol)
    return out


@dataclass(frozen=True)
class _Pairs:
    """One camera's (hypothesis, free line, segment) pairs that may fit:
    contender ``pc``, line ``li``, segment ``si`` and hypothesis ``ph``
    (P,) each; the segments projected, ``uv`` (C, N, 2, 2) and
    ``in_front`` (C, N); ``matched`` (contender, segment) -> its lines."""

    pc: np.ndarray
    li: np.ndarray
    si: np.ndarray
    ph: np.ndarray
    uv: np.ndarray
    in_front: np.ndarray
    matched: dict


def _candidate_pairs(part: Extension, tol) -> _Pairs | None:
    """The pairs of ``part`` to test (None: none)."""
    image_lines, segs, hyps, m = part.image_lines, part.segs, part.hyps, part.m
    usable = np.nonzero(image_lines.usable)[0]
    if not len(hyps) or not len(usable) or not len(segs):
        return None
    # Every candidate segment projected once per hypothesis (C, N, 2, 2).
    uv, in_front = project_segments(part.camera, part.poses[hyps][:, None, :],
                                    np.broadcast_to(segs, (len(hyps),) + segs.shape), tol.stage2.near_plane_m)
    # The lines each hypothesis left free, and the lines on each of its segments.
    may = _may_fit(image_lines.lines[usable], uv, in_front, tol)
    matched = {}  # (contender, segment) -> the lines on it
    if len(m):  # the lines matched before (none when a rig's verification matches afresh)
        where = {h: c for c, h in enumerate(hyps.tolist())}
        free = np.ones((len(hyps), len(image_lines.usable)), dtype=bool)
        mine = np.nonzero(np.isin(m.hyp, hyps))[0]
        for h_, s_, l_ in zip(m.hyp[mine].tolist(), m.local[mine].tolist(), m.line[mine].tolist()):
            free[where[h_], l_] = False
            matched.setdefault((where[h_], s_), []).append(l_)
        may &= free[:, usable, None]
    pc, ui, si = np.nonzero(may)
    if not len(pc):  # no usable line left free near a segment
        return None
    return _Pairs(pc, usable[ui], si, hyps[pc], uv, in_front, matched)


def _closest_first(part: Extension, pairs: _Pairs, ok: np.ndarray, dist: np.ndarray, tol) -> Matches:
    """The pairs of ``pairs`` that fit and are seen (``ok``), closest first
    within each hypothesis; a line is added once, a segment again only for
    a part of it not shown yet (:func:`extend_all`)."""
    pc, li, si, ph, uv, matched = pairs.pc, pairs.li, pairs.si, pairs.ph, pairs.uv, pairs.matched
    out_h, out_l, out_s = [], [], []
    lines_taken = set()  # (hypothesis, line)
    cand = np.nonzero(ok)[0]
    cand = cand[np.lexsort((dist[cand], ph[cand]))]
    # Each pair's line's span along its projected segment, all at once;
    # the spans of the lines already on a segment (the matches before this
    # extension) the first time a pair of that segment asks.
    spans = _spans_along(uv[pc[cand], si[cand]], part.image_lines.lines[li[cand]]).tolist()
    on_spans: dict = {}  # (contender, segment) -> the spans of the lines on it
    overlap_px = 2.0 * tol.line_end_px
    for c, h, s_, l_, (lo, hi) in zip(pc[cand].tolist(), ph[cand].tolist(), si[cand].tolist(), li[cand].tolist(),
                                      spans):
        if (h, l_) in lines_taken:
            continue
        on_it = on_spans.get((c, s_))
        if on_it is None:
            before = matched.get((c, s_), [])
            on_it = on_spans[(c, s_)] = _spans_along(np.broadcast_to(uv[c, s_], (len(before), 2, 2)),
                                                     part.image_lines.lines[before]).tolist() if before else []
        if any(min(b, hi) - max(a, lo) > overlap_px for a, b in on_it):
            continue
        on_it.append((lo, hi))
        lines_taken.add((h, l_))
        out_h.append(h)
        out_s.append(s_)
        out_l.append(l_)
    return Matches(np.array(out_h, dtype=np.int64), np.array(out_s, dtype=np.int64), np.array(out_l, dtype=np.int64))


def _may_fit(lines: np.ndarray, uv: np.ndarray, in_front: np.ndarray, tol) -> np.ndarray:
    """(C, U, N) bool: whether each line (U, 2, 2) may fit each projected
    segment ``uv`` (C, N, 2, 2) (``in_front`` (C, N)), by two consequences
    of :func:`~matcher.stage2.fit.fits` that cost one product per pair:
    both end points within the fit bound of the segment's line, so its
    middle is too, and the line turned from it by no more than twice the
    bound over its length allows. Pairs it drops cannot fit; the pairs it
    keeps get the whole test (most pairs of a view are far apart)."""
    dl = lines[:, 1] - lines[:, 0]
    L = np.hypot(dl[:, 0], dl[:, 1])
    bound = (fit_bound_px(L, tol) + 1e-6)[None, :, None]  # a hair over: rounding never drops a pair that fits
    mid = 0.5 * (lines[:, 0] + lines[:, 1])
    d = uv[..., 1, :] - uv[..., 0, :]
    lq = np.hypot(d[..., 0], d[..., 1])
    nx, ny = -d[..., 1] / np.maximum(lq, 1e-9), d[..., 0] / np.maximum(lq, 1e-9)  # (C, N) unit normals
    off = nx * uv[..., 0, 0] + ny * uv[..., 0, 1]
    across = np.abs(mid[None, :, 0, None] * nx[:, None] + mid[None, :, 1, None] * ny[:, None] - off[:, None])
    turn = np.abs(dl[None, :, 0, None] * nx[:, None] + dl[None, :, 1, None] * ny[:, None])  # L sin(angle)
    return (in_front & (lq > 1e-6))[:, None] & (across <= bound) & (turn <= 2.0 * bound)


def _spans_along(uv: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """(T, 2) the interval, pixels, that each line (T, 2, 2) covers along its
    projected segment ``uv`` (T, 2, 2), from the segment's first end point."""
    d = uv[:, 1] - uv[:, 0]
    d = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    t = np.einsum("tek,tk->te", lines - uv[:, None, 0], d)
    return np.sort(t, axis=1)
