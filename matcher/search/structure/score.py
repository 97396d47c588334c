"""Every (place, yaw) scored at once from the frame's structure.

A place is a floor point with its :class:`~.profiles.Profiles`; a yaw a
bearing bin ``k`` (heading ``k * 2 pi / bins``), so that an observation at
robot bearing ``beta`` looks along world bin ``k + floor(beta / width)``.
Two shares of the frame's evidence that the place explains (each in
[0, 1]):

- the **vertical lines** whose bearing (within its noise) meets a bin
  holding a vertical edge in sight (``Profiles.edge_cum``);
- the **bearings** (bins of the robot's turn) whose floor or ceiling
  samples (:class:`~.observed.Samples`) agree with the junction the map
  puts there: the tangent of the sample's elevation within its noise of
  the junction's (``-h / d`` below, ``(z - h) / d`` above), widened by what
  moving the camera by the profile's slack, the rig's lever and the map's
  error ``model_m`` does to it (``|z - h| slack / d^2``). Each bearing bin
  counts once however many samples fall in it (a sample's weight is one
  over the samples of its bin).

The score is their sum, each weighed by how little it says by chance
(:func:`chance_weights`): ``-log`` of its mean over every pose scored, the
log-likelihood ratio of a hit when the true place hits always and any
place by chance at that rate. Vertical edges are dense in a room and a
line's bearing meets one from most places (a mean share near 0.35, weight
about 1); a floor or ceiling elevation agrees from few (near 0.1, weight
about 2.3). Chosen on the ZInD sample tour's 32 panoramas, lost, seed 0,
lattice points alone: the true place first in 19 (15 unweighted, 19 with
depth counted twice), among the first six in 26 (23, 26).

Vectorised: per yaw, one gather of the profiles' rows for all places, a
block of samples at a time.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from matcher.search.structure.observed import Observed, Samples
from matcher.search.structure.profiles import Profiles

def score(profiles: Profiles, observed: Observed, yaws: np.ndarray, tol, weights=None,
          yaw_slack: int = 0) -> tuple[np.ndarray, tuple]:
    """``(scores (P, K) float32, weights)``: the score of each place of
    ``profiles`` at each yaw bin of ``yaws`` (K,) (module docstring), with
    the components' ``weights`` given, or else their
    :func:`chance_weights` over these poses; the map's error
    ``tol.model_m``; samples compared with all places in blocks of about
    ``MapIndexConstants.ray_chunk`` pairs (a work size); each vertical
    line's bearing widened by ``yaw_slack`` bins either way (yaws good to
    that many bins). Every observation is taken as seen from the place
    (the robot's centre), widened by the frame's lever."""
    vert, depth = shares(profiles, observed, yaws, tol, yaw_slack)
    if weights is None:
        weights = chance_weights(vert, depth)
    return _weighed(vert, depth, weights), weights


def score_on_grid(grid, rows: np.ndarray, observed: Observed, yaws: np.ndarray, tol,
                  yaw_slack: int = 0) -> tuple[np.ndarray, tuple]:
    """``(scores (R, K) float32, weights)`` as :func:`score`'s for the
    lattice points ``rows`` of ``grid`` (:class:`~.profiles.GridProfiles`)
    at yaw bins ``yaws``, each mount group's observations compared with
    the lattice point nearest its camera's place at each yaw (the rounding
    taken as the group's lever: at most half the lattice's diagonal, none
    for a camera at the robot's centre)."""
    width = 2 * math.pi / grid.bins
    vert = depth = 0
    for g, (mx, my) in enumerate(observed.mounts):
        part = observed.part(g)
        if mx == 0.0 and my == 0.0:
            v, d = _counts(grid.profiles.take(rows), part, yaws, tol, yaw_slack)
        else:
            v, d = np.zeros((len(rows), len(yaws)), np.float32), np.zeros((len(rows), len(yaws)), np.float32)
            for j, k in enumerate(np.asarray(yaws, dtype=np.int64)):
                c, s = math.cos(k * width), math.sin(k * width)
                cols, residual = grid.shifted(rows, np.array([c * mx - s * my, s * mx + c * my]))
                vk, dk = _counts(grid.profiles.take(cols), replace(part, lever=residual), yaws[j:j + 1], tol,
                                 yaw_slack)
                v[:, j], d[:, j] = vk[:, 0], dk[:, 0]
        vert, depth = vert + v, depth + d
    vert, depth = _normalised(vert, depth, observed)
    weights = chance_weights(vert, depth)
    return _weighed(vert, depth, weights), weights


def score_by_mount(parts: list, observed: Observed, yaws: np.ndarray, tol, weights: tuple) -> np.ndarray:
    """(P, K) float32 scores as :func:`score`'s, each mount group's
    observations (``observed.part(g)``) compared with the profiles seen
    from that group's own position: ``parts[g]`` the :class:`Profiles` of
    the P places' camera positions of group ``g`` (no lever: bearings and
    floor distances from each camera's own place)."""
    vert = depth = 0
    for g, profiles in enumerate(parts):
        v, d = _counts(profiles, observed.part(g), yaws, tol, 0)
        vert, depth = vert + v, depth + d
    return _weighed(*_normalised(vert, depth, observed), weights)


def _weighed(vert: np.ndarray, depth: np.ndarray, weights: tuple) -> np.ndarray:
    return vert * np.float32(weights[0]) + depth * np.float32(weights[1])


def chance_weights(vert: np.ndarray, depth: np.ndarray) -> tuple[float, float]:
    """Each share's weight: ``-log`` of its mean over the poses scored (the
    module docstring), the mean kept above one in a million (a share that
    never hits weighs 14 and adds nothing)."""
    return tuple(float(-np.log(max(float(x.mean()) if x.size else 1.0, 1e-6))) for x in (vert, depth))


def shares(profiles: Profiles, observed: Observed, yaws: np.ndarray, tol,
           yaw_slack: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``(vertical, depth)`` (P, K) float32 each: the two shares of the
    module docstring, of each place at each yaw bin (vertical bearings
    widened by ``yaw_slack`` bins)."""
    return _normalised(*_counts(profiles, observed, yaws, tol, yaw_slack), observed)


def _normalised(vert: np.ndarray, depth: np.ndarray, observed: Observed) -> tuple[np.ndarray, np.ndarray]:
    """The counts of :func:`_counts` as shares of the whole frame's vertical
    lines and bearing bins seen."""
    n_bins = float(observed.floor.weight.sum() + observed.ceiling.weight.sum())
    return (vert / np.float32(max(len(observed.vertical), 1)), depth / np.float32(n_bins) if n_bins else depth)


def _counts(profiles: Profiles, observed: Observed, yaws: np.ndarray, tol,
            yaw_slack: int) -> tuple[np.ndarray, np.ndarray]:
    """``(vertical, depth)`` (P, K) float32: the vertical lines that meet an
    edge in sight, and the weighted floor and ceiling samples that agree,
    of each place at each yaw bin."""
    P, K, bins = len(profiles.points), len(yaws), profiles.bins
    vert_out = np.zeros((P, K), dtype=np.float32)
    out = np.zeros((P, K), dtype=np.float32)
    if not P or not K:
        return vert_out, out
    width = 2 * math.pi / bins
    slack = profiles.slack_m + observed.lever + tol.model_m
    block = max(1, tol.map_index.ray_chunk // P)
    vert = _vertical_terms(observed, width, bins, yaw_slack)
    floor, ceiling = _Terms(observed.floor, width, slack, block), _Terms(observed.ceiling, width, slack, block)
    for j, k in enumerate(np.asarray(yaws, dtype=np.int64)):
        if vert is not None:
            lo, span = vert
            start = (k + lo) % bins
            hits = profiles.edge_cum[start + span + 1] > profiles.edge_cum[start]  # (J, P)
            vert_out[:, j] = hits.sum(axis=0, dtype=np.float32)
        if len(floor.bin) or len(ceiling.bin):
            out[:, j] = floor.hits(profiles.floor_inv, None, k) + ceiling.hits(profiles.ceiling_inv, profiles.ceiling_z, k)
    return vert_out, out


def _vertical_terms(observed: Observed, width: float, bins: int, yaw_slack: int):
    """``(lo (J,), span (J,))``: each vertical line's first bin (at yaw 0)
    and how many more its noise and ``yaw_slack`` reach; None without
    vertical lines."""
    if not len(observed.vertical):
        return None
    lo = np.floor((observed.vertical - observed.vertical_eps) / width).astype(np.int64) - yaw_slack
    hi = np.floor((observed.vertical + observed.vertical_eps) / width).astype(np.int64) + yaw_slack
    return lo, np.minimum(hi - lo, bins - 1)


class _Terms:
    """One kind of samples (floor or ceiling) ready to score: each one's bin
    at yaw 0, weight (:class:`~.observed.Samples`), the tangent of its
    elevation and its noise in tangent (the elevation's noise times the
    tangent's derivative), the camera height; ``slack`` the position
    slack, metres; ``block`` how many samples are compared with all
    places at once."""

    def __init__(self, samples: Samples, width: float, slack: float, block: int) -> None:
        self.block = block
        self.bin = np.floor(samples.bearing / width).astype(np.int64)
        self.weight = samples.weight.astype(np.float32)
        self.tan = np.tan(samples.elevation).astype(np.float32)[:, None]
        self.noise = (samples.eps / np.cos(samples.elevation) ** 2).astype(np.float32)[:, None]
        self.height = samples.height
        self.slack = np.float32(slack)

    def hits(self, inv: np.ndarray, height: np.ndarray | None, k: int) -> np.ndarray:
        """(P,) weighted count of the samples whose elevation agrees with the
        junctions ``inv`` (bins, P) (one over their distance) at yaw bin
        ``k``: floor junctions when ``height`` is None, else ceiling
        junctions at ``height`` (bins, P). The junctions' tangents and their
        slack are worked out once per camera height, per bin and place."""
        P, bins = inv.shape[1], inv.shape[0]
        out = np.zeros(P, dtype=np.float32)
        for h in np.unique(self.height):
            rise = np.float32(-h) if height is None else height - np.float32(h)  # (bins, P) or scalar
            pred = rise * inv
            with np.errstate(invalid="ignore"):
                widen = np.abs(rise) * self.slack * inv * inv
            mine = np.flatnonzero(self.height == h)
            for s0 in range(0, len(mine), self.block):
                sel = mine[s0:s0 + self.block]
                rows = (k + self.bin[sel]) % bins
                with np.errstate(invalid="ignore"):
                    hit = np.abs(pred[rows] - self.tan[sel]) <= self.noise[sel] + widen[rows]
                out += self.weight[sel] @ hit.astype(np.float32)
        return out
