"""Stage 1, second step: which correspondences can hold together (method.md
section 6).

Two correspondences are compatible when they match one to one (two lines
share a segment only if they may be pieces of one broken line), have a
common pose in the prior set at one grid yaw (their strips meet, within
both half-planes), and, for two vertical edges, pass the paper's binary
constraint. The interpretation tree takes this (K, K) table as given.
"""

from __future__ import annotations

import numpy as np

from matcher.budget import NO_LIMIT, Deadlines
from matcher.frame import ImageLines
from matcher.search.tree import posegrid
from matcher.search.tree.constraints import binary_constraint
from matcher.search.tree.correspondences import Correspondences
from matcher.tolerances import Tolerances


def pair_compatibility(image_lines: ImageLines, corr: Correspondences, dt: float, tol: Tolerances,
                       deadlines: Deadlines = NO_LIMIT) -> np.ndarray | None:
    """(K, K) bool pairwise compatibility: one-to-one (two lines share a
    segment only if they may be pieces of one line, ``image_lines.pieces``), a
    common pose of the two in the prior set at one grid yaw (within both
    half-planes, see :func:`_half_planes`), and the paper's binary
    constraint for two vertical correspondences. ``None`` when the search
    time of ``deadlines`` ran out first (a real view can hold thousands of
    correspondences: millions of pairs, seconds of work)."""
    near, seg_k, line_k, is_v, mask = corr.near, corr.seg_k, corr.line_k, corr.is_v, corr.mask
    centre = (float(corr.centre[0]), float(corr.centre[1]))
    K = len(seg_k)
    iu, ju = np.triu_indices(K, 1)
    distinct = seg_k[iu] != seg_k[ju]
    if image_lines.pieces is not None:
        distinct |= image_lines.pieces[line_k[iu], line_k[ju]]
    distinct &= line_k[iu] != line_k[ju]
    iu, ju = iu[distinct], ju[distinct]
    # In chunks of pairs, so that a huge prior (lost mode, a large dt with
    # any heading) does not need gigabytes; a frame's pairs are one chunk.
    step = max(1, tol.stage1.pair_chunk // mask.shape[1])
    chunks = []
    for c in range(0, len(iu), step):
        if not deadlines.may_search():
            return None
        chunks.append(_share_a_pose(iu[c:c + step], ju[c:c + step], corr, dt, tol))
    pair_ok = np.concatenate(chunks) if chunks else np.zeros(0, dtype=bool)
    sel = np.nonzero(is_v[iu] & is_v[ju] & pair_ok)[0]
    if len(sel):
        a_i, a_j = iu[sel], ju[sel]
        tol_ab = image_lines.alpha_eps[line_k[a_i]] + image_lines.alpha_eps[line_k[a_j]]
        pair_ok[sel] = binary_constraint(near[seg_k[a_i], :2], near[seg_k[a_j], :2], image_lines.alpha[line_k[a_i]],
                                         image_lines.alpha[line_k[a_j]], centre, dt, tol_ab)
    compat = np.zeros((K, K), dtype=bool)
    compat[iu[pair_ok], ju[pair_ok]] = True
    return compat | compat.T


def _share_a_pose(iu, ju, corr: Correspondences, dt: float, tol: Tolerances) -> np.ndarray:
    """(P,) bool: do correspondences ``iu[p]`` and ``ju[p]`` have a common
    pose in the prior set at one grid yaw, within both their half-planes?"""
    # (pair, yaw) entries where both masks hold. (np.nonzero on the 2-D
    # array, and fancy indexing of quad by two arrays, cost several times
    # the flat forms on these sizes.)
    mask, quad, front_c, front_b = corr.mask, corr.quad, corr.front_c, corr.front_b
    Y = mask.shape[1]
    p, g = np.divmod(np.flatnonzero(mask[iu] & mask[ju]), Y)
    at_i, at_j = iu[p] * Y + g, ju[p] * Y + g  # flat (correspondence, yaw) indices
    flat = quad.reshape(-1, 6)
    qi, qj = np.take(flat, at_i, axis=0), np.take(flat, at_j, axis=0)
    qs = qi + qj
    pval, zx, zy = posegrid.minimise(qs, dt)
    ok = (pval <= tol.stage1.pair_fit_max) & (posegrid.evaluate(qi, zx, zy) <= tol.q_max) & (posegrid.evaluate(qj, zx, zy) <= tol.q_max)
    # The half-planes, on the (pair, yaw) entries left and only for the
    # correspondences that have one (most of these arrays' entries fail the
    # value test).
    has_plane = np.isfinite(front_b).any(axis=1)
    e = np.nonzero(ok & (has_plane[iu[p]] | has_plane[ju[p]]))[0]
    if len(e):
        ell = posegrid.feasible_ellipse(qs[e], pval[e], zx[e], zy[e], 2, tol.q_max, dt)
        for at in (at_i[e], at_j[e]):  # (no disk test: both masks were cut by it)
            ok[e] &= posegrid.ellipse_reaches(ell, np.take(front_c.reshape(-1, 2), at, axis=0),
                                              np.take(front_b.reshape(-1), at), None)
    return np.bincount(p[ok], minlength=len(iu)) > 0
