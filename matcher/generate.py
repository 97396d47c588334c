"""Stage 1: matching hypotheses without computing poses (method.md sections 3-7).

Pipeline, for candidate model segments L (from the regions met by the prior
disk, cut to the horizontal field of view) and image lines l:

1. split L into vertical ``Lv`` and non-vertical ``Lh`` segments, and pick
   the image lines that may be vertical edges (exact test ``|n . R e_z|``);
2. unary test on ``Lh x l`` (yaw solution in the interval, position line
   meets the disk), bearing test on ``Lv x lv``: the survivors are the
   correspondences;
3. pairwise compatibility: one-to-one, the paper's binary test on couples of
   vertical correspondences, and for every couple a common pose in the prior
   set (strips of both meet inside the disk at one yaw of the grid);
4. interpretation tree (:mod:`matcher.tree`): the maximal sets of
   correspondences that are pairwise compatible and whose whole feasible
   pose set is non-empty, with at least the minimum number of matches.

Each hypothesis carries the grid yaw and position at which it is feasible:
the starting point of stage 2.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from matcher import posegrid
from linemap.geometry import segment_is_vertical
from matcher.budget import NO_LIMIT, Deadlines
from linemap.camera import Camera
from linemap.camera import world2cam_rotation
from matcher.constraints import binary_constraint, distinct_points, unary_constraint, wrap
from matcher.occlusion import SightRays
from matcher.overlap import ShownSpans
from matcher.tolerances import VERTICAL_AXIS_DEG, Tolerances
from matcher.tree import TreeInput, search


@dataclass
class ImageLines:
    """Per-line quantities, computed once per frame.

    ``lines`` (M, 2, 2) undistorted pixels; ``normals`` (M, 3) unit, camera
    frame; ``eps`` (M,) plane noise, radians, split into ``eps_rot`` (turn
    about the midpoint ray, from orientation noise) and ``eps_off`` (from
    offset noise); ``mid_rays`` (M, 3) unit rays of the midpoints; ``vertical`` (M,) bool vertical
    candidates; ``alpha`` (M,) bearings of vertical candidates, radians, to
    the right; ``alpha_eps`` (M,) their noise bound; ``usable`` (M,) bool long
    enough to use; ``pieces`` (M, M) bool, couples that may be pieces of one
    broken line (:func:`~matcher.constraints.line_pieces`), or None: none."""

    lines: np.ndarray
    normals: np.ndarray
    eps: np.ndarray
    vertical: np.ndarray
    alpha: np.ndarray
    alpha_eps: np.ndarray
    usable: np.ndarray
    eps_rot: np.ndarray
    eps_off: np.ndarray
    mid_rays: np.ndarray
    pieces: np.ndarray | None = None


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


def _vertical_sight(points, rows, alpha, yaw, centre, dt, width, step, sight, extent) -> np.ndarray:
    """(E,) bool per entry e: a vertical edge at floor point
    ``points[rows[e]]`` (points (U, 2)) seen at bearing ``alpha[e]`` (right
    of the axis) with heading ``yaw[e]``: the camera lies on the ray back
    from the edge at world bearing ``yaw - alpha``, up to the first wall that
    would hide the edge. True where that stretch comes within ``dt +
    width[e]`` of the disk centre; the stretch is also cut at
    ``extent[rows[e]]``, the farthest the edge can be for its image line to
    fit inside its projection (:func:`vertical_extent_bound`). The stretches
    come from the map's :class:`~matcher.occlusion.SightRays` table."""
    first, inv = distinct_points(points)  # edges shared by several correspondences: looked up once
    # For each entry: the bearing from camera to edge, and how far the ray
    # back from the edge runs.
    beta = yaw - alpha  # (E,)
    lam = sight.reach_along(points[first], inv[rows], beta + np.pi)
    rel = points[rows] - centre  # (E, 2) edge from the disk centre
    dist = np.hypot(rel[:, 0], rel[:, 1])
    lam = np.minimum(np.minimum(lam, dist + dt + 1.0), extent[rows])
    # Distance from the disk centre to the stretch P - s u, s in [0, lam].
    ux, uy = np.cos(beta), np.sin(beta)
    s_ = np.clip(rel[:, 0] * ux + rel[:, 1] * uy, 0.0, lam)
    gap = np.hypot(rel[:, 0] - s_ * ux, rel[:, 1] - s_ * uy)
    slack = width + dist * (0.5 * step + sight.step)
    return gap <= dt + slack


def vertical_extent_bound(camera: Camera, lines: np.ndarray, segments: np.ndarray, tol: Tolerances) -> np.ndarray:
    """(K,) largest horizontal distance, metres, at which a vertical segment
    (K, 2, 3) can stand for its image line (K, 2, 2) to fit inside its
    projection: an end point seen at elevation e < 0 needs the segment to
    reach down to ``h + d tan e``, so ``d <= (h - z_bottom) / tan(-e)``;
    likewise upwards. Elevations are moved toward the horizon by the
    end-point noise first, so the bound never cuts a true match."""
    rays = camera.pixel_rays(lines)  # (K, 2, 3)
    p = camera.pitch
    # World z of a camera ray: d_z * Y + f_z * Z with rows d, f of R.
    z = -math.cos(p) * rays[..., 1] - math.sin(p) * rays[..., 2]
    elev = np.arcsin(z / np.linalg.norm(rays, axis=-1))
    slack = (tol.line_end_px + tol.line_px) / min(camera.fx, camera.fy)
    elev = np.sign(elev) * np.maximum(np.abs(elev) - slack, 0.0)
    h = camera.height_m
    zlo = segments[:, :, 2].min(axis=1)[:, None]
    zhi = segments[:, :, 2].max(axis=1)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        down = np.where(elev < 0, np.maximum(h - zlo, 0.0) / np.tan(-elev), np.inf)
        up = np.where(elev > 0, np.maximum(zhi - h, 0.0) / np.tan(elev), np.inf)
    return np.minimum(down, up).min(axis=1)


def horizon_side_ok(camera: Camera, lines: np.ndarray, segments: np.ndarray, tol: Tolerances) -> np.ndarray:
    """(N, M) bool: can segment n (N, 2, 3) show as image line m (M, 2, 2) as
    far as heights go? Every point of a true line images a point of its
    segment, and a point seen above the horizon (world elevation > 0) lies
    above the camera. So a line reaching above the horizon (by more than its
    noise) needs a segment reaching above the camera height, and a line
    reaching below it a segment reaching below. A line crossing the horizon
    is thus never a horizontal segment away from camera height, whatever
    the heading: this cuts the floor and ceiling lines that a vertical image
    line would otherwise fit when they run along the sight line."""
    rays = camera.pixel_rays(lines)  # (M, 2, 3)
    p = camera.pitch
    z = -math.cos(p) * rays[..., 1] - math.sin(p) * rays[..., 2]
    elev = np.arcsin(z / np.linalg.norm(rays, axis=-1))
    slack = (tol.line_px + tol.line_end_px) / min(camera.fx, camera.fy) + math.radians(tol.line_deg) * 0.05
    reaches_above = elev.max(axis=1) > slack  # (M,)
    reaches_below = elev.min(axis=1) < -slack
    h = camera.height_m
    zlo, zhi = segments[:, :, 2].min(axis=1), segments[:, :, 2].max(axis=1)
    seg_below = zhi < h - tol.model_m  # (N,) wholly below the camera
    seg_above = zlo > h + tol.model_m
    bad = (reaches_above[None, :] & seg_below[:, None]) | (reaches_below[None, :] & seg_above[:, None])
    return ~bad


def collinear_classes(segments: np.ndarray, angle_deg: float = 0.5, dist_m: float = 0.01,
                      label: np.ndarray | None = None):
    """Group segments (N, 2, 3) lying on one 3D line (pieces of a wall split by
    a door, say): image lines cannot tell them apart, so stage 1 works on one
    representative per group. Returns ``(label (N,), reps (G, 2, 3))``, each
    representative spanning all its members. ``label`` (N,), if given, is a
    grouping already known (any integers, such as the map-wide
    :func:`collinear_labels` of these segments): only the spans are made."""
    if label is None:
        label = collinear_labels(segments, angle_deg, dist_m)
    # Groups numbered in order of their first member (as the greedy grouping
    # does), whatever integers ``label`` used.
    _, first, label = np.unique(label, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    label, first = rank[label.reshape(-1)], np.sort(first)
    if len(first) == 0:
        return label.astype(np.int64), np.zeros((0, 2, 3))
    # Span of each group along its first member's direction.
    p0 = segments[first, 0]  # (G, 3)
    v = segments[first, 1] - p0
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    t = np.einsum("nek,nk->ne", segments - p0[label][:, None], v[label])  # (N, 2)
    lo = np.full(len(first), np.inf)
    hi = np.full(len(first), -np.inf)
    np.minimum.at(lo, label, t.min(axis=1))
    np.maximum.at(hi, label, t.max(axis=1))
    reps = np.stack([p0 + lo[:, None] * v, p0 + hi[:, None] * v], axis=1)
    return label.astype(np.int64), reps


def collinear_labels(segments: np.ndarray, angle_deg: float = 0.5, dist_m: float = 0.01,
                     chunk: int = 256) -> np.ndarray:
    """(N,) group id of segments (N, 2, 3): two segments go together when
    they are parallel within ``angle_deg`` and each one's end points lie
    within ``dist_m`` of the other's line; groups form greedily in index
    order. The pairwise test runs in row chunks so that a large map does not
    need an (N, N, 2, 3) array; the pipeline makes this once per map."""
    n = len(segments)
    v = segments[:, 1] - segments[:, 0]
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    sin_max = math.sin(math.radians(angle_deg))
    near = np.zeros((n, n), dtype=bool)
    for i0 in range(0, n, chunk):
        rows = slice(i0, min(i0 + chunk, n))
        par = np.linalg.norm(np.cross(v[rows, None], v[None]), axis=2) <= sin_max
        rel = segments[None, :, :, :] - segments[rows, None, None, 0, :]  # (r, N, 2, 3): j's ends from i's start
        off = np.linalg.norm(np.cross(rel, v[rows, None, None, :]), axis=3).max(axis=2)
        near[rows] = par & (off <= dist_m)
    near &= near.T
    label = np.full(n, -1, dtype=np.int64)
    g = 0
    for i in range(n):
        if label[i] < 0:
            label[near[i] & (label < 0)] = g
            g += 1
    return label


def yaw_grid(yaw_e: float, dyaw: float, step: float) -> np.ndarray:
    """(Y,) yaws covering the interval with spacing at most ``step`` (radians)."""
    if dyaw >= math.pi:
        n = int(math.ceil(2 * math.pi / step))
        return wrap(yaw_e + np.arange(n) * (2 * math.pi / n))
    n = int(math.ceil(2 * dyaw / step)) + 1
    return yaw_e + np.linspace(-dyaw, dyaw, n)


def generate(
    segments: np.ndarray,
    seg_ids: np.ndarray,
    camera: Camera,
    img: ImageLines,
    prior: tuple[float, float, float],
    dt: float,
    dyaw: float,
    tol: Tolerances,
    walls: tuple[np.ndarray, np.ndarray] | None = None,
    debug: dict | None = None,
    free=None,
    sight=None,
    faces: np.ndarray | None = None,
    deadlines: Deadlines = NO_LIMIT,
) -> Hypotheses:
    """Stage 1 on candidate ``segments`` (N, 2, 3) with map ids ``seg_ids`` (N,).

    ``walls``: wall edges ``(a (E, 2), b (E, 2))`` for the visibility check
    of the tree's final test, or None; ``free`` the map's
    :class:`~matcher.freespace.FreeSpace`, or None to allow any position;
    ``sight`` the walls' :class:`~matcher.occlusion.SightRays` (kept with the
    map by the pipeline; made here from ``walls`` if None); ``faces`` (N, 2)
    the room-side normal of the wall face each candidate lies on, zeros for
    none (:func:`~matcher.occlusion.face_normals`), or None; ``deadlines``
    the call's time budget (:mod:`matcher.budget`): the tree stops at them,
    its sets so far are kept, ``truncated`` is set and
    ``counts["out_of_time"]`` says why. ``debug``, if a dict, receives the
    intermediate arrays (for tools)."""
    t_start = time.perf_counter()
    xe, ye, yaw_e = prior
    step = math.radians(tol.yaw_step_deg)
    h = camera.height_m
    ce = np.array([xe, ye, h])
    yaws = yaw_grid(yaw_e, dyaw, step)
    Rg = world2cam_rotation(yaws, camera.pitch)  # (Y, 3, 3)
    W = np.einsum("gki,mk->mgi", Rg, img.normals)  # (M, Y, 3) world normals R^T n
    fwd = Rg[:, 2, :]  # (Y, 3) optical axis

    vert_seg = segment_is_vertical(segments, VERTICAL_AXIS_DEG)
    v = segments[:, 1] - segments[:, 0]
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    tpar = np.einsum("nk,nk->n", ce - segments[:, 0], v)
    near = segments[:, 0] + tpar[:, None] * v  # point of each line nearest the prior centre
    usable = img.usable

    # ---- correspondences ------------------------------------------------
    ih = np.nonzero(~vert_seg)[0]
    uh, _ = unary_constraint(camera, img.normals, img.eps, segments[ih], prior, dt, dyaw, tol.model_m)
    uh &= usable[None, :]
    uh &= horizon_side_ok(camera, img.lines, segments[ih], tol)
    hi_, hj = np.nonzero(uh)
    hi_ = ih[hi_]
    iv = np.nonzero(vert_seg)[0]
    jv = np.nonzero(img.vertical & usable)[0]
    vv = horizon_side_ok(camera, img.lines[jv], segments[iv], tol)  # (Nv, Mv)
    vi_, vj = np.nonzero(vv)
    vi_, vj = iv[vi_], jv[vj]
    seg_k = np.concatenate([hi_, vi_]).astype(np.int64)
    line_k = np.concatenate([hj, vj]).astype(np.int64)
    is_v = np.concatenate([np.zeros(len(hi_), bool), np.ones(len(vi_), bool)])
    counts = {"segments": int(len(segments)), "vertical_segments": int(vert_seg.sum()),
              "lines": int(len(img.lines)), "vertical_lines": int(len(jv)),
              "unary_pairs": int(len(hi_)), "vertical_pairs": int(len(vi_))}
    empty = Hypotheses(seg_ids[seg_k] if len(seg_k) else np.zeros(0, np.int64), line_k, [], np.zeros((0, 3)),
                       len(segments), 0, False, counts)
    if len(seg_k) < tol.min_matches:
        return empty

    if sight is None and walls is not None:
        sight = SightRays(walls)
    mask, quad = _strips(camera, img, segments, v, near, seg_k, line_k, is_v, W, Rg, yaws, ce, dt, step,
                         tol, sight)
    val, zx, zy = posegrid.minimise(quad, dt)
    mask &= val <= 2.0
    front_c, front_b = _half_planes(img, segments, near, seg_k, line_k, is_v, yaws, ce, faces)
    mask &= posegrid.halfplane_reachable(quad, val, zx, zy, 1, tol.q_max, dt, front_c, front_b)
    keep = mask.any(axis=1)
    seg_k, line_k, is_v, mask, quad = seg_k[keep], line_k[keep], is_v[keep], mask[keep], quad[keep]
    front_c, front_b = front_c[keep], front_b[keep]
    # Each correspondence alone as the tree's root tests it (its own term
    # within q_max at the minimiser too), from the arrays at hand.
    val, zx, zy = val[keep], zx[keep], zy[keep]
    single_fit = np.where(mask & (posegrid.evaluate(quad, zx, zy) <= tol.q_max), val, np.inf).min(axis=1)
    K = len(seg_k)
    counts["correspondences"] = int(K)
    empty.segment, empty.line, empty.n_correspondences = seg_ids[seg_k], line_k, K
    if K < tol.min_matches:
        return empty

    # ---- pairwise compatibility ----------------------------------------
    t_pairs = time.perf_counter()
    compat = _pair_compat(img, near, seg_k, line_k, is_v, mask, quad, (xe, ye), dt, tol, front_c, front_b)
    counts["compatible_pairs"] = int(compat.sum() // 2)
    if debug is not None:
        debug.update(seg_k=seg_k, line_k=line_k, is_v=is_v, mask=mask, quad=quad, compat=compat, yaws=yaws,
                     uh=uh, ih=ih)

    # ---- interpretation tree -------------------------------------------
    t_tree = time.perf_counter()
    inp = TreeInput(quad, mask, yaws, compat, segments[seg_k], ce, dt, fwd, walls, vertical=is_v, line=line_k,
                    free=free, free_m=tol.free_space_m, front_c=front_c, front_b=front_b,
                    single_fit=single_fit, sight=sight, shown=ShownSpans(camera, segments[seg_k], img.lines[line_k]),
                    deadlines=deadlines)
    if debug is not None:
        debug["tree_input"] = inp
    sets, init, truncated, nodes, found = search(inp, tol)
    counts["out_of_time"] = bool(truncated and not deadlines.may_search())
    counts["tree_nodes"] = int(nodes)
    counts["sets_found"] = int(found)
    counts["ms_correspondences"] = round((t_pairs - t_start) * 1e3, 3)
    counts["ms_pairs"] = round((t_tree - t_pairs) * 1e3, 3)
    counts["ms_tree"] = round((time.perf_counter() - t_tree) * 1e3, 3)
    return Hypotheses(seg_ids[seg_k], line_k, sets, np.array(init).reshape(-1, 3), len(segments), K,
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


def _strips(camera, img, segments, v, near, seg_k, line_k, is_v, W, Rg, yaws, ce, dt, step, tol, sight):
    """Yaw masks (K, Y) and strip quadratics (K, Y, 6) of correspondences
    ``(seg_k, line_k)`` (K,); ``W`` (M, Y, 3) the image lines' world normals
    at each grid yaw, ``Rg`` (Y, 3, 3) the world-to-camera rotations at the
    grid yaws ``yaws`` (Y,), ``v`` (N, 3) unit directions, ``near`` (N, 3)
    points of the segments' lines nearest the prior centre ``ce`` (the
    camera centre of the prior: ``ce[2]`` is the camera height). Strips are
    computed only where the yaw mask holds (zeros elsewhere): a third of
    the entries or fewer."""
    K, Y = len(seg_k), len(yaws)
    # Yaw masks: direction constraint for non-vertical, bearing range for vertical.
    mask = np.empty((K, Y), dtype=bool)
    ih = np.nonzero(~is_v)[0]
    dir_res = np.abs(np.einsum("kgi,ki->kg", W[line_k[ih]], v[seg_k[ih]]))
    mask[ih] = dir_res <= img.eps[line_k[ih]][:, None] + 0.5 * step
    if is_v.any():
        pv = near[seg_k[is_v], :2] - ce[:2]
        dist = np.linalg.norm(pv, axis=1)
        beta = np.arctan2(pv[:, 1], pv[:, 0])
        half = np.arcsin(np.clip(dt / np.maximum(dist, 1e-9), 0, 1))
        half = np.where(dist <= dt, np.pi, half) + img.alpha_eps[line_k[is_v]] + 0.5 * step
        mask[is_v] = np.abs(wrap(yaws[None, :] - img.alpha[line_k[is_v]][:, None] - beta[:, None])) <= half[:, None]
    # The entries (correspondence k, grid yaw g) left.
    at = np.flatnonzero(mask)  # flat (correspondence, yaw) indices: cheaper than 2-D ones here
    k, g = np.divmod(at, Y)
    lk, sk = line_k[k], seg_k[k]
    Wk = np.take(W.reshape(-1, 3), lk * Y + g, axis=0)  # (E, 3)
    # Position strips (relative to the disk centre). The point of each model
    # line used is the one nearest the ray of the image line's midpoint (from
    # the disk centre, at each grid yaw). The line's orientation noise turns
    # its plane about that ray, so for a true correspondence the residual at
    # that point moves by the turn times the lever arm: how far the true ray
    # can pass from the point (the camera's offset in the disk, the yaw step,
    # the offset noise), not the distance to the whole segment.
    U = np.einsum("eki,ek->ei", Rg[g], img.mid_rays[lk])  # (E, 3) world direction of the midpoint ray
    P0, vk = segments[sk, 0], v[sk]
    w0 = ce - P0  # (E, 3)
    b_ = np.einsum("ei,ei->e", U, vk)
    d_ = np.einsum("ei,ei->e", U, w0)
    e_ = np.einsum("ei,ei->e", vk, w0)
    den = np.maximum(1.0 - b_ * b_, 1e-9)
    sp = np.where(1.0 - b_ * b_ > 1e-9, (e_ - b_ * d_) / den, e_)
    # On the segment itself: a true line's midpoint ray meets the segment,
    # and a segment running along the ray would otherwise put the point at
    # infinity and its lever arm with it.
    seg_len = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)[sk]
    sp = np.clip(sp, 0.0, seg_len)
    rel = P0 + sp[:, None] * vk - ce  # (E, 3) the point P* from the disk centre (camera height)
    D = np.sqrt(np.einsum("ei,ei->e", rel, rel)) + dt
    a_len = np.hypot(Wk[:, 0], Wk[:, 1])
    # a . c = d for camera positions c (relative to ce) with the plane
    # through the camera containing P*: W . (P* - C) = 0.
    d = np.einsum("ei,ei->e", Wk, rel)
    e_rot, e_off = img.eps_rot[lk], img.eps_off[lk]
    # Between grid yaws the residual moves at d r / d yaw = (-w_y, w_x) . (P - C).
    dr_dyaw = np.abs(Wk[:, 0] * rel[:, 1] - Wk[:, 1] * rel[:, 0]) + a_len * dt
    t = e_rot * (dt + (0.5 * step + e_off) * D) + e_off * D + 0.5 * step * dr_dyaw + tol.model_m
    quad = np.zeros((K, Y, 6))
    quad.reshape(-1, 6)[at] = posegrid.strip_quadratics(Wk[:, :2], d, t)
    if is_v.any() and sight is not None:
        ext = vertical_extent_bound(camera, img.lines[line_k[is_v]], segments[seg_k[is_v]], tol)
        ev = np.nonzero(is_v[k])[0]
        # Rows into the vertical correspondences (their edges' floor points).
        row = np.cumsum(is_v) - 1
        seen = _vertical_sight(near[seg_k[is_v], :2], row[k[ev]], img.alpha[lk[ev]], yaws[g[ev]], ce[:2], dt,
                               t[ev] / np.maximum(a_len[ev], 1e-9), step, sight, ext)
        mask.reshape(-1)[at[ev[~seen]]] = False
    return mask, quad


#: Slack of the half-plane constraints (:func:`_half_planes`), metres: a
#: vertical edge still counts as ahead from this far behind the camera, a
#: wall face as facing from this far behind it (pose grid and noise).
_FRONT_SLACK_M = 0.1


def _half_planes(img, segments, near, seg_k, line_k, is_v, yaws, ce, faces):
    """Half-planes ``c . z <= b`` (c (K, Y, 2), b (K, Y)) on the camera
    position z (relative to the disk centre) at each grid yaw, one per
    correspondence (c = 0, b = inf: none). A strip alone is a whole line,
    both sides of the segment; but
    - a vertical edge seen at bearing alpha lies ahead along the world
      bearing ``yaw - alpha``: the camera stands behind it on that ray;
    - a segment on a wall face (``faces``) is seen from the room side only."""
    K, Y = len(seg_k), len(yaws)
    c = np.zeros((K, Y, 2))
    b = np.full((K, Y), np.inf)
    if is_v.any():
        beta = yaws[None, :] - img.alpha[line_k[is_v]][:, None]  # (Kv, Y)
        u = np.stack([np.cos(beta), np.sin(beta)], axis=-1)
        rel = near[seg_k[is_v], :2] - ce[:2]  # (Kv, 2)
        c[is_v] = u
        b[is_v] = np.einsum("kgi,ki->kg", u, rel) + _FRONT_SLACK_M
    if faces is not None:
        f = faces[seg_k]  # (K, 2)
        has = ~is_v & (np.abs(f).sum(axis=1) > 0)
        if has.any():
            # Room side: f . (C - P) >= -slack, i.e. (-f) . z <= f . (ce - P) + slack.
            c[has] = -f[has][:, None, :]
            rel = ce[:2] - segments[seg_k[has], 0, :2]
            b[has] = (np.einsum("ki,ki->k", f[has], rel) + _FRONT_SLACK_M)[:, None]
    return c, b


def _pair_compat(img, near, seg_k, line_k, is_v, mask, quad, centre, dt, tol, front_c, front_b) -> np.ndarray:
    """(K, K) bool pairwise compatibility: one-to-one (two lines share a
    segment only if they may be pieces of one line, ``img.pieces``), a
    common pose of the two in the prior set at one grid yaw (within both
    half-planes, see :func:`_half_planes`), and the paper's binary
    constraint for two vertical correspondences."""
    K = len(seg_k)
    iu, ju = np.triu_indices(K, 1)
    distinct = seg_k[iu] != seg_k[ju]
    if img.pieces is not None:
        distinct |= img.pieces[line_k[iu], line_k[ju]]
    distinct &= line_k[iu] != line_k[ju]
    iu, ju = iu[distinct], ju[distinct]
    # In chunks of pairs, so that a huge prior (lost mode, a large dt with
    # any heading) does not need gigabytes; a frame's pairs are one chunk.
    step = max(1, _PAIR_ENTRIES // mask.shape[1])
    pair_ok = np.concatenate([_share_a_pose(iu[c:c + step], ju[c:c + step], mask, quad, dt, tol, front_c, front_b)
                              for c in range(0, len(iu), step)]) if len(iu) else np.zeros(0, dtype=bool)
    sel = np.nonzero(is_v[iu] & is_v[ju] & pair_ok)[0]
    if len(sel):
        a_i, a_j = iu[sel], ju[sel]
        tol_ab = img.alpha_eps[line_k[a_i]] + img.alpha_eps[line_k[a_j]]
        pair_ok[sel] = binary_constraint(near[seg_k[a_i], :2], near[seg_k[a_j], :2], img.alpha[line_k[a_i]],
                                         img.alpha[line_k[a_j]], centre, dt, tol_ab)
    compat = np.zeros((K, K), dtype=bool)
    compat[iu[pair_ok], ju[pair_ok]] = True
    return compat | compat.T


#: Most (pair, grid yaw) entries :func:`_pair_compat` handles at once: its
#: arrays then stay under about 15 MB each.
_PAIR_ENTRIES = 1 << 18


def _share_a_pose(iu, ju, mask, quad, dt, tol, front_c, front_b) -> np.ndarray:
    """(P,) bool: do correspondences ``iu[p]`` and ``ju[p]`` have a common
    pose in the prior set at one grid yaw, within both their half-planes?"""
    # (pair, yaw) entries where both masks hold. (np.nonzero on the 2-D
    # array, and fancy indexing of quad by two arrays, cost several times
    # the flat forms on these sizes.)
    Y = mask.shape[1]
    p, g = np.divmod(np.flatnonzero(mask[iu] & mask[ju]), Y)
    at_i, at_j = iu[p] * Y + g, ju[p] * Y + g  # flat (correspondence, yaw) indices
    flat = quad.reshape(-1, 6)
    qi, qj = np.take(flat, at_i, axis=0), np.take(flat, at_j, axis=0)
    qs = qi + qj
    pval, zx, zy = posegrid.minimise(qs, dt)
    ok = (pval <= 3.0) & (posegrid.evaluate(qi, zx, zy) <= tol.q_max) & (posegrid.evaluate(qj, zx, zy) <= tol.q_max)
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
