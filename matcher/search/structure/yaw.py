"""Yaw hypotheses from structure: the frame's level lines against the
map's wall directions.

Every level line of the frame (:mod:`.observed`) has a direction modulo a
half turn in the robot's frame; at robot heading ``theta`` it runs along
world direction ``theta + psi``. The map's level segments have their own
directions (four for a rectangular building, more where walls run more
ways), as a length-weighted histogram modulo a half turn. The circular
cross-correlation of the two histograms (the image's with each line spread
over its noise, :func:`image_directions`) peaks at the headings that lay the frame's lines along the
map's walls; each peak is a heading modulo a half turn, so two yaws. The
peaks kept are those within ``SharedConstants.yaw_peak_share`` of the
best; each is good to a bin.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.lmap import LineMap, SegmentKind
from matcher.search.structure.observed import Observed


def map_directions(linemap: LineMap, half_bins: int) -> np.ndarray:
    """(half_bins,) the map's level segments' lengths (seen from above) per
    direction bin modulo a half turn (bin ``k``: ``[k, k + 1) * pi /
    half_bins``)."""
    level = np.isin(linemap.kinds, (SegmentKind.FLOOR, SegmentKind.CEILING, SegmentKind.LINTEL, SegmentKind.WINDOW,
                                    SegmentKind.HORIZONTAL))
    d = linemap.segments[level, 1, :2] - linemap.segments[level, 0, :2]
    angle = np.mod(np.arctan2(d[:, 1], d[:, 0]), math.pi)
    k = np.floor(angle / (math.pi / half_bins)).astype(np.int64) % half_bins
    return np.bincount(k, weights=np.hypot(d[:, 0], d[:, 1]), minlength=half_bins)


def image_directions(observed: Observed, half_bins: int) -> np.ndarray:
    """(half_bins,) the frame's level lines' lengths per direction bin modulo
    a half turn, each line spread over its direction's noise: a normal
    density of the standard deviation of an error uniform within the
    noise bound (the bound over root 3), at least half a bin (a line near
    the horizon, whose direction is unknown, spreads over the whole
    turn)."""
    width = math.pi / half_bins
    middle = (np.arange(half_bins) + 0.5) * width
    sigma = np.maximum(np.minimum(observed.level_eps, math.pi) / math.sqrt(3.0), width / 2)[:, None]
    off = np.remainder(middle[None] - observed.level[:, None] + math.pi / 2, math.pi) - math.pi / 2
    dens = np.exp(-0.5 * (off / sigma) ** 2) / sigma
    return (observed.level_weight[:, None] * dens).sum(axis=0) * width / math.sqrt(2 * math.pi)


def yaw_bins(observed: Observed, map_hist: np.ndarray, bins: int, px: tuple | None, share: float) -> np.ndarray:
    """Sorted yaw bins (K,) (yaw ``k * 2 pi / bins``) to score: the peaks of
    the correlation of the frame's level lines with ``map_hist``
    (:func:`map_directions`, ``bins / 2`` of them) within ``share`` of the
    best, both ways round (good to a bin: the grid scores them with a bin
    of slack, the refinement tries their neighbours); within the prior's
    headings ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians; None: any). A
    prior whose headings hold no peak gets all its bins: the structure does
    not say which."""
    half = len(map_hist)
    img = image_directions(observed, half)
    corr = np.real(np.fft.ifft(np.conj(np.fft.fft(img)) * np.fft.fft(map_hist)))  # corr[k] = sum img[b] map[b + k]
    peak = (corr >= np.roll(corr, 1)) & (corr > np.roll(corr, -1)) & (corr >= share * corr.max()) & (corr > 0)
    k = np.flatnonzero(peak)
    cand = np.unique(np.concatenate([k, k + half]) % bins)
    if px is None or px[4] >= math.pi:
        return np.unique(cand)
    width = 2 * math.pi / bins
    yaw_e, dyaw = px[2], px[4]
    inside = np.abs(np.remainder(np.arange(bins) * width - yaw_e + math.pi, 2 * math.pi) - math.pi) <= dyaw + width
    kept = np.unique(cand[inside[cand]])
    return kept if len(kept) else np.flatnonzero(inside)
