"""The best places of a scored grid, each refined below the grid's step,
and the runner-up anywhere in the prior.

Peaks are taken best first, each one's neighbourhood (poses within
``VerdictConstants.ambiguous_m`` and ``ambiguous_deg``: the same answer to
the verdict) then put out of the running, so the second peak is the best
pose *elsewhere* in the whole prior: the rival a verdict needs, known
whether or not it is verified. Each peak is then refined on a finer
lattice around it (half the grid's step, the profiles cast afresh for
those points, the neighbouring yaws too), each camera's observations seen
from that camera's own place on the robot rather than its centre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from matcher.search.structure.observed import Observed
from matcher.search.structure.profiles import MapStructure, Profiles, profiles_at
from matcher.search.structure.score import score_by_mount


@dataclass(frozen=True)
class Peaks:
    """``poses`` (Q, 3) robot poses ``(x, y, theta)``, best first, refined;
    ``scores`` (Q,) their grid scores (:mod:`.score`); ``near_m`` (Q,) the
    median distance of the wall junctions seen from each, metres; ``slack_m`` and
    ``slack_rad``: how far the truth may still be from a refined peak:
    the grid score's own position tolerance (half the grid's diagonal,
    the farthest camera's lever and the map's error: the score cannot tell
    places apart within it, and the refinement's best may lie anywhere
    inside), and a yaw bin."""

    poses: np.ndarray
    scores: np.ndarray
    near_m: np.ndarray
    slack_m: float
    slack_rad: float


def best_peaks(scores: np.ndarray, points: np.ndarray, yaws: np.ndarray, count: int, apart_m: float,
               apart_rad: float) -> list[tuple[int, int]]:
    """``(place, yaw)`` indices of the ``count`` best entries of ``scores``
    (P, K) (places ``points`` (P, 2), yaw angles ``yaws`` (K,) radians),
    each farther than ``apart_m`` or ``apart_rad`` from the ones before."""
    s = np.array(scores, dtype=np.float64)
    out = []
    while len(out) < count and s.size and np.isfinite(s).any():
        p, k = np.unravel_index(int(np.argmax(s)), s.shape)
        if not np.isfinite(s[p, k]):
            break
        out.append((int(p), int(k)))
        near = np.hypot(points[:, 0] - points[p, 0], points[:, 1] - points[p, 1]) <= apart_m
        close = np.abs(np.remainder(yaws - yaws[k] + math.pi, 2 * math.pi) - math.pi) <= apart_rad
        s[np.ix_(near, close)] = -np.inf
    return out


def beside_best(scores: np.ndarray, points: np.ndarray, yaws: np.ndarray, picks: list, apart_m: float,
                apart_rad: float, reach_m: float) -> list[tuple[int, int]]:
    """The best entry of ``scores`` (P, K) in the best pick's neighbourhood
    (within ``apart_m`` and ``apart_rad``: the same answer to the verdict)
    but beyond the refinement's reach (``reach_m``, or a yaw bin), as a
    list of one pick (none when there is none): a grid's best point a few
    decimetres from the truth puts the truth's own peak out of the running,
    and the refinement does not reach it."""
    if not picks:
        return []
    p0, k0 = picks[0]
    d = np.hypot(points[:, 0] - points[p0, 0], points[:, 1] - points[p0, 1])
    turn = np.abs(np.remainder(yaws - yaws[k0] + math.pi, 2 * math.pi) - math.pi)
    step = np.min(np.abs(np.diff(np.sort(yaws)))) if len(yaws) > 1 else math.inf
    inside = (d[:, None] <= apart_m) & (turn[None] <= apart_rad)
    beyond = (d[:, None] > reach_m) | (turn[None] > 1.5 * step)
    s = np.where(inside & beyond, scores, -np.inf)
    if not np.isfinite(s).any():
        return []
    p, k = np.unravel_index(int(np.argmax(s)), s.shape)
    return [(int(p), int(k))]


def refined(structure: MapStructure, grid: Profiles, observed: Observed, picks: list, yaws: np.ndarray,
            scored: tuple, step: float, tol) -> Peaks:
    """The :class:`Peaks` of ``picks`` (:func:`best_peaks` over ``grid`` at
    yaw bins ``yaws``, ``scored`` the grid's scores and their weights,
    :func:`~.score.score`): each moved to the best of the lattice half
    ``step`` apart around it (5 x 5 points, the yaw bin and its
    neighbours), each camera's observations compared with what the map
    shows from that camera's own place on the robot
    (:func:`~.score.score_by_mount`)."""
    grid_scores, weights = scored
    bins = grid.bins
    width = 2 * math.pi / bins
    fine = step / 2.0
    ticks = fine * np.arange(-2, 3)  # the grid's own neighbours and the points halfway to them
    offsets = np.stack(np.meshgrid(ticks, ticks), axis=-1).reshape(-1, 2)
    if not picks:
        return Peaks(np.zeros((0, 3)), np.zeros(0), np.zeros(0), fine / math.sqrt(2.0), width)
    centres = grid.points[[p for p, _ in picks]]
    headings = np.array([yaws[k] for _, k in picks], dtype=float) * width
    robot = centres[:, None] + offsets[None]  # (Q, O, 2) the robot's places
    G, O = len(observed.mounts), len(offsets)
    c, s_ = np.cos(headings), np.sin(headings)
    lever = np.stack([c[:, None] * observed.mounts[None, :, 0] - s_[:, None] * observed.mounts[None, :, 1],
                      s_[:, None] * observed.mounts[None, :, 0] + c[:, None] * observed.mounts[None, :, 1]], axis=-1)
    pts = robot[:, None] + lever[:, :, None]  # (Q, G, O, 2) each mount group's camera place
    around = profiles_at(structure, pts.reshape(-1, 2), bins, fine / math.sqrt(2.0), tol)
    poses = []
    for i, (_, k) in enumerate(picks):
        ks = (yaws[k] + np.array([-1, 0, 1])) % bins
        # Each group seen from its own place at the pick's heading (a yaw
        # bin either side moves a camera by its lever times a bin: a few
        # millimetres).
        parts = [around.take(np.arange((i * G + g) * O, (i * G + g + 1) * O)) for g in range(G)]
        s = score_by_mount(parts, observed, ks, tol, weights)
        # Ties keep the grid's own point and yaw (the middle of each axis).
        s = s + np.float32(1e-6) * (np.arange(O) == O // 2)[:, None] + np.float32(1e-6) * (np.arange(3) == 1)[None]
        q, j = np.unravel_index(int(np.argmax(s)), s.shape)
        poses.append([robot[i, q, 0], robot[i, q, 1], float(ks[j]) * width])
    rows = [p for p, _ in picks]
    near = grid.typical_m(rows)
    return Peaks(np.array(poses), np.array([grid_scores[p, k] for p, k in picks]), near,
                 grid.slack_m + observed.lever + tol.model_m, width)
