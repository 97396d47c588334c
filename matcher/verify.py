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

from matcher.camera import world2cam_rotation

#: Gauss-Newton iterations: from the grid start (within half a yaw step and a
#: few centimetres) the fit converges in 3 to 4.
_ITERATIONS = 6
#: With robust weights, this many plain iterations come first: the stage-1
#: start may be tens of centimetres off along a weakly fixed direction, and
#: weighting residuals from there would throw out true matches.
_PLAIN_FIRST = 2
#: Gauss-Newton stops early once no hypothesis moves more than this (metres
#: and radians) in one step: a micrometre, far below the pose's noise.
_CONVERGED = 1e-6


def _cross(a, b):
    """Cross product of vectors given as 3-tuples of (T,) arrays."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _residuals(params, hyp, seg_a, seg_b, ray_a, ray_b, pitch, height, jacobian=False):
    """(T, 2) image-side residuals, and with ``jacobian`` their derivatives
    (T, 2, 3) in (x, y, yaw); params (H, 3), hyp (T,) hypothesis of each match.

    Written on components (3-tuples of (T,) arrays): the arrays are short and
    numpy's per-call cost dominates, so no (T, 3, 3) rotations or stacks."""
    p = params[hyp]
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    cp, sp = math.cos(pitch), math.sin(pitch)
    ax, ay, az = seg_a[:, 0] - p[:, 0], seg_a[:, 1] - p[:, 1], seg_a[:, 2] - height
    bx, by, bz = seg_b[:, 0] - p[:, 0], seg_b[:, 1] - p[:, 1], seg_b[:, 2] - height
    # R (P - C) with rows r, d, f of method.md section 2.
    ha, hb = c * ax + s * ay, c * bx + s * by
    qa = (s * ax - c * ay, -sp * ha - cp * az, cp * ha - sp * az)
    qb = (s * bx - c * by, -sp * hb - cp * bz, cp * hb - sp * bz)
    m = _cross(qa, qb)
    nm = np.sqrt(_dot(m, m))
    mh = (m[0] / nm, m[1] / nm, m[2] / nm)
    ra = (ray_a[:, 0], ray_a[:, 1], ray_a[:, 2])
    rb = (ray_b[:, 0], ray_b[:, 1], ray_b[:, 2])
    r = np.stack([_dot(mh, ra), _dot(mh, rb)], axis=1)
    if not jacobian:
        return r
    # d q / d x = -R e_x, d q / d y = -R e_y for both end points, so
    # d (qa x qb) = e x (qa - qb) with e = R e_x (or R e_y); d q / d yaw = R' (P - C).
    dq = (qa[0] - qb[0], qa[1] - qb[1], qa[2] - qb[2])
    ex = (s, -sp * c, cp * c)
    ey = (-c, -sp * s, cp * s)
    ga, gb = -s * ax + c * ay, -s * bx + c * by  # d/dyaw of ha, hb
    dqa = (ha, -sp * ga, cp * ga)
    dqb = (hb, -sp * gb, cp * gb)
    dyaw = tuple(u + v for u, v in zip(_cross(dqa, qb), _cross(qa, dqb)))
    J = np.empty(r.shape + (3,))
    for k, dm in enumerate((_cross(ex, dq), _cross(ey, dq), dyaw)):
        t = _dot(mh, dm)
        dmh = ((dm[0] - mh[0] * t) / nm, (dm[1] - mh[1] * t) / nm, (dm[2] - mh[2] * t) / nm)
        J[:, 0, k] = _dot(dmh, ra)
        J[:, 1, k] = _dot(dmh, rb)
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
        step = np.linalg.solve(A, b[..., None])[..., 0]
        params -= step
        if np.abs(step).max() < _CONVERGED and (robust_scale is None or it >= _PLAIN_FIRST):
            break  # every hypothesis has converged (with its robust weights, if any)
    return params


def score_e(params, hyp, normals, seg_a, seg_b, pitch, height):
    """The paper's E (H,) for poses (H, 3); per match t: image plane normals
    ``normals`` (T, 3) camera frame, segment end points ``seg_a, seg_b`` (T, 3)."""
    p = params[hyp]
    R = world2cam_rotation(p[:, 2], pitch)
    C = np.stack([p[:, 0], p[:, 1], np.full(len(p), height)], axis=1)
    v = seg_b - seg_a
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    mid = 0.5 * (seg_a + seg_b)
    e_dir = np.einsum("ti,tij,tj->t", normals, R, v)
    e_pos = np.einsum("ti,tij,tj->t", normals, R, mid - C)
    H = len(params)
    n = np.bincount(hyp, minlength=H).astype(float)
    return (np.bincount(hyp, e_dir**2, minlength=H) + np.bincount(hyp, e_pos**2, minlength=H)) / np.maximum(n, 1)
