"""Segments on one 3D line: the groups image lines cannot tell apart.

A wall split by a door gives two collinear segments, and an image line on
that wall fits both: stage 1 works on one representative per group (its
span), stage 2 picks the piece the line shows at the refined pose. The
map-wide grouping is made once per map (:class:`~matcher.map_index.MapIndex`),
the spans per frame on the candidate segments.
"""

from __future__ import annotations

import math

import numpy as np


def collinear_classes(segments: np.ndarray, angle_deg: float, dist_m: float, label: np.ndarray | None = None):
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


def collinear_labels(segments: np.ndarray, angle_deg: float, dist_m: float, chunk: int = 256) -> np.ndarray:
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


def class_faces(faces: np.ndarray, label: np.ndarray) -> np.ndarray:
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
