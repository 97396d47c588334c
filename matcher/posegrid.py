"""Feasible pose sets of correspondences, on a grid of yaws.

For a fixed yaw every correspondence (model segment i, image line j) says
that the camera centre lies on a floor-plane line (method.md section 5):
``a . c = d`` with ``a, d`` from the world normal ``w = R^T n``. Image noise
widens it to a strip ``|a . c - d| <= t``. A set of correspondences is
consistent if, for one yaw of the grid, its strips and the uncertainty disk
have a common point.

The test is run on quadratic forms, so that a set is checked with a sum and
a 2x2 solve: with ``q_k(c) = ((a_k . c - d_k) / t_k)^2`` and
``q_0(c) = |c - c_e|^2 / dt^2``, a feasible point makes every term <= 1, hence

    min_c  q_0(c) + sum_k q_k(c)  <=  |S| + 1.

That bound is a necessary condition (it never rejects a truly feasible set);
each term at the minimiser must also stay below ``q_max``. Coordinates are
relative to the disk centre. Quadratic layout (6,): ``[Axx, Axy, Ayy, bx, by,
c]`` for ``q(z) = z^T A z - 2 b . z + c``.
"""

from __future__ import annotations

import numpy as np


def strip_quadratics(a: np.ndarray, d: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(..., 6) quadratics of strips ``|a . z - d| <= t``; a (..., 2), d and t (...)."""
    s = 1.0 / (t * t)
    return np.stack(
        [a[..., 0] ** 2 * s, a[..., 0] * a[..., 1] * s, a[..., 1] ** 2 * s, a[..., 0] * d * s, a[..., 1] * d * s, d * d * s],
        axis=-1,
    )


def minimise(q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum over z of ``q(z) + |z|^2/dt^2`` for quadratics q (..., 6).

    Returns ``(value (...), zx (...), zy (...))``."""
    inv = 1.0 / (dt * dt)
    axx, axy, ayy = q[..., 0] + inv, q[..., 1], q[..., 2] + inv
    bx, by = q[..., 3], q[..., 4]
    det = axx * ayy - axy * axy
    zx = (ayy * bx - axy * by) / det
    zy = (axx * by - axy * bx) / det
    return q[..., 5] - (bx * zx + by * zy), zx, zy


def evaluate(q: np.ndarray, zx: np.ndarray, zy: np.ndarray) -> np.ndarray:
    """q(z) for quadratics (..., 6) at points ``(zx, zy)`` (...)."""
    return (
        q[..., 0] * zx * zx + 2 * q[..., 1] * zx * zy + q[..., 2] * zy * zy
        - 2 * (q[..., 3] * zx + q[..., 4] * zy) + q[..., 5]
    )


def stretch(q: np.ndarray, z: np.ndarray, e: np.ndarray, q_max: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The stretch ``[lo, hi]`` (...) of the line ``z + s e`` (z, e (..., 2),
    z relative to the disk centre, e unit) on which every quadratic of ``q``
    (S, ..., 6) stays <= ``q_max`` and which lies in the disk of radius
    ``dt``: how far the feasible set of a set of strips reaches in that
    direction (lo > hi: nowhere). Summed quadratics understate it: N
    coinciding strips sum to a curvature N times one strip's, yet meet all
    along the same band."""
    ex, ey = e[..., 0], e[..., 1]
    zx, zy = z[..., 0], z[..., 1]
    alpha = q[..., 0] * ex**2 + 2 * q[..., 1] * ex * ey + q[..., 2] * ey**2
    beta = 2 * ((q[..., 0] * zx + q[..., 1] * zy - q[..., 3]) * ex + (q[..., 1] * zx + q[..., 2] * zy - q[..., 4]) * ey)
    gamma = evaluate(q, zx, zy) - q_max
    # Each quadratic alpha s^2 + beta s + gamma <= 0 on [lo, hi]; a flat one
    # (alpha ~ 0: a strip along e) does not bound s.
    bounded = alpha > 1e-12
    a = np.where(bounded, alpha, 1.0)
    root = np.sqrt(np.maximum(beta * beta - 4 * a * gamma, 0.0))
    lo = np.where(bounded, (-beta - root) / (2 * a), -np.inf).max(axis=0)
    hi = np.where(bounded, (-beta + root) / (2 * a), np.inf).min(axis=0)
    # The disk: |z + s e|^2 <= dt^2.
    ze = zx * ex + zy * ey
    root = np.sqrt(np.maximum(ze * ze - (zx * zx + zy * zy - dt * dt), 0.0))
    return np.maximum(lo, -ze - root), np.minimum(hi, -ze + root)


def halfplane_reachable(q: np.ndarray, val: np.ndarray, zx: np.ndarray, zy: np.ndarray, n_terms,
                        q_max: float, dt: float, c: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...) bool: can a point of the feasible set of summed quadratics ``q``
    (..., 6) satisfy ``c . z <= b`` (c (..., 2), b (...))? A necessary test.

    ``val, zx, zy`` are :func:`minimise`'s output for ``q`` and ``n_terms``
    the number of strips summed. Every feasible point keeps each strip's term
    <= ``q_max`` and lies in the disk, so ``F(z) = q(z) + |z|^2/dt^2 <=
    n_terms q_max + 1``: an ellipse around the minimiser, on which the
    smallest ``c . z`` is ``c . z* - sqrt(rho c^T A^-1 c)`` (A the Hessian
    half, rho the level above the minimum). The disk gives ``-|c| dt``; the
    larger of the two lower bounds holds."""
    inv = 1.0 / (dt * dt)
    axx, axy, ayy = q[..., 0] + inv, q[..., 1], q[..., 2] + inv
    det = axx * ayy - axy * axy
    cx, cy = c[..., 0], c[..., 1]
    cAc = (ayy * cx * cx - 2 * axy * cx * cy + axx * cy * cy) / det
    rho = np.maximum(n_terms * q_max + 1.0 - val, 0.0)
    lo_ellipse = cx * zx + cy * zy - np.sqrt(rho * np.maximum(cAc, 0.0))
    lo_disk = -np.hypot(cx, cy) * dt
    return np.maximum(lo_ellipse, lo_disk) <= b


def weak_axes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For quadratics (..., 6): the unit direction (..., 2) in which they fix
    the position least, and the eigenvalues (small, large) of their
    quadratic part, in closed form."""
    axx, axy, ayy = q[..., 0], q[..., 1], q[..., 2]
    mean, diff = 0.5 * (axx + ayy), np.sqrt(0.25 * (axx - ayy) ** 2 + axy * axy)
    lam_lo, lam_hi = mean - diff, mean + diff
    ex, ey = axy, lam_lo - axx
    norm = np.hypot(ex, ey)
    flat = norm < 1e-12
    ex = np.where(flat, np.where(axx <= ayy, 1.0, 0.0), ex / np.where(flat, 1.0, norm))
    ey = np.where(flat, np.where(axx <= ayy, 0.0, 1.0), ey / np.where(flat, 1.0, norm))
    return np.stack([ex, ey], axis=-1), lam_lo, lam_hi
