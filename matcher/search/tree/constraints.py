"""The paper's geometric tests on 2D-3D pairs (method.md sections 4 to 6).

No pose is computed here: each test says whether a correspondence, or a
couple of correspondences, can hold for some pose of the prior set
``{(x, y, yaw): |(x, y) - (xe, ye)| <= dt, |yaw - yaw_e| <= dyaw}``.

Shapes: image lines (M, 2, 2) pixels; interpretation-plane normals (M, 3)
unit, camera frame; model directions (N, 3) unit, world frame. Angles in
radians.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.camera import Camera
from linemap.geometry import world_normals, wrap


#: The noise cases of :func:`_perturbed_lines`: (rotation, offset) signs.
#: The first four are the extreme cases of the noise model; then rotation
#: alone and offset alone.
#: Line pairs per block of :func:`line_pieces` (a work size: it bounds the
#: float temporaries, 32 MB each, not a tolerance of the method).
_PAIR_BLOCK = 4_000_000

_NOISE_CASES = np.array([[-1, -1], [-1, 1], [1, -1], [1, 1], [-1, 0], [1, 0], [0, -1], [0, 1]], dtype=float)


def distinct_points(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(first, inverse)`` for floor points (P, 2): the index of the first
    of each distinct point, and each point's distinct index (P,). Found
    through a complex view: np.unique on rows is several times slower."""
    _, first, inv = np.unique(points[:, 0] + 1j * points[:, 1], return_index=True, return_inverse=True)
    return first, inv.reshape(-1)


def _perturbed_lines(lines: np.ndarray, px: float, deg: float) -> np.ndarray:
    """(8, M, 2, 2): each line rotated by ``+-deg`` about its midpoint and
    shifted by ``+-px`` along its normal, in the cases of _NOISE_CASES."""
    a, b = lines[:, 0], lines[:, 1]
    mid = 0.5 * (a + b)
    half = 0.5 * (b - a)
    ln = np.hypot(half[:, 0], half[:, 1])[:, None]  # (M, 1)
    d = half / ln
    perp = np.stack([-d[:, 1], d[:, 0]], axis=1)
    rot = np.radians(deg) * _NOISE_CASES[:, 0]
    c, s = np.cos(rot)[:, None, None], np.sin(rot)[:, None, None]  # (8, 1, 1)
    dr = c * d + s * perp  # (8, M, 2): d turned by rot
    m = mid + (px * _NOISE_CASES[:, 1])[:, None, None] * perp
    return np.stack([m - ln * dr, m + ln * dr], axis=2)


def plane_noise(camera: Camera, lines: np.ndarray, px: float, deg: float) -> np.ndarray:
    """(M,) largest angle, radians, between the interpretation plane of each
    line and that of the line moved by the noise bounds (``px`` offset, ``deg``
    rotation about its midpoint). Any residual ``n . X`` of a unit vector X
    lying in the true plane is then at most this (plus second order)."""
    return plane_noises(camera, lines, px, deg)[0]


def plane_noises(camera: Camera, lines: np.ndarray, px: float, deg: float):
    """``(eps, eps_rot, eps_off)``, each (M,): :func:`plane_noise` for both
    bounds, for the rotation alone and for the offset alone, from one batch
    of perturbed lines."""
    M = len(lines)
    n = camera.interpretation_normals(lines)
    pert = _perturbed_lines(lines, px, deg)  # (4 + 2 + 2, M, 2, 2)
    n2 = camera.interpretation_normals(pert.reshape(-1, 2, 2)).reshape(8, M, 3)
    c = np.cross(n[None], n2)
    s = np.sqrt((c * c).sum(axis=-1))  # (8, M) sines of the turns
    ang = np.arcsin(np.clip(np.stack([s[:4].max(axis=0), s[4:6].max(axis=0), s[6:].max(axis=0)]), 0.0, 1.0))
    eps = ang * 1.05 + 1e-4
    return eps[0], eps[1], eps[2]


def vertical_residual(camera: Camera, normals: np.ndarray) -> np.ndarray:
    """(M,) ``|n . R e_z| = |ny cos p + nz sin p|``: zero when the interpretation
    plane contains the vertical direction, for every yaw (method.md section 6)."""
    p = camera.pitch
    return np.abs(normals[:, 1] * math.cos(p) + normals[:, 2] * math.sin(p))


def vertical_candidates(camera: Camera, normals: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """(M,) bool: lines that may be images of vertical edges (exact test,
    widened by each line's plane noise ``eps`` (M,))."""
    return vertical_residual(camera, normals) <= eps


def line_pieces(lines: np.ndarray, normals: np.ndarray, eps: np.ndarray, gap_px: float) -> np.ndarray:
    """(M, M) bool: may lines i and j (M, 2, 2) pixels be pieces of one line,
    broken where its contrast fades or something stands in front? Their
    interpretation planes (unit ``normals`` (M, 3)) agree within the sum of
    their noise bounds ``eps`` (M,) radians, and they do not overlap along
    the line by more than ``gap_px`` (the end points' noise). Such lines may
    show one model segment together; the diagonal is False."""
    M = len(lines)
    out = np.zeros((M, M), dtype=bool)
    if M < 2:
        return out
    # Planes within the noise: |cos| of the angle between the normals; rows
    # a block at a time, so that the float temporaries stay near
    # ``_PAIR_BLOCK`` entries however many lines there are.
    pairs = []
    rows = max(1, _PAIR_BLOCK // M)
    for r0 in range(0, M - 1, rows):
        r = slice(r0, min(r0 + rows, M))
        bound = np.cos(np.minimum(eps[r, None] + eps[None, :], 0.5 * np.pi))
        bi, bj = np.nonzero(np.triu(np.abs(normals[r] @ normals.T) >= bound, 1 + r0))
        pairs.append((bi + r0, bj))
    i = np.concatenate([p[0] for p in pairs])
    j = np.concatenate([p[1] for p in pairs])
    if not len(i):
        return out
    # Line j's span along line i, from i's first end point; i's own is [0, L].
    d = lines[i, 1] - lines[i, 0]
    length = np.hypot(d[:, 0], d[:, 1])
    d = d / np.maximum(length, 1e-12)[:, None]
    t = np.einsum("pek,pk->pe", lines[j] - lines[i, None, 0], d)  # (pairs, 2)
    overlap = np.minimum(t.max(axis=1), length) - np.maximum(t.min(axis=1), 0.0)
    keep = overlap <= gap_px
    out[i[keep], j[keep]] = True
    return out | out.T


def vertical_bearing(camera: Camera, lines: np.ndarray) -> np.ndarray:
    """(M,) bearing alpha, radians, of the vertical edge imaged by each line,
    positive to the right of the optical axis (horizon correction of
    method.md section 6: ``tan alpha = cos p (u_h - cx) / fx`` where the line
    meets the horizon row ``v_h = cy - fy tan p``)."""
    p = camera.pitch
    v_h = camera.cy - camera.fy * math.tan(p)
    a, b = lines[:, 0], lines[:, 1]
    dv = b[:, 1] - a[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (v_h - a[:, 1]) / dv
    u_h = np.where(np.abs(dv) > 1e-9, a[:, 0] + t * (b[:, 0] - a[:, 0]), 0.5 * (a[:, 0] + b[:, 0]))
    return np.arctan(math.cos(p) * (u_h - camera.cx) / camera.fx)


def bearing_noise(camera: Camera, lines: np.ndarray, px: float, deg: float) -> np.ndarray:
    """(M,) largest change of :func:`vertical_bearing` under the noise bounds."""
    M = len(lines)
    alpha = vertical_bearing(camera, lines)
    moved = vertical_bearing(camera, _perturbed_lines(lines, px, deg)[:4].reshape(-1, 2, 2)).reshape(4, M)
    return np.abs(moved - alpha).max(axis=0) * 1.05 + 1e-4


# --------------------------------------------------------------------------
# Unary constraint (non-vertical segments), method.md section 5


def unary_coefficients(normals: np.ndarray, directions: np.ndarray, pitch: float):
    """``A, B, G`` of ``A cos yaw + B sin yaw + G = n . R(yaw) v``, for every
    pair: normals (M, 3), directions (N, 3) -> three (N, M) arrays."""
    nx, ny, nz = (normals[None, :, k] for k in range(3))
    vx, vy, vz = (directions[:, None, k] for k in range(3))
    k = nz * math.cos(pitch) - ny * math.sin(pitch)
    m = ny * math.cos(pitch) + nz * math.sin(pitch)
    return k * vx - nx * vy, nx * vx + k * vy, -m * vz


def unary_yaws(normals: np.ndarray, directions: np.ndarray, pitch: float):
    """Both yaw solutions of ``n . R v = 0`` for every pair.

    Returns ``(yaw1, yaw2, slope)``, each (N, M): yaws in (-pi, pi] (NaN where
    ``|G| > sqrt(A^2 + B^2)``: no solution), and ``slope = sqrt(A^2+B^2-G^2)``,
    the rate of change of ``n . R v`` with yaw at the roots (small slope:
    poorly determined yaw)."""
    A, B, G = unary_coefficients(normals, directions, pitch)
    rad = np.hypot(A, B)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.arccos(np.clip(-G / rad, -1.0, 1.0))
    base = np.arctan2(B, A)
    none = (np.abs(G) > rad) | (rad < 1e-12)
    y1 = np.where(none, np.nan, wrap(base + c))
    y2 = np.where(none, np.nan, wrap(base - c))
    slope = np.sqrt(np.maximum(rad**2 - G**2, 0.0))
    return y1, y2, slope




def position_line(normal_world: np.ndarray, point: np.ndarray, height: float):
    """Floor-plane line ``a . (x, y) = d`` on which the camera must lie for the
    world point ``point`` (..., 3) to be in the plane of world normal
    ``normal_world`` (..., 3) = R^T n. Returns ``a`` (..., 2) and ``d`` (...)."""
    a = normal_world[..., :2]
    d = np.einsum("...k,...k->...", normal_world, point) - normal_world[..., 2] * height
    return a, d


def unary_constraint(
    camera: Camera,
    normals: np.ndarray,
    eps: np.ndarray,
    segments: np.ndarray,
    prior: tuple[float, float, float],
    dt: float,
    dyaw: float,
    model_m: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The paper's unary test on every pair (non-vertical segment i, image line j).

    ``normals`` (M, 3) unit, camera frame; ``eps`` (M,) plane noise of each
    line (radians); ``segments`` (N, 2, 3) world. A pair is acceptable if a
    yaw solution lies within ``dyaw`` of the prior yaw (widened by the yaw
    uncertainty ``eps / slope``) and, at that yaw, the position line meets the
    disk of radius ``dt`` around the prior position (widened by the plane
    noise times the distance to the segment, plus ``model_m``).

    Returns ``(ok (N, M) bool, yaw (N, M))``, yaw the accepted solution (NaN
    where none).
    """
    xe, ye, yaw_e = prior
    v = segments[:, 1] - segments[:, 0]
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    y1, y2, slope = unary_yaws(normals, v, camera.pitch)
    with np.errstate(divide="ignore"):
        dyaw_noise = np.minimum(np.arcsin(np.clip(eps[None, :] / np.maximum(slope, 1e-12), 0, 1)), math.pi)
    ce = np.array([xe, ye, camera.height_m])
    # Point of each segment's line nearest to the prior camera centre.
    t = np.einsum("nk,nk->n", ce - segments[:, 0], v)
    near = segments[:, 0] + t[:, None] * v
    reach = np.linalg.norm(near - ce, axis=1) + dt  # farthest the camera can be from it
    ok = np.zeros(y1.shape, dtype=bool)
    best = np.full(y1.shape, np.nan)
    for yaw in (y1, y2):
        yaw_ok = np.abs(wrap(yaw - yaw_e)) <= dyaw + dyaw_noise
        yaw_c = np.where(yaw_ok, yaw_e + np.clip(wrap(yaw - yaw_e), -dyaw, dyaw), yaw_e)
        w = world_normals(normals, yaw_c, camera.pitch)  # (N, M, 3) R^T n
        a, d = position_line(w, near[:, None, :], camera.height_m)
        na = np.linalg.norm(a, axis=-1)
        dist = np.abs(a[..., 0] * xe + a[..., 1] * ye - d)  # residual at the disk centre
        slack = (eps[None, :] + np.abs(wrap(yaw - yaw_c))) * reach[:, None] + model_m
        meets = dist <= na * dt + slack
        hit = yaw_ok & meets & ~np.isnan(yaw)
        best = np.where(hit & ~ok, yaw, best)
        ok |= hit
    return ok, best


# --------------------------------------------------------------------------
# Binary constraint (vertical segments), method.md section 6

def binary_constraint(
    points_i: np.ndarray,
    points_k: np.ndarray,
    alpha_i: np.ndarray,
    alpha_k: np.ndarray,
    centre: tuple[float, float],
    dt: float,
    tol: np.ndarray,
) -> np.ndarray:
    """The paper's binary test on couples of vertical correspondences.

    For couples ``(L_i - l_i, L_k - l_k)`` with floor points ``points_i``,
    ``points_k`` (C, 2) and edge bearings ``alpha_i``, ``alpha_k`` (C,)
    (positive to the right, from :func:`vertical_bearing`), the camera sees
    ``P_k`` at ``rho = alpha_i - alpha_k`` counter-clockwise of ``P_i``; the
    positions doing so form an arc through both points (inscribed angle),
    on the side that keeps the left/right order. The couple is acceptable if
    that arc, widened by ``tol`` (C,) radians, meets the disk of radius
    ``dt`` around ``centre``. Returns (C,) bool.

    In closed form: with floor points as complex numbers relative to the
    centre (``a = P_i - c``, ``b = P_k - c``, camera ``z``), the angle is
    ``arg w`` with ``w = (b - z) / (a - z)``. That Moebius map takes the
    disk's circle to a circle of centre ``w0`` (the image of the point
    mirroring ``a`` in the circle, ``dt^2 / conj(a)``) and radius ``r``; when
    neither point is in the disk the angle is continuous there and harmonic,
    so over the disk it spans ``arg w0 +- asin(r / |w0|)``, the args of that
    image circle.
    """
    c = complex(centre[0], centre[1])
    a = points_i[:, 0] + 1j * points_i[:, 1] - c
    b = points_k[:, 0] + 1j * points_k[:, 1] - c
    rho = alpha_i - alpha_k
    inside = np.minimum(np.abs(a), np.abs(b)) <= dt * 1.0001  # a point in the disk: every angle occurs
    with np.errstate(divide="ignore", invalid="ignore"):
        mirror = dt * dt / np.conj(a)
        w0 = (b - mirror) / (a - mirror)
        r = np.abs((b - dt) / (a - dt) - w0)  # dt: any point of the circle
        half = np.arcsin(np.clip(r / np.abs(w0), 0.0, 1.0))
    return inside | (np.abs(wrap(np.angle(w0) - rho)) <= half + tol)
