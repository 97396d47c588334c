"""Stage 2: pose, fit and score of every hypothesis, and their ranking
(method.md section 8).

For each hypothesis, all at once where the arrays allow:

1. a robust least-squares pose (:func:`matcher.stage2.refine.refine`) from the
   stage-1 grid pose (that grid start is the yaw search and linear solve);
2. each match's model segment: the piece of its collinear group that the
   image line overlaps most at that pose; a loosely fixed pose whose lines
   stick out of their segments slides to where they fit
   (:mod:`matcher.stage2.slide`);
3. matches that do not fit at the pose (line off its projected segment by
   more than the noise, sticking out beyond its end points, or the segment
   hidden by a wall) are dropped, and the pose refitted;
4. for the contenders (most fitting matches, within one), the lines of
   other visible segments that fit at the pose are added
   (:mod:`matcher.stage2.extend`) and the pose refitted: a hypothesis that lost a true line to a clutter line in
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

from linemap.geometry import project_segments, segment_is_vertical
from matcher.candidates import Candidates
from matcher.prior import within_prior
from matcher.projection import covered_span, projected_end_distances
from matcher.stage2 import refine
from matcher.stage2.covariance import pose_covariance, pose_spread
from matcher.stage2.extend import extend_all
from matcher.stage2.fit import fit_bound_px, fits, resolve_pieces, unit_rays, visible
from matcher.stage2.slide import slide_to_fit


@dataclass
class Ranked:
    """Verified hypotheses. Per match t: ``hyp`` (T,), ``local`` (T,) index
    into the candidate segments, ``line`` (T,) image line. Per hypothesis:
    ``poses`` (H, 3) ``(x, y, yaw)``, ``score`` (H,) E (inf when dropped),
    ``order`` (H,) best first; ``why`` the reason when none is left;
    ``cost`` (H,) the reprojection cost the ranking uses
    (:func:`reprojection_cost`)."""

    hyp: np.ndarray
    local: np.ndarray
    line: np.ndarray
    poses: np.ndarray
    score: np.ndarray
    order: np.ndarray
    why: str
    cost: np.ndarray | None = None


def verify_hypotheses(camera, img, cands: Candidates, hyps, prior, tol) -> Ranked:
    """Stage 2 on stage 1's ``hyps`` (group ids in ``hyps.segment``) under
    ``prior`` ``(xe, ye, yaw_e, dt, dyaw)``; ``cands`` the candidate
    segments, their collinear groups and the map's walls and free space."""
    segs, label, reps, walls, free = cands.segments, cands.label, cands.reps, cands.walls, cands.free
    work = tol.internals
    n_h = len(hyps.sets)
    members = np.concatenate(hyps.sets)
    hyp = np.repeat(np.arange(n_h), [len(x) for x in hyps.sets])
    cls = hyps.segment[members]
    line_ids = hyps.line[members]
    rays = unit_rays(camera, img.lines[line_ids])
    lengths = np.linalg.norm(img.lines[line_ids, 1] - img.lines[line_ids, 0], axis=1)
    scale = fit_bound_px(lengths, tol) / camera.fx
    poses = refine.refine(hyps.init, hyp, reps[cls, 0], reps[cls, 1], rays[:, 0], rays[:, 1],
                          camera.pitch, camera.height_m, work, robust_scale=scale)
    local = resolve_pieces(camera, poses[hyp], label, cls, segs, img.lines[line_ids], work.near_plane_m)
    inl, dist = fits(camera, img, poses[hyp], segs[local], line_ids, tol)
    poses, slid = slide_to_fit(camera, img, segs, poses, hyp, local, line_ids, tol, inl,
                               stuck_out=~inl & (dist <= fit_bound_px(lengths, tol)))
    if slid.any():  # their lines judged again at the new poses
        local = resolve_pieces(camera, poses[hyp], label, cls, segs, img.lines[line_ids], work.near_plane_m)
        inl = fits(camera, img, poses[hyp], segs[local], line_ids, tol)[0]
    at = inl.nonzero()[0]  # visibility only where the line fits
    inl[at] = visible(camera, poses[hyp[at]], segs[local[at]], img.lines[line_ids[at]], walls, work)
    n_in = np.bincount(hyp, inl, minlength=n_h)
    keep = inl & (n_in[hyp] >= tol.min_matches)
    hyp, line_ids, local = hyp[keep], line_ids[keep], local[keep]
    alive = n_in >= tol.min_matches

    def in_prior(poses, hyp, local, line_ids):
        """(H,) bool, :func:`within_prior`: with the fixed slack, then, for
        the hypotheses of ``alive`` it drops, with the pose's own spread (a
        loosely fixed pose; rare, and the covariance costs a few tenths of
        a millisecond)."""
        ok = within_prior(poses, prior, free, tol)
        loose = np.nonzero(alive & ~ok)[0]
        if len(loose):
            sel = np.isin(hyp, loose)
            cov = pose_covariance(camera, img, segs, poses[loose], np.searchsorted(loose, hyp[sel]), local[sel],
                                  line_ids[sel], tol)
            ok[loose] = within_prior(poses[loose], prior, free, tol, pose_spread(cov))
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
    fixed = np.bincount(hyp, np.where(segment_is_vertical(segs[local], work.vertical_axis_deg), 1.0, 2.0), minlength=n_h)
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
        E = refine.score_e(poses, hyp, img.normals[line_ids], segs[local, 0], segs[local, 1], camera.pitch,
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
    return Ranked(hyp, local, line_ids, poses, E, order, why, cost)


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
    d = projected_end_distances(*project_segments(camera, poses[hyp], segments, tol.internals.near_plane_m),
                                lines)  # (T, 2)
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
    new = refine.refine(poses, hyp, segs[local, 0], segs[local, 1], r[:, 0], r[:, 1], camera.pitch,
                        camera.height_m, tol.internals, iterations=tol.internals.refit_iterations)
    if slid.any():  # judged as the slide judges, so that they go back as far
        sel = slid[hyp]
        inl = np.ones(len(hyp), dtype=bool)
        inl[sel] = fits(camera, img, new[hyp[sel]], segs[local[sel]], line_ids[sel], tol, end_px=tol.line_end_px)[0]
        new, _ = slide_to_fit(camera, img, segs, new, hyp, local, line_ids, tol, inl)
    return new
