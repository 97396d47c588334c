"""The interpretation tree of stage 1: consistent sets of correspondences.

The tree of the paper's setting: one level per image line, whose branches
are the line's candidate model segments (those that passed the unary or
vertical tests) and "unmatched" (clutter, or a segment not in the lists).
A node is a set R of correspondences whose feasible pose set is non-empty:
a child adds a candidate that is pairwise compatible with every member and
keeps the whole set feasible (:mod:`matcher.posegrid`, checked for all the
line's candidates at once). Pairwise compatibility holds matching one to
one: two lines share a segment only when they are pieces of one broken
line (:func:`matcher.constraints.line_pieces`). A branch is cut when
it cannot reach the minimum number of matches, which rises to the largest
set found minus ``match_slack``. A leaf is reported if it is maximal (no
skipped line could join). The tree is searched first in passes that aim at
the largest sets (every line matched, then one fewer, ...), so that the
small sets a dive from the minimum would meet first are never enumerated.

Once three members pin the position, the set's best grid pose must stand in
the map's free space (near its regions), and every matched segment must be
in front of the camera and, when the map has walls, not hidden behind one
there; each leaf gets that check again before it becomes a hypothesis.
Sets that leave the position loose are tested only in scenes that need
many nodes: a vertical edge just added must be visible from some free
point of the set's feasible region.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from matcher import posegrid
from matcher.budget import NO_LIMIT, Deadlines
from matcher.occlusion import sight_clear
from matcher.tolerances import Tolerances

#: A sight line counts as blocked only if it crosses a wall more than this
#: far from both its ends, metres: the segment itself lies on a wall face,
#: and the pose from the grid is a few centimetres off.
_OCCLUSION_END_M = 0.05
#: Points of a segment tested for visibility (fractions of its length, or
#: of the part its image line shows).
_SAMPLES = np.array([0.02, 0.26, 0.5, 0.74, 0.98])
#: The part of a segment its image line shows at a set's grid pose is
#: widened by this much at both ends before visibility is tested, metres.
_SHOWN_WIDEN_M = 0.1
#: Points of that part tested (fractions of it): it is short, three do.
_SHOWN_SAMPLES = np.array([0.05, 0.5, 0.95])
#: A segment counts as seen if it is seen from the set's best point or from
#: one of these four around it, metres: that point is a few centimetres off,
#: and a sight line through a doorway swings onto a jamb over that distance.
#: Too small a radius loses true sets behind door jambs; too large only
#: keeps a few more false ones for stage 2.
_CAMERA_JITTER = np.array([[0.0, 0.0], [0.15, 0.0], [-0.15, 0.0], [0.0, 0.15], [0.0, -0.15]])
#: Visibility and free space are checked inside the tree only once the set
#: fixes the position: its feasible points at the best yaw reach less than
#: this far, metres, in any direction. Before that the best point may be far
#: from the truth and the tests would prune true sets.
_PINNED_M = 0.15
#: A set that leaves the position loose gets a test of its own
#: (:func:`_edge_seen_from_region`) once the search has used this share of
#: its node budget (200 nodes by default). It costs a few tenths of a
#: millisecond, and the scenes that need it are those where loose sets
#: multiply (a row of door jambs seen along a wall, each jamb line fitting
#: many jambs): most frames end well before.
_LOOSE_TEST_AFTER = 0.1
#: Spacing, metres, of the camera positions that test samples in a set's
#: feasible region at each yaw, and the most per axis.
_REGION_STEP_M = 0.15
_REGION_MAX = 16
#: Share of the node budget the passes that aim at large sets may spend
#: without finding one (see :func:`search`).
_AIM_HIGH_SHARE = 0.05
#: Up to this many lines (levels), the lines a candidate reaches are the
#: bits of one int64 (sign bit spared); past it, a one-hot matrix product.
_BIT_LEVELS = 63
#: A sort key above every real one.
_NEVER = np.iinfo(np.int64).max


@dataclass
class TreeInput:
    """Per correspondence k: strip quadratics ``quad`` (K, Y, 6) and yaw masks
    ``mask`` (K, Y) on the grid ``yaws`` (Y,); ``compat`` (K, K) bool pairwise
    compatibility (the tree relies on it: a pair in compat is taken as
    feasible, as :func:`matcher.generate._pair_compat` tests it, and two
    correspondences on one segment are in compat only if their lines may be
    pieces of one line); ``segments``
    (K, 2, 3) the matched model segment (world); ``centre`` (3,) the prior
    camera centre, ``dt`` the disk radius; ``forward`` (Y, 3) the optical axis
    at each grid yaw; ``walls`` a pair of (E, 2) arrays, the wall edges' end
    points, or None; ``vertical`` (K,) bool, correspondences of vertical
    segments (explored last: each fixes only a bearing, so they are compatible
    with much and prune little); ``line`` (K,) the image line of each
    correspondence; ``free`` the map's :class:`~matcher.freespace.FreeSpace`
    (or None) and ``free_m`` how far outside it the camera may stand;
    ``front_c`` (K, Y, 2) and ``front_b`` (K, Y) half-planes ``c . z <= b`` on
    the camera position relative to the centre that keep a vertical edge ahead
    of the camera (c = 0, b = inf for the others), or None; ``single_fit`` (K,)
    each correspondence's best value alone (the root's look-ahead: the summed
    quadratic's minimum over the yaws where it passes every test of the
    look-ahead, inf where none), or None to compute it at the root; ``sight``
    the walls' :class:`~matcher.occlusion.SightRays` (how far one sees from a
    vertical edge, per bearing), or None to cast sight lines; ``shown`` the
    :class:`~matcher.overlap.ShownSpans` of the correspondences (``segments``
    with their image lines), or None: with it, visibility is tested on the
    part of the segment the line shows at the set's pose (else on points
    spread over the whole segment); ``deadlines`` the caller's time budget
    (:class:`~matcher.budget.Deadlines`): past its ``search`` the tree stops
    as at ``max_nodes``, past its ``checks`` the final tests of the sets
    found stop."""

    quad: np.ndarray
    mask: np.ndarray
    yaws: np.ndarray
    compat: np.ndarray
    segments: np.ndarray
    centre: np.ndarray
    dt: float
    forward: np.ndarray
    walls: tuple[np.ndarray, np.ndarray] | None
    vertical: np.ndarray | None = None
    line: np.ndarray | None = None
    free: object | None = None
    free_m: float = 0.0
    front_c: np.ndarray | None = None
    front_b: np.ndarray | None = None
    single_fit: np.ndarray | None = None
    sight: object | None = None
    shown: object | None = None
    deadlines: Deadlines = NO_LIMIT

    def __post_init__(self):
        self.seg_length = np.maximum(np.linalg.norm(self.segments[:, 1] - self.segments[:, 0], axis=1), 1e-9)

    def in_free_space(self, xy: np.ndarray) -> np.ndarray:
        """(...) bool: camera positions ``xy`` (..., 2) within ``free_m`` of
        the map's regions (:mod:`matcher.freespace`); all True without a map."""
        if self.free is None:
            return np.ones(np.shape(xy)[:-1], dtype=bool)
        return self.free.distance(xy) <= self.free_m


def search(inp: TreeInput, tol: Tolerances, eager: bool = False, aim_high: bool = True):
    """Maximal consistent sets (leaves tested for visibility as found if
    ``eager``, else afterwards; passes that aim at large sets first if
    ``aim_high``, see below). Returns ``(sets, inits, truncated, nodes,
    found)``: sets as sorted index arrays, ``inits`` (x, y, yaw) their best
    grid pose; at most ``max_hypotheses`` of the ``found`` sets: the largest,
    then those that fit best."""
    quad, mask, compat, dt = inp.quad, inp.mask, inp.compat, inp.dt
    K, Y = mask.shape
    sets: list[np.ndarray] = []
    inits: list[tuple] = []
    state = {"bound": tol.min_matches, "truncated": False, "nodes": 0, "give_up_at": np.inf}
    cache: dict = {}
    weak = np.zeros(K, dtype=bool) if inp.vertical is None else inp.vertical
    degree = compat.sum(axis=1)
    has_plane = np.zeros(K, dtype=bool) if inp.front_b is None else np.isfinite(inp.front_b).any(axis=1)

    # Levels: image lines. Lines with a non-vertical candidate first (their
    # unary constraint fixes the yaw, so the pose gets pinned early), then
    # by number of candidates. Candidates of a line: most connected first,
    # so that the first dive tends to follow the true match.
    lines = np.unique(inp.line)
    # Support of a correspondence: how many other lines have a candidate
    # compatible with it. The true ones see every other true line.
    line_idx = np.searchsorted(lines, inp.line)
    touch = np.zeros((K, len(lines)), dtype=bool)
    ki, kj = np.nonzero(compat)
    touch[ki, line_idx[kj]] = True
    support = touch.sum(axis=1)
    has_strong = np.array([(~weak[inp.line == j]).any() for j in lines])
    n_cand = np.array([(inp.line == j).sum() for j in lines])
    lines = lines[np.lexsort((n_cand, ~has_strong))]
    cands = []
    for j in lines:
        c = np.nonzero(inp.line == j)[0]
        cands.append(c[np.lexsort((-degree[c], -support[c], weak[c]))])
    L = len(lines)
    level_of = np.empty(K, dtype=np.int64)
    for lv, c in enumerate(cands):
        level_of[c] = lv
    order_rank = np.empty(K, dtype=np.int64)
    order_rank[np.concatenate(cands)] = np.arange(K)

    def feasible_with(R: list[int], Qsum: np.ndarray, mR: np.ndarray, cand: np.ndarray, fit: bool = False):
        """(C,) bool: is R + {u} feasible, for each u in cand; with ``fit``
        also (C,) the best summed quadratic of R + {u} (inf if infeasible)."""
        G = mR.nonzero()[0]
        if len(G) == 0:
            no = np.zeros(len(cand), dtype=bool)
            return (no, np.full(len(cand), np.inf)) if fit else no
        # Index arrays broadcast (C, 1) x (G,) rather than np.ix_: this runs
        # at every node and np.ix_ alone cost a third of it.
        cc = cand[:, None]
        qc = quad[cc, G]  # (C, G, 6)
        qs = Qsum[G] + qc
        val, zx, zy = posegrid.minimise(qs, dt)
        phi = posegrid.monomials(zx, zy)  # (C, G, 6)
        ok = mask[cc, G] & (val <= len(R) + 2.0) & (posegrid.evaluate_at(qc, phi) <= tol.q_max)
        if R:
            each = np.einsum("sgk,cgk->scg", quad[np.array(R)[:, None], G], phi)  # (S, C, G)
            ok &= (each <= tol.q_max).all(axis=0)
        if inp.front_c is not None:
            # Half-planes (vertical edges ahead, wall faces seen from the
            # room): the candidates' own and those of R's members (the
            # feasible set shrinks as R grows), each at every candidate.
            hp = [r for r in R if has_plane[r]]
            if hp or has_plane[cand].any():
                ell = posegrid.feasible_ellipse(qs, val, zx, zy, len(R) + 1, tol.q_max, dt)
                # One test for all: row 0 the candidates' own half-planes,
                # then one row per member of R broadcast over the candidates;
                # (H + 1, C, 1) indices against G.
                rows = np.empty((len(hp) + 1, len(cand), 1), dtype=np.int64)
                rows[0, :, 0] = cand
                rows[1:] = np.array(hp, dtype=np.int64)[:, None, None]
                # (The disk is left out: every mask here was cut by it in stage 1.)
                ok &= posegrid.ellipse_reaches(ell, inp.front_c[rows, G], inp.front_b[rows, G], None).all(axis=0)
        if fit:
            best = np.where(ok, val, np.inf).min(axis=1)
            return np.isfinite(best), best
        return ok.any(axis=1)

    def open_candidates(level: int, R: list[int]) -> np.ndarray:
        """Candidates of the line at ``level`` pairwise compatible with every
        member of R (so not using a matched segment, but for pieces of one
        broken line)."""
        c = cands[level]
        if R and c.size:
            c = c[compat[np.array(R)[:, None], c].all(axis=0)]
        return c

    def maximal(R: list[int], Qsum, mR, skipped: list[int]) -> bool:
        """No skipped line can take a candidate consistent with all of R."""
        extra = [open_candidates(lv, R) for lv in skipped]
        extra = np.concatenate(extra) if extra else np.zeros(0, dtype=np.int64)
        return not (extra.size and feasible_with(R, Qsum, mR, extra).any())

    def emit(R: list[int], Qsum, mR) -> None:
        if eager:
            res = final_check(inp, np.array(sorted(R)), tol, cache)
        else:
            # Every addition kept the set feasible at some grid yaw, so the
            # geometry holds; visibility, the dearer test, runs at the end on
            # the sets that could become hypotheses (inner nodes tested it
            # once the pose was pinned). Here only the best grid pose.
            G = mR.nonzero()[0]
            val, zx, zy = posegrid.minimise(Qsum[G], dt)
            g = int(val.argmin())
            res = (np.array(sorted(R)), (float(inp.centre[0] + zx[g]), float(inp.centre[1] + zy[g]),
                                          float(inp.yaws[G[g]]), float(val[g]) / len(R)))
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

    strong_level = np.array([(~weak[c]).any() for c in cands], dtype=bool)
    if L <= _BIT_LEVELS:
        # compat_bits[u, v]: the bit of v's level where u and v are
        # compatible, else 0; OR-ed over a pool, the lines u can still reach.
        compat_bits = np.where(compat, (np.int64(1) << level_of)[None, :], np.int64(0))
    else:
        level_hot = np.eye(L, dtype=np.int32)  # row l: one-hot of level l

    def lines_reached(cand: np.ndarray, pool: np.ndarray) -> np.ndarray:
        """(C,) for each of ``cand``: how many lines hold a candidate of
        ``pool`` compatible with it (a bitwise OR and a bit count; a matrix
        product of one-hot levels past _BIT_LEVELS lines)."""
        if not pool.size:
            return np.zeros(len(cand), dtype=np.int64)
        if L <= _BIT_LEVELS:
            return np.bitwise_count(np.bitwise_or.reduce(compat_bits[cand][:, pool], axis=1)).astype(np.int64)
        return (compat[cand[:, None], pool].astype(np.int32) @ level_hot[level_of[pool]] > 0).sum(axis=1)

    def well_supported(n_members: int, ahead: np.ndarray) -> np.ndarray:
        """(A,) bool: the candidates of ``ahead`` that can still be part of a
        set of the bound's size with ``n_members`` others: compatible with
        candidates of enough other lines of ``ahead`` (repeated until no more
        go: each removal lowers the others' counts). Pairwise only, so cheap
        next to a feasibility pass, which it spares those candidates."""
        keep = np.full(len(ahead), True)
        while keep.any():
            idx = keep.nonzero()[0]
            ok = n_members + 1 + lines_reached(ahead[idx], ahead[idx]) >= state["bound"]
            if ok.all():
                break
            keep[idx[~ok]] = False
        return keep

    def rec(R: list[int], Qsum, mR, skipped: list[int], pool: np.ndarray,
            fit: np.ndarray | None) -> None:
        """``pool``: candidates of the lines not yet decided. With ``fit``
        None, R just grew and the pool is filtered against it (consistency
        only shrinks as R grows, so the parent's pool is enough); otherwise
        it is the parent's filtered pool and ``fit`` their best fits."""
        if state["truncated"]:
            return
        state["nodes"] += 1
        if (state["nodes"] > tol.max_nodes or (state["nodes"] > state["give_up_at"] and not sets)
                or not inp.deadlines.may_search()):
            state["truncated"] = True
            return
        # Look ahead: the open candidates of all lines still to decide, kept if
        # consistent with R. Lines with none cannot be matched any more.
        ahead = pool
        if fit is None and not R and inp.single_fit is not None:
            # The root: each candidate alone, as stage 1 already tested it.
            ahead = ahead[np.isfinite(inp.single_fit[ahead])]
            ahead = ahead[well_supported(0, ahead)]
            fit = inp.single_fit[ahead]
        elif fit is None:
            if R and ahead.size:
                ahead = ahead[compat[R[-1], ahead]]
            ahead = ahead[well_supported(len(R), ahead)]
            fit = np.zeros(len(ahead))
            if ahead.size and len(R) >= 2:
                # (With one member, R + {u} feasible is the pairwise test of
                # stage 1 that compat holds, and the fits order nothing yet.)
                ok, fit = feasible_with(R, Qsum, mR, ahead, fit=True)
                ahead, fit = ahead[ok], fit[ok]
        else:  # the bound may have risen since the parent filtered the pool
            keep = well_supported(len(R), ahead)
            ahead, fit = ahead[keep], fit[keep]
        counts = np.bincount(level_of[ahead], minlength=L)
        reachable = int((counts > 0).sum())
        if len(R) + reachable < state["bound"]:
            return
        if reachable == 0:
            if maximal(R, Qsum, mR, skipped):
                emit(R, Qsum, mR)
            return
        # Fail first: decide next the line with the fewest candidates left
        # (lines with a non-vertical candidate first among equals).
        key = np.where(counts > 0, counts * 2 - strong_level, _NEVER)
        level = int(key.argmin())
        here = level_of[ahead] == level
        c = ahead[here]
        # Best fitting first once the pose is pinned by a few members, else
        # the most connected: either way the first dive tends to follow the
        # true match, which raises the bound for the rest of the search.
        c = c[np.lexsort((order_rank[c], fit[here]))] if len(R) >= 2 else c[np.argsort(order_rank[c])]
        rest = ahead[~here]
        # Lines each candidate can still reach: its child's look-ahead keeps
        # only the rest compatible with it, so a candidate that cannot reach
        # the bound is not worth a node (a cheap count against a feasibility
        # pass over the whole pool).
        reach = lines_reached(c, rest)
        for v, reach_v in zip(c.tolist(), reach.tolist()):
            if len(R) + 1 + reach_v < state["bound"]:
                continue
            R2, Q2, m2 = R + [v], Qsum + quad[v], mR & mask[v]
            loose = len(R2) + reach_v if state["nodes"] > _LOOSE_TEST_AFTER * tol.max_nodes else 0
            if len(R2) >= tol.min_matches and not _visible_at_best(inp, R2, Q2, m2, tol.q_max, cache, loose):
                continue
            rec(R2, Q2, m2, skipped, rest, None)
            if state["truncated"]:
                return
        if len(R) + reachable - 1 >= state["bound"]:
            # The line left unmatched: R is unchanged, so is its filtered pool.
            rec(R, Qsum, mR, skipped + [level], rest, fit[~here])

    def run(target: int, allowance: float = np.inf) -> bool:
        """One pass of the tree for the sets of at least ``target`` members;
        False if it was given up, having met no set within ``allowance``
        more nodes."""
        state["bound"] = target
        state["give_up_at"] = state["nodes"] + allowance
        rec([], np.zeros((Y, 6)), np.ones(Y, dtype=bool), [], np.arange(K), None)
        given_up = state["truncated"] and not sets and state["nodes"] > state["give_up_at"]
        if given_up:
            state["truncated"] = False
        return not given_up

    # Aim high first: one pass per target size, from every line matched
    # down, until a pass finds a set. A pass whose target is out of reach
    # mostly dies near the root (the look-ahead counts cut it), while a
    # single pass from the minimum enumerates every small set met before its
    # first dive finds a large one. Where sets that leave the position loose
    # abound (a row of door jambs), a target out of reach can cost many
    # nodes: after _AIM_HIGH_SHARE of the budget the passes stop and one
    # pass from the minimum raises its bound as it finds sets, as do the
    # searches that keep more than the largest sets (a slack, or every leaf
    # tested as found).
    if aim_high and not eager and tol.match_slack == 0:
        alone = np.arange(K) if inp.single_fit is None else np.nonzero(np.isfinite(inp.single_fit))[0]
        target = len(np.unique(level_of[alone]))
        while target > tol.min_matches and not sets and not state["truncated"]:
            if not run(target, _AIM_HIGH_SHARE * tol.max_nodes - state["nodes"]):
                break
            target -= 1
    if not sets and not state["truncated"]:
        run(tol.min_matches)
    sets, inits = _drop_duplicates(sets, inits)
    state["found"] = len(sets)
    found_any = bool(sets)
    sets, inits = _visible_best(inp, sets, inits, tol, cache)
    if not inp.deadlines.may_check():  # the final tests may have been cut short
        state["truncated"] = True
    if found_any and not sets and not eager:
        # Every set failed the visibility test: the sets that raised the bound
        # may have hidden smaller valid ones. Search again, testing each leaf.
        again = search(inp, tol, eager=True)
        return again[0], again[1], again[2], state["nodes"] + again[3], again[4]
    return sets, [p[:3] for p in inits], state["truncated"], state["nodes"], state["found"]


def _visible_best(inp: TreeInput, sets, inits, tol: Tolerances, cache):
    """The hypotheses: sets passing the visibility test (a set failing it
    loses its unseen members and queues again), largest first, then best
    fitting, at most ``max_hypotheses``, all at least as large as the
    largest passing set minus ``match_slack``; those found by the
    deadline of the checks."""
    import heapq

    heap = [(-len(s), p[3], i, s) for i, (s, p) in enumerate(zip(sets, inits))]
    heapq.heapify(heap)
    out, out_init, seen_keys, n = [], [], set(), len(heap)
    while heap and len(out) < tol.max_hypotheses and inp.deadlines.may_check():
        neg, fit, _, m = heapq.heappop(heap)
        if out and -neg < len(out[0]) - tol.match_slack:
            break
        if m.tobytes() in seen_keys:
            continue
        passed, smaller, init = check_once(inp, m, tol, cache)
        if passed:
            seen_keys.add(m.tobytes())
            out.append(m)
            out_init.append(init)
        elif smaller is not None:  # repaired by one step: back in the queue at its new size
            n += 1
            heapq.heappush(heap, (-len(smaller), fit if init is None else init[3], n, smaller))
    return _drop_dominated(out, out_init)


def _best_pose(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, q_max: float):
    """``(pinned, g, cam)`` for a set R: its best grid yaw index ``g`` (None
    when no yaw is left) and camera position ``cam`` (2,) there. The
    position is pinned when the set's feasible points at that yaw (every
    member's term <= ``q_max``) reach less than _PINNED_M along the
    direction the strips fix least."""
    G = mR.nonzero()[0]
    if len(G) == 0:
        return False, None, None
    val, zx, zy = posegrid.minimise(Qsum[G], inp.dt)
    i = int(val.argmin())
    g = int(G[i])
    z = (float(zx[i]), float(zy[i]))
    cam = inp.centre[:2] + z
    e, lam, _ = posegrid.weak_axis(Qsum[g])
    if lam < 1.0 / _PINNED_M**2:  # cheap early out: even the summed strips leave it loose
        return False, g, cam
    lo, hi = posegrid.stretch(inp.quad[R, g], z, e, q_max, inp.dt)
    return hi - lo <= _PINNED_M, g, cam


def _visible_at_best(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, q_max: float,
                     cache: dict | None = None, loose: int = 0) -> bool:
    """Once a set fixes the pose (three members or more): is its best grid
    pose in free space, with all its segments in front of the camera and
    unhidden? (Before that the best point may be far from the truth and the
    test would prune true sets.) With ``loose`` (the most members a leaf
    below R can have; 0: off), a set that does not fix the position and has
    just taken a vertical edge is tested too, on its whole feasible region
    (:func:`_edge_seen_from_region`)."""
    pinned, g, cam = _best_pose(inp, R, Qsum, mR, q_max)
    if g is None:
        return False
    if not pinned:
        if loose and inp.walls is not None and inp.vertical is not None and inp.vertical[R[-1]]:
            return _edge_seen_from_region(inp, R, Qsum, mR, q_max, loose)
        return True
    if not inp.in_free_space(cam):
        return False
    return bool(_seen_cached(inp, np.asarray(sorted(R)), cam, g, cache).all())


def _edge_seen_from_region(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, q_max: float,
                           most: int) -> bool:
    """Can the vertical edge of ``R[-1]`` be seen from some point of R's
    feasible region that lies in free space? If not, no leaf below R passes
    the leaf test (its pose is such a point, and must see every member).

    The region at each yaw of ``mR`` is taken as the box spanned by its
    stretches (every member's term <= ``q_max``) along the two axes of the
    summed quadratic through its minimiser, sampled every _REGION_STEP_M: a
    box holds the points of the region near those axes and more, so the
    test errs towards keeping. The edge stands at one floor point, so one
    sight line per sample decides. Only yaws where a leaf of at most
    ``most`` members could stand count: adding members only raises the
    summed quadratic's minimum, and a leaf's must stay <= its size + 1."""
    G = mR.nonzero()[0]
    val, zx, zy = posegrid.minimise(Qsum[G], inp.dt)
    near = val <= most + 1.0
    G, zx, zy = G[near], zx[near], zy[near]
    if len(G) == 0:
        return False
    qs = Qsum[G]
    ex, ey = posegrid.weak_axes(qs)  # (G,)
    q = inp.quad[np.array(R)[:, None], G]  # (S, G, 6)
    # Both axes in one call: rows 0 the weak axis e, 1 the strong one (e turned).
    lo, hi = posegrid.stretches(q[:, None], zx, zy, np.stack([ex, -ey]), np.stack([ey, ex]), q_max, inp.dt)
    (lo_w, lo_s), (hi_w, hi_s) = lo, hi
    ok = (lo_w <= hi_w) & (lo_s <= hi_s)
    if not ok.any():
        return False
    lo_w, hi_w, lo_s, hi_s = lo_w[ok], hi_w[ok], lo_s[ok], hi_s[ok]
    n_w = int(min(np.ceil((hi_w - lo_w).max() / _REGION_STEP_M) + 1, _REGION_MAX))
    n_s = int(min(np.ceil((hi_s - lo_s).max() / _REGION_STEP_M) + 1, _REGION_MAX))
    tw = lo_w[:, None] + np.linspace(0.0, 1.0, n_w)[None, :] * (hi_w - lo_w)[:, None]  # (G', n_w)
    ts = lo_s[:, None] + np.linspace(0.0, 1.0, n_s)[None, :] * (hi_s - lo_s)[:, None]  # (G', n_s)
    e = np.stack([ex[ok], ey[ok]], axis=-1)[:, None, None, :]
    f = np.stack([-ey[ok], ex[ok]], axis=-1)[:, None, None, :]
    z = np.stack([zx[ok], zy[ok]], axis=-1)[:, None, None, :]
    pts = (inp.centre[:2] + z + tw[:, :, None, None] * e + ts[:, None, :, None] * f).reshape(-1, 2)
    pts = pts[inp.in_free_space(pts)]
    if not len(pts):
        return False
    edge = inp.segments[R[-1], 0, :2]
    if inp.sight is None:
        return bool(sight_clear(pts, np.broadcast_to(edge, pts.shape), inp.walls, _OCCLUSION_END_M).any())
    # The map's sight table (rays cast from the edge once per map): a sample
    # sees the edge if the ray from the edge towards it runs that far.
    rel = pts - edge
    far = inp.sight.reach_along(edge[None], np.zeros(len(pts), dtype=np.int64), np.arctan2(rel[:, 1], rel[:, 0]))
    return bool((np.hypot(rel[:, 0], rel[:, 1]) <= far).any())


def final_check(inp: TreeInput, members: np.ndarray, tol: Tolerances, cache: dict | None = None,
                visibility: bool = True):
    """``(members, (x, y, yaw, fit))`` for the largest subset found feasible by
    dropping the worst member, or None if it falls below ``min_matches``.

    Feasible at a grid yaw: every member's yaw mask holds, the summed strip
    quadratic's minimum is <= |S| + 1 and lies in free space, every member's
    own term there is <= ``q_max``, and at that best point every segment has a part in front of
    the camera and, with walls, a part not hidden by a wall (unless
    ``visibility`` is False). ``fit`` is the summed quadratic's minimum per
    member."""
    while True:
        passed, members, init = check_once(inp, members, tol, cache, visibility)
        if passed or members is None:
            return None if members is None else (members, init)


def check_once(inp: TreeInput, members: np.ndarray, tol: Tolerances, cache: dict | None = None,
               visibility: bool = True):
    """One step of :func:`final_check`: ``(True, members, (x, y, yaw, fit))``
    if the set passes; else ``(False, smaller, (x, y, yaw, fit))`` with the
    members that failed dropped (the pose where the set was tested, None
    when no yaw was left to test), or ``(False, None, None)`` once it falls
    below ``min_matches``. Repairing one step at a time lets the caller
    test the other large sets before it finishes repairing this one."""
    if len(members) < tol.min_matches:
        return False, None, None
    ce, yaws = inp.centre, inp.yaws
    # Only the yaws every member's mask holds can qualify.
    G = inp.mask[members].all(axis=0).nonzero()[0]
    if not len(G):  # no common yaw: drop the member agreeing least with the others
        m = inp.mask[members].astype(int)
        return False, np.delete(members, int(np.argmin(m @ m.sum(axis=0)))), None
    q = inp.quad[members[:, None], G]  # (S, G, 6)
    val, zx, zy = posegrid.minimise(q.sum(axis=0), inp.dt)
    each = posegrid.evaluate(q, zx, zy)  # (S, G)
    good = (val <= len(members) + 1.0) & (each <= tol.q_max).all(axis=0)
    at = good.nonzero()[0]  # free space only where the rest holds
    good[at] = inp.in_free_space(ce[:2] + np.stack([zx[at], zy[at]], axis=-1))
    if not good.any():
        i = int(val.argmin())
        init = (float(ce[0] + zx[i]), float(ce[1] + zy[i]), float(yaws[G[i]]), float(val[i]) / len(members))
        return False, np.delete(members, int(each[:, i].argmax())), init
    i = int(np.where(good, val, np.inf).argmin())
    g = int(G[i])
    init = (float(ce[0] + zx[i]), float(ce[1] + zy[i]), float(yaws[g]), float(val[i]) / len(members))
    if not visibility:
        return True, members, init
    seen = _seen_cached(inp, members, np.array(init[:2]), g, cache)
    if seen.all():
        return True, members, init
    return False, members[seen], init


def _seen_cached(inp: TreeInput, members: np.ndarray, cam: np.ndarray, g: int, cache: dict | None) -> np.ndarray:
    """:func:`_seen` remembered per (members, grid yaw, centimetre of
    position): a leaf repeats the test its last node made."""
    if cache is None:
        return _seen(inp, members, cam, g)
    key = (members.tobytes(), g, int(round(cam[0] * 100)), int(round(cam[1] * 100)))
    hit = cache.get(key)
    if hit is None:
        hit = cache[key] = _seen(inp, members, cam, g)
    return hit


def _seen(inp: TreeInput, members: np.ndarray, cam: np.ndarray, g: int) -> np.ndarray:
    """(S,) bool: the member's segment has a sample point in front of the
    camera at ``cam`` (2,) and grid yaw index ``g`` and, with walls, with a
    clear sight line."""
    if inp.shown is not None:
        pts = _shown_points(inp, members, cam, float(inp.yaws[g]))
    else:
        segs = inp.segments[members]  # (S, 2, 3)
        pts = segs[:, None, 0] + _SAMPLES[None, :, None] * (segs[:, None, 1] - segs[:, None, 0])
    forward = inp.forward[g]
    C = np.array([cam[0], cam[1], inp.centre[2]])
    S, n = pts.shape[:2]
    front = (pts - C) @ forward > 0.05  # (S, n)
    flat = pts[..., :2]
    # Seen from the point or from any of four points around it
    # (_CAMERA_JITTER): first from the point itself, then, for members not
    # yet seen, from the four others in one batch.
    todo_s, todo_p = front.nonzero()
    seen = np.zeros(S, dtype=bool)
    if len(todo_s) == 0:
        return seen
    seen[todo_s[sight_clear(cam, flat[todo_s, todo_p], inp.walls, _OCCLUSION_END_M)]] = True
    todo_s, todo_p = (front & ~seen[:, None]).nonzero()
    if len(todo_s):
        J = len(_CAMERA_JITTER) - 1
        cams = (cam + _CAMERA_JITTER[1:])[np.tile(np.arange(J), len(todo_s))]
        pts = np.repeat(flat[todo_s, todo_p], J, axis=0)
        clear = sight_clear(cams, pts, inp.walls, _OCCLUSION_END_M)
        seen[np.repeat(todo_s, J)[clear]] = True
    return seen


def _shown_points(inp: TreeInput, members: np.ndarray, cam: np.ndarray, yaw: float) -> np.ndarray:
    """(S, n, 3) points of the part of each member's segment that its image
    line shows at the pose (cam, yaw) (:func:`~matcher.overlap.covered_span`),
    that part widened by _SHOWN_WIDEN_M at both ends: the grid pose is a few
    centimetres and up to half a yaw step off."""
    segs = inp.segments[members]  # (S, 2, 3)
    span = inp.shown.at(members, float(cam[0]), float(cam[1]), yaw)  # (S, 2)
    widen = _SHOWN_WIDEN_M / inp.seg_length[members]
    lo = np.maximum(span[:, 0] - widen, 0.0)
    t = lo[:, None] + _SHOWN_SAMPLES[None, :] * (np.minimum(span[:, 1] + widen, 1.0) - lo)[:, None]  # (S, n)
    return segs[:, None, 0] + t[..., None] * (segs[:, None, 1] - segs[:, None, 0])


def _drop_duplicates(sets, inits):
    """Remove repeated sets (a repaired leaf can equal another leaf)."""
    kept, kept_init, keys = [], [], set()
    for s, p in zip(sets, inits):
        k = s.tobytes()
        if k not in keys:
            keys.add(k)
            kept.append(s)
            kept_init.append(p)
    return kept, kept_init


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
