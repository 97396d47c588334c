"""Stage 2: a least-squares pose and the paper's score E per hypothesis
(method.md section 8).

Stage 1 hands each hypothesis the yaw of the grid and the position at which
its strips meet best: that is the yaw search plus the linear solve. Here all
hypotheses are refined at once by Gauss-Newton on image-side residuals: for
each matched line, the sines of the angles between the rays of its two end
points and the plane through the optical centre and the model segment
(pixels over focal length, so the fit weighs image noise evenly). Then

    E = 1/N sum (n . R v)^2 + 1/N sum (n . R (P_mid - C))^2

with ``n`` the image line's plane normal, ``v`` the segment's direction and
``P_mid`` its midpoint.
"""

from __future__ import annotations

import numpy as np

from matcher.constraints import rotations

#: Gauss-Newton iterations: from the grid start (within half a yaw step and a
#: few centimetres) the fit converges in 3 to 4.
_ITERATIONS = 6
#: Finite-difference steps for (x, y, yaw): metres, metres, radians.
_STEPS = np.array([1e-5, 1e-5, 1e-6])


def _residuals(params, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height):
    """(T, 2) image-side residuals; params (H, 3), hyp (T,) hypothesis of each match."""
    p = params[hyp]
    R = rotations(p[:, 2], pitch)  # (T, 3, 3)
    C = np.stack([p[:, 0], p[:, 1], np.full(len(p), height)], axis=1)
    qa = np.einsum("tij,tj->ti", R, seg_a - C)
    qb = np.einsum("tij,tj->ti", R, seg_b - C)
    m = np.cross(qa, qb)
    m /= np.linalg.norm(m, axis=1, keepdims=True)
    return np.stack([np.einsum("ti,ti->t", m, ray_a), np.einsum("ti,ti->t", m, ray_b)], axis=1)


def refine(init, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height):
    """Gauss-Newton on all hypotheses together.

    ``init`` (H, 3) ``(x, y, yaw)``; per match t: ``hyp`` (T,), model segment
    end points ``seg_a, seg_b`` (T, 3) world, unit rays of the image line end
    points ``ray_a, ray_b`` (T, 3) camera frame. Returns poses (H, 3)."""
    params = np.array(init, dtype=float)
    H = len(params)
    for _ in range(_ITERATIONS):
        r0 = _residuals(params, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height)
        J = np.empty(r0.shape + (3,))
        for k in range(3):
            dp = params.copy()
            dp[:, k] += _STEPS[k]
            J[..., k] = (_residuals(dp, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height) - r0) / _STEPS[k]
        JtJ = np.einsum("tsi,tsj->tij", J, J)
        Jtr = np.einsum("tsi,ts->ti", J, r0)
        A = np.zeros((H, 3, 3))
        b = np.zeros((H, 3))
        np.add.at(A, hyp, JtJ)
        np.add.at(b, hyp, Jtr)
        # Small Levenberg damping keeps degenerate hypotheses (all lines
        # parallel) from jumping away; it is negligible for a well-posed set.
        A += np.eye(3)[None] * (1e-9 + 1e-6 * np.trace(A, axis1=1, axis2=2))[:, None, None]
        params -= np.linalg.solve(A, b[..., None])[..., 0]
    return params


def score_e(params, hyp, normals, seg_a, seg_b, pitch, height):
    """The paper's E (H,) for poses (H, 3); per match t: image plane normals
    ``normals`` (T, 3) camera frame, segment end points ``seg_a, seg_b`` (T, 3)."""
    p = params[hyp]
    R = rotations(p[:, 2], pitch)
    C = np.stack([p[:, 0], p[:, 1], np.full(len(p), height)], axis=1)
    v = seg_b - seg_a
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    mid = 0.5 * (seg_a + seg_b)
    e_dir = np.einsum("ti,tij,tj->t", normals, R, v)
    e_pos = np.einsum("ti,tij,tj->t", normals, R, mid - C)
    H = len(params)
    n = np.bincount(hyp, minlength=H).astype(float)
    return (np.bincount(hyp, e_dir**2, minlength=H) + np.bincount(hyp, e_pos**2, minlength=H)) / np.maximum(n, 1)
