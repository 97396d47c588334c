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
``P_mid`` its midpoint (the paper's; :mod:`matcher.stage2.rank` scores the middle
of the part of the segment that the line shows, the same point for a
segment seen whole).
"""

from __future__ import annotations

import numpy as np

from linemap.camera import world2cam_rotation
from linemap.geometry import world_normals
from matcher.tolerances import Stage2Constants



class MatchTerms:
    """Per match, the constants of its residuals, so that a Gauss-Newton
    iteration is a handful of operations on (T,) and (T, 2) arrays.

    In the world frame the normal of the plane through the camera centre
    ``C = (x, y, h)`` and a model segment ``A B`` is

        m(C) = (A - C) x (B - C) = A x B + d x C,   d = B - A,

    affine in (x, y). With horizontal parts as complex numbers (``P = x + iy``,
    ``D = d_x + i d_y``) that is ``m_h = m0_h + i d_z P`` and ``m_z = m0_z +
    Im(conj(D) P)``. An image end point's ray, taken to the world frame
    (``R^T ray``), has horizontal part ``w_h e^{i yaw}`` and vertical part
    ``w_z``, both fixed by the pitch. The residual of an end point is the sine
    of the angle between its ray and the plane: ``m . u / |m|``, the same
    number in the camera frame (R is a rotation)."""

    def __init__(self, seg_a, seg_b, ray_a, ray_b, pitch: float, height: float) -> None:
        """``seg_a, seg_b`` (T, 3) world end points; ``ray_a, ray_b`` (T, 3)
        unit camera-frame rays of the image line's end points."""
        seg_a, seg_b = np.asarray(seg_a, dtype=float), np.asarray(seg_b, dtype=float)
        d = seg_b - seg_a
        (ax, ay, az), (bx, by, bz) = seg_a.T, seg_b.T
        # A x B + d x (0, 0, h), written out (np.cross costs more on short arrays).
        self.m0_h = (ay * bz - az * by + d[:, 1] * height) + 1j * (az * bx - ax * bz - d[:, 0] * height)  # (T,)
        self.m0_z = ax * by - ay * bx
        self.D = d[:, 0] + 1j * d[:, 1]
        self.dz = d[:, 2]
        self.idz = 1j * d[:, 2]
        rays = np.empty((len(d), 2, 3))
        rays[:, 0], rays[:, 1] = ray_a, ray_b
        # R^T ray at yaw 0; a yaw turns its horizontal part by e^{i yaw}.
        w = world_normals(rays, np.zeros(rays.shape[:2]), pitch)  # (T, 2, 3)
        self.w_h = w[..., 0] + 1j * w[..., 1]  # (T, 2)
        self.w_z = w[..., 2]


def joined_terms(many: list) -> MatchTerms:
    """The matches of several :class:`MatchTerms` as one (a rig's cameras:
    each camera's pitch and height are in its own matches' terms)."""
    out = MatchTerms.__new__(MatchTerms)
    for name in ("m0_h", "m0_z", "D", "dz", "idz", "w_h", "w_z"):
        setattr(out, name, np.concatenate([getattr(t, name) for t in many]))
    return out


def residuals(params, hyp, terms: MatchTerms, jacobian=False):
    """(T, 2) image-side residuals (and with ``jacobian`` their derivatives
    (T, 2, 3) in (x, y, yaw)) of matches t at poses ``params`` (H, 3); ``hyp``
    (T,) the pose of each match; ``terms`` the matches' segments and rays
    (:class:`MatchTerms`).

    The derivatives, with ``N = m . u`` and ``n = |m|``: ``dr = (dN - r (m .
    dm) / n) / n``. In x and y (as ``d/dx + i d/dy``): ``dN = i (D w_z - d_z
    U)`` with ``U = w_h e^{i yaw}``, and ``m . dm = i (D m_z - d_z m_h)``; in
    yaw m is fixed and ``dN = -Im(conj(m_h) U)``."""
    p = params[hyp]
    P = p[:, 0] + 1j * p[:, 1]
    m_h = terms.m0_h + terms.idz * P
    m_z = terms.m0_z + (terms.D.conjugate() * P).imag
    n = np.sqrt(m_h.real**2 + m_h.imag**2 + m_z**2)
    U = terms.w_h * np.exp(1j * p[:, 2])[:, None]  # (T, 2)
    cm = m_h.conjugate()[:, None] * U
    r = (cm.real + m_z[:, None] * terms.w_z) / n[:, None]
    if not jacobian:
        return r
    dN = 1j * (terms.D[:, None] * terms.w_z - terms.dz[:, None] * U)  # (T, 2): d/dx + i d/dy
    mdm = 1j * (terms.D * m_z - terms.dz * m_h)  # (T,)
    J = np.empty(r.shape + (3,))
    J[..., 0] = dN.real - r * (mdm.real / n)[:, None]
    J[..., 1] = dN.imag - r * (mdm.imag / n)[:, None]
    J[..., 2] = -cm.imag
    J /= n[:, None, None]
    return r, J


def refine(init, hyp, terms: MatchTerms, work: Stage2Constants, robust_scale=None, iterations: int | None = None):
    """Gauss-Newton on all hypotheses together.

    ``init`` (H, 3) ``(x, y, yaw)``; per match t: ``hyp`` (T,) and its
    residuals' constants ``terms`` (:class:`MatchTerms`: the model segment's
    end points, the unit rays of the image line's). With ``robust_scale`` (T,)
    (radians), residuals are weighted by Tukey's biweight (zero beyond twice
    the scale; iteratively reweighted), so that a wrong match does not drag
    the pose of the others away. ``work`` gives the iterations (``refine_iterations``
    unless ``iterations``), the plain ones before robust weights and the
    convergence step. Returns poses (H, 3)."""
    params = np.array(init, dtype=float)
    H = len(params)
    # Sums over each hypothesis's matches as one product: (H, 2T) one-hot of
    # each residual's hypothesis (np.add.at costs more on these short arrays).
    onehot = (np.repeat(hyp, 2)[None, :] == np.arange(H)[:, None]).astype(float)
    plain_first, converged = work.refine_plain_first, work.refine_converged
    diag_at = np.arange(3)
    for it in range(work.refine_iterations if iterations is None else iterations):
        r0, J = residuals(params, hyp, terms, jacobian=True)
        if robust_scale is None or it < plain_first:
            Jw = J
        else:  # Tukey's biweight: residuals beyond twice the scale get no say
            u = np.clip(np.abs(r0) / (2.0 * robust_scale[:, None]), 0.0, 1.0)
            Jw = J * ((1.0 - u * u) ** 2 + 1e-6)[..., None]
        Jw, J = Jw.reshape(-1, 3), J.reshape(-1, 3)
        A = (onehot @ (Jw[:, :, None] * J[:, None, :]).reshape(-1, 9)).reshape(H, 3, 3)
        b = onehot @ (Jw * r0.reshape(-1, 1))
        # Small Levenberg damping keeps degenerate hypotheses (all lines
        # parallel) from jumping away; it is negligible for a well-posed set.
        diag = A[:, diag_at, diag_at]
        A[:, diag_at, diag_at] = diag + (1e-9 + 1e-6 * diag.sum(axis=1))[:, None]
        step = np.linalg.solve(A, b[..., None])[..., 0]
        params -= step
        if np.abs(step).max() < converged and (robust_scale is None or it >= plain_first):
            break  # every hypothesis has converged (with its robust weights, if any)
    return params


def score_e(params, hyp, normals, seg_a, seg_b, pitch, height, mid=None):
    """The paper's E (H,) for poses (H, 3); per match t: image plane normals
    ``normals`` (T, 3) camera frame, segment end points ``seg_a, seg_b`` (T,
    3), and ``mid`` (T, 3) the point of the segment whose distance to the
    plane is scored (the paper's: the segment's midpoint, the default)."""
    p = params[hyp]
    R = world2cam_rotation(p[:, 2], pitch)
    C = np.stack([p[:, 0], p[:, 1], np.full(len(p), height)], axis=1)
    v = seg_b - seg_a
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    mid = 0.5 * (seg_a + seg_b) if mid is None else mid
    e_dir = np.einsum("ti,tij,tj->t", normals, R, v)
    e_pos = np.einsum("ti,tij,tj->t", normals, R, mid - C)
    H = len(params)
    n = np.bincount(hyp, minlength=H).astype(float)
    return (np.bincount(hyp, e_dir**2, minlength=H) + np.bincount(hyp, e_pos**2, minlength=H)) / np.maximum(n, 1)
