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

import math

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


def stretch(q: np.ndarray, z: tuple[float, float], e: tuple[float, float], q_max: float,
            dt: float) -> tuple[float, float]:
    """The stretch ``[lo, hi]`` of the line ``z + s e`` (z relative to the
    disk centre, e unit) on which every quadratic of ``q`` (S, 6), all at one
    yaw, stays <= ``q_max`` and which lies in the disk of radius ``dt``: how
    far the feasible set of a set of strips reaches in that direction (lo >
    hi: nowhere). Summed quadratics understate it: N coinciding strips sum to
    a curvature N times one strip's, yet meet all along the same band.

    Plain floats: S is a handful and this runs at every tree node, where
    numpy's per-call cost would dominate."""
    zx, zy = z
    ex, ey = e
    lo, hi = -math.inf, math.inf
    for qxx, qxy, qyy, bx, by, c in q.tolist():
        alpha = qxx * ex * ex + 2 * qxy * ex * ey + qyy * ey * ey
        if alpha <= 1e-12:  # a strip along e does not bound s
            continue
        beta = 2 * ((qxx * zx + qxy * zy - bx) * ex + (qxy * zx + qyy * zy - by) * ey)
        gamma = qxx * zx * zx + 2 * qxy * zx * zy + qyy * zy * zy - 2 * (bx * zx + by * zy) + c - q_max
        root = math.sqrt(max(beta * beta - 4 * alpha * gamma, 0.0))
        lo = max(lo, (-beta - root) / (2 * alpha))
        hi = min(hi, (-beta + root) / (2 * alpha))
    # The disk: |z + s e|^2 <= dt^2.
    ze = zx * ex + zy * ey
    root = math.sqrt(max(ze * ze - (zx * zx + zy * zy - dt * dt), 0.0))
    return max(lo, -ze - root), min(hi, -ze + root)


def stretches(q: np.ndarray, zx: np.ndarray, zy: np.ndarray, ex: np.ndarray, ey: np.ndarray, q_max: float,
              dt: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`stretch` for many lines at once: quadratics q (S, ..., 6), the
    lines ``z + s e`` given by (...) arrays. Returns ``(lo, hi)`` (...)."""
    alpha = q[..., 0] * ex * ex + 2 * q[..., 1] * ex * ey + q[..., 2] * ey * ey
    beta = 2 * ((q[..., 0] * zx + q[..., 1] * zy - q[..., 3]) * ex + (q[..., 1] * zx + q[..., 2] * zy - q[..., 4]) * ey)
    gamma = evaluate(q, zx, zy) - q_max
    bounds = alpha > 1e-12  # a strip along e does not bound s
    a = np.where(bounds, alpha, 1.0)
    root = np.sqrt(np.maximum(beta * beta - 4 * a * gamma, 0.0))
    lo = np.where(bounds, (-beta - root) / (2 * a), -np.inf).max(axis=0)
    hi = np.where(bounds, (-beta + root) / (2 * a), np.inf).min(axis=0)
    ze = zx * ex + zy * ey
    root = np.sqrt(np.maximum(ze * ze - (zx * zx + zy * zy - dt * dt), 0.0))
    return np.maximum(lo, -ze - root), np.minimum(hi, -ze + root)


def weak_axes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`weak_axis`'s direction for quadratics q (..., 6): ``(ex, ey)``
    (...) unit vectors."""
    axx, axy, ayy = q[..., 0], q[..., 1], q[..., 2]
    lam_lo = 0.5 * (axx + ayy) - np.hypot(0.5 * (axx - ayy), axy)
    ex, ey = axy, lam_lo - axx
    norm = np.hypot(ex, ey)
    flat = norm < 1e-12  # isotropic or axis-aligned: the axis with less weight
    x_axis = axx <= ayy
    ex = np.where(flat, np.where(x_axis, 1.0, 0.0), ex / np.where(flat, 1.0, norm))
    ey = np.where(flat, np.where(x_axis, 0.0, 1.0), ey / np.where(flat, 1.0, norm))
    return ex, ey


def halfplane_reachable(q: np.ndarray, minimum: tuple, n_terms, q_max: float, dt: float, c: np.ndarray,
                        b: np.ndarray) -> np.ndarray:
    """(...) bool: can a point of the feasible set of summed quadratics ``q``
    (..., 6) satisfy ``c . z <= b`` (c (..., 2), b (...))? A necessary test.

    ``minimum`` is :func:`minimise`'s output ``(val, zx, zy)`` for ``q`` and ``n_terms``
    the number of strips summed. Every feasible point keeps each strip's term
    <= ``q_max`` and lies in the disk, so ``F(z) = q(z) + |z|^2/dt^2 <=
    n_terms q_max + 1``: an ellipse around the minimiser, on which the
    smallest ``c . z`` is ``c . z* - sqrt(rho c^T A^-1 c)`` (A the Hessian
    half, rho the level above the minimum). The disk gives ``-|c| dt``; the
    larger of the two lower bounds holds."""
    val, zx, zy = minimum
    return ellipse_reaches(feasible_ellipse(q, val, zx, zy, n_terms, q_max, dt), c, b, dt)


def feasible_ellipse(q: np.ndarray, val: np.ndarray, zx: np.ndarray, zy: np.ndarray, n_terms, q_max: float,
                     dt: float) -> tuple[np.ndarray, ...]:
    """The ellipse holding the feasible set of summed quadratics ``q`` (...,
    6) (see :func:`halfplane_reachable`): ``(zx, zy, sxx, sxy, syy)``, its
    centre and ``rho A^-1``, so that the smallest ``c . z`` on it is
    ``c . z* - sqrt(c^T S c)``. Made once and tested against many
    half-planes with :func:`ellipse_reaches`."""
    inv = 1.0 / (dt * dt)
    axx, axy, ayy = q[..., 0] + inv, q[..., 1], q[..., 2] + inv
    k = np.maximum(n_terms * q_max + 1.0 - val, 0.0) / (axx * ayy - axy * axy)
    return zx, zy, ayy * k, -axy * k, axx * k


def ellipse_reaches(ell: tuple[np.ndarray, ...], c: np.ndarray, b: np.ndarray, dt: float | None) -> np.ndarray:
    """(...) bool: does the ellipse of :func:`feasible_ellipse` (or the disk
    of radius ``dt``, whichever is smaller there) reach ``c . z <= b``? c
    (..., 2) and b (...) broadcast against the ellipse's shape. ``dt`` None
    leaves the disk out, for entries known to pass it: a yaw mask that
    :func:`halfplane_reachable` has cut (stage 1 does so for every
    correspondence) holds only where its half-plane meets the disk."""
    zx, zy, sxx, sxy, syy = ell
    cx, cy = c[..., 0], c[..., 1]
    spread = np.sqrt(np.maximum(cx * (sxx * cx + sxy * cy) + cy * (sxy * cx + syy * cy), 0.0))
    low = cx * zx + cy * zy - spread
    if dt is not None:
        low = np.maximum(low, np.hypot(cx, cy) * -dt)
    return low <= b


def evaluate_at(q: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """q(z) for quadratics q (..., 6) at points given by their
    :func:`monomials` ``phi`` (..., 6): one product-sum instead of a dozen
    array operations (this runs at every tree node)."""
    return (q * phi).sum(axis=-1)


def monomials(zx: np.ndarray, zy: np.ndarray) -> np.ndarray:
    """(..., 6) ``[x^2, 2xy, y^2, -2x, -2y, 1]`` at points ``(zx, zy)`` (...):
    a quadratic's value there is its dot product with these."""
    phi = np.empty(np.shape(zx) + (6,))
    phi[..., 0] = zx * zx
    phi[..., 1] = 2 * zx * zy
    phi[..., 2] = zy * zy
    phi[..., 3] = -2 * zx
    phi[..., 4] = -2 * zy
    phi[..., 5] = 1.0
    return phi


def weak_axis(q: np.ndarray) -> tuple[tuple[float, float], float, float]:
    """For one quadratic (6,): the unit direction ``(ex, ey)`` in which it
    fixes the position least, and the eigenvalues (small, large) of its
    quadratic part, in closed form (plain floats, as :func:`stretch`)."""
    axx, axy, ayy = float(q[0]), float(q[1]), float(q[2])
    mean, diff = 0.5 * (axx + ayy), math.hypot(0.5 * (axx - ayy), axy)
    lam_lo, lam_hi = mean - diff, mean + diff
    ex, ey = axy, lam_lo - axx
    norm = math.hypot(ex, ey)
    if norm < 1e-12:  # isotropic or axis-aligned: the axis with less weight
        return ((1.0, 0.0) if axx <= ayy else (0.0, 1.0)), lam_lo, lam_hi
    return (ex / norm, ey / norm), lam_lo, lam_hi
