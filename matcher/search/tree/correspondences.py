"""Stage 1, first step: the correspondences and their pose strips
(method.md sections 4 to 6).

For candidate model segments L (one per collinear group, cut to the field
of view) and image lines l:

1. split L into vertical ``Lv`` and non-vertical ``Lh`` segments, and pick
   the image lines that may be vertical edges (exact test ``|n . R e_z|``);
2. unary test on ``Lh x l`` (yaw solution in the interval, position line
   meets the disk), bearing test on ``Lv x lv``, and the horizon test on
   heights: the survivors are the correspondences;
3. for each correspondence and grid yaw: the yaw mask (direction or bearing
   constraint), the position strip as a quadratic (:mod:`matcher.search.tree.posegrid`)
   and a half-plane (vertical edges lie ahead; wall faces are seen from the
   room side); a correspondence with no feasible grid pose is dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera, world2cam_rotation
from linemap.geometry import segment_is_vertical
from matcher.frame import ImageLines
from matcher.search.tree import posegrid
from matcher.search.tree.constraints import distinct_points, unary_constraint, wrap
from matcher.tolerances import Tolerances


@dataclass
class Correspondences:
    """Stage 1's correspondences k (K,): ``seg_k`` candidate segment index,
    ``line_k`` image line, ``is_v`` vertical; per grid yaw g of ``yaws``
    (Y,): ``mask`` (K, Y) the yaw test, ``quad`` (K, Y, 6) the position
    strip's quadratic (relative to the disk centre), ``front_c`` (K, Y, 2)
    and ``front_b`` (K, Y) the half-plane ``c . z <= b`` (c = 0, b = inf:
    none); ``single_fit`` (K,) each one's best value alone (inf: none);
    ``near`` (N, 3) the point of each candidate's line nearest the prior
    centre ``centre`` (3,) (camera height in z); ``forward`` (Y, 3) the
    optical axis at each grid yaw."""

    seg_k: np.ndarray
    line_k: np.ndarray
    is_v: np.ndarray
    mask: np.ndarray
    quad: np.ndarray
    front_c: np.ndarray
    front_b: np.ndarray
    single_fit: np.ndarray
    yaws: np.ndarray
    near: np.ndarray
    centre: np.ndarray
    forward: np.ndarray

    def __len__(self) -> int:
        return len(self.seg_k)

    def subset(self, keep: np.ndarray) -> "Correspondences":
        """The correspondences where ``keep`` (K,) bool holds."""
        return Correspondences(self.seg_k[keep], self.line_k[keep], self.is_v[keep], self.mask[keep],
                               self.quad[keep], self.front_c[keep], self.front_b[keep], self.single_fit[keep],
                               self.yaws, self.near, self.centre, self.forward)


@dataclass(frozen=True)
class YawGrid:
    """The prior's grid of yaws and what each gives: ``yaws`` (Y,) radians,
    ``spacing`` (radians) between them, ``R`` (Y, 3, 3) the world-to-camera
    rotations, ``W`` (M, Y, 3) the image lines' world normals ``R^T n``;
    the prior's disk: ``centre`` (3,) (its camera centre, the camera height
    in z) and radius ``dt``."""

    yaws: np.ndarray
    spacing: float
    R: np.ndarray
    W: np.ndarray
    centre: np.ndarray
    dt: float


@dataclass(frozen=True)
class ModelLines:
    """The candidate ``segments`` (N, 2, 3) as lines: ``v`` (N, 3) unit
    directions, ``near`` (N, 3) the point of each line nearest the prior's
    centre."""

    segments: np.ndarray
    v: np.ndarray
    near: np.ndarray


@dataclass(frozen=True)
class Pairs:
    """Candidate correspondences k (K,): ``seg_k`` segment index, ``line_k``
    image line, ``is_v`` whether a vertical edge."""

    seg_k: np.ndarray
    line_k: np.ndarray
    is_v: np.ndarray


def find_correspondences(segments: np.ndarray, camera: Camera, image_lines: ImageLines, prior, tol: Tolerances,
                         sight=None, faces: np.ndarray | None = None, counts: dict | None = None):
    """The correspondences of candidate ``segments`` (N, 2, 3) and the
    frame's lines ``image_lines`` under ``prior`` ``(xe, ye, yaw_e, dt, dyaw)``
    (radians): a :class:`Correspondences`, or ``(seg_k, line_k)`` of the
    survivors when fewer than ``min_matches`` of them, or of their lines,
    have a feasible grid pose. ``sight`` the walls' :class:`~matcher.map_geometry.occlusion.SightRays`
    (None: no walls); ``faces`` (N, 2) the room-side normal of each
    candidate's wall face (zeros: none) or None. ``counts``, a dict, gets
    the numbers of each step."""
    xe, ye, yaw_e, dt, dyaw = prior
    counts = {} if counts is None else counts
    step = math.radians(tol.yaw_step_deg)
    ce = np.array([xe, ye, camera.height_m])
    yaws = yaw_grid(yaw_e, dyaw, step)
    Rg = world2cam_rotation(yaws, camera.pitch)  # (Y, 3, 3)
    W = np.einsum("gki,mk->mgi", Rg, image_lines.normals)  # (M, Y, 3) world normals R^T n
    fwd = Rg[:, 2, :]  # (Y, 3) optical axis

    vert_seg = segment_is_vertical(segments, tol.shared.vertical_axis_deg)
    v = segments[:, 1] - segments[:, 0]
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    tpar = np.einsum("nk,nk->n", ce - segments[:, 0], v)
    near = segments[:, 0] + tpar[:, None] * v  # point of each line nearest the prior centre
    usable = image_lines.searched  # the longest usable lines (Tolerances.search_lines)

    ih = np.nonzero(~vert_seg)[0]
    uh, _ = unary_constraint(camera, image_lines.normals, image_lines.eps, segments[ih], (xe, ye, yaw_e), dt, dyaw,
                             tol.model_m)
    uh &= usable[None, :]
    uh &= horizon_side_ok(camera, image_lines.lines, segments[ih], tol)
    hi_, hj = np.nonzero(uh)
    hi_ = ih[hi_]
    iv = np.nonzero(vert_seg)[0]
    jv = np.nonzero(image_lines.vertical & usable)[0]
    vv = horizon_side_ok(camera, image_lines.lines[jv], segments[iv], tol)  # (Nv, Mv)
    vi_, vj = np.nonzero(vv)
    vi_, vj = iv[vi_], jv[vj]
    seg_k = np.concatenate([hi_, vi_]).astype(np.int64)
    line_k = np.concatenate([hj, vj]).astype(np.int64)
    is_v = np.concatenate([np.zeros(len(hi_), bool), np.ones(len(vi_), bool)])
    counts.update({"segments": int(len(segments)), "vertical_segments": int(vert_seg.sum()),
                   "lines": int(len(image_lines.lines)), "vertical_lines": int(len(jv)),
                   "unary_pairs": int(len(hi_)), "vertical_pairs": int(len(vi_))})
    if len(seg_k) < tol.min_matches:
        return seg_k, line_k

    grid = YawGrid(yaws, step, Rg, W, ce, dt)
    model, pairs = ModelLines(segments, v, near), Pairs(seg_k, line_k, is_v)
    mask, quad = _strips(camera, image_lines, model, pairs, grid, tol, sight)
    val, zx, zy = posegrid.minimise(quad, dt)
    mask &= val <= tol.stage1.single_fit_max
    front_c, front_b = _half_planes(image_lines, model, pairs, grid, faces, tol.stage1.front_slack_m)
    mask &= posegrid.halfplane_reachable(quad, (val, zx, zy), 1, tol.q_max, dt, front_c, front_b)
    keep = mask.any(axis=1)
    # Each correspondence alone as the tree's root tests it (its own term
    # within q_max at the minimiser too), from the arrays at hand.
    val, zx, zy, m = val[keep], zx[keep], zy[keep], mask[keep]
    single_fit = np.where(m & (posegrid.evaluate(quad[keep], zx, zy) <= tol.q_max), val, np.inf).min(axis=1)
    corr = Correspondences(seg_k, line_k, is_v, mask, quad, front_c, front_b, np.zeros(len(seg_k)), yaws, near,
                           ce, fwd).subset(keep)
    corr.single_fit = single_fit
    counts["correspondences"] = int(len(corr))
    # A set takes one correspondence per image line: with fewer lines than
    # min_matches left, no set can form (and the pairwise tests are spared).
    if len(corr) < tol.min_matches or len(np.unique(corr.line_k)) < tol.min_matches:
        return corr.seg_k, corr.line_k
    return corr


def yaw_grid(yaw_e: float, dyaw: float, step: float) -> np.ndarray:
    """(Y,) yaws covering the interval with spacing at most ``step`` (radians)."""
    if dyaw >= math.pi:
        n = int(math.ceil(2 * math.pi / step))
        return wrap(yaw_e + np.arange(n) * (2 * math.pi / n))
    n = int(math.ceil(2 * dyaw / step)) + 1
    return yaw_e + np.linspace(-dyaw, dyaw, n)


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


def _vertical_sight(points, rows, alpha, yaw, grid: YawGrid, width, sight, extent) -> np.ndarray:
    """(E,) bool per entry e: a vertical edge at floor point
    ``points[rows[e]]`` (points (U, 2)) seen at bearing ``alpha[e]`` (right
    of the axis) with heading ``yaw[e]``: the camera lies on the ray back
    from the edge at world bearing ``yaw - alpha``, up to the first wall that
    would hide the edge. True where that stretch comes within ``dt +
    width[e]`` of the centre of the ``grid``'s disk; the stretch is also cut at
    ``extent[rows[e]]``, the farthest the edge can be for its image line to
    fit inside its projection (:func:`vertical_extent_bound`). The stretches
    come from the map's :class:`~matcher.map_geometry.occlusion.SightRays` table."""
    centre, dt, step = grid.centre[:2], grid.dt, grid.spacing
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


def _strips(camera, image_lines, model: ModelLines, pairs: Pairs, grid: YawGrid, tol, sight):
    """Yaw masks (K, Y) and strip quadratics (K, Y, 6) of the correspondences
    ``pairs`` (K,) of the ``model`` lines at each yaw of the ``grid``
    (relative to its disk centre). Strips are computed only where the yaw
    mask holds (zeros elsewhere): a third of the entries or fewer."""
    segments, v, near = model.segments, model.v, model.near
    seg_k, line_k, is_v = pairs.seg_k, pairs.line_k, pairs.is_v
    W, Rg, yaws, ce, dt, step = grid.W, grid.R, grid.yaws, grid.centre, grid.dt, grid.spacing
    K, Y = len(seg_k), len(yaws)
    # Yaw masks: direction constraint for non-vertical, bearing range for vertical.
    mask = np.empty((K, Y), dtype=bool)
    ih = np.nonzero(~is_v)[0]
    dir_res = np.abs(np.einsum("kgi,ki->kg", W[line_k[ih]], v[seg_k[ih]]))
    mask[ih] = dir_res <= image_lines.eps[line_k[ih]][:, None] + 0.5 * step
    if is_v.any():
        pv = near[seg_k[is_v], :2] - ce[:2]
        dist = np.linalg.norm(pv, axis=1)
        beta = np.arctan2(pv[:, 1], pv[:, 0])
        half = np.arcsin(np.clip(dt / np.maximum(dist, 1e-9), 0, 1))
        half = np.where(dist <= dt, np.pi, half) + image_lines.alpha_eps[line_k[is_v]] + 0.5 * step
        turn = wrap(yaws[None, :] - image_lines.alpha[line_k[is_v]][:, None] - beta[:, None])
        mask[is_v] = np.abs(turn) <= half[:, None]
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
    U = np.einsum("eki,ek->ei", Rg[g], image_lines.mid_rays[lk])  # (E, 3) world direction of the midpoint ray
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
    e_rot, e_off = image_lines.eps_rot[lk], image_lines.eps_off[lk]
    # Between grid yaws the residual moves at d r / d yaw = (-w_y, w_x) . (P - C).
    dr_dyaw = np.abs(Wk[:, 0] * rel[:, 1] - Wk[:, 1] * rel[:, 0]) + a_len * dt
    t = e_rot * (dt + (0.5 * step + e_off) * D) + e_off * D + 0.5 * step * dr_dyaw + tol.model_m
    quad = np.zeros((K, Y, 6))
    quad.reshape(-1, 6)[at] = posegrid.strip_quadratics(Wk[:, :2], d, t)
    if is_v.any() and sight is not None:
        ext = vertical_extent_bound(camera, image_lines.lines[line_k[is_v]], segments[seg_k[is_v]], tol)
        ev = np.nonzero(is_v[k])[0]
        # Rows into the vertical correspondences (their edges' floor points).
        row = np.cumsum(is_v) - 1
        seen = _vertical_sight(near[seg_k[is_v], :2], row[k[ev]], image_lines.alpha[lk[ev]], yaws[g[ev]], grid,
                               t[ev] / np.maximum(a_len[ev], 1e-9), sight, ext)
        mask.reshape(-1)[at[ev[~seen]]] = False
    return mask, quad


def _half_planes(image_lines, model: ModelLines, pairs: Pairs, grid: YawGrid, faces, slack: float):
    """Half-planes ``c . z <= b`` (c (K, Y, 2), b (K, Y)) on the camera
    position z (relative to the disk centre) at each yaw of the ``grid``,
    one per correspondence of ``pairs`` (c = 0, b = inf: none). A strip alone is a whole line,
    both sides of the segment; but
    - a vertical edge seen at bearing alpha lies ahead along the world
      bearing ``yaw - alpha``: the camera stands behind it on that ray;
    - a segment on a wall face (``faces``) is seen from the room side only."""
    segments, near, yaws, ce = model.segments, model.near, grid.yaws, grid.centre
    seg_k, line_k, is_v = pairs.seg_k, pairs.line_k, pairs.is_v
    K, Y = len(seg_k), len(yaws)
    c = np.zeros((K, Y, 2))
    b = np.full((K, Y), np.inf)
    if is_v.any():
        beta = yaws[None, :] - image_lines.alpha[line_k[is_v]][:, None]  # (Kv, Y)
        u = np.stack([np.cos(beta), np.sin(beta)], axis=-1)
        rel = near[seg_k[is_v], :2] - ce[:2]  # (Kv, 2)
        c[is_v] = u
        b[is_v] = np.einsum("kgi,ki->kg", u, rel) + slack
    if faces is not None:
        f = faces[seg_k]  # (K, 2)
        has = ~is_v & (np.abs(f).sum(axis=1) > 0)
        if has.any():
            # Room side: f . (C - P) >= -slack, i.e. (-f) . z <= f . (ce - P) + slack.
            c[has] = -f[has][:, None, :]
            rel = ce[:2] - segments[seg_k[has], 0, :2]
            b[has] = (np.einsum("ki,ki->k", f[has], rel) + slack)[:, None]
    return c, b
