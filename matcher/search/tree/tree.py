"""The interpretation tree of stage 1: consistent sets of correspondences.

The tree of the paper's setting: one level per image line, whose branches
are the line's candidate model segments (those that passed the unary or
vertical tests) and "unmatched" (clutter, or a segment not in the lists).
A node is a set R of correspondences whose feasible pose set is non-empty:
a child adds a candidate that is pairwise compatible with every member and
keeps the whole set feasible (:mod:`matcher.search.tree.posegrid`, checked for all the
line's candidates at once). Pairwise compatibility holds matching one to
one: two lines share a segment only when they are pieces of one broken
line (:func:`matcher.search.tree.constraints.line_pieces`). A branch is cut when
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

from typing import NamedTuple

import numpy as np

from matcher.search.tree import posegrid
from matcher.search.tree.set_visibility import check_once, final_check, visible_at_best, visible_best
from matcher.search.tree.tree_input import TreeInput
from matcher.tolerances import Tolerances

#: A sort key above every real one.
_NEVER = np.iinfo(np.int64).max
#: Up to this many lines (levels), the lines a candidate reaches are the
#: bits of one int64 (sign bit spared); past it, a one-hot matrix product.
_BIT_LEVELS = np.iinfo(np.int64).bits - 1

__all__ = ["InterpretationTree", "TreeInput", "TreeResult", "check_once", "final_check", "search"]


class TreeResult(NamedTuple):
    """The tree's output: ``sets`` as sorted index arrays into the
    correspondences, ``inits`` their best grid pose ``(x, y, yaw)``;
    ``truncated`` whether a budget (nodes, sets, time) cut the search,
    ``nodes`` the nodes visited and ``found`` the sets found before the
    final checks."""

    sets: list
    inits: list
    truncated: bool
    nodes: int
    found: int


def search(inp: TreeInput, tol: Tolerances, eager: bool = False, aim_high: bool = True) -> TreeResult:
    """Maximal consistent sets of ``inp``: :meth:`InterpretationTree.search`."""
    return InterpretationTree(inp, tol, eager).search(aim_high)


class InterpretationTree:
    """One search of the tree on one frame's correspondences.

    Levels are image lines, ordered so that the pose gets pinned early:
    lines with a non-vertical candidate first (their unary constraint fixes
    the yaw), then by number of candidates; a line's candidates most
    connected first, so that the first dive tends to follow the true match.
    The search state (the sets found, the bound on their size, the node
    count, whether a budget cut it) lives in the fields; :meth:`search`
    runs it. With ``eager`` every leaf gets the set checks as it is found
    (:func:`~matcher.search.tree.set_visibility.final_check`) instead of afterwards.
    """

    def __init__(self, inp: TreeInput, tol: Tolerances, eager: bool = False) -> None:
        self.inp, self.tol, self.eager = inp, tol, eager
        compat = inp.compat
        K, self.Y = inp.mask.shape
        self.K = K
        self.sets: list[np.ndarray] = []
        self.inits: list[tuple] = []
        self.bound = tol.min_matches  # the smallest set still worth finding
        self.truncated = False
        self.nodes = 0
        self.give_up_at = np.inf  # the node count past which a pass that found nothing stops
        self.cache: dict = {}  # visibility tests of (members, grid yaw, position)
        weak = np.zeros(K, dtype=bool) if inp.vertical is None else inp.vertical
        self.weak = weak
        degree = compat.sum(axis=1)
        self.has_plane = np.zeros(K, dtype=bool) if inp.front_b is None else np.isfinite(inp.front_b).any(axis=1)
        self._order_levels(weak, degree)

    def _order_levels(self, weak: np.ndarray, degree: np.ndarray) -> None:
        """The levels (image lines) in search order, each line's candidates
        in trial order: ``cands`` (list of (C_l,) arrays), ``level_of`` (K,),
        ``order_rank`` (K,) each candidate's place in that order."""
        inp, K, compat = self.inp, self.K, self.inp.compat
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
        self.cands = cands
        self.L = L = len(lines)
        self.level_of = np.empty(K, dtype=np.int64)
        for lv, c in enumerate(cands):
            self.level_of[c] = lv
        self.order_rank = np.empty(K, dtype=np.int64)
        self.order_rank[np.concatenate(cands)] = np.arange(K)
        self.strong_level = np.array([(~weak[c]).any() for c in cands], dtype=bool)
        if L <= _BIT_LEVELS:
            # compat_bits[u, v]: the bit of v's level where u and v are
            # compatible, else 0; OR-ed over a pool, the lines u can still reach.
            self.compat_bits = np.where(compat, (np.int64(1) << self.level_of)[None, :], np.int64(0))
        else:
            self.level_hot = np.eye(L, dtype=np.int32)  # row l: one-hot of level l

    # ---- the search ------------------------------------------------------

    def search(self, aim_high: bool = True) -> TreeResult:
        """Maximal consistent sets, at most ``max_hypotheses`` of those found
        (the largest, then those that fit best), each passing the set checks.

        Aim high first (``aim_high``): one pass per target size, from every
        line matched down, until a pass finds a set. A pass whose target is
        out of reach mostly dies near the root (the look-ahead counts cut
        it), while a single pass from the minimum enumerates every small set
        met before its first dive finds a large one. Where sets that leave
        the position loose abound (a row of door jambs), a target out of
        reach can cost many nodes: after ``aim_high_share`` of the budget the
        passes stop and one pass from the minimum raises its bound as it
        finds sets, as do the searches that keep more than the largest sets
        (a slack, or every leaf tested as found)."""
        inp, tol = self.inp, self.tol
        if aim_high and not self.eager and tol.match_slack == 0:
            alone = np.arange(self.K) if inp.single_fit is None else np.nonzero(np.isfinite(inp.single_fit))[0]
            target = len(np.unique(self.level_of[alone]))
            while target > tol.min_matches and not self.sets and not self.truncated:
                if not self._run(target, tol.stage1.aim_high_share * tol.max_nodes - self.nodes):
                    break
                target -= 1
        if not self.sets and not self.truncated:
            self._run(tol.min_matches)
        sets, inits = _drop_duplicates(self.sets, self.inits)
        found = len(sets)
        sets, inits = visible_best(inp, sets, inits, tol, self.cache)
        truncated = self.truncated or not inp.deadlines.may_check()  # the final tests may have been cut short
        if found and not sets and not self.eager:
            # Every set failed the visibility test: the sets that raised the bound
            # may have hidden smaller valid ones. Search again, testing each leaf.
            again = InterpretationTree(inp, tol, eager=True).search()
            return again._replace(nodes=self.nodes + again.nodes)
        return TreeResult(sets, [p[:3] for p in inits], truncated, self.nodes, found)

    def _run(self, target: int, allowance: float = np.inf) -> bool:
        """One pass of the tree for the sets of at least ``target`` members;
        False if it was given up, having met no set within ``allowance``
        more nodes."""
        self.bound = target
        self.give_up_at = self.nodes + allowance
        self._visit([], np.zeros((self.Y, 6)), np.ones(self.Y, dtype=bool), [], np.arange(self.K), None)
        given_up = self.truncated and not self.sets and self.nodes > self.give_up_at
        if given_up:
            self.truncated = False
        return not given_up

    def _out_of_budget(self) -> bool:
        """Count the node; True (and the search marked truncated) once a
        budget is spent: nodes, a pass's allowance, or time."""
        self.nodes += 1
        if (self.nodes > self.tol.max_nodes or (self.nodes > self.give_up_at and not self.sets)
                or not self.inp.deadlines.may_search()):
            self.truncated = True
        return self.truncated

    def _visit(self, R: list[int], Qsum, mR, skipped: list[int], pool: np.ndarray, fit: np.ndarray | None) -> None:
        """The node of set R. ``pool``: candidates of the lines not yet
        decided. With ``fit`` None, R just grew and the pool is filtered
        against it (consistency only shrinks as R grows, so the parent's pool
        is enough); otherwise it is the parent's filtered pool and ``fit``
        their best fits."""
        if self.truncated or self._out_of_budget():
            return
        ahead, fit = self._look_ahead(R, Qsum, mR, pool, fit)
        level_of, L = self.level_of, self.L
        counts = np.bincount(level_of[ahead], minlength=L)
        reachable = int((counts > 0).sum())
        if len(R) + reachable < self.bound:
            return
        if reachable == 0:
            if self._maximal(R, Qsum, mR, skipped):
                self._emit(R, Qsum, mR)
            return
        # Fail first: decide next the line with the fewest candidates left
        # (lines with a non-vertical candidate first among equals).
        key = np.where(counts > 0, counts * 2 - self.strong_level, _NEVER)
        level = int(key.argmin())
        here = level_of[ahead] == level
        c = ahead[here]
        # Best fitting first once the pose is pinned by a few members, else
        # the most connected: either way the first dive tends to follow the
        # true match, which raises the bound for the rest of the search.
        order_rank = self.order_rank
        c = c[np.lexsort((order_rank[c], fit[here]))] if len(R) >= 2 else c[np.argsort(order_rank[c])]
        rest = ahead[~here]
        self._branch(R, Qsum, mR, skipped, c, rest)
        if self.truncated:
            return
        if len(R) + reachable - 1 >= self.bound:
            # The line left unmatched: R is unchanged, so is its filtered pool.
            self._visit(R, Qsum, mR, skipped + [level], rest, fit[~here])

    def _branch(self, R: list[int], Qsum, mR, skipped: list[int], c: np.ndarray, rest: np.ndarray) -> None:
        """The children of R that match the next line to each of its
        candidates ``c`` in turn; ``rest`` the pool of the lines after it."""
        inp, tol = self.inp, self.tol
        quad, mask = inp.quad, inp.mask
        loose_after = tol.stage1.loose_test_after * tol.max_nodes
        # Lines each candidate can still reach: its child's look-ahead keeps
        # only the rest compatible with it, so a candidate that cannot reach
        # the bound is not worth a node (a cheap count against a feasibility
        # pass over the whole pool).
        reach = self._lines_reached(c, rest)
        for v, reach_v in zip(c.tolist(), reach.tolist()):
            if len(R) + 1 + reach_v < self.bound:
                continue
            R2, Q2, m2 = R + [v], Qsum + quad[v], mR & mask[v]
            loose = len(R2) + reach_v if self.nodes > loose_after else 0
            if len(R2) >= tol.min_matches and not visible_at_best(inp, R2, Q2, m2, tol, self.cache, loose):
                continue
            self._visit(R2, Q2, m2, skipped, rest, None)
            if self.truncated:
                return

    def _look_ahead(self, R: list[int], Qsum, mR, pool: np.ndarray, fit: np.ndarray | None):
        """``(ahead, fit)``: the open candidates of all lines still to decide
        that are consistent with R, and their best fits with R. Lines with
        none cannot be matched any more."""
        inp = self.inp
        ahead = pool
        if fit is None and not R and inp.single_fit is not None:
            # The root: each candidate alone, as stage 1 already tested it.
            ahead = ahead[np.isfinite(inp.single_fit[ahead])]
            ahead = ahead[self._well_supported(0, ahead)]
            return ahead, inp.single_fit[ahead]
        if fit is None:
            if R and ahead.size:
                ahead = ahead[inp.compat[R[-1], ahead]]
            ahead = ahead[self._well_supported(len(R), ahead)]
            fit = np.zeros(len(ahead))
            if ahead.size and len(R) >= 2:
                # (With one member, R + {u} feasible is the pairwise test of
                # stage 1 that compat holds, and the fits order nothing yet.)
                ok, fit = self._feasible_with(R, Qsum, mR, ahead, fit=True)
                ahead, fit = ahead[ok], fit[ok]
            return ahead, fit
        # The bound may have risen since the parent filtered the pool.
        keep = self._well_supported(len(R), ahead)
        return ahead[keep], fit[keep]

    # ---- tests on candidates ------------------------------------------------

    def _feasible_with(self, R: list[int], Qsum: np.ndarray, mR: np.ndarray, cand: np.ndarray, fit: bool = False):
        """(C,) bool: is R + {u} feasible, for each u in cand; with ``fit``
        also (C,) the best summed quadratic of R + {u} (inf if infeasible)."""
        G = mR.nonzero()[0]
        if len(G) == 0:
            no = np.zeros(len(cand), dtype=bool)
            return (no, np.full(len(cand), np.inf)) if fit else no
        inp, tol = self.inp, self.tol
        quad = inp.quad
        # Index arrays broadcast (C, 1) x (G,) rather than np.ix_: this runs
        # at every node and np.ix_ alone cost a third of it.
        cc = cand[:, None]
        qc = quad[cc, G]  # (C, G, 6)
        qs = Qsum[G] + qc
        val, zx, zy = posegrid.minimise(qs, inp.dt)
        phi = posegrid.monomials(zx, zy)  # (C, G, 6)
        ok = inp.mask[cc, G] & (val <= len(R) + 2.0) & (posegrid.evaluate_at(qc, phi) <= tol.q_max)
        if R:
            each = np.einsum("sgk,cgk->scg", quad[np.array(R)[:, None], G], phi)  # (S, C, G)
            ok &= (each <= tol.q_max).all(axis=0)
        if inp.front_c is not None:
            # Half-planes (vertical edges ahead, wall faces seen from the
            # room): the candidates' own and those of R's members (the
            # feasible set shrinks as R grows), each at every candidate.
            has_plane = self.has_plane
            hp = [r for r in R if has_plane[r]]
            if hp or has_plane[cand].any():
                ell = posegrid.feasible_ellipse(qs, val, zx, zy, len(R) + 1, tol.q_max, inp.dt)
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

    def _open_candidates(self, level: int, R: list[int]) -> np.ndarray:
        """Candidates of the line at ``level`` pairwise compatible with every
        member of R (so not using a matched segment, but for pieces of one
        broken line)."""
        c = self.cands[level]
        if R and c.size:
            c = c[self.inp.compat[np.array(R)[:, None], c].all(axis=0)]
        return c

    def _maximal(self, R: list[int], Qsum, mR, skipped: list[int]) -> bool:
        """No skipped line can take a candidate consistent with all of R."""
        extra = [self._open_candidates(lv, R) for lv in skipped]
        extra = np.concatenate(extra) if extra else np.zeros(0, dtype=np.int64)
        return not (extra.size and self._feasible_with(R, Qsum, mR, extra).any())

    def _lines_reached(self, cand: np.ndarray, pool: np.ndarray) -> np.ndarray:
        """(C,) for each of ``cand``: how many lines hold a candidate of
        ``pool`` compatible with it (a bitwise OR and a bit count; a matrix
        product of one-hot levels past _BIT_LEVELS lines)."""
        if not pool.size:
            return np.zeros(len(cand), dtype=np.int64)
        if self.L <= _BIT_LEVELS:
            return np.bitwise_count(np.bitwise_or.reduce(self.compat_bits[cand][:, pool], axis=1)).astype(np.int64)
        compat = self.inp.compat
        return (compat[cand[:, None], pool].astype(np.int32) @ self.level_hot[self.level_of[pool]] > 0).sum(axis=1)

    def _well_supported(self, n_members: int, ahead: np.ndarray) -> np.ndarray:
        """(A,) bool: the candidates of ``ahead`` that can still be part of a
        set of the bound's size with ``n_members`` others: compatible with
        candidates of enough other lines of ``ahead`` (repeated until no more
        go: each removal lowers the others' counts). Pairwise only, so cheap
        next to a feasibility pass, which it spares those candidates."""
        keep = np.full(len(ahead), True)
        while keep.any():
            idx = keep.nonzero()[0]
            ok = n_members + 1 + self._lines_reached(ahead[idx], ahead[idx]) >= self.bound
            if ok.all():
                break
            keep[idx[~ok]] = False
        return keep

    # ---- leaves ------------------------------------------------------------

    def _emit(self, R: list[int], Qsum, mR) -> None:
        """Record the leaf R (tested now if eager), raising the bound."""
        inp, tol = self.inp, self.tol
        if self.eager:
            res = final_check(inp, np.array(sorted(R)), tol, self.cache)
        else:
            # Every addition kept the set feasible at some grid yaw, so the
            # geometry holds; visibility, the dearer test, runs at the end on
            # the sets that could become hypotheses (inner nodes tested it
            # once the pose was pinned). Here only the best grid pose.
            G = mR.nonzero()[0]
            val, zx, zy = posegrid.minimise(Qsum[G], inp.dt)
            g = int(val.argmin())
            res = (np.array(sorted(R)), (float(inp.centre[0] + zx[g]), float(inp.centre[1] + zy[g]),
                                          float(inp.yaws[G[g]]), float(val[g]) / len(R)))
        if res is None or len(res[0]) < self.bound:
            return
        new_bound = max(self.bound, len(res[0]) - tol.match_slack)
        if new_bound > self.bound:  # sets now too small are dropped at once
            keep = [i for i, s in enumerate(self.sets) if len(s) >= new_bound]
            self.sets[:], self.inits[:] = [self.sets[i] for i in keep], [self.inits[i] for i in keep]
            self.bound = new_bound
        self.sets.append(res[0])
        self.inits.append(res[1])
        if len(self.sets) >= tol.max_sets:
            self.truncated = True


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
