"""The structure search's ranking of a frame: every (place, yaw) the prior
allows scored, the best few peaks refined.

    frame's lines -> observations in the robot's frame (observed.py)
                  -> yaw hypotheses (yaw.py, against the map's wall directions)
                  -> every lattice point of the prior x every yaw scored (score.py,
                     against the map's profiles, profiles.py)
                  -> the best peaks, the runner-up elsewhere, refined (peaks.py)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from matcher.search.structure.observed import Observed, observe
from matcher.search.structure.peaks import Peaks, beside_best, best_peaks, refined
from matcher.search.structure.profiles import grid_profiles
from matcher.search.structure.score import score_on_grid
from matcher.search.structure.yaw import yaw_bins
from matcher.tolerances import Tolerances


@dataclass(frozen=True)
class Ranking:
    """The ranking of one frame: its ``peaks`` (:class:`~.peaks.Peaks`, best
    first: the second is the best pose elsewhere in the prior), the
    ``places`` and ``yaws`` scored, the frame's ``observed`` structure and
    the milliseconds it took."""

    peaks: Peaks
    places: int
    yaws: int
    observed: Observed
    ms: float


def rank_places(linemap, views, px: tuple | None, tol: Tolerances, count: int) -> Ranking:
    """The :class:`Ranking` of the rig frame's camera ``views``
    (:class:`~matcher.rig.frame.CameraView`) under the robot's prior ``px``
    ``(xe, ye, yaw_e, dt, dyaw)`` (radians; None: lost, the whole floor at
    any heading): the ``count`` best peaks."""
    import time

    t0 = time.perf_counter()
    grid = grid_profiles(linemap, tol)
    bins = grid.bins
    observed = observe(views, 2 * math.pi / bins)
    yaws = yaw_bins(observed, grid.directions, bins, px, tol.shared.yaw_peak_share)
    rows = np.arange(len(grid.profiles.points))
    if px is not None:
        pts = grid.profiles.points
        rows = np.flatnonzero(np.hypot(pts[:, 0] - px[0], pts[:, 1] - px[1]) <= px[3] + grid.step / math.sqrt(2))
    profiles = grid.profiles.take(rows)
    scores, weights = score_on_grid(grid, rows, observed, yaws, tol, yaw_slack=1)
    angles = yaws * (2 * math.pi / bins)
    picks = best_peaks(scores, profiles.points, angles, count, tol.verdict.ambiguous_m,
                       math.radians(tol.verdict.ambiguous_deg))
    picks[2:2] = beside_best(scores, profiles.points, angles, picks, tol.verdict.ambiguous_m,
                             math.radians(tol.verdict.ambiguous_deg), 2 * grid.step)
    peaks = refined(grid.structure, profiles, observed, picks, yaws, (scores, weights), grid.step, tol)
    return Ranking(peaks, int(scores.size), len(yaws), observed, (time.perf_counter() - t0) * 1e3)

