"""Stage 1: matching hypotheses without computing poses (method.md sections 3-7).

For one prior (a disk of positions, an interval of headings) and the
candidate model segments it meets:

1. correspondences (:mod:`matcher.search.tree.correspondences`): the unary,
   vertical and horizon tests, then each survivor's yaw mask, position
   strip and half-plane on the pose grid;
2. pairwise compatibility (:mod:`matcher.search.tree.pairwise`);
3. the interpretation tree (:mod:`matcher.search.tree.tree`): the maximal sets of
   correspondences that are pairwise compatible and whose whole feasible
   pose set is non-empty, with at least the minimum number of matches,
   each passing the set checks (:mod:`matcher.search.tree.set_visibility`).

Each hypothesis carries the grid yaw and position at which it is feasible:
the starting point of stage 2. The tree's input stays with the hypotheses
(``Hypotheses.tree_input``), for the other hypothesis sources of
:mod:`matcher.search.tree.strategy` and for tools that look inside.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from linemap.camera import Camera
from matcher.budget import NO_LIMIT, Deadlines
from matcher.candidates import Candidates
from matcher.frame import ImageLines
from matcher.projection import ShownSpans
from matcher.map_geometry.occlusion import SightRays
from matcher.search.tree.correspondences import Correspondences, find_correspondences
from matcher.search.tree.pairwise import pair_compatibility
from matcher.search.tree.tree import TreeInput, search
from matcher.tolerances import Tolerances


@dataclass
class Hypotheses:
    """Stage 1 output. Correspondence k pairs ``segment[k]`` (map id) with
    ``line[k]`` (image line index). ``sets`` lists hypotheses as arrays of
    correspondence indices; ``init`` (H, 3) their feasible ``(x, y, yaw)``."""

    segment: np.ndarray
    line: np.ndarray
    sets: list[np.ndarray]
    init: np.ndarray
    n_segments: int
    n_correspondences: int
    truncated: bool = False
    counts: dict = field(default_factory=dict)
    #: The tree's input (correspondences' strips, pairwise compatibility,
    #: which of them are vertical), for :func:`search_again` and the
    #: resection; None when stage 1 stopped before the tree.
    tree_input: TreeInput | None = None


def generate(cands: Candidates, camera: Camera, image_lines: ImageLines, prior, tol: Tolerances,
             deadlines: Deadlines = NO_LIMIT) -> Hypotheses:
    """Stage 1 on the collinear groups of ``cands`` (their spans ``reps``) under ``prior`` ``(xe, ye,
    yaw_e, dt, dyaw)`` (radians). ``deadlines`` the call's time budget
    (:mod:`matcher.budget`): the tree stops at them, its sets so far are
    kept, ``truncated`` is set and ``counts["out_of_time"]`` says why.
    ``Hypotheses.segment`` holds group indices (into ``cands.reps``)."""
    t_start = time.perf_counter()
    segments, dt = cands.reps, prior[3]
    sight = cands.sight
    if sight is None and cands.walls is not None:
        sight = SightRays(cands.walls, tol.map_index)
    counts: dict = {}
    corr = find_correspondences(segments, camera, image_lines, prior, tol, sight, cands.faces, counts)
    if not isinstance(corr, Correspondences):  # too few: the unary survivors, for the counts
        seg_k, line_k = corr
        return Hypotheses(seg_k.astype(np.int64), line_k, [], np.zeros((0, 3)), len(segments),
                          int(counts.get("correspondences", 0)), False, counts)

    t_pairs = time.perf_counter()
    compat = pair_compatibility(image_lines, corr, dt, tol, deadlines)
    if compat is None:  # out of time before the tree could start
        counts.update(out_of_time=True, tree_nodes=0, sets_found=0)
        return Hypotheses(corr.seg_k, corr.line_k, [], np.zeros((0, 3)), len(segments), len(corr), True, counts)
    counts["compatible_pairs"] = int(compat.sum() // 2)

    t_tree = time.perf_counter()
    seg_k, line_k = corr.seg_k, corr.line_k
    inp = TreeInput(corr.quad, corr.mask, corr.yaws, compat, segments[seg_k], corr.centre, dt, corr.forward,
                    cands.walls, vertical=corr.is_v, line=line_k, free=cands.free, free_m=tol.free_space_m,
                    front_c=corr.front_c, front_b=corr.front_b, single_fit=corr.single_fit, sight=sight,
                    shown=ShownSpans(camera, segments[seg_k], image_lines.lines[line_k]), deadlines=deadlines)
    sets, init, truncated, nodes, found = search(inp, tol)
    counts["out_of_time"] = bool(truncated and not deadlines.may_search())
    counts["tree_nodes"] = int(nodes)
    counts["sets_found"] = int(found)
    counts["ms_correspondences"] = round((t_pairs - t_start) * 1e3, 3)
    counts["ms_pairs"] = round((t_tree - t_pairs) * 1e3, 3)
    counts["ms_tree"] = round((time.perf_counter() - t_tree) * 1e3, 3)
    return Hypotheses(seg_k, line_k, sets, np.array(init).reshape(-1, 3), len(segments), len(corr),
                      truncated, counts, tree_input=inp)


def search_again(hyps: Hypotheses, tol: Tolerances) -> Hypotheses:
    """Stage 1's tree run again on the correspondences of ``hyps`` with
    other tolerances (the second search, keeping sets smaller than the
    largest: ``tol.match_slack``). The correspondences, their strips and
    pairwise tests do not depend on the slack, so only the tree runs."""
    if hyps.tree_input is None:
        return hyps
    t0 = time.perf_counter()
    sets, init, truncated, nodes, found = search(hyps.tree_input, tol)
    counts = dict(hyps.counts, tree_nodes=int(nodes), sets_found=int(found),
                  out_of_time=bool(truncated and not hyps.tree_input.deadlines.may_search()),
                  ms_tree=round((time.perf_counter() - t0) * 1e3, 3))
    return replace(hyps, sets=sets, init=np.array(init).reshape(-1, 3), truncated=truncated, counts=counts)
