"""Cross marks: the X drawn across a box to mark a lift, a shaft or a void.

Plans mark the spaces a robot cannot enter (a lift's car, a pipe shaft, a
void over the floor below) by the box's two diagonals. Read as walls, the X
cuts the box into four triangles: thin ones become wall material, wide ones
free space of their own, and where the diagonals stop short of the centre
(drawn as four strokes from the corners) the triangles join through the
gap between their ends as if it were a doorway. They are marks, not walls:
taken out, the box is one enclosed space, left out of the free space when
no door leads into it (:mod:`.reachable`), a room when one does.

A cross: two straight lines about as long as each other (the shorter at
least ``CROSS_MARK_LENGTH_RATIO`` of the longer: a box's diagonals; a wall
line and a short chamfer crossing it are no cross), each one stroke or two
strokes in line with a gap of at most ``CROSS_MARK_MAX_GAP`` between them,
that cross at
``CROSS_MARK_MIN_ANGLE_DEG`` or more, each in the middle of the other
(within ``CROSS_MARK_MIDDLE_SHARE`` of its length about its centre; a
diagonal drawn in two strokes, in the gap between them), and whose ends
lie at the box's corners: at least three of the four ends on a corner of
the other wall strokes (an end or a vertex, within ``SNAP_GAP``; one
diagonal may stop short where a door swings) whose side there runs at a
slant to it. Walls crossing in a '+' end on the side of a wall, or meet
the walls at their ends square or in line. Strokes of a block insert and
fills are kept.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import LineString

from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import (CROSS_MARK_IN_LINE_DEG, CROSS_MARK_LENGTH_RATIO, CROSS_MARK_MAX_GAP,
                               CROSS_MARK_MIDDLE_SHARE, CROSS_MARK_MIN_ANGLE_DEG, CROSS_MARK_MIN_ARM, MERGE, SNAP_GAP)


def split_cross_marks(strokes: list[Stroke]) -> tuple[list[Stroke], list[Stroke]]:
    """``(kept, marks)``: the wall strokes less the strokes of cross marks,
    and those (see the module docstring)."""
    straight = [k for k, s in enumerate(strokes) if _is_straight(s)]
    if len(straight) < 2:
        return strokes, []
    lines = _lines(strokes, straight)
    corners = _corners(strokes)
    # Candidate pairs: lines whose extents cross (a box's diagonals cross at their middles).
    extents = [LineString([ln.p, ln.q]) for ln in lines]
    left, right = shapely.STRtree(extents).query(extents, predicate="intersects")
    marked: set[int] = set()
    for i, j in zip(left.tolist(), right.tolist()):
        if j <= i:
            continue
        a, b = lines[i], lines[j]
        if marked & (set(a.pieces) | set(b.pieces)) or set(a.pieces) & set(b.pieces):
            continue
        if _crossing(a, b) and _at_corners(a, b, corners):
            marked |= set(a.pieces) | set(b.pieces)
    if not marked:
        return strokes, []
    return ([s for k, s in enumerate(strokes) if k not in marked],
            [s for k, s in enumerate(strokes) if k in marked])


class _Line:
    """A straight line drawn as one stroke or two in line: its ends ``p``,
    ``q`` (metres), the indices of its ``pieces``, and the gap between two
    pieces along it (``gap``: (t0, t1) from ``p``, or None)."""

    def __init__(self, p: np.ndarray, q: np.ndarray, pieces: tuple[int, ...], gap: tuple[float, float] | None = None):
        self.p, self.q, self.pieces, self.gap = p, q, pieces, gap
        self.length = float(np.linalg.norm(q - p))
        self.u = (q - p) / self.length


def _is_straight(s: Stroke) -> bool:
    return (not s.closed and not s.filled and s.group is None and len(s.coords) == 2
            and float(np.linalg.norm(s.coords[1][:2] - s.coords[0][:2])) >= CROSS_MARK_MIN_ARM)


def _lines(strokes: list[Stroke], straight: list[int]) -> list[_Line]:
    """Each straight stroke as a line, and each pair of them in line with a
    gap of at most ``CROSS_MARK_MAX_GAP`` as one."""
    single = [_Line(np.asarray(strokes[k].coords[0][:2], float), np.asarray(strokes[k].coords[1][:2], float), (k,))
              for k in straight]
    out = list(single)
    ends = np.array([[ln.p, ln.q] for ln in single]).reshape(-1, 2)
    tree = cKDTree(ends)
    cos_in_line = math.cos(math.radians(CROSS_MARK_IN_LINE_DEG))
    for e, f in tree.query_pairs(CROSS_MARK_MAX_GAP, output_type="ndarray").tolist():
        i, j = sorted((e // 2, f // 2))
        if i == j:
            continue
        a, b = single[i], single[j]
        if abs(float(a.u @ b.u)) < cos_in_line:
            continue
        normal = np.array([-a.u[1], a.u[0]])
        if max(abs(float((b.p - a.p) @ normal)), abs(float((b.q - a.p) @ normal))) > SNAP_GAP:
            continue
        tb = sorted((float((b.p - a.p) @ a.u), float((b.q - a.p) @ a.u)))
        if tb[0] >= a.length:
            gap = (a.length, tb[0])
        elif tb[1] <= 0:
            gap = (tb[1], 0.0)
        else:
            continue  # overlapping: one line drawn twice, not a crossing's halves
        if not 0 < gap[1] - gap[0] <= CROSS_MARK_MAX_GAP:
            continue
        lo, hi = min(0.0, tb[0]), max(a.length, tb[1])
        out.append(_Line(a.p + a.u * lo, a.p + a.u * hi, (a.pieces[0], b.pieces[0]), (gap[0] - lo, gap[1] - lo)))
    return out


def _crossing(a: _Line, b: _Line) -> bool:
    """Whether ``a`` and ``b`` are about as long as each other (the shorter
    at least ``CROSS_MARK_LENGTH_RATIO`` of the longer) and cross at
    ``CROSS_MARK_MIN_ANGLE_DEG`` or more, each in the middle of the other
    (in the gap between its pieces, if two)."""
    if min(a.length, b.length) < CROSS_MARK_LENGTH_RATIO * max(a.length, b.length):
        return False  # a box's diagonals are as long as each other
    sin = abs(float(a.u[0] * b.u[1] - a.u[1] * b.u[0]))
    if sin < math.sin(math.radians(CROSS_MARK_MIN_ANGLE_DEG)):
        return False
    # p_a + s u_a = p_b + t u_b
    m = np.array([[a.u[0], -b.u[0]], [a.u[1], -b.u[1]]])
    s, t = np.linalg.solve(m, b.p - a.p)
    for line, at in ((a, float(s)), (b, float(t))):
        if abs(at - line.length / 2) > CROSS_MARK_MIDDLE_SHARE * line.length / 2:
            return False
        if line.gap is not None and not line.gap[0] - MERGE <= at <= line.gap[1] + MERGE:
            return False
    return True


def _corners(strokes: list[Stroke]) -> tuple[cKDTree, np.ndarray, np.ndarray]:
    """The ends and vertices of all strokes: a KD-tree over them, per point
    the index of its stroke, and per point the unit directions of the (one
    or two) segments of its stroke that meet there, ``(P, 2, 2)`` (a
    missing one repeats the other)."""
    pts, owner, dirs = [], [], []
    for k, s in enumerate(strokes):
        if s.filled:
            continue
        c = np.asarray(s.coords, float)[:, :2]
        ring = np.vstack([c, c[:1]]) if s.closed else c
        seg = np.diff(ring, axis=0)
        seg = seg / np.maximum(np.linalg.norm(seg, axis=1, keepdims=True), MERGE)
        n = len(c)
        after = np.array([seg[i] if i < len(seg) else seg[i - 1] for i in range(n)])
        before = np.array([seg[i - 1] if (i > 0 or s.closed) else seg[0] for i in range(n)])
        pts.append(c)
        owner.append(np.full(n, k))
        dirs.append(np.stack([before, after], axis=1))
    return cKDTree(np.concatenate(pts)), np.concatenate(owner), np.concatenate(dirs)


def _at_corners(a: _Line, b: _Line, corners) -> bool:
    """Whether at least three of the four ends of ``a`` and ``b`` lie on an
    end or vertex of a wall stroke that is not part of the cross, a side of
    the box there running oblique to the line (between
    ``CROSS_MARK_MIN_ANGLE_DEG / 2`` and 90 less that from it: a box's
    diagonal meets its sides at a slant; a wall crossing others in a '+'
    meets them square, or runs on in line)."""
    tree, owner, dirs = corners
    ours = set(a.pieces) | set(b.pieces)
    lo, hi = math.sin(math.radians(CROSS_MARK_MIN_ANGLE_DEG / 2)), math.cos(math.radians(CROSS_MARK_MIN_ANGLE_DEG / 2))
    hits = 0
    for line, end in ((a, a.p), (a, a.q), (b, b.p), (b, b.q)):
        for k in tree.query_ball_point(end, SNAP_GAP):
            if int(owner[k]) in ours:
                continue
            sines = np.abs(dirs[k] @ np.array([-line.u[1], line.u[0]]))
            if np.any((sines >= lo) & (sines <= hi)):
                hits += 1
                break
    return hits >= 3


__all__ = ["split_cross_marks"]
