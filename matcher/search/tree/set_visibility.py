"""Stage 1: the tests a set of correspondences passes beyond feasibility.

The interpretation tree (:mod:`matcher.search.tree.tree`) keeps a set when its
strips meet at some grid pose. A set must also put the camera where the
robot can stand (free space) and see each matched segment there (in front
of the camera, not hidden by a wall). Those tests need a pose that the set
pins down, so inside the tree they run once the set fixes the position
(:func:`visible_at_best`), and every leaf gets them at its best grid pose
before it becomes a hypothesis (:func:`check_once`, :func:`visible_best`).

Visibility here is at a grid pose, a few centimetres and up to half a yaw
step off: a sight line counts as blocked only well away from its ends
(``Stage1Constants.grid_sight_end_m``) and a segment counts as seen from the pose
or a point around it (``Stage1Constants.grid_jitter_m``). Stage 2's test at the
refined pose (:func:`matcher.stage2.fit.visible`) is stricter.
"""

from __future__ import annotations

import heapq

import numpy as np

from matcher.map_geometry.occlusion import sight_clear
from matcher.search.tree import posegrid
from matcher.search.tree.tree_input import TreeInput
from matcher.tolerances import SharedConstants, Stage1Constants, Tolerances


def visible_best(inp: TreeInput, sets, inits, tol: Tolerances, cache):
    """The hypotheses: sets passing the visibility test (a set failing it
    loses its unseen members and queues again), largest first, then best
    fitting, at most ``max_hypotheses``, all at least as large as the
    largest passing set minus ``match_slack``; those found by the
    deadline of the checks."""
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
    return drop_dominated(out, out_init)


def _best_pose(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, tol: Tolerances):
    """``(pinned, g, cam)`` for a set R: its best grid yaw index ``g`` (None
    when no yaw is left) and camera position ``cam`` (2,) there. The
    position is pinned when the set's feasible points at that yaw (every
    member's term <= ``q_max``) reach less than ``pinned_m`` along the
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
    pinned_m = tol.stage1.pinned_m
    if lam < 1.0 / pinned_m**2:  # cheap early out: even the summed strips leave it loose
        return False, g, cam
    lo, hi = posegrid.stretch(inp.quad[R, g], z, e, tol.q_max, inp.dt)
    return hi - lo <= pinned_m, g, cam


def visible_at_best(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, tol: Tolerances,
                    cache: dict | None = None, loose: int = 0) -> bool:
    """Once a set fixes the pose (three members or more): is its best grid
    pose in free space, with all its segments in front of the camera and
    unhidden? (Before that the best point may be far from the truth and the
    test would prune true sets.) With ``loose`` (the most members a leaf
    below R can have; 0: off), a set that does not fix the position and has
    just taken a vertical edge is tested too, on its whole feasible region
    (:func:`edge_seen_from_region`)."""
    pinned, g, cam = _best_pose(inp, R, Qsum, mR, tol)
    if g is None:
        return False
    if not pinned:
        if loose and inp.walls is not None and inp.vertical is not None and inp.vertical[R[-1]]:
            return edge_seen_from_region(inp, R, Qsum, mR, tol, loose)
        return True
    if not inp.in_free_space(cam):
        return False
    return bool(_seen_cached(inp, np.asarray(sorted(R)), cam, g, tol, cache).all())


def edge_seen_from_region(inp: TreeInput, R: list[int], Qsum: np.ndarray, mR: np.ndarray, tol: Tolerances,
                          most: int) -> bool:
    """Can the vertical edge of ``R[-1]`` be seen from some point of R's
    feasible region that lies in free space? If not, no leaf below R passes
    the leaf test (its pose is such a point, and must see every member).

    The region at each yaw of ``mR`` is taken as the box spanned by its
    stretches (every member's term <= ``q_max``) along the two axes of the
    summed quadratic through its minimiser, sampled every ``region_step_m``: a
    box holds the points of the region near those axes and more, so the
    test errs towards keeping. The edge stands at one floor point, so one
    sight line per sample decides. Only yaws where a leaf of at most
    ``most`` members could stand count: adding members only raises the
    summed quadratic's minimum, and a leaf's must stay <= its size + 1."""
    q_max, work = tol.q_max, tol.stage1
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
    n_w = int(min(np.ceil((hi_w - lo_w).max() / work.region_step_m) + 1, work.region_max))
    n_s = int(min(np.ceil((hi_s - lo_s).max() / work.region_step_m) + 1, work.region_max))
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
        return bool(sight_clear(pts, np.broadcast_to(edge, pts.shape), inp.walls, work.grid_sight_end_m, tol.shared).any())
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
    seen = _seen_cached(inp, members, np.array(init[:2]), g, tol, cache)
    if seen.all():
        return True, members, init
    return False, members[seen], init


def _seen_cached(inp: TreeInput, members: np.ndarray, cam: np.ndarray, g: int, tol: Tolerances,
                 cache: dict | None) -> np.ndarray:
    """:func:`_seen` remembered per (members, grid yaw, centimetre of
    position): a leaf repeats the test its last node made."""
    if cache is None:
        return _seen(inp, members, cam, g, tol.stage1, tol.shared)
    key = (members.tobytes(), g, int(round(cam[0] * 100)), int(round(cam[1] * 100)))
    hit = cache.get(key)
    if hit is None:
        hit = cache[key] = _seen(inp, members, cam, g, tol.stage1, tol.shared)
    return hit


def _seen(inp: TreeInput, members: np.ndarray, cam: np.ndarray, g: int, work: Stage1Constants,
          shared: SharedConstants) -> np.ndarray:
    """(S,) bool: the member's segment has a sample point in front of the
    camera at ``cam`` (2,) and grid yaw index ``g`` and, with walls, with a
    clear sight line."""
    if inp.shown is not None:
        pts = _shown_points(inp, members, cam, float(inp.yaws[g]), work)
    else:
        segs = inp.segments[members]  # (S, 2, 3)
        pts = segs[:, None, 0] + work.grid_sight_array[None, :, None] * (segs[:, None, 1] - segs[:, None, 0])
    forward = inp.forward[g]
    C = np.array([cam[0], cam[1], inp.centre[2]])
    S, n = pts.shape[:2]
    front = (pts - C) @ forward > work.in_front_m  # (S, n)
    flat = pts[..., :2]
    # Seen from the point or from any of four points around it
    # (``grid_jitter_m``): first from the point itself, then, for members not
    # yet seen, from the four others in one batch.
    todo_s, todo_p = front.nonzero()
    seen = np.zeros(S, dtype=bool)
    if len(todo_s) == 0:
        return seen
    seen[todo_s[sight_clear(cam, flat[todo_s, todo_p], inp.walls, work.grid_sight_end_m, shared)]] = True
    todo_s, todo_p = (front & ~seen[:, None]).nonzero()
    if len(todo_s):
        jitter = work.jitter_array
        J = len(jitter) - 1
        cams = (cam + jitter[1:])[np.tile(np.arange(J), len(todo_s))]
        pts = np.repeat(flat[todo_s, todo_p], J, axis=0)
        clear = sight_clear(cams, pts, inp.walls, work.grid_sight_end_m, shared)
        seen[np.repeat(todo_s, J)[clear]] = True
    return seen


def _shown_points(inp: TreeInput, members: np.ndarray, cam: np.ndarray, yaw: float, work: Stage1Constants) -> np.ndarray:
    """(S, n, 3) points of the part of each member's segment that its image
    line shows at the pose (cam, yaw) (:func:`~matcher.projection.covered_span`),
    that part widened by ``shown_widen_m`` at both ends: the grid pose is a few
    centimetres and up to half a yaw step off."""
    segs = inp.segments[members]  # (S, 2, 3)
    span = inp.shown.at(members, float(cam[0]), float(cam[1]), yaw)  # (S, 2)
    widen = work.shown_widen_m / inp.seg_length[members]
    lo = np.maximum(span[:, 0] - widen, 0.0)
    t = lo[:, None] + work.shown_array[None, :] * (np.minimum(span[:, 1] + widen, 1.0) - lo)[:, None]  # (S, n)
    return segs[:, None, 0] + t[..., None] * (segs[:, None, 1] - segs[:, None, 0])


def drop_dominated(sets, inits):
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
