"""A rig's verified poses judged against the E their own matches' noise
allows (matcher.rig.verify.e_limit), not a threshold fitted to one data set."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from linemap.camera import Camera
from linemap.geometry import project_segments
from matcher.frame import prepare_lines
from matcher.rig.verify import _score, e_limit
from matcher.stage2.fit import fit_bound_px
from matcher.stage2.matches import Matches
from matcher.tolerances import DEFAULT as TOL

CAM = Camera.from_fov(90.0, 800, 600, 1.4, 5.0)


def _room(distance_m: float) -> np.ndarray:
    """(T, 2, 3) a room's lines seen from the origin looking along +x at
    ``distance_m``: the far wall's floor and ceiling junctions and its two
    corners, a door's jambs and lintel."""
    d, w = distance_m, 0.8 * distance_m
    return np.array([[[d, -w, 0.0], [d, w, 0.0]], [[d, -w, 2.5], [d, w, 2.5]],
                     [[d, -w, 0.0], [d, -w, 2.5]], [[d, w, 0.0], [d, w, 2.5]],
                     [[d, 0.1, 0.0], [d, 0.1, 2.0]], [[d, 0.9, 0.0], [d, 0.9, 2.0]],
                     [[d, 0.1, 2.0], [d, 0.9, 2.0]]])


def _seen(segments: np.ndarray, pose: np.ndarray, share: float, turn: bool) -> np.ndarray:
    """(T, 2, 2) the segments' image lines at ``pose``, each end point moved
    across the line by ``share`` of its fit bound: both ends to one side
    (an offset) or to opposite sides (``turn``)."""
    uv, ok = project_segments(CAM, np.repeat(pose[None], len(segments), 0), segments, TOL.stage2.near_plane_m)
    assert ok.all()
    along = uv[:, 1] - uv[:, 0]
    length = np.linalg.norm(along, axis=1)
    across = np.stack([-along[:, 1], along[:, 0]], axis=1) / length[:, None]
    b = share * fit_bound_px(length, TOL)
    sign = np.array([-1.0, 1.0]) if turn else np.array([1.0, 1.0])
    return uv + sign[None, :, None] * b[:, None, None] * across[:, None, :]


def _e_and_limit(distance_m: float, share: float, turn: bool) -> tuple[float, float]:
    segments = _room(distance_m)
    pose = np.zeros((1, 3))
    lines = _seen(segments, pose[0], share, turn)
    view = SimpleNamespace(camera=CAM, lines=prepare_lines(CAM, lines, TOL))
    idx = np.arange(len(segments))
    m = Matches(np.zeros(len(idx), np.int64), idx, idx)
    return float(_score(view, segments, pose, m)[0]), float(e_limit(view, segments, pose, m, TOL)[0])


def test_matches_within_their_fit_bound_score_within_the_limit_however_far_the_walls():
    """E's position term grows with the distance of the walls seen: the same
    pixel residuals score ten times more at 6 m than at 2 m, so a threshold
    fixed in advance (the rig's former 3e-3) refuses a large room's right
    pose; the limit grows with them."""
    for turn in (False, True):
        near, near_limit = _e_and_limit(2.0, 0.9, turn)
        far, far_limit = _e_and_limit(6.0, 0.9, turn)
        assert near <= near_limit and far <= far_limit
        assert far_limit > 3.0 * near_limit
    # Lines at half their bound from walls 6 m away: E over the former fixed
    # threshold, within the noise model's.
    far, far_limit = _e_and_limit(6.0, 0.5, False)
    assert 3e-3 < far <= far_limit


def test_the_limit_is_tight_for_lines_at_their_bound_and_far_above_a_true_fit():
    exact, limit = _e_and_limit(4.0, 0.0, False)
    assert exact < 1e-3 * limit
    at_bound, limit = _e_and_limit(4.0, 1.0, False)
    assert 0.5 * limit < at_bound <= limit
