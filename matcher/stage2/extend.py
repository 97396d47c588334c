"""Stage 2: the lines a hypothesis left unmatched that fit visible segments
at its pose, added back (a hypothesis that lost a true line to a clutter
line in stage 1 gets it back; a line broken in pieces is explained whole).
"""

from __future__ import annotations

import numpy as np

from linemap.geometry import project_segments
from matcher.stage2.fit import fit_bound_px, fits_projected, visible
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
    usable = np.nonzero(image_lines.usable)[0]
    empty = np.zeros(0, dtype=np.int64)
    if not len(hyps) or not len(usable) or not len(segs):
        return Matches(empty, empty, empty)
    # Every candidate segment projected once per hypothesis (C, N, 2, 2).
    uv, in_front = project_segments(camera, poses[hyps][:, None, :], np.broadcast_to(segs, (len(hyps),) + segs.shape),
                                    tol.stage2.near_plane_m)
    # The lines each hypothesis left free, and the lines on each of its segments.
    where = {h: c for c, h in enumerate(hyps.tolist())}
    free = np.ones((len(hyps), len(image_lines.usable)), dtype=bool)
    matched = {}  # (contender, segment) -> the lines on it
    mine = np.nonzero(np.isin(m.hyp, hyps))[0]
    for h_, s_, l_ in zip(m.hyp[mine].tolist(), m.local[mine].tolist(), m.line[mine].tolist()):
        free[where[h_], l_] = False
        matched.setdefault((where[h_], s_), []).append(l_)
    pc, ui, si = np.nonzero(_may_fit(image_lines.lines[usable], uv, in_front, tol) & free[:, usable, None])
    li = usable[ui]
    if not len(pc):  # no usable line left free near a segment
        return Matches(empty, empty, empty)
    ph = hyps[pc]
    ok, dist = fits_projected(image_lines, uv[pc, si], in_front[pc, si], li, tol)
    if ok.any():
        sel = np.nonzero(ok)[0]
        ok[sel] = visible(camera, poses[ph[sel]], segs[si[sel]], image_lines.lines[li[sel]], walls, tol.stage2, tol.shared)
    out_h, out_l, out_s = [], [], []
    lines_taken = set()  # (hypothesis, line)
    # Closest first within each hypothesis; a line is added once, a segment
    # again only for a part of it not shown yet.
    cand = np.nonzero(ok)[0]
    for k in cand[np.lexsort((dist[cand], ph[cand]))].tolist():
        c, h, s_, l_ = int(pc[k]), int(ph[k]), int(si[k]), int(li[k])
        if (h, l_) in lines_taken:
            continue
        on_it = matched.setdefault((c, s_), [])
        if on_it:
            spans = _spans_along(np.broadcast_to(uv[c, s_], (len(on_it) + 1, 2, 2)), image_lines.lines[on_it + [l_]])
            overlap = np.minimum(spans[:-1, 1], spans[-1, 1]) - np.maximum(spans[:-1, 0], spans[-1, 0])
            if (overlap > 2.0 * tol.line_end_px).any():
                continue
        on_it.append(l_)
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
