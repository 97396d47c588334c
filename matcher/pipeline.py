"""The two-stage matcher: :func:`localize` from a prior, :func:`localize_global` when lost."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from linemap.lmap import LineMap
from matcher.budget import NO_LIMIT, Deadlines
from linemap.camera import Camera
from matcher.checks import check_lines, check_prior
from matcher.constraints import (bearing_noise, line_pieces, plane_noises, vertical_bearing, vertical_candidates,
                                 wrap)
from matcher.map_index import MapIndex
from linemap.geometry import in_field_of_view
from matcher.generate import ImageLines, collinear_classes, generate, search_again
from matcher.rank import pose_std_of, verify_hypotheses
from matcher.resection import vertical_hypotheses
from matcher.result import LocalizeResult
from matcher.tolerances import DEFAULT, Tolerances


def prepare_lines(camera: Camera, lines: np.ndarray, tol: Tolerances) -> ImageLines:
    """Per-line quantities of validated pixel lines (M, 2, 2) of the ideal
    (undistorted) camera: plane normals and their noise, vertical candidates
    and their bearings."""
    und = lines
    normals = camera.interpretation_normals(und)
    eps, eps_rot, eps_off = plane_noises(camera, und, tol.line_px, tol.line_deg)
    vert = vertical_candidates(camera, normals, eps)
    alpha = vertical_bearing(camera, und)
    alpha_eps = bearing_noise(camera, und, tol.line_px, tol.line_deg)
    usable = np.linalg.norm(und[:, 1] - und[:, 0], axis=1) >= tol.min_line_px
    mid = camera.pixel_rays(0.5 * (und[:, 0] + und[:, 1]))
    mid /= np.linalg.norm(mid, axis=1, keepdims=True)
    pieces = line_pieces(und, normals, eps, 2.0 * tol.line_end_px)
    return ImageLines(und, normals, eps, vert, alpha, alpha_eps, usable, eps_rot, eps_off, mid, pieces)


def localize(linemap, camera: Camera, lines, prior, dt: float, dyaw: float, tolerances: Tolerances | None = None):
    """Localise the camera from image ``lines`` (M, 2, 2) or (M, 4) pixels of
    the ideal pinhole (as :func:`matcher.detect_lines` gives them: undistorted
    when the camera has distortion).

    ``prior`` is ``(x, y, yaw_deg)``; the true pose is within ``dt`` metres
    and ``dyaw`` degrees of it. Returns a :class:`LocalizeResult`, falsy with
    a ``reason`` when no hypothesis is accepted. Bad input (shapes, NaN,
    ranges) raises ValueError."""
    t0 = time.perf_counter()
    tol, img = _checked_inputs(linemap, camera, lines, tolerances)
    px = check_prior(prior, dt, dyaw)
    return _localize(linemap, camera, img, px, tol, t0, Deadlines.from_budget(t0, tol.time_budget_ms))


def _checked_inputs(linemap, camera, lines, tolerances) -> tuple[Tolerances, ImageLines]:
    """ValueError unless the map, camera and tolerances are of their types
    and the lines valid; the tolerances to use and the prepared lines."""
    if not isinstance(linemap, LineMap):
        raise ValueError(f"linemap must be a map from matcher.load_map('map.lmap'), got {type(linemap).__name__}")
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a matcher.Camera (Camera.load('camera.json')), got {type(camera).__name__}")
    if tolerances is not None and not isinstance(tolerances, Tolerances):
        raise ValueError(f"tolerances must be a matcher.Tolerances, got {type(tolerances).__name__}")
    tol = tolerances or DEFAULT
    return tol, prepare_lines(camera, check_lines(lines, camera, tol), tol)


def _localize(linemap, camera, img, px, tol, t0, deadlines: Deadlines = NO_LIMIT, candidate_ids=None):
    """One prior ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians), within the
    time budget's ``deadlines``."""
    xe, ye, yaw_e, dt, dyaw = px
    times: dict[str, float] = {}
    spent = False  # a step skipped, or its result dropped, for want of time

    def in_time() -> bool:
        """Time left to search; noted when there is not (asked only when
        a step would otherwise run)."""
        nonlocal spent
        spent = spent or not deadlines.may_search()
        return not spent

    def fail(reason, hyps=None):
        times["total"] = (time.perf_counter() - t0) * 1e3
        return LocalizeResult(False, reason, time_ms=times, stage1={} if hyps is None else stage1_of(hyps))

    def stage1_of(hyps) -> dict:
        """Stage 1's counters, with whether the time budget cut anything."""
        return dict(hyps.counts, out_of_time=bool(hyps.counts.get("out_of_time") or spent))

    # ---- selection: regions met by the disk, field of view ---------------
    ids = linemap.candidate_segments(xe, ye, dt) if candidate_ids is None else candidate_ids
    near = len(linemap.regions_near(xe, ye, dt)) if len(ids) == 0 else 1
    if len(ids) == 0:
        if near == 0:
            return fail(f"the prior ({xe:.6g}, {ye:.6g}) is farther than dt={dt:g} m from every region of the map; "
                        "check the prior or use localize_global")
        return fail("no model segment is visible from the regions met by the prior disk")
    segs = linemap.segments[ids]
    fov = in_field_of_view(segs, camera, (xe, ye, yaw_e), dt, dyaw)
    ids, segs = ids[fov], segs[fov]
    times["select"] = (time.perf_counter() - t0) * 1e3
    if len(ids) == 0:
        return fail("no candidate segment lies in the field of view for any heading of the prior interval")
    too_few = _too_few_lines(img, tol)
    if too_few:
        return fail(too_few)

    # ---- stage 1 ---------------------------------------------------------
    t1 = time.perf_counter()
    # Collinear groups: made once per map, spans per frame.
    index = linemap.derived(MapIndex)
    label, reps = collinear_classes(segs, label=index.collinear[ids])
    walls, free, sight = index.walls, index.free, index.sight
    faces = _class_faces(index.faces[ids], label)
    hyps = generate(reps, np.arange(len(reps)), camera, img, (xe, ye, yaw_e), dt, dyaw, tol, walls,
                    free=free, sight=sight, faces=faces, deadlines=deadlines)
    times["generate"] = (time.perf_counter() - t1) * 1e3
    n_h = len(hyps.sets)
    if n_h == 0 and hyps.truncated and in_time():
        hyps = _with_resection(hyps, [], reps, img, px, tol, free, deadlines.search)
        n_h = len(hyps.sets)
    if n_h == 0:
        return fail(f"no consistent set of {tol.min_matches} or more correspondences "
                    f"({hyps.n_correspondences} correspondences passed the unary tests)"
                    + _cut_short(hyps, tol, spent), hyps)

    # ---- stage 2 ---------------------------------------------------------
    t2 = time.perf_counter()
    ranked_h = verify_hypotheses(camera, img, segs, label, reps, hyps, (xe, ye, yaw_e, dt, dyaw), tol, walls,
                                 free)
    if _doubtful(ranked_h, hyps, tol) and tol.match_slack == 0 and in_time():
        # The largest consistent sets held wrong matches (stage 2 threw them
        # out): the true set may be one smaller and was cut by the bound.
        # Search again keeping sets one smaller than the largest.
        t3 = time.perf_counter()
        again = search_again(hyps, replace(tol, match_slack=1))
        if again.counts["out_of_time"]:  # cut short: the first search's sets stand
            spent = True
        else:
            hyps, n_h = again, len(again.sets)
            ranked_h = verify_hypotheses(camera, img, segs, label, reps, hyps, (xe, ye, yaw_e, dt, dyaw), tol,
                                         walls, free)
        times["second_search"] = (time.perf_counter() - t3) * 1e3
    if ((hyps.truncated or not ranked_h.score[ranked_h.order[0]] <= tol.e_accept) and "resection" not in hyps.counts
            and in_time()):
        # The tree ran out of budget or nothing it found held: where vertical
        # edges leave the position loose, resect from their triples instead.
        t4 = time.perf_counter()
        held = [int(h) for h in ranked_h.order if np.isfinite(ranked_h.score[h])][:_TREE_KEPT]
        more = _with_resection(hyps, held, reps, img, px, tol, free, deadlines.search)
        if more.counts["resection"]:
            hyps, n_h = more, len(more.sets)
            ranked_h = verify_hypotheses(camera, img, segs, label, reps, hyps, (xe, ye, yaw_e, dt, dyaw), tol,
                                         walls, free)
        times["resection"] = (time.perf_counter() - t4) * 1e3
    E = ranked_h.score
    order = ranked_h.order

    def matches_of(h):
        sel = ranked_h.hyp == h
        return sorted([int(ids[a]), int(b)] for a, b in zip(ranked_h.local[sel], ranked_h.line[sel]))

    def pose_deg(p):
        return (float(p[0]), float(p[1]), float(math.degrees(wrap(p[2]))))

    ranked = [(float(E[h]), matches_of(h), pose_deg(ranked_h.poses[h])) for h in order]
    best = int(order[0])
    runner = float(E[order[1]]) if n_h > 1 and np.isfinite(E[order[1]]) else None
    times["verify"] = (time.perf_counter() - t2) * 1e3
    times["total"] = (time.perf_counter() - t0) * 1e3
    common = dict(hypotheses=n_h, runner_up_score=runner, time_ms=times, ranked=ranked,
                  sets_found=int(hyps.counts.get("sets_found", n_h)), stage1=stage1_of(hyps))
    if not E[best] <= tol.e_accept:
        why = ranked_h.why if not np.isfinite(E[best]) else (
            f"best score E={E[best]:.3g} is above the acceptance threshold {tol.e_accept:g}")
        res = LocalizeResult(False, why + _cut_short(hyps, tol, spent), **common)
        res.score = float(E[best]) if np.isfinite(E[best]) else None
        return res
    res = LocalizeResult(True, "", pose=pose_deg(ranked_h.poses[best]), score=float(E[best]),
                         matches=matches_of(best), **common)
    # Worked out when first read (a few tenths of a millisecond a robot
    # that only wants the pose does not spend).
    res.pose_std_from(lambda: pose_std_of(camera, img, segs, ranked_h, best, tol))
    return res


#: When resection adds hypotheses, the tree's that stage 2 kept stay with
#: them, at most this many (best ranked first); the resection fills the rest
#: of ``max_hypotheses``.
_TREE_KEPT = 5


def _with_resection(hyps, held, reps, img: ImageLines, px, tol: Tolerances, free, deadline=math.inf):
    """The sets ``held`` (indices) of stage 1's hypotheses followed by those
    of :mod:`matcher.resection` (poses resected from triples of vertical
    edges), at most ``max_hypotheses`` in all; ``counts["resection"]`` says
    how many the resection gave."""
    counts = dict(hyps.counts)
    counts["resection"] = 0
    inp = hyps.tree_input
    if inp is None:
        return replace(hyps, counts=counts)
    sets, inits = vertical_hypotheses(reps[hyps.segment, 0, :2], hyps.segment, hyps.line, inp.vertical,
                                      inp.compat, img.alpha, img.alpha_eps, px, free, tol.free_space_m,
                                      tol.max_hypotheses - len(held), min_lines=tol.min_matches + 1,
                                      deadline=deadline)
    counts["resection"] = len(sets)
    init = hyps.init.reshape(-1, 3)[held]
    return replace(hyps, sets=[hyps.sets[h] for h in held] + sets, init=np.concatenate([init, inits]),
                   counts=counts)


def _cut_short(hyps, tol: Tolerances, spent: bool) -> str:
    """What a failure's reason adds when the search stopped early: the time
    budget spent (by stage 1, or ``spent``: a later step skipped), or
    stage 1's node or set budget."""
    if hyps.counts.get("out_of_time") or spent:
        return f" (time budget of {tol.time_budget_ms:g} ms spent)"
    return " (hypothesis search truncated)" if hyps.truncated else ""


def _too_few_lines(img: ImageLines, tol: Tolerances) -> str:
    """Why the image lines cannot give a pose, or "" if they may."""
    n = int(img.usable.sum())
    if n >= tol.min_matches:
        return ""
    return f"only {n} usable image lines (need {tol.min_matches} of >= {tol.min_line_px:g} px)"


def _class_faces(faces: np.ndarray, label: np.ndarray) -> np.ndarray:
    """(G, 2) wall-face normal per collinear group: its members' when they
    all agree, else zeros (no constraint)."""
    G = int(label.max()) + 1 if len(label) else 0
    out = np.zeros((G, 2))
    first = np.full(G, -1)
    first[label[::-1]] = np.arange(len(label))[::-1]
    ref = faces[first]
    agree = np.ones(G, dtype=bool)
    np.logical_and.at(agree, label, np.abs(faces - ref[label]).max(axis=1) < 1e-9)
    out[agree] = ref[agree]
    return out


def _doubtful(ranked, hyps, tol) -> bool:
    """Nothing accepted, or the best hypothesis kept fewer matches than the
    largest stage-1 set had (and stage 1 was not cut short): a clutter line
    may have padded the largest sets past the true one. One match fewer is
    doubted only when the best also fits loosely (E above ``e_doubt``): a
    clutter line dropped from the true set leaves it fitting as well as
    ever, while the remains of a padded set, whose clutter line took a true
    line's segment, sit at a pose a few centimetres off."""
    if hyps.truncated:  # a second search would run out of budget too
        return False
    best = int(ranked.order[0])
    if not ranked.score[best] <= tol.e_accept:
        return True
    short = max(len(x) for x in hyps.sets) - int((ranked.hyp == best).sum())
    return short >= 2 or (short == 1 and ranked.score[best] > tol.e_doubt)


#: Lost mode multiplies the tree's node and set budgets by this.
_LOST_BUDGET = 10


def localize_global(linemap, camera: Camera, lines, tolerances: Tolerances | None = None,
                    first_accepted: bool = False, progress=None):
    """Lost mode (method.md section 3): one prior per region (its centre,
    ``dt`` its radius, any heading, the region's own visible list).

    Regions are tried largest first. With ``first_accepted`` the search
    stops at the first region that gives an accepted hypothesis (the
    paper's loop).
    Otherwise every region is tried and the accepted result that explains
    the most lines wins, then the smallest E: a wrong room can hold a few
    lines that fit well, the right one explains more of the image.
    ``time_ms['total']`` covers all tries (the other entries are the winning
    region's); ``time_ms['regions_tried']`` counts them. ``progress``, if
    given, is called as ``progress(done, total)`` as the regions are done,
    last with ``done == total``. The tolerances' ``time_budget_ms`` bounds
    the whole call: regions are tried until it is spent. Returns a falsy
    result if no region gives one."""
    t0 = time.perf_counter()
    tol, img = _checked_inputs(linemap, camera, lines, tolerances)
    deadlines = Deadlines.from_budget(t0, tol.time_budget_ms)
    if linemap.n_regions == 0:
        return LocalizeResult(False, "the map has no regions", time_ms={"total": 0.0, "regions_tried": 0})
    too_few = _too_few_lines(img, tol)
    if too_few:  # the same for every region
        return LocalizeResult(False, too_few, time_ms={"total": (time.perf_counter() - t0) * 1e3, "regions_tried": 0})
    # The robot is stopped: a larger search budget per region.
    tol = replace(tol, max_nodes=tol.max_nodes * _LOST_BUDGET, max_sets=tol.max_sets * _LOST_BUDGET)
    centres, radii = linemap.region_centres(), linemap.region_radii()
    # Largest region first: with no estimate, the robot stands most likely
    # on the most floor, and a budget spent early has searched the most.
    order = np.argsort(-linemap.region_areas(), kind="stable")
    tried, best, out_of_time = 0, None, False
    for done, r in enumerate(order.tolist()):
        if progress is not None and done:
            progress(done, linemap.n_regions)
        if not deadlines.may_search():
            out_of_time = True
            break
        cx, cy = (float(v) for v in centres[r])
        dt = float(radii[r])
        if not (math.isfinite(cx) and math.isfinite(cy) and dt > 0):
            continue
        tried += 1
        res = _localize(linemap, camera, img, (cx, cy, 0.0, min(dt, 100.0), math.pi), tol, time.perf_counter(),
                        deadlines, candidate_ids=linemap.region_list(r))
        out_of_time |= bool(res.stage1.get("out_of_time"))
        if res and (best is None or (len(res.matches), -res.score) > (len(best.matches), -best.score)):
            best = res
            if first_accepted:
                break
    if progress is not None:
        progress(linemap.n_regions, linemap.n_regions)
    total = (time.perf_counter() - t0) * 1e3
    if best is None:
        spent = f"; the time budget of {tol.time_budget_ms:g} ms ran out" if out_of_time else ""
        return LocalizeResult(False, f"no region gave an accepted hypothesis ({tried} of {linemap.n_regions} "
                              f"tried{spent})",
                              time_ms={"total": total, "regions_tried": tried})
    best.time_ms["total"] = total
    best.time_ms["regions_tried"] = tried
    # The best of the regions searched, not of all: the result says so.
    best.stage1["out_of_time"] = out_of_time
    return best
