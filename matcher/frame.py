"""A frame's image lines and what stage 1 needs of each, computed once.

:func:`prepare_lines` turns validated pixel lines (M, 2, 2) of the ideal
pinhole into :class:`ImageLines`: interpretation-plane normals and their
noise, which lines may be vertical edges and their bearings, which are long
enough to use, and which couples may be pieces of one broken line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera
from matcher.search.tree.constraints import bearing_noise, line_pieces, plane_noises, vertical_bearing, vertical_candidates
from matcher.tolerances import Tolerances


@dataclass
class ImageLines:
    """Per-line quantities, computed once per frame.

    ``lines`` (M, 2, 2) undistorted pixels; ``normals`` (M, 3) unit, camera
    frame; ``eps`` (M,) plane noise, radians, split into ``eps_rot`` (turn
    about the midpoint ray, from orientation noise) and ``eps_off`` (from
    offset noise); ``mid_rays`` (M, 3) unit rays of the midpoints; ``vertical`` (M,) bool vertical
    candidates; ``alpha`` (M,) bearings of vertical candidates, radians, to
    the right; ``alpha_eps`` (M,) their noise bound; ``usable`` (M,) bool long
    enough to use; ``searched`` (M,) bool the longest usable ones, those
    stage 1 searches with (:func:`searched_lines`); ``pieces`` (M, M) bool, couples that may be pieces of one
    broken line (:func:`~matcher.search.tree.constraints.line_pieces`), or None: none."""

    lines: np.ndarray
    normals: np.ndarray
    eps: np.ndarray
    vertical: np.ndarray
    alpha: np.ndarray
    alpha_eps: np.ndarray
    usable: np.ndarray
    eps_rot: np.ndarray
    eps_off: np.ndarray
    mid_rays: np.ndarray
    searched: np.ndarray
    pieces: np.ndarray | None = None


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
    return ImageLines(und, normals, eps, vert, alpha, alpha_eps, usable, eps_rot, eps_off, mid,
                      searched_lines(und, usable, vert, tol), pieces)


def searched_lines(lines: np.ndarray, usable: np.ndarray, vertical: np.ndarray, tol: Tolerances) -> np.ndarray:
    """(M,) bool: the lines stage 1 searches with: the longest
    ``search_lines`` of the ``usable`` ones, at most ``search_vertical_lines``
    of them vertical candidates (``vertical`` (M,) bool)."""
    pool = usable & ~vertical
    pool[longest(lines, usable & vertical, tol.search_vertical_lines)] = True
    out = np.zeros(len(lines), dtype=bool)
    out[longest(lines, pool, tol.search_lines)] = True
    return out


def longest(lines: np.ndarray, mask: np.ndarray, count: int) -> np.ndarray:
    """Indices, ascending, of the ``count`` longest lines (M, 2, 2) among
    ``mask`` (M,) bool (all of them when there are no more): long lines
    are the surest."""
    idx = np.flatnonzero(mask)
    if len(idx) <= count:
        return idx
    length = np.linalg.norm(lines[idx, 1] - lines[idx, 0], axis=1)
    return np.sort(idx[np.argsort(-length, kind="stable")[:count]])


def lines_needed(image_lines: ImageLines, tol: Tolerances) -> int:
    """How many lines an accepted pose must explain in this frame:
    ``min_matches`` and a share of the lines searched (a wrong pose among
    clutter explains some by chance; ``VerdictConstants.chance_fit_share``)."""
    return needed_of(int(image_lines.searched.sum()), tol)


def needed_of(searched: int, tol: Tolerances) -> int:
    """:func:`lines_needed` of a frame (or a rig's frame) whose stage 1
    searches with ``searched`` lines."""
    return tol.min_matches + int(tol.verdict.chance_fit_share * searched)


def too_few_lines(image_lines: ImageLines, tol: Tolerances) -> str:
    """Why the image lines cannot give a pose, or "" if they may."""
    n = int(image_lines.usable.sum())
    if n >= tol.min_matches:
        return ""
    return f"only {n} usable image lines (need {tol.min_matches} of >= {tol.min_line_px:g} px)"
