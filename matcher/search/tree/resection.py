"""Hypotheses from vertical edges by resection: stage 1's second way in.

Image lines of vertical edges fix only bearings, so sets of them leave the
position loose until three are in, and the interpretation tree, which tests
one set per node, meets thousands of consistent sets where a view looks
along a wall of door jambs: its node budget runs out before the true set is
found (docs/matcher.md). Three bearings of three known edges fix the pose
exactly (the three-point resection of surveying), and a pose can be tested
against every other line at once. So, for frames the tree could not settle,
this module takes every triple of pairwise compatible vertical
correspondences on three different lines, solves each for its pose in one
batch, counts at each pose the image lines whose bearing some candidate
edge explains within the noise, and hands the best poses, each with its
explained lines as a set, to stage 2 like the tree's sets.

Resection in closed form: the camera sees edge ``p_i`` (floor point, world)
at bearing ``alpha_i`` (right of the optical axis), so in the camera's
floor frame ``q_i = R(-yaw) (p_i - c)`` points along ``(cos alpha_i,
-sin alpha_i)``. With ``u, v = cos yaw, sin yaw`` and ``t = -R(-yaw) c``,
``q_i = (u px + v py + tx, -v px + u py + ty)`` is linear in
``(u, v, tx, ty)``, and each edge gives one homogeneous linear equation.
Three give a 3 x 4 system whose null vector (the 4-D cross product of its
rows), scaled to ``u^2 + v^2 = 1`` with the sign that puts the edges in
front, is the pose.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

from linemap.geometry import wrap
from matcher.prior import within_prior
from matcher.tolerances import Tolerances

def resect(points: np.ndarray, alpha: np.ndarray, min_range_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Camera poses from three vertical edges each.

    ``points`` (P, 3, 2) the edges' floor points (world, metres), ``alpha``
    (P, 3) their bearings, radians, right of the optical axis. Returns
    ``(poses (P, 3) x, y, yaw in radians, ok (P,) bool)``; ``ok`` is False
    where the three are degenerate (the camera on the circle through them,
    or edges not all at least ``min_range_m`` in front)."""
    s, c = np.sin(alpha), np.cos(alpha)
    px, py = points[..., 0], points[..., 1]
    # Rows of the 3 x 4 system in (u, v, tx, ty): -s qx - c qy = 0.
    A = np.stack([-(s * px + c * py), c * px - s * py, -s, -c], axis=-1)  # (P, 3, 4)
    # Null vector: signed 3 x 3 minors (the 4-D cross product of the rows).
    cols = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]
    n = np.stack([(-1) ** j * np.linalg.det(A[:, :, cols[j]]) for j in range(4)], axis=-1)  # (P, 4)
    norm = np.hypot(n[:, 0], n[:, 1])
    scale = np.max(np.abs(A), axis=(1, 2)) ** 3
    ok = norm > 1e-9 * np.maximum(scale, 1e-12)
    n = n / np.where(ok, norm, 1.0)[:, None]
    u, v, tx, ty = n.T
    # q_i . (cos a, -sin a) > 0 for an edge in front; flip the sign if the
    # first edge is behind, then require all three in front.
    qx = u[:, None] * px + v[:, None] * py + tx[:, None]
    qy = -v[:, None] * px + u[:, None] * py + ty[:, None]
    ahead = qx * c - qy * s
    flip = np.where(ahead[:, 0] < 0, -1.0, 1.0)
    u, v, tx, ty, ahead = u * flip, v * flip, tx * flip, ty * flip, ahead * flip[:, None]
    ok &= (ahead > min_range_m).all(axis=1)
    x = -(u * tx - v * ty)
    y = -(v * tx + u * ty)
    return np.stack([x, y, np.arctan2(v, u)], axis=-1), ok


def triples(compat: np.ndarray, corr: np.ndarray, line: np.ndarray, most: int) -> np.ndarray:
    """(T, 3) triples of correspondences of ``corr`` (indices into ``compat``
    (K, K) bool), on three different lines (``line`` (K,)), pairwise
    compatible. Line triples whose lines have the fewest candidates come
    first; at most ``most`` triples."""
    lines = np.unique(line[corr])
    by_line = {int(j): corr[line[corr] == j] for j in lines}
    combos = sorted(itertools.combinations(lines.tolist(), 3),
                    key=lambda t: len(by_line[t[0]]) * len(by_line[t[1]]) * len(by_line[t[2]]))
    out, total = [], 0
    for a, b, c in combos:
        ka, kb, kc = by_line[a], by_line[b], by_line[c]
        ab = compat[ka[:, None], kb[None, :]]  # (A, B)
        ia, ib = np.nonzero(ab)
        if not len(ia):
            continue
        ok = compat[ka[ia][:, None], kc[None, :]] & compat[kb[ib][:, None], kc[None, :]]  # (AB, C)
        r, ic = np.nonzero(ok)
        if not len(r):
            continue
        t = np.stack([ka[ia[r]], kb[ib[r]], kc[ic]], axis=1)
        out.append(t[: most - total])
        total += len(out[-1])
        if total >= most:
            break
    return np.concatenate(out) if out else np.zeros((0, 3), dtype=np.int64)


@dataclass(frozen=True)
class EdgeCorrespondences:
    """Stage 1's correspondences as the resection takes them. Per
    correspondence k (K,): ``points`` (K, 2) the floor point of its segment
    (used for the vertical ones), ``segment`` that segment's id, ``line``
    its image line, ``vertical`` whether it pairs a vertical edge with a
    vertical line; ``compat`` (K, K) stage 1's pairwise compatibility. Per
    image line: ``alpha``, ``alpha_eps`` (M,) bearing and its noise bound,
    radians."""

    points: np.ndarray
    segment: np.ndarray
    line: np.ndarray
    vertical: np.ndarray
    compat: np.ndarray
    alpha: np.ndarray
    alpha_eps: np.ndarray


def vertical_hypotheses(corr: EdgeCorrespondences, prior, free, tol: Tolerances, max_hypotheses: int,
                        min_lines: int, deadline: float = math.inf):
    """Sets of correspondences ``corr`` from resected poses.

    ``prior`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians), ``free`` the map's
    free space or None. Triples are solved in batches of
    ``resection_chunk``; none is started once ``time.perf_counter()`` is
    past ``deadline``.

    Every pairwise compatible triple on three lines is resected; at each
    pose inside the prior (and free space) the lines explained are those
    with a vertical correspondence whose edge is seen within
    ``resection_bearing_slack`` times the line's noise bound of its bearing. Poses
    explaining at least ``min_lines`` lines, most first, then smallest
    normalised bearing error, give the sets (per explained line its best
    edge, one edge per line) with the pose. Returns ``(sets, inits)``: at
    most ``max_hypotheses`` index arrays into the correspondences and
    (H, 3) poses ``(x, y, yaw)``."""
    work = tol.stage1
    vert = np.nonzero(corr.vertical)[0]
    empty = ([], np.zeros((0, 3)))
    if len(np.unique(corr.line[vert])) < max(3, min_lines):
        return empty
    tri = triples(corr.compat, vert, corr.line, work.resection_max_triples)
    if not len(tri):
        return empty
    # Vertical correspondences sorted by line, so that a line's best edge
    # is a minimum over one run of columns.
    vert = vert[np.argsort(corr.line[vert], kind="stable")]
    keys, kept_poses, kept_err = [], [], []
    for c0 in range(0, len(tri), work.resection_chunk):
        if c0 and time.perf_counter() > deadline:
            break
        best = _best_of_chunk(corr, vert, tri[c0:c0 + work.resection_chunk], prior, free, tol, min_lines)
        if best is not None:
            keys += best[0]
            kept_poses.append(best[1])
            kept_err.append(best[2])
    if not keys:
        return empty
    kept_poses, kept_err = np.concatenate(kept_poses), np.concatenate(kept_err)
    sets, inits, seen_sets = [], [], set()
    for i in sorted(range(len(keys)), key=keys.__getitem__):
        s = _explained(kept_err[i], vert, corr.segment, corr.line, work.resection_bearing_slack)
        key = s.tobytes()
        if len(s) < min_lines or key in seen_sets:
            continue
        seen_sets.add(key)
        sets.append(s)
        inits.append(kept_poses[i])
        if len(sets) >= max_hypotheses:
            break
    return sets, np.array(inits).reshape(-1, 3)


def _best_of_chunk(corr: EdgeCorrespondences, vert: np.ndarray, t: np.ndarray, prior, free, tol: Tolerances,
                   min_lines: int):
    """The triples ``t`` (T, 3) resected: of the poses inside the prior (and
    free space) explaining at least ``min_lines`` lines, the best
    ``resection_keep`` as ``(keys, poses (P, 3), err (P, Kv))``: sort keys
    (minus the lines explained, the summed squared normalised bearing
    error) and each vertical correspondence's (``vert``, sorted by line)
    normalised bearing error at the pose; None when there is none."""
    work = tol.stage1
    poses, ok = resect(corr.points[t], corr.alpha[corr.line[t]], work.resection_min_range_m)
    poses = poses[ok]
    poses = poses[within_prior(poses, prior, free, tol)]
    if not len(poses):
        return None
    # Bearing of every vertical correspondence's edge at every pose,
    # against its line's: (P, Kv) normalised error, inf behind.
    rel = corr.points[vert][None, :, :] - poses[:, None, :2]
    seen = wrap(poses[:, None, 2] - np.arctan2(rel[..., 1], rel[..., 0]))
    lines = corr.line[vert]
    err = np.abs(wrap(seen - corr.alpha[lines][None, :])) / corr.alpha_eps[lines][None, :]
    err = np.where(np.abs(seen) < 0.5 * math.pi, err, np.inf)
    # Per pose and line: the best edge's error (inf if none).
    starts = np.unique(lines, return_index=True)[1]
    per_line = np.minimum.reduceat(err, starts, axis=1)  # (P, V)
    hit = per_line <= work.resection_bearing_slack
    n = hit.sum(axis=1)
    good = np.nonzero(n >= min_lines)[0]
    if not len(good):
        return None
    cost = np.where(hit[good], per_line[good] ** 2, 0.0).sum(axis=1)
    # Only the best few of a chunk can be among the best overall.
    best = np.lexsort((cost, -n[good]))[:work.resection_keep]
    top = good[best]
    return list(zip((-n[top]).tolist(), cost[best].tolist())), poses[top], err[top]


def _explained(err: np.ndarray, corr: np.ndarray, corr_seg: np.ndarray, corr_line: np.ndarray,
               slack: float) -> np.ndarray:
    """Sorted correspondence indices: for each line some correspondence of
    ``corr`` explains (normalised error ``err`` (Kv,) within
    ``slack``), the one of smallest error whose edge no clearer fit
    took (one edge per line)."""
    picks, lines_done, segs_used = [], set(), set()
    for k in np.argsort(err).tolist():
        if not err[k] <= slack:
            break
        j, g = int(corr_line[corr[k]]), int(corr_seg[corr[k]])
        if j in lines_done or g in segs_used:
            continue
        picks.append(int(corr[k]))
        lines_done.add(j)
        segs_used.add(g)
    return np.array(sorted(picks), dtype=np.int64)
