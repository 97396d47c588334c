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
from matcher.stage2.matches import Matches
from matcher.stage2.slide import slide_to_fit


@dataclass
class Ranked:
    """Verified hypotheses. ``matches`` (:class:`~matcher.stage2.matches.Matches`:
    per match its hypothesis, its candidate segment, its image line). Per
    hypothesis: ``poses`` (H, 3) ``(x, y, yaw)``, ``score`` (H,) E (inf
    when dropped), ``order`` (H,) best first; ``why`` the reason when none
    is left; ``cost`` (H,) the reprojection cost the ranking uses
    (:func:`reprojection_cost`)."""

    matches: Matches
    poses: np.ndarray
    score: np.ndarray
    order: np.ndarray
    why: str
    cost: np.ndarray | None = None


def verify_hypotheses(camera, image_lines, cands: Candidates, hyps, prior, tol) -> Ranked:
    """Stage 2 on stage 1's ``hyps`` (group ids in ``hyps.segment``) under
    ``prior`` ``(xe, ye, yaw_e, dt, dyaw)``; ``cands`` the candidate
    segments, their collinear groups and the map's walls and free space
    (the module docstring's steps, in order)."""
    segs = cands.segments
    n_h = len(hyps.sets)
    poses, m, inl, slid = _fitted(camera, image_lines, cands, hyps, tol)
    n_in = np.bincount(m.hyp, inl, minlength=n_h)
    keep = inl & (n_in[m.hyp] >= tol.min_matches)
    m = m.subset(keep)
    alive = n_in >= tol.min_matches
    if alive.any() and not keep.all():
        # Matches were dropped: refit, so that the lines added back below
        # are judged at a pose the dropped ones no longer pull.
        poses = _refit(camera, image_lines, segs, poses, m, tol, slid)
    if alive.any():
        alive &= _in_prior(camera, image_lines, cands, prior, tol, poses, m, alive)
    if alive.any():
        # Contenders get the lines they are missing back, then a last refit
        # (plain least squares on the final matches).
        top = int(n_in[alive].max())
        contenders = np.nonzero(alive & (n_in >= top - 1))[0]
        m = m.with_added(extend_all(camera, image_lines, segs, poses, m, contenders, tol, cands.walls))
        poses = _refit(camera, image_lines, segs, poses, m, tol, slid)
        alive &= _in_prior(camera, image_lines, cands, prior, tol, poses, m, alive)
    n_fin = np.bincount(m.hyp, minlength=n_h)
    # A vertical edge's line fixes one number of the pose (its bearing), any
    # other line two. Matches that fix no more than the pose's three leave
    # nothing over to check it: three vertical edges fit exactly (E = 0)
    # whichever they are. Such a hypothesis is not accepted.
    fixed = np.bincount(m.hyp, np.where(segment_is_vertical(segs[m.local], tol.shared.vertical_axis_deg), 1.0, 2.0),
                        minlength=n_h)
    exact = alive & (fixed <= 3)
    alive &= ~exact
    E = _score(camera, image_lines, segs, poses, m)
    # Ranked among the hypotheses that explain the most lines (a hypothesis
    # trimmed down to a few lines fits them well but explains less) by the
    # reprojection error: the end points' distances to their projected
    # segments, each over its line's noise bound, in the image space the
    # detector's noise is stated in. E, the paper's score, mixes radians and
    # metres: two aliases (the near and far faces of a jamb, 20 cm and 3
    # degrees apart) often score E alike while their reprojection errors
    # differ threefold (docs/matcher.md). E breaks ties, is reported, and is
    # what the acceptance threshold applies to.
    cost = reprojection_cost(camera, image_lines, poses, m, segs, tol, n_h)
    best_n = int(n_fin[alive].max()) if alive.any() else 0
    E = np.where(alive & (n_fin >= max(best_n, tol.min_matches)) & np.isfinite(E), E, np.inf)
    order = np.lexsort((E, cost, -n_fin * alive))
    # Hypotheses that ended with the same matches are one: only the best
    # ranked keeps its score (so the runner-up is a different match).
    keys = {}
    for h in order:
        sel = m.hyp == h
        key = tuple(sorted(zip(m.local[sel].tolist(), m.line[sel].tolist())))
        if key in keys and np.isfinite(E[h]):
            E[h] = np.inf
        keys.setdefault(key, h)
    order = np.lexsort((E, cost, -n_fin * (alive & np.isfinite(E))))
    why = "" if np.isfinite(E).any() else _why_none(exact, n_in, tol)
    return Ranked(m, poses, E, order, why, cost)


def _fitted(camera, image_lines, cands: Candidates, hyps, tol) -> tuple:
    """Steps 1 to 3 of the module docstring on every hypothesis of stage
    1's ``hyps``: ``(poses (H, 3), matches, fit (T,) bool, slid (H,)
    bool)``; the matches with the piece of its group each line shows, the
    fit the line's at its pose (and its segment visible there), slid which
    poses moved to where their lines fit."""
    segs, label, reps, work = cands.segments, cands.label, cands.reps, tol.stage2
    n_h = len(hyps.sets)
    members = np.concatenate(hyps.sets)
    hyp = np.repeat(np.arange(n_h), [len(x) for x in hyps.sets])
    cls = hyps.segment[members]
    line_ids = hyps.line[members]
    lines = image_lines.lines[line_ids]
    rays = unit_rays(camera, lines)
    lengths = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    scale = fit_bound_px(lengths, tol) / camera.fx
    terms = refine.MatchTerms(reps[cls, 0], reps[cls, 1], rays[:, 0], rays[:, 1], camera.pitch, camera.height_m)
    poses = refine.refine(hyps.init, hyp, terms, work, robust_scale=scale)
    m = Matches(hyp, resolve_pieces(camera, poses[hyp], label, cls, segs, lines, work.near_plane_m), line_ids)
    inl, dist = fits(camera, image_lines, poses[hyp], segs[m.local], line_ids, tol)
    poses, slid = slide_to_fit(camera, image_lines, segs, poses, m, tol, inl,
                               stuck_out=~inl & (dist <= fit_bound_px(lengths, tol)))
    if slid.any():  # their lines judged again at the new poses
        m = Matches(hyp, resolve_pieces(camera, poses[hyp], label, cls, segs, lines, work.near_plane_m), line_ids)
        inl = fits(camera, image_lines, poses[hyp], segs[m.local], line_ids, tol)[0]
    at = inl.nonzero()[0]  # visibility only where the line fits
    inl[at] = visible(camera, poses[hyp[at]], segs[m.local[at]], lines[at], cands.walls, work, tol.shared)
    return poses, m, inl, slid


def _in_prior(camera, image_lines, cands: Candidates, prior, tol, poses, m: Matches, alive) -> np.ndarray:
    """(H,) bool, :func:`within_prior`: with the fixed slack, then, for the
    hypotheses of ``alive`` it drops, with the pose's own spread (a loosely
    fixed pose; rare, and the covariance costs a few tenths of a
    millisecond)."""
    ok = within_prior(poses, prior, cands.free, tol)
    loose = np.nonzero(alive & ~ok)[0]
    if len(loose):
        cov = pose_covariance(camera, image_lines, cands.segments, poses[loose], m.of(loose), tol)
        ok[loose] = within_prior(poses[loose], prior, cands.free, tol, pose_spread(cov))
    return ok


def _score(camera, image_lines, segs, poses, m: Matches) -> np.ndarray:
    """The paper's E (H,) of every hypothesis at ``poses`` (H, 3) (inf
    without matches)."""
    if not len(m):
        return np.full(len(poses), np.inf)
    # E's position term at the middle of the part of each segment that
    # its line shows, not of the whole segment: a short line on a long,
    # partly hidden segment turns its plane about its own middle by its
    # orientation noise, and that turn, times the distance to a far
    # midpoint, would swamp E (the two agree for a segment seen whole).
    span = covered_span(camera, poses[m.hyp], segs[m.local], image_lines.lines[m.line])  # (T, 2)
    shown_mid = segs[m.local, 0] + span.mean(axis=1)[:, None] * (segs[m.local, 1] - segs[m.local, 0])
    return refine.score_e(poses, m.hyp, image_lines.normals[m.line], segs[m.local, 0], segs[m.local, 1], camera.pitch,
                          camera.height_m, mid=shown_mid)


def _why_none(exact: np.ndarray, n_in: np.ndarray, tol) -> str:
    """Why no hypothesis is left: ``exact`` (H,) those whose matches fix
    the pose exactly, ``n_in`` (H,) their matches that fitted at first."""
    if exact.any():
        return ("the hypotheses left fix the pose exactly (three vertical edges, say), with nothing over to "
                "verify it; more image lines are needed")
    if (n_in >= tol.min_matches).any():
        return "no hypothesis kept its pose inside the prior bounds and the map's free space"
    return f"no hypothesis kept {tol.min_matches} matches that fit at its pose"


def reprojection_cost(camera, image_lines, poses, m: Matches, segs, tol, n_h) -> np.ndarray:
    """(H,) per hypothesis: the sum over its matches ``m`` (their segments
    indices into ``segs`` (N, 2, 3)) and both end points of the line of (d / s)^2,
    d the end point's distance, pixels, to the line of the segment
    projected at the hypothesis' pose (``poses`` (H, 3)) and s the line's
    noise bound (``line_px`` plus ``line_deg`` over half its length); inf
    for a segment behind the camera."""
    if not len(m):
        return np.full(n_h, np.inf)
    lines = image_lines.lines[m.line]
    d = projected_end_distances(*project_segments(camera, poses[m.hyp], segs[m.local], tol.stage2.near_plane_m),
                                lines)  # (T, 2)
    length = np.hypot(*(lines[:, 1] - lines[:, 0]).T)
    noise = tol.line_px + math.tan(math.radians(tol.line_deg)) * 0.5 * length
    return np.bincount(m.hyp, ((d / noise[:, None]) ** 2).sum(axis=1), minlength=n_h)


def _refit(camera, image_lines, segs, poses, m: Matches, tol, slid):
    """Poses (H, 3) refitted by plain least squares on the matches ``m``.
    Those of the hypotheses ``slid`` (H,) bool (:func:`slide_to_fit`) slide
    again if their lines no longer fit: least squares alone takes them back
    out along the direction their bearings leave loose."""
    if len(m) == 0:
        return poses
    r = unit_rays(camera, image_lines.lines[m.line])
    terms = refine.MatchTerms(segs[m.local, 0], segs[m.local, 1], r[:, 0], r[:, 1], camera.pitch, camera.height_m)
    new = refine.refine(poses, m.hyp, terms, tol.stage2, iterations=tol.stage2.refit_iterations)
    if slid.any():  # judged as the slide judges, so that they go back as far
        sel = slid[m.hyp]
        inl = np.ones(len(m), dtype=bool)
        inl[sel] = fits(camera, image_lines, new[m.hyp[sel]], segs[m.local[sel]], m.line[sel], tol,
                        end_px=tol.line_end_px)[0]
        new, _ = slide_to_fit(camera, image_lines, segs, new, m, tol, inl)
    return new
