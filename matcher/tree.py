"""The interpretation tree of stage 1: consistent sets of correspondences.

A node is a set R of correspondences (model segment, image line) whose
feasible pose set is non-empty; its children add one more correspondence
that is compatible with every member (pairwise graph) and keeps the whole
set feasible (:mod:`matcher.posegrid`, checked for all candidates at once).
The search lists the maximal consistent sets, Bron-Kerbosch style: ``P``
holds the candidates that may still join R, ``X`` those already tried, and
a pivot of highest degree cuts the branches that could only rebuild a set
found elsewhere. A branch is cut too when it cannot reach the minimum
number of matches, which rises to the largest accepted set minus
``match_slack`` as sets are found.

Each set found gets a final check at its best grid pose (every matched
segment has a point in front of the camera and, when the map has walls,
not hidden behind one), then becomes a hypothesis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from matcher import posegrid
from matcher.occlusion import sight_clear
from matcher.tolerances import Tolerances

#: A sight line counts as blocked only if it crosses a wall more than this
#: far from both its ends, metres: the segment itself lies on a wall face,
#: and the pose from the grid is a few centimetres off.
_OCCLUSION_END_M = 0.05
#: Greedy dives from this many best-connected correspondences before the
#: exhaustive search (each costs a few tree nodes).
_GREEDY_SEEDS = 2
_CAMERA_JITTER = np.array([[0.0, 0.0], [0.06, 0.0], [-0.06, 0.0], [0.0, 0.06], [0.0, -0.06]])
#: Visibility is checked inside the tree only once the set's strips fix the
#: position to within this (1-sigma of the strips, metres); before that the
#: best point of the set may be far from the truth and the test would prune
#: true sets.
_PINNED_M = 0.05


@dataclass
class TreeInput:
    """Per correspondence k: strip quadratics ``quad`` (K, Y, 6) and yaw masks
    ``mask`` (K, Y) on the grid ``yaws`` (Y,); ``compat`` (K, K) bool pairwise
    compatibility; ``segments`` (K, 2, 3) the matched model segment (world);
    ``centre`` (3,) the prior camera centre, ``dt`` the disk radius;
    ``forward`` (Y, 3) the optical axis at each grid yaw; ``walls`` a pair of
    (E, 2) arrays, the wall edges' end points, or None."""

    quad: np.ndarray
    mask: np.ndarray
    yaws: np.ndarray
    compat: np.ndarray
    segments: np.ndarray
    centre: np.ndarray
    dt: float
    forward: np.ndarray
    walls: tuple[np.ndarray, np.ndarray] | None


def search(inp: TreeInput, tol: Tolerances):
    """Maximal consistent sets. Returns ``(sets, inits, truncated, nodes,
    found)``: sets as sorted index arrays, ``inits`` (x, y, yaw) their best
    grid pose; at most ``max_hypotheses`` of the ``found`` sets, those that
    fit best."""
    quad, mask, compat, dt = inp.quad, inp.mask, inp.compat, inp.dt
    K, Y = mask.shape
    sets: list[np.ndarray] = []
    inits: list[tuple[float, float, float]] = []
    state = {"bound": tol.min_matches, "truncated": False, "nodes": 0}

    def feasible_with(R: list[int], Qsum: np.ndarray, mR: np.ndarray, cand: np.ndarray) -> np.ndarray:
        """(C,) bool: is R + {u} feasible, for each u in cand."""
        G = np.nonzero(mR)[0]
        if len(G) == 0:
            return np.zeros(len(cand), dtype=bool)
        qc = quad[cand][:, G]  # (C, G, 6)
        val, z = posegrid.minimise(Qsum[G][None] + qc, dt)
        ok = mask[cand][:, G] & (val <= len(R) + 2.0) & (posegrid.evaluate(qc, z) <= tol.q_max)
        if R:
            each = posegrid.evaluate(quad[R][:, G][:, None], z[None])  # (S, C, G)
            ok &= (each <= tol.q_max).all(axis=0)
        return ok.any(axis=1)

    def emit(R: list[int]) -> None:
        res = final_check(inp, np.array(sorted(R)), tol)
        if res is None or len(res[0]) < state["bound"]:
            return
        new_bound = max(state["bound"], len(res[0]) - tol.match_slack)
        if new_bound > state["bound"]:  # sets now too small are dropped at once
            keep = [i for i, s in enumerate(sets) if len(s) >= new_bound]
            sets[:], inits[:] = [sets[i] for i in keep], [inits[i] for i in keep]
            state["bound"] = new_bound
        sets.append(res[0])
        inits.append(res[1])
        if len(sets) >= tol.max_sets:
            state["truncated"] = True

    nbr = [int.from_bytes(row.tobytes(), "little") for row in np.packbits(compat, axis=1, bitorder="little")]
    degree = compat.sum(axis=1)

    def color_bound(P: np.ndarray) -> int:
        """Colours of a greedy colouring of P: a clique in P has at most that many."""
        classes: list[int] = []
        for v in P[np.argsort(-degree[P], kind="stable")]:
            v = int(v)
            for i, cls in enumerate(classes):
                if not cls & nbr[v]:
                    classes[i] = cls | (1 << v)
                    break
            else:
                classes.append(1 << v)
        return len(classes)

    def child(R, Qsum, mR, v, P, X):
        """State of R + {v}: its quadratic, mask, and the candidates of P and X
        compatible with v that keep the set feasible."""
        R2 = R + [v]
        Q2 = Qsum + quad[v]
        m2 = mR & mask[v]
        P2 = P[compat[v, P]]
        X2 = X[compat[v, X]]
        both = np.concatenate([P2, X2])
        if both.size:
            ok = feasible_with(R2, Q2, m2, both)
            P2, X2 = P2[ok[: P2.size]], X2[ok[P2.size :]]
        return R2, Q2, m2, P2, X2

    def rec(R: list[int], Qsum: np.ndarray, mR: np.ndarray, P: np.ndarray, X: np.ndarray) -> None:
        if state["truncated"]:
            return
        state["nodes"] += 1
        if P.size == 0:
            if X.size == 0 and len(R) >= state["bound"]:
                emit(R)
            return
        if len(R) + P.size < state["bound"] or len(R) + color_bound(P) < state["bound"]:
            return
        PX = np.concatenate([P, X])
        pivot = PX[int(np.argmax(compat[np.ix_(PX, P)].sum(axis=1)))]
        branch = P[~compat[pivot, P]]
        # Most connected first: the true match is a large clique, finding it
        # early raises the bound and cuts the rest of the search.
        branch = branch[np.argsort(-compat[np.ix_(branch, P)].sum(axis=1), kind="stable")]
        for v in branch:
            v = int(v)
            R2, Q2, m2, P2, X2 = child(R, Qsum, mR, v, P, X)
            if len(R2) < tol.min_matches or _visible_at_best(inp, R2, Q2, m2):
                rec(R2, Q2, m2, P2, X2)
            P = P[P != v]
            X = np.append(X, v)
            if len(R) + P.size < state["bound"] or state["truncated"]:
                return

    def greedy(v: int) -> None:
        """Dive from v, always adding the candidate with most neighbours: a
        large consistent set found this way raises the bound before the
        exhaustive search starts."""
        R, Q, m = [], np.zeros((Y, 6)), np.ones(Y, dtype=bool)
        P, X = np.arange(K), np.zeros(0, dtype=np.int64)
        while P.size:
            R2, Q2, m2, P2, _ = child(R, Q, m, v, P, X)
            if len(R2) >= tol.min_matches and not _visible_at_best(inp, R2, Q2, m2):
                P = P[P != v]
            else:
                R, Q, m, P = R2, Q2, m2, P2
            if P.size:
                v = int(P[np.argmax(compat[np.ix_(P, P)].sum(axis=1))])
        if len(R) >= state["bound"]:
            emit(R)

    for seed in np.argsort(-degree, kind="stable")[:_GREEDY_SEEDS]:
        greedy(int(seed))
    rec([], np.zeros((Y, 6)), np.ones(Y, dtype=bool), np.arange(K), np.zeros(0, dtype=np.int64))
    if sets:
        top = max(len(s) for s in sets)
        keep = [i for i, s in enumerate(sets) if len(s) >= top - tol.match_slack]
        sets, inits = [sets[i] for i in keep], [inits[i] for i in keep]
    sets, inits = _drop_dominated(sets, inits)
    state["found"] = len(sets)
    if len(sets) > tol.max_hypotheses:
        best = np.argsort([fit for *_, fit in inits], kind="stable")[: tol.max_hypotheses]
        sets, inits = [sets[i] for i in best], [inits[i] for i in best]
    return sets, [p[:3] for p in inits], state["truncated"], state["nodes"], state["found"]


def _visible_at_best(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray) -> bool:
    """Once a set fixes the pose (three members or more): are all its
    segments in front of the camera and unhidden at its best grid pose?"""
    G = np.nonzero(mR)[0]
    if len(G) == 0:
        return False
    val, z = posegrid.minimise(Qsum[G], inp.dt)
    g = int(np.argmin(val))
    q = Qsum[G[g]]
    # Only judge once the strips alone pin the position: smallest eigenvalue
    # of their quadratic above 1 / _PINNED_M^2.
    tr, det = q[0] + q[2], q[0] * q[2] - q[1] * q[1]
    lam_min = 0.5 * (tr - np.sqrt(max(tr * tr - 4 * det, 0.0)))
    if lam_min < 1.0 / _PINNED_M**2:
        return True
    return bool(_seen(inp, np.asarray(R), inp.centre[:2] + z[g], inp.forward[G[g]]).all())


def final_check(inp: TreeInput, members: np.ndarray, tol: Tolerances):
    """``(members, (x, y, yaw, fit))`` for the largest subset found feasible by
    dropping the worst member, or None if it falls below ``min_matches``.

    Feasible at a grid yaw: every member's yaw mask holds, the summed strip
    quadratic's minimum is <= |S| + 1, every member's own term there is <=
    ``q_max``, and at that best point every segment has a part in front of
    the camera and, with walls, a part not hidden by a wall. ``fit`` is the
    summed quadratic's minimum per member."""
    ce, yaws = inp.centre, inp.yaws
    while len(members) >= tol.min_matches:
        q = inp.quad[members]  # (S, Y, 6)
        allm = inp.mask[members].all(axis=0)
        val, z = posegrid.minimise(q.sum(axis=0), inp.dt)
        each = posegrid.evaluate(q, z[None])  # (S, Y)
        good = allm & (val <= len(members) + 1.0) & (each <= tol.q_max).all(axis=0)
        if not good.any():
            if allm.any():
                g = int(np.argmin(np.where(allm, val, np.inf)))
                worst = int(np.argmax(each[:, g]))
            else:  # no common yaw: drop the member agreeing least with the others
                m = inp.mask[members].astype(int)
                worst = int(np.argmin(m @ m.sum(axis=0)))
            members = np.delete(members, worst)
            continue
        g = int(np.argmin(np.where(good, val, np.inf)))
        cam = ce[:2] + z[g]
        seen = _seen(inp, members, cam, inp.forward[g])
        if seen.all():
            return members, (float(cam[0]), float(cam[1]), float(yaws[g]), float(val[g]) / len(members))
        members = members[seen]
    return None


def _seen(inp: TreeInput, members: np.ndarray, cam: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """(S,) bool: the member's segment has a sample point in front of the
    camera at ``cam`` (2,) and, with walls, with a clear sight line."""
    segs = inp.segments[members]  # (S, 2, 3)
    t = np.linspace(0.02, 0.98, 7)
    pts = segs[:, None, 0] + t[None, :, None] * (segs[:, None, 1] - segs[:, None, 0])  # (S, 7, 3)
    C = np.array([cam[0], cam[1], inp.centre[2]])
    front = (pts - C) @ forward > 0.05
    flat = pts[..., :2].reshape(-1, 2)
    clear = np.zeros(len(flat), dtype=bool)
    # Seen from the point or from any of four points around it: the grid pose
    # is a few centimetres off, and a sight line through a doorway far away
    # can swing onto a jamb over that distance.
    for off in _CAMERA_JITTER:
        clear |= sight_clear(cam + off, flat, inp.walls, _OCCLUSION_END_M)
    return (front & clear.reshape(front.shape)).any(axis=1)


def _drop_dominated(sets, inits):
    """Remove duplicates and sets contained in another."""
    order = sorted(range(len(sets)), key=lambda i: -len(sets[i]))
    kept, kept_init, seen = [], [], []
    for i in order:
        s = frozenset(int(x) for x in sets[i])
        if any(s <= o for o in seen):
            continue
        seen.append(s)
        kept.append(np.array(sorted(s), dtype=np.int64))
        kept_init.append(inits[i])
    return kept, kept_init
