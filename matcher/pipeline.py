"""The two-stage matcher: :func:`localize` from a prior, :func:`localize_global` when lost."""

from __future__ import annotations

import math
import time

import numpy as np

from matcher import verify
from matcher.camera import Camera
from matcher.checks import check_lines, check_prior
from matcher.constraints import bearing_noise, plane_noise, vertical_bearing, vertical_candidates, wrap
from matcher.generate import ImageLines, class_samples, collinear_classes, generate, in_field_of_view
from matcher.occlusion import sight_clear, wall_edges
from matcher.overlap import distance_and_overlap
from matcher.result import LocalizeResult
from matcher.tolerances import DEFAULT, Tolerances


#: Stage 2's visibility test ignores wall crossings this close to the
#: segment, metres (the segment lies on a wall face; the pose is refined).
_VISIBLE_END_M = 0.02


def prepare_lines(camera: Camera, lines: np.ndarray, tol: Tolerances) -> ImageLines:
    """Per-line quantities of validated pixel lines (M, 2, 2) of the ideal
    (undistorted) camera: plane normals and their noise, vertical candidates
    and their bearings."""
    und = lines
    normals = camera.interpretation_normals(und)
    eps = plane_noise(camera, und, tol.line_px, tol.line_deg)
    vert = vertical_candidates(camera, normals, eps)
    alpha = vertical_bearing(camera, und)
    alpha_eps = bearing_noise(camera, und, tol.line_px, tol.line_deg)
    usable = np.linalg.norm(und[:, 1] - und[:, 0], axis=1) >= tol.min_line_px
    eps_rot = plane_noise(camera, und, 0.0, tol.line_deg)
    eps_off = plane_noise(camera, und, tol.line_px, 0.0)
    mid = camera.pixel_rays(0.5 * (und[:, 0] + und[:, 1]))
    mid /= np.linalg.norm(mid, axis=1, keepdims=True)
    return ImageLines(und, normals, eps, vert, alpha, alpha_eps, usable, eps_rot, eps_off, mid)


def localize(linemap, camera: Camera, lines, prior, dt: float, dyaw: float, tolerances: Tolerances | None = None):
    """Localise the camera from image ``lines`` (M, 2, 2) or (M, 4) pixels of
    the ideal pinhole (as :func:`matcher.detect_lines` gives them: undistorted
    when the camera has distortion).

    ``prior`` is ``(x, y, yaw_deg)``; the true pose is within ``dt`` metres
    and ``dyaw`` degrees of it. Returns a :class:`LocalizeResult`, falsy with
    a ``reason`` when no hypothesis is accepted. Bad input (shapes, NaN,
    ranges) raises ValueError."""
    tol = tolerances or DEFAULT
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a matcher.Camera, got {type(camera).__name__}")
    t0 = time.perf_counter()
    arr = check_lines(lines, camera, tol)
    px = check_prior(prior, dt, dyaw)
    img = prepare_lines(camera, arr, tol)
    return _localize(linemap, camera, img, px, tol, t0)


def _localize(linemap, camera, img, px, tol, t0, candidate_ids=None):
    xe, ye, yaw_e, dt, dyaw = px
    times: dict[str, float] = {}

    def fail(reason, hyps=0):
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, reason, hypotheses=hyps, time_ms=times)

    # ---- selection: regions met by the disk, field of view ---------------
    # The region query divides by zero on horizontal ring edges (harmless, the
    # result is right); keep its warnings off the robot's console.
    with np.errstate(invalid="ignore", divide="ignore"):
        ids = linemap.candidate_segments(xe, ye, dt) if candidate_ids is None else candidate_ids
        near = len(linemap.regions_near(xe, ye, dt)) if len(ids) == 0 else 1
    if len(ids) == 0:
        if near == 0:
            return fail(f"the prior ({xe:.2f}, {ye:.2f}) is farther than dt={dt:g} m from every region of the map; "
                        "check the prior or use localize_global")
        return fail("no model segment is visible from the regions met by the prior disk")
    segs = linemap.segments[ids]
    fov = in_field_of_view(segs, camera, (xe, ye, yaw_e), dt, dyaw)
    ids, segs = ids[fov], segs[fov]
    times["select"] = (time.perf_counter() - t0) * 1e3
    if len(ids) == 0:
        return fail("no candidate segment lies in the field of view for any heading of the prior interval")
    if int(img.usable.sum()) < tol.min_matches:
        return fail(f"only {int(img.usable.sum())} usable image lines (need {tol.min_matches} of "
                    f">= {tol.min_line_px:g} px)")

    # ---- stage 1 ---------------------------------------------------------
    t1 = time.perf_counter()
    label, reps = collinear_classes(segs)
    walls = wall_edges(linemap)
    hyps = generate(reps, np.arange(len(reps)), camera, img, (xe, ye, yaw_e), dt, dyaw, tol, walls,
                    class_samples(segs, label))
    times["generate"] = (time.perf_counter() - t1) * 1e3
    n_h = len(hyps.sets)
    if n_h == 0:
        return fail(f"no consistent set of {tol.min_matches} or more correspondences "
                    f"({hyps.n_correspondences} correspondences passed the unary tests)")

    # ---- stage 2 ---------------------------------------------------------
    t2 = time.perf_counter()
    members = np.concatenate(hyps.sets)
    hyp = np.repeat(np.arange(n_h), [len(x) for x in hyps.sets])
    cls = hyps.segment[members]
    line_ids = hyps.line[members]
    rays = _unit_rays(camera, img.lines[line_ids])
    lengths = np.linalg.norm(img.lines[line_ids, 1] - img.lines[line_ids, 0], axis=1)
    scale = _fit_bound_px(lengths, tol) / camera.fx
    poses = verify.refine(hyps.init, hyp, reps[cls, 0], reps[cls, 1], rays[:, 0], rays[:, 1],
                          camera.pitch, camera.height_m, robust_scale=scale)
    local = _resolve_pieces(camera, poses[hyp], label, cls, segs, img.lines[line_ids])
    # Matches that do not fit at the hypothesis's pose (a clutter line that
    # lay within the stage-1 tolerance of a model line) are dropped and the
    # pose refitted on the others.
    inl = _fits(camera, img, poses[hyp], segs[local], line_ids, tol) & _visible(poses[hyp], segs[local], walls)
    n_in = np.bincount(hyp, inl, minlength=n_h)
    if not inl.all():
        keep = inl & (n_in[hyp] >= tol.min_matches)
        hyp, cls, line_ids, local, rays = hyp[keep], cls[keep], line_ids[keep], local[keep], rays[keep]
        poses = verify.refine(poses, hyp, segs[local, 0], segs[local, 1], rays[:, 0], rays[:, 1],
                              camera.pitch, camera.height_m)
    E = verify.score_e(poses, hyp, img.normals[line_ids], segs[local, 0], segs[local, 1], camera.pitch,
                       camera.height_m)
    # A refined pose that left the prior set is not a solution of this problem.
    off = np.hypot(poses[:, 0] - xe, poses[:, 1] - ye) > dt + tol.model_m + 0.05
    off |= np.abs(wrap(poses[:, 2] - yaw_e)) > dyaw + math.radians(2.0)
    # Ranked by E among the hypotheses that keep the most fitting matches: a
    # hypothesis trimmed down to a few lines fits them well but explains less.
    few = n_in < max(tol.min_matches, int(n_in.max()))
    E = np.where(off | ~np.isfinite(E) | few, np.inf, E)
    order = np.argsort(E, kind="stable")

    def matches_of(sel_local, sel_lines):
        return sorted([int(ids[a]), int(b)] for a, b in zip(sel_local, sel_lines))

    def pose_deg(p):
        return (float(p[0]), float(p[1]), float(math.degrees(wrap(p[2]))))

    ranked = [(float(E[h]), matches_of(local[hyp == h], line_ids[hyp == h]), pose_deg(poses[h])) for h in order]
    best = int(order[0])
    runner = float(E[order[1]]) if n_h > 1 else None
    common = dict(hypotheses=n_h, runner_up_score=runner, time_ms=times, ranked=ranked)
    if not E[best] <= tol.e_accept:
        times["verify"] = (time.perf_counter() - t2) * 1e3
        times["total"] = (time.perf_counter() - t0) * 1e3
        why = "no hypothesis kept its pose inside the prior bounds" if not np.isfinite(E[best]) else (
            f"best score E={E[best]:.3g} is above the acceptance threshold {tol.e_accept:g}")
        res = LocalizeResult(False, why + (" (hypothesis search truncated)" if hyps.truncated else ""), **common)
        res.score = float(E[best]) if np.isfinite(E[best]) else None
        return res
    # Accepted: add the lines of visible segments stage 1 left out, refit.
    sel = hyp == best
    b_local, b_lines = _extend(camera, img, segs, poses[best], local[sel], line_ids[sel], tol)
    b_rays = _unit_rays(camera, img.lines[b_lines])
    zero = np.zeros(len(b_local), dtype=np.int64)
    pose = verify.refine(poses[best][None], zero, segs[b_local, 0], segs[b_local, 1], b_rays[:, 0], b_rays[:, 1],
                         camera.pitch, camera.height_m)
    score = float(verify.score_e(pose, zero, img.normals[b_lines], segs[b_local, 0], segs[b_local, 1],
                                 camera.pitch, camera.height_m)[0])
    times["verify"] = (time.perf_counter() - t2) * 1e3
    times["total"] = (time.perf_counter() - t0) * 1e3
    return LocalizeResult(True, "", pose=pose_deg(pose[0]), score=score, matches=matches_of(b_local, b_lines),
                          **common)


def _unit_rays(camera, lines):
    """(T, 2, 3) unit camera-frame rays of the end points of lines (T, 2, 2)."""
    r = camera.pixel_rays(lines)
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def _resolve_pieces(camera, poses, label, cls, segs, lines):
    """(T,) local segment of each match: the member of its collinear group
    whose projection overlaps the image line most, at the match's pose
    (T, 3)."""
    order = np.argsort(label, kind="stable")
    sizes = np.bincount(label)
    starts = np.concatenate([[0], np.cumsum(sizes)])
    n = sizes[cls]
    t = np.repeat(np.arange(len(cls)), n)
    k = np.arange(len(t)) - np.repeat(np.cumsum(n) - n, n)
    cand = order[starts[cls][t] + k]
    _, ov = distance_and_overlap(camera, poses[t], segs[cand], lines[t])
    # Best overlap per match: sort by (match, -overlap) and take the first of each run.
    o = np.lexsort((-ov, t))
    first = np.concatenate([[True], t[o][1:] != t[o][:-1]])
    return cand[o][first]


def _fits(camera, img, poses, segments, line_ids, tol) -> np.ndarray:
    """(T,) bool: the image line lies within its noise bound (plus 2 px for
    the pose) of the projected segment, and inside its extent: occlusion and
    the image border only ever shorten the image of a segment, so a line
    sticking out beyond a projected end point by more than the end-point
    noise shows another segment."""
    lines = img.lines[line_ids]
    L = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    dist, ov = distance_and_overlap(camera, poses, segments, lines)
    return (dist <= _fit_bound_px(L, tol)) & (ov >= L - 2 * tol.line_end_px - 2.0)


def _visible(poses, segments, walls) -> np.ndarray:
    """(T,) bool: some point of each segment (T, 2, 3) is in plain sight from
    the camera at poses (T, 3), walls as occluders. At a refined pose (a
    centimetre off) a sight line that cuts a wall 2 cm or more from the
    segment is blocked: it tells the near and far faces of a door jamb apart."""
    if walls is None:
        return np.ones(len(poses), dtype=bool)
    t = np.array([0.02, 0.26, 0.5, 0.74, 0.98])
    pts = segments[:, None, 0, :2] + t[None, :, None] * (segments[:, None, 1, :2] - segments[:, None, 0, :2])
    cams = np.repeat(poses[:, :2], len(t), axis=0)
    clear = sight_clear(cams, pts.reshape(-1, 2), walls, _VISIBLE_END_M)
    return clear.reshape(len(poses), -1).any(axis=1)


def _fit_bound_px(length, tol):
    """Largest distance, pixels, of a true line's end points from the
    projected segment: offset and rotation noise over half its length,
    plus 2 px for the pose's own error."""
    return tol.line_px + math.tan(math.radians(tol.line_deg)) * 0.5 * length + 2.0


def _extend(camera, img, segs, pose, local, line_ids, tol):
    """Add (segment, line) pairs that fit at ``pose`` among the unmatched
    usable lines and segments: both end points within the line's noise bound
    (plus 2 px for the pose) of the projected segment, and overlapping it."""
    free_lines = np.setdiff1d(np.nonzero(img.usable)[0], line_ids)
    free_segs = np.setdiff1d(np.arange(len(segs)), local)
    if len(free_lines) == 0 or len(free_segs) == 0:
        return local, line_ids
    li, si = np.repeat(free_lines, len(free_segs)), np.tile(free_segs, len(free_lines))
    lines = img.lines[li]
    L = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    dist, ov = distance_and_overlap(camera, np.repeat(pose[None], len(li), 0), segs[si], lines)
    ok = (dist <= _fit_bound_px(L, tol)) & (ov >= L - 2 * tol.line_end_px - 2.0)
    add_s, add_l = [], []
    for k in np.argsort(np.where(ok, dist, np.inf))[: int(ok.sum())]:
        if si[k] in add_s or li[k] in add_l:
            continue
        add_s.append(int(si[k]))
        add_l.append(int(li[k]))
    return np.concatenate([local, add_s]).astype(np.int64), np.concatenate([line_ids, add_l]).astype(np.int64)


def localize_global(linemap, camera: Camera, lines, tolerances: Tolerances | None = None, dt_margin: float = 0.0):
    """Lost mode (method.md section 3): one prior per region (its centre,
    ``dt`` its radius plus ``dt_margin``, any heading) until one hypothesis is
    accepted. Regions are tried in order of id. Returns the first accepted
    result (``time_ms['total']`` covers all tries), or a falsy result."""
    tol = tolerances or DEFAULT
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a matcher.Camera, got {type(camera).__name__}")
    t0 = time.perf_counter()
    arr = check_lines(lines, camera, tol)
    img = prepare_lines(camera, arr, tol)
    centres, radii = linemap.region_centres(), linemap.region_radii()
    if linemap.n_regions == 0:
        return LocalizeResult(False, "the map has no regions")
    tried = 0
    for r in range(linemap.n_regions):
        cx, cy = (float(v) for v in centres[r])
        dt = float(radii[r]) + dt_margin
        if not (math.isfinite(cx) and math.isfinite(cy) and dt > 0):
            continue
        tried += 1
        res = _localize(linemap, camera, img, (cx, cy, 0.0, min(dt, 100.0), math.pi), tol, t0,
                        candidate_ids=linemap.region_list(r) if dt_margin == 0 else None)
        if res:
            res.time_ms["total"] = (time.perf_counter() - t0) * 1e3
            res.time_ms["regions_tried"] = tried
            return res
    return LocalizeResult(False, f"no region gave an accepted hypothesis ({tried} tried)",
                          time_ms={"total": (time.perf_counter() - t0) * 1e3, "regions_tried": tried})
