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

import math

import numpy as np

from matcher.constraints import rotations

#: Gauss-Newton iterations: from the grid start (within half a yaw step and a
#: few centimetres) the fit converges in 3 to 4.
_ITERATIONS = 6
#: With robust weights, this many plain iterations come first: the stage-1
#: start may be tens of centimetres off along a weakly fixed direction, and
#: weighting residuals from there would throw out true matches.
_PLAIN_FIRST = 2


def _cross(a, b):
    """Row-wise cross product of (T, 3) arrays (np.cross is slow on small arrays)."""
    return np.stack(
        [a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2], a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]],
        axis=1,
    )


def _to_cam(c, s, cp, sp, d):
    """R (P - C) for offsets d (T, 3) and yaw cosines/sines c, s (T,): rows
    r, d, f of method.md section 2, written out (no (T, 3, 3) array)."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    return np.stack([s * x - c * y, -sp * (c * x + s * y) - cp * z, cp * (c * x + s * y) - sp * z], axis=1)


def _to_cam_dyaw(c, s, cp, sp, d):
    """d/dyaw of :func:`_to_cam`."""
    x, y = d[:, 0], d[:, 1]
    h = -s * x + c * y  # d/dyaw of (c x + s y)
    return np.stack([c * x + s * y, -sp * h, cp * h], axis=1)


def _residuals(params, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height, jacobian=False):
    """(T, 2) image-side residuals, and with ``jacobian`` their derivatives
    (T, 2, 3) in (x, y, yaw); params (H, 3), hyp (T,) hypothesis of each match."""
    p = params[hyp]
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    cp, sp = math.cos(pitch), math.sin(pitch)
    C = np.stack([p[:, 0], p[:, 1], np.full(len(p), height)], axis=1)
    da, db = seg_a - C, seg_b - C
    qa, qb = _to_cam(c, s, cp, sp, da), _to_cam(c, s, cp, sp, db)
    m = _cross(qa, qb)
    nm = np.sqrt((m * m).sum(axis=1))[:, None]
    mh = m / nm
    r = np.stack([(mh * ray_a).sum(axis=1), (mh * ray_b).sum(axis=1)], axis=1)
    if not jacobian:
        return r
    J = np.empty(r.shape + (3,))
    # d q / d x = -R e_x and d q / d y = -R e_y, the same for both end points.
    ex = np.stack([s, -sp * c, cp * c], axis=1)
    ey = np.stack([-c, -sp * s, cp * s], axis=1)
    dms = [_cross(-ex, qb) + _cross(qa, -ex), _cross(-ey, qb) + _cross(qa, -ey),
           _cross(_to_cam_dyaw(c, s, cp, sp, da), qb) + _cross(qa, _to_cam_dyaw(c, s, cp, sp, db))]
    for k, dm in enumerate(dms):
        dmh = (dm - mh * (mh * dm).sum(axis=1)[:, None]) / nm
        J[:, 0, k] = (dmh * ray_a).sum(axis=1)
        J[:, 1, k] = (dmh * ray_b).sum(axis=1)
    return r, J


def refine(init, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height, robust_scale=None, iterations=_ITERATIONS):
    """Gauss-Newton on all hypotheses together.

    ``init`` (H, 3) ``(x, y, yaw)``; per match t: ``hyp`` (T,), model segment
    end points ``seg_a, seg_b`` (T, 3) world, unit rays of the image line end
    points ``ray_a, ray_b`` (T, 3) camera frame. With ``robust_scale`` (T,)
    (radians), residuals are weighted by Tukey's biweight (zero beyond twice
    the scale; iteratively reweighted), so that a wrong match does not drag
    the pose of the others away. Returns poses (H, 3)."""
    params = np.array(init, dtype=float)
    H = len(params)
    for it in range(iterations):
        r0, J = _residuals(params, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height, jacobian=True)
        if robust_scale is None or it < _PLAIN_FIRST:
            w = np.ones_like(r0)
        else:  # Tukey's biweight: residuals beyond twice the scale get no say
            u = np.clip(np.abs(r0) / (2.0 * robust_scale[:, None]), 0.0, 1.0)
            w = (1.0 - u * u) ** 2 + 1e-6
        JtJ = np.einsum("tsi,ts,tsj->tij", J, w, J)
        Jtr = np.einsum("tsi,ts,ts->ti", J, w, r0)
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
