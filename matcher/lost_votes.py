"""Pose votes for lost mode: where in the map the robot may stand, from the
image's horizontal lines alone, before any interpretation tree.

With the camera's height and pitch known, an image line that is a map
segment at height ``z`` is a known 3D line in the camera's level frame: the
interpretation plane cut at ``z - height`` (method.md section 4). Matched to
one horizontal map segment it fixes the heading (the two lines parallel,
one of two ways) and puts the camera on a line parallel to the segment, on
a stretch where the piece seen lies on the segment. Two such matches of
different lines with about the same heading and non-parallel segments meet
in one pose. Every such meeting is a vote; the right pose gathers the votes
of every pair of its lines, a wrong one only chance meetings.

The places with the most votes become narrow priors for
:func:`matcher.from_prior.localize_prepared` (:mod:`matcher.lost`), which
verifies them with both stages of the method.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera
from linemap.geometry import segment_is_vertical, world_normals
from matcher.frame import ImageLines, longest
from matcher.map_index import index_of
from matcher.tolerances import LostConstants, Tolerances


@dataclass
class Sightings:
    """Every (image line, horizontal map segment, heading) that can hold, K
    of them: ``yaw`` (K,) radians; the camera on the line ``c . nrm = off``
    with ``c = base + a * u``, ``a`` in [``a_lo``, ``a_hi``]; ``u``, ``nrm``
    (K, 2) the segment's unit direction and normal, ``base`` (K, 2) the point
    of the camera's line where ``a = 0``; ``line`` (K,) the image line."""

    yaw: np.ndarray
    u: np.ndarray
    nrm: np.ndarray
    base: np.ndarray
    a_lo: np.ndarray
    a_hi: np.ndarray
    line: np.ndarray


def vote_places(linemap, camera: Camera, image_lines: ImageLines, tol: Tolerances, count: int) -> np.ndarray:
    """Up to ``count`` places (n, 4): x, y (metres), yaw (radians) and
    score (the image lines that voted for it), best first, no two closer
    than ``vote_apart_m`` and ``vote_apart_deg`` (``tol.lost``). Empty when
    the lines give no vote."""
    work = tol.lost
    s = sightings(linemap, camera, image_lines, tol)
    votes = np.concatenate([meetings(s, work), edge_meetings(linemap, image_lines, s, tol)])
    if len(votes):
        free = index_of(linemap).free(tol.map_index)
        votes = votes[free.distance(votes[:, :2]) <= work.vote_free_m]
    return _peaks(votes, work, count) if len(votes) else np.zeros((0, 4))


def sightings(linemap, camera: Camera, image_lines: ImageLines, tol: Tolerances) -> Sightings:
    """The :class:`Sightings` of the frame's usable non-vertical lines on the
    map's horizontal segments (see the module docstring); ``tol.lost``
    bounds them."""
    index, work = index_of(linemap), tol.lost
    segs = linemap.segments
    horiz = ~segment_is_vertical(segs, tol.shared.vertical_axis_deg)
    flat = np.abs(segs[:, 1, 2] - segs[:, 0, 2]) <= work.vote_flat_m
    sid = np.flatnonzero(horiz & flat)
    lid = longest(image_lines.lines, image_lines.usable & ~image_lines.vertical, work.vote_lines)
    if len(sid) == 0 or len(lid) == 0:
        return _no_sightings()
    # End points of each line on the plane z = segment height, camera frame
    # levelled and turned to yaw 0 (x ahead, y left): per line and height.
    heights, h_of = np.unique(np.round(0.5 * (segs[sid, 0, 2] + segs[sid, 1, 2]), 2), return_inverse=True)
    rays = world_normals(camera.pixel_rays(image_lines.lines[lid]), 0.0, camera.pitch)  # (L, 2, 3)
    dz = heights - camera.height_m  # (H,)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = dz[None, :, None] / rays[:, None, :, 2]  # (L, H, 2)
    pts = t[..., None] * rays[:, None, :, :2]  # (L, H, 2, 2)
    reach = np.linalg.norm(pts, axis=-1)
    ok_lh = np.all((t > 0) & (reach <= work.vote_range_m), axis=-1)  # (L, H)
    li, sj = np.nonzero(ok_lh[:, h_of])  # pairs (line, segment) whose plane cut lies ahead
    if len(li) == 0:
        return _no_sightings()
    p = pts[li, h_of[sj]]  # (P, 2, 2)
    seg = segs[sid[sj], :, :2]
    d_img = p[:, 1] - p[:, 0]
    d_seg = seg[:, 1] - seg[:, 0]
    length = np.linalg.norm(d_seg, axis=1)
    u = d_seg / length[:, None]
    nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
    yaw0 = np.arctan2(u[:, 1], u[:, 0]) - np.arctan2(d_img[:, 1], d_img[:, 0])
    faces = index.faces(tol.map_index)[sid[sj]]
    slack = work.vote_slack_m + work.vote_slack_share * reach[li, h_of[sj]].max(axis=1)
    out = []
    for turn in (0.0, math.pi):
        yaw = yaw0 + turn
        c, s_ = np.cos(yaw), np.sin(yaw)
        q = np.stack([c[:, None] * p[..., 0] - s_[:, None] * p[..., 1],
                      s_[:, None] * p[..., 0] + c[:, None] * p[..., 1]], axis=-1)  # (P, 2, 2) world offsets
        along = np.einsum("pkc,pc->pk", q, u)
        b = -np.einsum("pc,pc->p", q[:, 0], nrm)  # camera's offset from the segment's line, along nrm
        a_lo = -slack - along.min(axis=1)
        a_hi = length + slack - along.max(axis=1)
        room_side = np.einsum("pc,pc->p", faces, nrm) * b
        keep = (a_lo <= a_hi) & (room_side >= 0.0) & (np.abs(b) >= work.vote_min_offset_m)
        base = seg[:, 0] + b[:, None] * nrm
        out.append((yaw[keep], u[keep], nrm[keep], base[keep], a_lo[keep], a_hi[keep], lid[li[keep]]))
    return Sightings(*(np.concatenate(parts) for parts in zip(*out)))


def meetings(s: Sightings, work: LostConstants) -> np.ndarray:
    """(V, 3) poses x, y, yaw where two sightings of different lines, about
    the same heading (``work.vote_yaw_deg``) and segments at least
    ``work.vote_cross_deg`` apart in direction, put the camera in one place
    within both stretches."""
    n = len(s.yaw)
    if n < 2:
        return np.zeros((0, 5))
    yaw = np.mod(s.yaw, 2 * np.pi)
    order = np.argsort(yaw)
    ys = yaw[order]
    tol = math.radians(work.vote_yaw_deg)
    # Pairs (i, j), i < j in heading order, within tol (and across 0 = 2 pi).
    ext = np.concatenate([ys, ys + 2 * np.pi])
    hi = np.searchsorted(ext, ys + tol, side="right")
    counts = np.minimum(hi - np.arange(n) - 1, n - 1)
    if counts.sum() == 0:
        return np.zeros((0, 5))
    first = np.repeat(np.arange(n), counts)
    step = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + 1
    second = (first + step) % n
    i, j = order[first], order[second]
    cross = s.u[i, 0] * s.u[j, 1] - s.u[i, 1] * s.u[j, 0]
    keep = (s.line[i] != s.line[j]) & (np.abs(cross) >= math.sin(math.radians(work.vote_cross_deg)))
    i, j, cross = i[keep], j[keep], cross[keep]
    # c = base_i + a_i u_i = base_j + a_j u_j: a_i = ((base_j - base_i) x u_j) / (u_i x u_j).
    d = s.base[j] - s.base[i]
    a_i = (d[:, 0] * s.u[j, 1] - d[:, 1] * s.u[j, 0]) / cross
    a_j = (d[:, 0] * s.u[i, 1] - d[:, 1] * s.u[i, 0]) / cross
    inside = (a_i >= s.a_lo[i]) & (a_i <= s.a_hi[i]) & (a_j >= s.a_lo[j]) & (a_j <= s.a_hi[j])
    i, j, a_i = i[inside], j[inside], a_i[inside]
    c = s.base[i] + a_i[:, None] * s.u[i]
    mean_yaw = np.arctan2(np.sin(s.yaw[i]) + np.sin(s.yaw[j]), np.cos(s.yaw[i]) + np.cos(s.yaw[j]))
    return np.column_stack([c, mean_yaw, s.line[i], s.line[j]])


def edge_meetings(linemap, image_lines: ImageLines, s: Sightings, tol: Tolerances) -> np.ndarray:
    """(V, 3) poses x, y, yaw where a sighting's camera line meets the ray
    back from a vertical map edge along a vertical image line's bearing at
    the sighting's heading (in front of the edge, within the stretch)."""
    segs, work = linemap.segments, tol.lost
    vid = np.flatnonzero(segment_is_vertical(segs, tol.shared.vertical_axis_deg))
    lid = longest(image_lines.lines, image_lines.usable & image_lines.vertical, work.vote_lines)
    if len(vid) == 0 or len(lid) == 0 or len(s.yaw) == 0:
        return np.zeros((0, 5))
    edge = segs[vid, 0, :2]  # (E, 2)
    out = []
    for li in lid:
        beta = s.yaw - image_lines.alpha[li]  # (K,) world bearing of the edge from the camera
        w = np.stack([np.cos(beta), np.sin(beta)], axis=1)  # (K, 2)
        cross = s.u[:, 0] * w[:, 1] - s.u[:, 1] * w[:, 0]  # (K,)
        ok = np.abs(cross) >= math.sin(math.radians(work.vote_cross_deg))
        k = np.flatnonzero(ok)
        d = edge[None, :, :] - s.base[k, None, :]  # (k, E, 2)
        a = (d[..., 0] * w[k, None, 1] - d[..., 1] * w[k, None, 0]) / cross[k, None]
        t = (s.u[k, None, 0] * d[..., 1] - s.u[k, None, 1] * d[..., 0]) / cross[k, None]
        hit = (a >= s.a_lo[k, None]) & (a <= s.a_hi[k, None]) & (t >= work.vote_min_offset_m) & (t <= work.vote_range_m)
        kk, ee = np.nonzero(hit)
        c = s.base[k[kk]] + a[kk, ee, None] * s.u[k[kk]]
        out.append(np.column_stack([c, s.yaw[k[kk]], s.line[k[kk]], np.full(len(kk), li)]))
    return np.concatenate(out) if out else np.zeros((0, 5))


def _peaks(votes: np.ndarray, work: LostConstants, count: int) -> np.ndarray:
    """The ``count`` best places of ``votes`` (V, 5: x, y, yaw, the two
    image lines): a place's score is the number of distinct image lines
    whose votes fall in its cell (``vote_cell_m`` by ``vote_cell_deg``; two
    grids half a cell apart, so a pose on a cell border is not split), its
    pose the mean of those votes; no two kept closer than ``vote_apart_m``
    and ``vote_apart_deg``."""
    cell_yaw = math.radians(work.vote_cell_deg)
    yaw = np.mod(votes[:, 2], 2 * np.pi)
    lines = votes[:, 3:5].astype(np.int64)
    n_lines = int(lines.max()) + 1
    places = []
    for shift in (0.0, 0.5):
        ix = np.floor(votes[:, 0] / work.vote_cell_m + shift).astype(np.int64)
        iy = np.floor(votes[:, 1] / work.vote_cell_m + shift).astype(np.int64)
        iw = np.floor(yaw / cell_yaw + shift).astype(np.int64)
        ix -= ix.min()
        iy -= iy.min()
        key = (ix * (iy.max() + 1) + iy) * (iw.max() + 1) + iw  # one integer a cell
        cells, inv = np.unique(key, return_inverse=True)
        inv = inv.ravel()
        n_v = np.bincount(inv, minlength=len(cells))
        # distinct lines per cell
        pair = np.unique(np.concatenate([inv * n_lines + lines[:, 0], inv * n_lines + lines[:, 1]]))
        score = np.bincount(pair // n_lines, minlength=len(cells))
        sx = np.bincount(inv, votes[:, 0], len(cells)) / n_v
        sy = np.bincount(inv, votes[:, 1], len(cells)) / n_v
        syaw = np.arctan2(np.bincount(inv, np.sin(yaw), len(cells)), np.bincount(inv, np.cos(yaw), len(cells)))
        places.append(np.column_stack([sx, sy, syaw, score + n_v / (n_v.max() + 1.0)]))
    places = np.concatenate(places)
    places = places[np.argsort(-places[:, 3], kind="stable")]
    kept: list[int] = []
    apart_m, apart = work.vote_apart_m, math.radians(work.vote_apart_deg)
    for k in range(len(places)):
        if len(kept) >= count:
            break
        x, y, w = places[k, :3]
        if all(math.hypot(x - places[m, 0], y - places[m, 1]) > apart_m
               or abs(math.remainder(w - places[m, 2], 2 * math.pi)) > apart for m in kept):
            kept.append(k)
    return places[kept]


def _no_sightings() -> Sightings:
    z, z2 = np.zeros(0), np.zeros((0, 2))
    return Sightings(z, z2, z2, z2, z, z, np.zeros(0, dtype=np.int64))
