"""Stage 2: pose, fit and score of every hypothesis, and their ranking
(method.md section 8).

For each hypothesis, all at once where the arrays allow:

1. a robust least-squares pose (:func:`matcher.verify.refine`) from the
   stage-1 grid pose (that grid start is the yaw search and linear solve);
2. each match's model segment: the piece of its collinear group that the
   image line overlaps most at that pose; a loosely fixed pose whose lines
   stick out of their segments slides to where they fit
   (:mod:`matcher.slide`);
3. matches that do not fit at the pose (line off its projected segment by
   more than the noise, sticking out beyond its end points, or the segment
   hidden by a wall) are dropped, and the pose refitted;
4. for the contenders (most fitting matches, within one), the lines of
   other visible segments that fit at the pose are added and the pose
   refitted: a hypothesis that lost a true line to a clutter line in
   stage 1 gets it back;
5. the paper's score E. Hypotheses are ranked by number of matches, then
   by the reprojection error (the lines' end points' pixel distances to the
   projected segments, each over its line's noise bound), then E; E is what
   the acceptance threshold tests. A hypothesis whose matches fix no more
   than the pose's three numbers (three vertical edges) is not accepted:
   it fits exactly, whatever it matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from matcher import slide, verify
from matcher.constraints import wrap
from linemap.geometry import segment_is_vertical
from matcher.tolerances import VERTICAL_AXIS_DEG
from matcher.occlusion import sight_clear
from matcher.overlap import (covered_span, distance_and_overlap, project_segments, projected_distance_and_overlap,
                             projected_end_distances)

#: Stage 2's visibility test ignores wall crossings this close to the
#: segment, metres (the segment lies on a wall face; the pose is refined):
#: it tells the near and far faces of a door jamb apart.
_VISIBLE_END_M = 0.02
#: Points tested for visibility along the part of a segment a line shows
#: (fractions of that part, its ends moved in a little: they are the least sure).
_SPAN_SAMPLES = np.array([0.05, 0.275, 0.5, 0.725, 0.95])
#: A refined pose may leave the prior bounds by this much (metres, degrees)
#: before the hypothesis is dropped: noise on a pose at the border. A pose
#: its matches fix loosely gets more: this many of its standard deviations
#: (:func:`pose_spread`), e.g. six far vertical edges on one side, which
#: leave the position uncertain by a decimetre.
_PRIOR_SLACK_M = 0.1
_PRIOR_SLACK_DEG = 2.0
_PRIOR_SLACK_SIGMAS = 3.0
#: Hypotheses matching this many horizontal segments or more are not slid
#: (:func:`slide_to_fit`): their lines fix the position.
_SLIDE_MAX_HORIZONTAL = 2


@dataclass
class Ranked:
    """Verified hypotheses. Per match t: ``hyp`` (T,), ``local`` (T,) index
    into the candidate segments, ``line`` (T,) image line. Per hypothesis:
    ``poses`` (H, 3) ``(x, y, yaw)``, ``score`` (H,) E (inf when dropped),
    ``order`` (H,) best first; ``why`` the reason when none is left."""

    hyp: np.ndarray
    local: np.ndarray
    line: np.ndarray
    poses: np.ndarray
    score: np.ndarray
    order: np.ndarray
    why: str


def verify_hypotheses(camera, img, segs, label, reps, hyps, prior, tol, walls, free=None) -> Ranked:
    """Stage 2 on stage 1's ``hyps`` (class ids in ``hyps.segment``); ``segs``
    (N, 2, 3) candidate segments, ``label`` (N,) their collinear group,
    ``reps`` (G, 2, 3) the groups' spans; ``prior`` ``(xe, ye, yaw_e, dt, dyaw)``;
    ``free`` the map's :class:`~matcher.freespace.FreeSpace` or None."""
    xe, ye, yaw_e, dt, dyaw = prior
    n_h = len(hyps.sets)
    members = np.concatenate(hyps.sets)
    hyp = np.repeat(np.arange(n_h), [len(x) for x in hyps.sets])
    cls = hyps.segment[members]
    line_ids = hyps.line[members]
    rays = unit_rays(camera, img.lines[line_ids])
    lengths = np.linalg.norm(img.lines[line_ids, 1] - img.lines[line_ids, 0], axis=1)
    scale = fit_bound_px(lengths, tol) / camera.fx
    poses = verify.refine(hyps.init, hyp, reps[cls, 0], reps[cls, 1], rays[:, 0], rays[:, 1],
                          camera.pitch, camera.height_m, robust_scale=scale)
    local = resolve_pieces(camera, poses[hyp], label, cls, segs, img.lines[line_ids])
    inl, dist = fits_and_distance(camera, img, poses[hyp], segs[local], line_ids, tol)
    poses, slid = slide_to_fit(camera, img, segs, poses, hyp, local, line_ids, tol, inl,
                               stuck_out=~inl & (dist <= fit_bound_px(lengths, tol)))
    if slid.any():  # their lines judged again at the new poses
        local = resolve_pieces(camera, poses[hyp], label, cls, segs, img.lines[line_ids])
        inl = fits(camera, img, poses[hyp], segs[local], line_ids, tol)
    at = inl.nonzero()[0]  # visibility only where the line fits
    inl[at] = visible(camera, poses[hyp[at]], segs[local[at]], img.lines[line_ids[at]], walls)
    n_in = np.bincount(hyp, inl, minlength=n_h)
    keep = inl & (n_in[hyp] >= tol.min_matches)
    hyp, line_ids, local = hyp[keep], line_ids[keep], local[keep]
    alive = n_in >= tol.min_matches

    def in_prior(poses, hyp, local, line_ids):
        """(H,) bool, :func:`within_prior`: with the fixed slack, then, for
        the hypotheses of ``alive`` it drops, with the pose's own spread (a
        loosely fixed pose; rare, and the covariance costs a few tenths of
        a millisecond)."""
        ok = within_prior(poses, prior, free, tol.free_space_m)
        loose = np.nonzero(alive & ~ok)[0]
        if len(loose):
            sel = np.isin(hyp, loose)
            cov = pose_covariance(camera, img, segs, poses[loose], np.searchsorted(loose, hyp[sel]), local[sel],
                                  line_ids[sel], tol)
            ok[loose] = within_prior(poses[loose], prior, free, tol.free_space_m, pose_spread(cov))
        return ok

    if alive.any() and not keep.all():
        # Matches were dropped: refit, so that the lines added back below
        # are judged at a pose the dropped ones no longer pull.
        poses = _refit(camera, img, segs, poses, hyp, local, line_ids, tol, slid)
    if alive.any():
        alive &= in_prior(poses, hyp, local, line_ids)
    if alive.any():
        # Contenders get the lines they are missing back, then a last refit
        # (plain least squares on the final matches).
        top = int(n_in[alive].max())
        contenders = np.nonzero(alive & (n_in >= top - 1))[0]
        add_h, add_l, add_s = extend_all(camera, img, segs, poses, hyp, local, line_ids, contenders, tol, walls)
        hyp, local, line_ids = (np.concatenate(a).astype(np.int64)
                                for a in ((hyp, add_h), (local, add_s), (line_ids, add_l)))
        order_t = np.argsort(hyp, kind="stable")
        hyp, local, line_ids = hyp[order_t], local[order_t], line_ids[order_t]
        poses = _refit(camera, img, segs, poses, hyp, local, line_ids, tol, slid)
        alive &= in_prior(poses, hyp, local, line_ids)
    n_fin = np.bincount(hyp, minlength=n_h)
    # A vertical edge's line fixes one number of the pose (its bearing), any
    # other line two. Matches that fix no more than the pose's three leave
    # nothing over to check it: three vertical edges fit exactly (E = 0)
    # whichever they are. Such a hypothesis is not accepted.
    fixed = np.bincount(hyp, np.where(segment_is_vertical(segs[local], VERTICAL_AXIS_DEG), 1.0, 2.0), minlength=n_h)
    exact = alive & (fixed <= 3)
    alive &= ~exact
    E = np.full(n_h, np.inf)
    if len(hyp):
        # E's position term at the middle of the part of each segment that
        # its line shows, not of the whole segment: a short line on a long,
        # partly hidden segment turns its plane about its own middle by its
        # orientation noise, and that turn, times the distance to a far
        # midpoint, would swamp E (the two agree for a segment seen whole).
        span = covered_span(camera, poses[hyp], segs[local], img.lines[line_ids])  # (T, 2)
        shown_mid = segs[local, 0] + span.mean(axis=1)[:, None] * (segs[local, 1] - segs[local, 0])
        E = verify.score_e(poses, hyp, img.normals[line_ids], segs[local, 0], segs[local, 1], camera.pitch,
                           camera.height_m, mid=shown_mid)
    # Ranked among the hypotheses that explain the most lines (a hypothesis
    # trimmed down to a few lines fits them well but explains less) by the
    # reprojection error: the end points' distances to their projected
    # segments, each over its line's noise bound, in the image space the
    # detector's noise is stated in. E, the paper's score, mixes radians and
    # metres: two aliases (the near and far faces of a jamb, 20 cm and 3
    # degrees apart) often score E alike while their reprojection errors
    # differ threefold (docs/matcher.md). E breaks ties, is reported, and is
    # what the acceptance threshold applies to.
    cost = reprojection_cost(camera, img, poses, hyp, segs[local], line_ids, tol, n_h)
    best_n = int(n_fin[alive].max()) if alive.any() else 0
    E = np.where(alive & (n_fin >= max(best_n, tol.min_matches)) & np.isfinite(E), E, np.inf)
    order = np.lexsort((E, cost, -n_fin * alive))
    # Hypotheses that ended with the same matches are one: only the best
    # ranked keeps its score (so the runner-up is a different match).
    keys = {}
    for h in order:
        sel = hyp == h
        key = tuple(sorted(zip(local[sel].tolist(), line_ids[sel].tolist())))
        if key in keys and np.isfinite(E[h]):
            E[h] = np.inf
        keys.setdefault(key, h)
    order = np.lexsort((E, cost, -n_fin * (alive & np.isfinite(E))))
    why = ""
    if not np.isfinite(E).any():
        if exact.any():
            why = ("the hypotheses left fix the pose exactly (three vertical edges, say), with nothing over to "
                   "verify it; more image lines are needed")
        elif (n_in >= tol.min_matches).any():
            why = "no hypothesis kept its pose inside the prior bounds and the map's free space"
        else:
            why = f"no hypothesis kept {tol.min_matches} matches that fit at its pose"
    return Ranked(hyp, local, line_ids, poses, E, order, why)


def reprojection_cost(camera, img, poses, hyp, segments, line_ids, tol, n_h) -> np.ndarray:
    """(H,) per hypothesis: the sum over its matches t (``hyp`` (T,),
    ``segments`` (T, 2, 3), ``line_ids`` (T,)) and both end points of the
    line of (d / s)^2, d the end point's distance, pixels, to the line of
    the segment projected at the hypothesis' pose (``poses`` (H, 3)) and s
    the line's noise bound (``line_px`` plus ``line_deg`` over half its
    length); inf for a segment behind the camera."""
    if not len(hyp):
        return np.full(n_h, np.inf)
    lines = img.lines[line_ids]
    d = projected_end_distances(*project_segments(camera, poses[hyp], segments), lines)  # (T, 2)
    length = np.hypot(*(lines[:, 1] - lines[:, 0]).T)
    noise = tol.line_px + math.tan(math.radians(tol.line_deg)) * 0.5 * length
    return np.bincount(hyp, ((d / noise[:, None]) ** 2).sum(axis=1), minlength=n_h)


def _refit(camera, img, segs, poses, hyp, local, line_ids, tol, slid):
    """Poses (H, 3) refitted by plain least squares on the matches. Those of
    the hypotheses ``slid`` (H,) bool (:func:`slide_to_fit`) slide again if
    their lines no longer fit: least squares alone takes them back out
    along the direction their bearings leave loose."""
    if len(hyp) == 0:
        return poses
    r = unit_rays(camera, img.lines[line_ids])
    new = verify.refine(poses, hyp, segs[local, 0], segs[local, 1], r[:, 0], r[:, 1], camera.pitch,
                        camera.height_m, iterations=3)
    if slid.any():  # judged as the slide judges, so that they go back as far
        sel = slid[hyp]
        inl = np.ones(len(hyp), dtype=bool)
        inl[sel] = _fits_inside(camera, img, new[hyp[sel]], segs[local[sel]], line_ids[sel], tol)
        new, _ = slide_to_fit(camera, img, segs, new, hyp, local, line_ids, tol, inl)
    return new


def _fits_inside(camera, img, poses, segments, line_ids, tol) -> np.ndarray:
    """(T,) bool: :func:`fits`, allowing only the end points' noise beyond
    the projected ends (the slide's test: a pose that passes it sits where
    the lines lie inside their segments, not at the edge of :func:`fits`)."""
    return _fits_projected(img, *project_segments(camera, poses, segments), line_ids, tol, end_px=tol.line_end_px)[0]


def _fit_counter(camera, img, segs, hyp, local, line_ids, tol, which):
    """``count(p)``: for poses ``p`` (W, N, 3) of the hypotheses ``which``
    (W,), (W, N) how many of their lines pass :func:`_fits_inside`."""
    sel = np.nonzero(np.isin(hyp, which))[0]
    w_of = np.searchsorted(which, hyp[sel])
    seg_sel, line_sel = segs[local[sel]], line_ids[sel]

    def count(p: np.ndarray) -> np.ndarray:
        n = p.shape[1]
        good = _fits_inside(camera, img, p[w_of].reshape(-1, 3), np.repeat(seg_sel, n, axis=0),
                            np.repeat(line_sel, n), tol)
        out = np.zeros((len(which), n))
        np.add.at(out, (np.repeat(w_of, n), np.tile(np.arange(n), len(sel))), good)
        return out

    return count


def slide_to_fit(camera, img, segs, poses, hyp, local, line_ids, tol, inl, stuck_out=None):
    """Poses (H, 3), those of loosely fixed hypotheses with a line that does
    not fit (``inl`` (T,) False) moved to where more of their lines fit
    (:func:`matcher.slide.slide_to_fit`); and (H,) bool, which moved.
    Tried are the hypotheses with lines enough to be a contender if all
    fitted, matching fewer than _SLIDE_MAX_HORIZONTAL horizontal segments
    and, with ``stuck_out`` (T,) bool, with a line that lies along its
    projected segment but sticks out of it (a line off its segment's line
    says the match is wrong, not the distance)."""
    n_h = len(poses)
    slid = np.zeros(n_h, dtype=bool)
    n_all = np.bincount(hyp, minlength=n_h)
    n_fit = np.bincount(hyp, inl, minlength=n_h)
    worth = (n_fit < n_all) & (n_all >= max(tol.min_matches, int(n_fit.max(initial=0)) - 1))
    # Bearings are what leave a position loose: two horizontal segments' lines
    # fix it (each puts the camera on a line of the floor at a given yaw).
    worth &= np.bincount(hyp, ~segment_is_vertical(segs[local], VERTICAL_AXIS_DEG), minlength=n_h) < _SLIDE_MAX_HORIZONTAL
    if stuck_out is not None:
        worth &= np.bincount(hyp, stuck_out, minlength=n_h) > 0
    cand = np.nonzero(worth)[0]
    if not len(cand):
        return poses, slid
    sel = np.isin(hyp, cand)
    info = pose_information(camera, img, segs, poses[cand], np.searchsorted(cand, hyp[sel]), local[sel],
                            line_ids[sel], tol)
    count = _fit_counter(camera, img, segs, hyp, local, line_ids, tol, cand)
    moved, move = slide.slide_to_fit(poses[cand], info, count, n_fit[cand])
    poses = poses.copy()
    poses[cand[move]] = moved[move]
    slid[cand[move]] = True
    return poses, slid


def within_prior(poses, prior, free, free_m: float, spread=None) -> np.ndarray:
    """(H,) bool: poses (H, 3) within the prior bounds ``(xe, ye, yaw_e, dt,
    dyaw)`` (plus noise slack: _PRIOR_SLACK_M and _PRIOR_SLACK_DEG, or
    _PRIOR_SLACK_SIGMAS times the pose's standard deviations ``spread`` (H,
    2) (metres, radians; :func:`pose_spread`) where more) and, with
    ``free``, within ``free_m`` of the map's regions (looked up only for
    the poses inside the prior)."""
    xe, ye, yaw_e, dt, dyaw = prior
    slack_m, slack_yaw = _PRIOR_SLACK_M, math.radians(_PRIOR_SLACK_DEG)
    if spread is not None:
        slack_m = np.maximum(slack_m, _PRIOR_SLACK_SIGMAS * spread[:, 0])
        slack_yaw = np.maximum(slack_yaw, _PRIOR_SLACK_SIGMAS * spread[:, 1])
    ok = np.hypot(poses[:, 0] - xe, poses[:, 1] - ye) <= dt + slack_m
    ok &= np.abs(wrap(poses[:, 2] - yaw_e)) <= dyaw + slack_yaw
    if free is not None and ok.any():
        at = np.nonzero(ok)[0]
        ok[at] = free.distance(poses[at, :2]) <= free_m
    return ok


def pose_std_of(camera, img, segs, ranked: Ranked, h: int, tol):
    """``(x, y, yaw_deg)`` standard deviations of hypothesis ``h``'s pose
    (metres, degrees; :func:`pose_covariance`), or None where its matches do
    not fix it."""
    sel = ranked.hyp == h
    cov = pose_covariance(camera, img, segs, ranked.poses[h:h + 1], np.zeros(int(sel.sum()), dtype=np.int64),
                          ranked.local[sel], ranked.line[sel], tol)[0]
    if not np.isfinite(cov).all():
        return None
    return float(math.sqrt(cov[0, 0])), float(math.sqrt(cov[1, 1])), float(math.degrees(math.sqrt(cov[2, 2])))


def pose_spread(cov: np.ndarray) -> np.ndarray:
    """(H, 2) standard deviations of poses with covariances ``cov`` (H, 3,
    3) (:func:`pose_covariance`): of the position along its worst-fixed
    direction (metres) and of the yaw (radians); inf where not fixed."""
    out = np.full((len(cov), 2), np.inf)
    fixed = np.isfinite(cov).all(axis=(1, 2))
    if fixed.any():
        out[fixed, 0] = np.sqrt(np.maximum(np.linalg.eigvalsh(cov[fixed, :2, :2])[:, 1], 0.0))
        out[fixed, 1] = np.sqrt(np.maximum(cov[fixed, 2, 2], 0.0))
    return out


def pose_covariance(camera, img, segs, poses, hyp, local, line_ids, tol) -> np.ndarray:
    """(H, 3, 3) per hypothesis the covariance of its least-squares pose
    ``(x, y, yaw)`` (metres, radians) that image noise leaves. First order:
    the inverse of J^T J, J the derivatives of the residuals
    (:func:`matcher.verify.residuals`) weighted by their noise. Each
    residual (the sine of the angle between an end point's ray and the
    segment's plane, which at the fit is the line's own plane) is first
    turned into pixels across its line: divided by its derivative along the
    line's image normal, ``n . dp / |p|`` with ``n`` the line's
    interpretation-plane normal and ``p`` the end point's ray ``K^-1 (u, v,
    1)`` (a pixel spans less angle off the image centre). Then a line's two
    end points are taken as their mean and half difference: an offset of
    the line moves both ends alike (``line_px``), a turn about its middle
    moves them apart (``line_deg`` over half its length); each bound is
    taken as that of a uniform variable (standard deviation bound /
    sqrt 3). Matches ``hyp, local, line_ids`` (T,) as for
    :func:`reprojection_cost`. A hypothesis whose matches do not fix its
    pose gets inf."""
    A = pose_information(camera, img, segs, poses, hyp, local, line_ids, tol)
    out = np.full(A.shape, np.inf)
    fixed = np.linalg.det(A) > 1e-12 * np.maximum(np.abs(A).max(axis=(1, 2)), 1e-300) ** 3
    if fixed.any():
        out[fixed] = np.linalg.inv(A[fixed])
    return out


def pose_information(camera, img, segs, poses, hyp, local, line_ids, tol) -> np.ndarray:
    """(H, 3, 3) per hypothesis ``J^T J``, the inverse of
    :func:`pose_covariance` (singular where the matches leave a direction of
    the pose free)."""
    n_h = len(poses)
    A = np.zeros((n_h, 3, 3))
    if not len(hyp):
        return A
    lines = img.lines[line_ids]  # (T, 2, 2)
    p = camera.pixel_rays(lines)  # (T, 2, 3)
    p_len = np.linalg.norm(p, axis=2)  # (T, 2)
    rays = p / p_len[..., None]
    _, J = verify.residuals(poses, hyp, segs[local, 0], segs[local, 1], rays[:, 0], rays[:, 1], camera.pitch,
                            camera.height_m, jacobian=True)  # (T, 2, 3)
    d = lines[:, 1] - lines[:, 0]
    length = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
    # d(ray)/d(pixel across the line): (-d_v / fx, d_u / fy, 0) / length.
    dp_x, dp_y = -d[:, 1] / (length * camera.fx), d[:, 0] / (length * camera.fy)
    n = img.normals[line_ids]  # (T, 3) unit
    per_px = (n[:, 0] * dp_x + n[:, 1] * dp_y)[:, None] / p_len  # (T, 2)
    per_px = np.where(np.abs(per_px) > 1e-12, per_px, 1e-12)
    Jpx = J / per_px[..., None]  # (T, 2, 3): pixels across the line per unit of pose
    sigma_offset = tol.line_px / math.sqrt(3.0)
    sigma_turn = math.tan(math.radians(tol.line_deg)) * 0.5 * length / math.sqrt(3.0)  # (T,)
    Jw = np.stack([0.5 * (Jpx[:, 0] + Jpx[:, 1]) / sigma_offset,
                   0.5 * (Jpx[:, 0] - Jpx[:, 1]) / sigma_turn[:, None]], axis=1)  # (T, 2, 3)
    np.add.at(A, hyp, np.einsum("tki,tkj->tij", Jw, Jw))
    return A


def unit_rays(camera, lines):
    """(T, 2, 3) unit camera-frame rays of the end points of lines (T, 2, 2)."""
    r = camera.pixel_rays(lines)
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def resolve_pieces(camera, poses, label, cls, segs, lines):
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


def fits(camera, img, poses, segments, line_ids, tol) -> np.ndarray:
    """(T,) bool: the image line lies within its noise bound (plus 2 px for
    the pose) of the projected segment, and inside its extent: occlusion and
    the image border only ever shorten the image of a segment, so a line
    sticking out beyond a projected end point by more than the end-point
    noise shows another segment."""
    return fits_and_distance(camera, img, poses, segments, line_ids, tol)[0]


def fits_and_distance(camera, img, poses, segments, line_ids, tol):
    """:func:`fits` (T,) and the lines' distances (T,), pixels, to the
    projected segments."""
    return _fits_projected(img, *project_segments(camera, poses, segments), line_ids, tol)


def _fits_projected(img, uv, in_front, line_ids, tol, end_px=None):
    """:func:`fits_and_distance` on segments already projected
    (:func:`~matcher.overlap.project_segments`); a line may stick out of
    its projected segment by ``end_px`` pixels in all (default: both end
    points' noise and 2 px for the pose)."""
    lines = img.lines[line_ids]
    L = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    dist, ov = projected_distance_and_overlap(uv, in_front, lines)
    end_px = 2 * tol.line_end_px + 2.0 if end_px is None else end_px
    return (dist <= fit_bound_px(L, tol)) & (ov >= L - end_px), dist


def visible(camera, poses, segments, lines, walls) -> np.ndarray:
    """(T,) bool: some point of the part of each segment (T, 2, 3) that its
    image line (T, 2, 2) shows (:func:`~matcher.overlap.covered_span`) is in
    plain sight from the camera at poses (T, 3), walls as occluders. (Points
    spread over the whole segment would miss a sliver seen past a jamb, and
    would let a line showing the hidden part of a segment pass on another
    part's visibility.) At a refined pose (a centimetre off) a sight line
    that cuts a wall 2 cm or more from the segment is blocked: it tells the
    near and far faces of a door jamb apart."""
    if walls is None or not len(poses):
        return np.ones(len(poses), dtype=bool)
    span = covered_span(camera, poses, segments, lines)  # (T, 2)
    t = span[:, :1] + _SPAN_SAMPLES[None, :] * (span[:, 1:] - span[:, :1])  # (T, n)
    a, b = segments[:, None, 0, :2], segments[:, None, 1, :2]
    pts = a + t[..., None] * (b - a)
    cams = np.repeat(poses[:, :2], len(_SPAN_SAMPLES), axis=0)
    clear = sight_clear(cams, pts.reshape(-1, 2), walls, _VISIBLE_END_M)
    return clear.reshape(len(poses), -1).any(axis=1)


def fit_bound_px(length, tol):
    """Largest distance, pixels, of a true line's end points from the
    projected segment: offset and rotation noise over half its length,
    plus 2 px for the pose's own error."""
    return tol.line_px + math.tan(math.radians(tol.line_deg)) * 0.5 * length + 2.0


def extend_all(camera, img, segs, poses, hyp, local, line_ids, hyps, tol, walls):
    """For each hypothesis h of ``hyps``: the (segment, line) pairs that fit
    at its pose ``poses[h]`` among its unmatched usable lines (see
    :func:`fits`; the segment visible too), closest first, each line once.
    A segment takes a further line only where that line shows another part
    of it than its lines so far (they overlap by at most the end-point
    noise): a detector breaks a line where its contrast fades or something
    stands in front, and the pieces are all explained by the one segment,
    while one-to-one matching would leave all but one unexplained (and a
    wrong pose that spreads the pieces over several segments would explain
    more lines). All hypotheses' pairs are tested in one batch. Returns
    ``(hyp, line, local)`` (A,) of the pairs to add; matches are given as
    ``hyp, local, line_ids`` (T,)."""
    usable = np.nonzero(img.usable)[0]
    N = len(segs)
    empty = np.zeros(0, dtype=np.int64)
    if not len(hyps):
        return empty, empty, empty
    # Every candidate segment projected once per hypothesis (C, N, 2, 2),
    # then each (hypothesis, free line, segment) pair looks it up.
    uv, in_front = project_segments(camera, poses[hyps][:, None, :], np.broadcast_to(segs, (len(hyps),) + segs.shape))
    ph, pl, ps = [], [], []
    matched = {}  # (contender, segment) -> the lines on it
    for c, h in enumerate(hyps.tolist()):
        sel = np.nonzero(hyp == h)[0]
        lines_free = np.ones(len(img.usable), dtype=bool)
        lines_free[line_ids[sel]] = False
        fl = usable[lines_free[usable]]
        ph.append(np.full(len(fl) * N, c))
        pl.append(np.repeat(fl, N))
        ps.append(np.tile(np.arange(N), len(fl)))
        for s_, l_ in zip(local[sel].tolist(), line_ids[sel].tolist()):
            matched.setdefault((c, s_), []).append(l_)
    pc, li, si = (np.concatenate(a).astype(np.int64) for a in (ph, pl, ps))
    if not len(pc):  # no usable line left free
        return empty, empty, empty
    ph = hyps[pc]
    ok, dist = _fits_projected(img, uv[pc, si], in_front[pc, si], li, tol)
    if ok.any():
        sel = np.nonzero(ok)[0]
        ok[sel] = visible(camera, poses[ph[sel]], segs[si[sel]], img.lines[li[sel]], walls)
    out_h, out_l, out_s = [], [], []
    lines_taken = set()  # (hypothesis, line)
    # Closest first within each hypothesis; a line is added once, a segment
    # again only for a part of it not shown yet.
    cand = np.nonzero(ok)[0]
    for k in cand[np.lexsort((dist[cand], ph[cand]))].tolist():
        c, h, s_, l_ = int(pc[k]), int(ph[k]), int(si[k]), int(li[k])
        if (h, l_) in lines_taken:
            continue
        on_it = matched.setdefault((c, s_), [])
        if on_it:
            spans = _spans_along(np.broadcast_to(uv[c, s_], (len(on_it) + 1, 2, 2)), img.lines[on_it + [l_]])
            overlap = np.minimum(spans[:-1, 1], spans[-1, 1]) - np.maximum(spans[:-1, 0], spans[-1, 0])
            if (overlap > 2.0 * tol.line_end_px).any():
                continue
        on_it.append(l_)
        lines_taken.add((h, l_))
        out_h.append(h)
        out_s.append(s_)
        out_l.append(l_)
    return (np.array(out_h, dtype=np.int64), np.array(out_l, dtype=np.int64), np.array(out_s, dtype=np.int64))


def _spans_along(uv: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """(T, 2) the interval, pixels, that each line (T, 2, 2) covers along its
    projected segment ``uv`` (T, 2, 2), from the segment's first end point."""
    d = uv[:, 1] - uv[:, 0]
    d = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    t = np.einsum("tek,tk->te", lines - uv[:, None, 0], d)
    return np.sort(t, axis=1)
