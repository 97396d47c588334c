"""Stage 2: does an image line fit a model segment at a refined pose, and is
the segment visible there?

One fit test (:func:`fits`) serves the whole of stage 2: dropping matches
that do not fit, sliding a loose pose (with a tighter end allowance), and
adding the lines of other visible segments. One visibility test
(:func:`visible`) at the refined pose; stage 1's own, at a grid pose a few
centimetres off, is looser (:mod:`matcher.search.tree.set_visibility`).
"""

from __future__ import annotations

import math

import numpy as np

from linemap.geometry import clip_lines, project_segments
from matcher.projection import covered_span, distance_and_overlap, projected_distance_and_overlap
from matcher.map_geometry.occlusion import sight_clear
from matcher.tolerances import SharedConstants, Stage2Constants


def fits(camera, image_lines, poses, segments, line_ids, tol, end_px=None):
    """The fit test of a line to its segment at a pose: ``(ok (T,) bool,
    dist (T,) pixels)`` for matches t of segments (T, 2, 3) and image lines
    ``line_ids`` (T,) at poses (T, 3). A line fits when it lies within its
    noise bound (:func:`fit_bound_px`) of the projected segment, and inside
    its extent: occlusion and the image border only ever shorten the image
    of a segment, so a line sticking out beyond a projected end point by
    more than the end-point noise shows another segment. ``end_px``: how
    far, pixels, a line may stick out in all (default: both end points'
    noise and ``fit_pose_px`` for the pose; the slide passes the end points'
    noise alone, so that a pose it accepts has the lines inside their
    segments). ``dist`` is the lines' larger end-point distance to the
    projected segment's line."""
    uv, in_front = project_segments(camera, poses, segments, tol.stage2.near_plane_m)
    return fits_projected(image_lines, uv, in_front, line_ids, tol, end_px)


def fits_projected(image_lines, uv, in_front, line_ids, tol, end_px=None):
    """:func:`fits` on segments already projected
    (:func:`linemap.geometry.project_segments`' ``uv`` (T, 2, 2), ``in_front`` (T,))."""
    return fits_lines(image_lines.lines[line_ids], uv, in_front, tol, end_px)


def fits_lines(lines, uv, in_front, tol, end_px=None):
    """:func:`fits_projected` of the pixel lines themselves (T, 2, 2)."""
    L = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1)
    dist, ov = projected_distance_and_overlap(uv, in_front, lines)
    end_px = 2 * tol.line_end_px + tol.stage2.fit_pose_px if end_px is None else end_px
    return (dist <= fit_bound_px(L, tol)) & (ov >= L - end_px), dist


def fit_bound_px(length, tol):
    """Largest distance, pixels, of a true line's end points from the
    projected segment: offset and rotation noise over half its length,
    plus ``fit_pose_px`` for the pose's own error."""
    return tol.line_px + math.tan(math.radians(tol.line_deg)) * 0.5 * length + tol.stage2.fit_pose_px


def visible(camera, poses, segments, lines, walls, work: Stage2Constants, shared: SharedConstants) -> np.ndarray:
    """(T,) bool: some point of the part of each segment (T, 2, 3) that its
    image line (T, 2, 2) shows (:func:`~matcher.projection.covered_span`) is in
    plain sight from the camera at poses (T, 3), walls as occluders. (Points
    spread over the whole segment would miss a sliver seen past a jamb, and
    would let a line showing the hidden part of a segment pass on another
    part's visibility.) At a refined pose (a centimetre off) a sight line
    that cuts a wall ``refined_sight_end_m`` or more from the segment is
    blocked: it tells the near and far faces of a door jamb apart.
    ``shared`` sizes the sight-line test's work (``box_filter_edges``)."""
    if walls is None or not len(poses):
        return np.ones(len(poses), dtype=bool)
    return visible_points([sight_points(camera, poses, segments, lines, work)], [walls], work, shared)[0]


def sight_points(camera, poses, segments, lines, work: Stage2Constants) -> tuple:
    """:func:`visible`'s sight lines: ``(cams (T * n, 2), points (T * n,
    2))``, ``n`` points spread over the part of each segment its line
    shows (``refined_sight_array``)."""
    if not len(poses):
        return np.zeros((0, 2)), np.zeros((0, 2))
    span = covered_span(camera, poses, segments, lines)  # (T, 2)
    samples = work.refined_sight_array
    t = span[:, :1] + samples[None, :] * (span[:, 1:] - span[:, :1])  # (T, n)
    a, b = segments[:, None, 0, :2], segments[:, None, 1, :2]
    pts = a + t[..., None] * (b - a)
    return np.repeat(poses[:, :2], len(samples), axis=0), pts.reshape(-1, 2)


def visible_points(shown: list, walls: list, work: Stage2Constants, shared: SharedConstants) -> list:
    """Per :func:`sight_points` of ``shown``: (T,) whether any of each
    segment's points is in plain sight (:func:`visible`), its ``walls`` as
    occluders (None: everything is). Parts that share their walls (a rig's
    cameras on one map) are tested in one batch."""
    n = len(work.refined_sight_array)
    out = [np.ones(len(cams) // n, dtype=bool) for cams, _ in shown]
    for w in {id(w): w for w in walls if w is not None}.values():
        same = [k for k, x in enumerate(walls) if x is w and len(shown[k][0])]
        if not same:
            continue
        seen = _any_clear(np.concatenate([shown[k][0] for k in same]).reshape(-1, n, 2),
                          np.concatenate([shown[k][1] for k in same]).reshape(-1, n, 2), w, work, shared)
        bounds = np.cumsum([0] + [len(shown[k][0]) // n for k in same])
        for k, a, b in zip(same, bounds[:-1], bounds[1:]):
            out[k] = seen[a:b]
    return out


def _any_clear(cams: np.ndarray, points: np.ndarray, walls, work: Stage2Constants, shared: SharedConstants) -> np.ndarray:
    """(T,) bool: is any of the sight lines from ``cams`` (T, n, 2) to
    ``points`` (T, n, 2) clear (:func:`~matcher.map_geometry.occlusion.sight_clear`)?
    The middle points' first, the others only where it is hidden (most
    segments a line fits are in sight at their middle); each sight line's
    test is its own, so the answer is the one of testing all."""
    T, n = points.shape[:2]
    mid = n // 2
    seen = sight_clear(cams[:, mid], points[:, mid], walls, work.refined_sight_end_m, shared)
    hidden = np.flatnonzero(~seen)
    if len(hidden) and n > 1:
        rest = np.delete(np.arange(n), mid)
        c, p = cams[hidden][:, rest].reshape(-1, 2), points[hidden][:, rest].reshape(-1, 2)
        seen[hidden] = sight_clear(c, p, walls, work.refined_sight_end_m, shared).reshape(-1, n - 1).any(axis=1)
    return seen


def resolve_pieces(camera, poses, label, cls, segs, lines, near_m: float):
    """(T,) local segment of each match: the member of its collinear group
    whose projection overlaps the image line most, at the match's pose
    (T, 3) (segments cut ``near_m`` in front of the camera)."""
    order = np.argsort(label, kind="stable")
    sizes = np.bincount(label)
    starts = np.concatenate([[0], np.cumsum(sizes)])
    n = sizes[cls]
    t = np.repeat(np.arange(len(cls)), n)
    k = np.arange(len(t)) - np.repeat(np.cumsum(n) - n, n)
    cand = order[starts[cls][t] + k]
    _, ov = distance_and_overlap(camera, poses[t], segs[cand], lines[t], near_m)
    # Best overlap per match: sort by (match, -overlap) and take the first of each run.
    o = np.lexsort((-ov, t))
    first = np.concatenate([[True], t[o][1:] != t[o][:-1]])
    return cand[o][first]


def unit_rays(camera, lines):
    """(T, 2, 3) unit camera-frame rays of the end points of lines (T, 2, 2)."""
    r = camera.pixel_rays(lines)
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def coverage(camera, pose: np.ndarray, segments: np.ndarray, label: np.ndarray, matched: np.ndarray, walls,
             tol) -> tuple[int, int]:
    """``(predicted, seen)``: how many of the candidate ``segments`` (N, 2, 3)
    a camera at ``pose`` (3,) should see as lines of ``coverage_min_px`` or
    more (projected, cut to the image, in plain sight), and how many of those
    belong to a collinear group (``label`` (N,)) that a match holds
    (``matched``: indices into ``segments``). The sight test, the dear part,
    runs only when the segments in view alone fall short of
    ``coverage_min_share``: it can only drop unmatched ones (the matched
    are in sight by stage 2's own test). Thresholds: ``tol.verdict``'s
    (it judges the best pose), projection and sight: ``tol.stage2``'s."""
    poses, uv, cand, held = _in_view(camera, pose, segments, label, matched, tol)
    if held.sum() >= tol.verdict.coverage_min_share * len(cand):
        return int(len(cand)), int(held.sum())
    in_sight = visible(camera, poses[cand], segments[cand], uv[cand], walls, tol.stage2, tol.shared)
    return int(in_sight.sum()), int((held & in_sight).sum())


def coverage_in_sight(camera, pose: np.ndarray, segments: np.ndarray, label: np.ndarray, matched: np.ndarray, walls,
                      tol) -> tuple[np.ndarray, np.ndarray]:
    """:func:`coverage`'s segments themselves: ``(predicted, held)``,
    the indices into ``segments`` of those the camera should see (in plain
    sight, always tested) and, per one of them, whether a match holds its
    collinear group (bool). A rig counts the map segments around the robot
    once, however many of its cameras see them."""
    poses, uv, cand, held = _in_view(camera, pose, segments, label, matched, tol)
    in_sight = visible(camera, poses[cand], segments[cand], uv[cand], walls, tol.stage2, tol.shared)
    return cand[in_sight], held[in_sight]


def _in_view(camera, pose: np.ndarray, segments: np.ndarray, label: np.ndarray, matched: np.ndarray, tol):
    """The candidates projected long enough inside the image: ``(poses (N,
    3), uv (N, 2, 2) clipped, cand (C,) their indices, held (C,) bool)``."""
    poses = np.broadcast_to(pose, (len(segments), 3))
    uv, ahead = project_segments(camera, poses, segments, tol.stage2.near_plane_m)
    uv, inside = clip_lines(uv, (0.0, camera.width, 0.0, camera.height))
    length = np.hypot(*(uv[:, 1] - uv[:, 0]).T)
    cand = np.nonzero(ahead & inside & (length >= tol.verdict.coverage_min_px))[0]
    return poses, uv, cand, np.isin(label[cand], label[matched])
