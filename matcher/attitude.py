"""A frame's own pitch and roll, and its lines moved to the nominal camera.

A camera is rarely mounted exactly, and a robot rocks: a frame's pitch and
roll stray from the camera file's by up to a few of its ``pitch_std_deg``
and ``roll_std_deg``. A turn of the camera about its optical centre moves
image points by the homography ``K R_n R_a^T K^-1`` (``R_a`` the frame's
rotation, ``R_n`` the nominal one: the file's pitch, no roll), whatever the
scene: mapped through it, the lines are those of the nominal camera and the
whole matcher runs on them unchanged.

The frame's attitude comes in two steps:

1. From the lines alone (:func:`from_verticals`): the world's vertical seen
   from the camera, ``v = R_a e_z``, lies in the interpretation plane of
   every vertical edge's line; a robust least squares over the lines that
   may be vertical edges, the file's values as a Gaussian prior weighted
   by its standard deviations. It fixes the roll well; the pitch only from
   vertical lines far from the image centre, so little of it.
2. From the map (:func:`fit_on_matches`): after a first localisation with
   the tolerances widened by what step 1 left (:func:`widened`), the pose,
   pitch and roll are fitted together on the matched segments; the lines
   are moved again with that attitude and localised with the tolerances as
   they are (:func:`localize_with_attitude`).

With standard deviations 0 nothing is estimated: a fixed roll (or none)
is one homography (or none: the lines are the caller's, unchanged).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from linemap.camera import Camera, world2cam_rotation
from matcher.input_validation import check_lines
from matcher.search.tree.constraints import plane_noises
from matcher.tolerances import Tolerances


@dataclass(frozen=True)
class Attitude:
    """A frame's ``pitch`` and ``roll`` (radians) and how sure they are
    (standard deviations, radians)."""

    pitch: float
    roll: float
    pitch_std: float
    roll_std: float


def applies(camera) -> bool:
    """Does ``camera`` (a :class:`Camera` or anything, checked later) give a
    roll or leave its pitch and roll uncertain?"""
    return isinstance(camera, Camera) and bool(camera.roll_deg or camera.attitude_free)


def nominal(camera: Camera) -> Camera:
    """The camera the matcher works with: the file's pitch, no roll, exact."""
    if not (camera.roll_deg or camera.attitude_free):
        return camera
    return replace(camera, roll_deg=0.0, pitch_std_deg=0.0, roll_std_deg=0.0)


def of_file(camera: Camera) -> Attitude:
    """The camera file's attitude and standard deviations."""
    return Attitude(camera.pitch, camera.roll, math.radians(camera.pitch_std_deg), math.radians(camera.roll_std_deg))


def homography(camera: Camera, pitch: float, roll: float) -> np.ndarray:
    """(3, 3) pixels of a frame taken at ``pitch``, ``roll`` (radians) to
    pixels of the nominal camera (:func:`nominal`)."""
    Ra = world2cam_rotation(0.0, pitch, roll)
    Rn = world2cam_rotation(0.0, camera.pitch)
    K = camera.K
    return K @ Rn @ Ra.T @ np.linalg.inv(K)


def rectify(camera: Camera, lines: np.ndarray, att: Attitude) -> np.ndarray:
    """Lines (M, 2, 2) pixels of a frame at ``att`` as the nominal camera
    would see them."""
    H = homography(camera, att.pitch, att.roll)
    p = np.concatenate([lines, np.ones(lines.shape[:2] + (1,))], axis=-1) @ H.T
    return p[..., :2] / p[..., 2:3]


def _vertical_in_camera(pitch: float, roll: float):
    """The world's up-down axis in camera coordinates, ``R_a e_z`` (3,), and
    its derivatives in pitch and roll."""
    cp, sp, cr, sr = math.cos(pitch), math.sin(pitch), math.cos(roll), math.sin(roll)
    v = np.array([-sr * cp, -cr * cp, -sp])
    dp = np.array([sr * sp, cr * sp, -cp])
    dr = np.array([-cr * cp, sr * cp, 0.0])
    return v, dp, dr


def from_verticals(camera: Camera, lines: np.ndarray, tol: Tolerances) -> Attitude:
    """The frame's pitch and roll from its lines (M, 2, 2) pixels that may
    be vertical edges (step 1 of the module docstring): robust Gauss-Newton
    on ``n . v(pitch, roll)`` over the lines within the prior's reach, the
    file's values a Gaussian prior. The standard deviations are those of
    the estimate (the prior's where the lines fix nothing)."""
    work = tol.attitude
    prior = of_file(camera)
    if not camera.attitude_free or len(lines) == 0:
        return replace(prior, pitch_std=0.0, roll_std=0.0) if not camera.attitude_free else prior
    n = camera.interpretation_normals(lines)
    eps = plane_noises(camera, lines, tol.line_px, tol.line_deg)[0]
    sigma = np.maximum(eps * work.attitude_line_sigma, 1e-6)  # the bound as a standard deviation
    long_ = np.linalg.norm(lines[:, 1] - lines[:, 0], axis=1) >= tol.min_line_px
    sp_, sr_ = max(prior.pitch_std, 1e-9), max(prior.roll_std, 1e-9)
    v0 = _vertical_in_camera(prior.pitch, prior.roll)[0]
    reach = math.sin(min(work.attitude_sigmas * math.hypot(prior.pitch_std, prior.roll_std), 0.5 * math.pi))
    cand = long_ & (np.abs(n @ v0) <= eps + reach)
    x = np.array([prior.pitch, prior.roll])
    A = np.diag([1.0 / sp_**2, 1.0 / sr_**2])
    for _ in range(work.attitude_iterations):
        v, dp, dr = _vertical_in_camera(*x)
        r = (n[cand] @ v) / sigma[cand]
        J = np.stack([n[cand] @ dp, n[cand] @ dr], axis=1) / sigma[cand, None]
        c = work.attitude_robust_c
        w = 1.0 / (1.0 + (r / c) ** 2)  # Cauchy weights: a horizontal line that passes for vertical counts little
        rp = np.array([(x[0] - prior.pitch) / sp_, (x[1] - prior.roll) / sr_])
        Jp = np.diag([1.0 / sp_, 1.0 / sr_])
        A = (J * w[:, None]).T @ J + Jp.T @ Jp
        b = (J * w[:, None]).T @ r + Jp.T @ rp
        step = np.linalg.solve(A, b)
        x = x - step
        # Bound the estimate to the prior's reach: a few lines of clutter
        # must not carry it off.
        lim = work.attitude_sigmas * np.array([sp_, sr_])
        x = np.clip(x, [prior.pitch, prior.roll] - lim, [prior.pitch, prior.roll] + lim)
        if np.abs(step).max() < 1e-7:
            break
    cov = np.linalg.inv(A)
    return Attitude(float(x[0]), float(x[1]), float(math.sqrt(cov[0, 0])), float(math.sqrt(cov[1, 1])))


def widened(tol: Tolerances, camera: Camera, att: Attitude, sigmas: float) -> Tolerances:
    """The tolerances for lines moved with an attitude known to ``att``'s
    standard deviations: a pitch error moves the picture by ``fy tan(err)``
    pixels, a roll error turns it about the centre (by up to half the image
    diagonal times ``tan(err)`` pixels, and its lines' orientation by
    ``err``), each taken ``sigmas`` times."""
    if att.pitch_std == 0.0 and att.roll_std == 0.0:
        return tol
    half_diag = 0.5 * math.hypot(camera.width, camera.height)
    px = camera.fy * math.tan(sigmas * att.pitch_std) + half_diag * math.tan(sigmas * att.roll_std)
    return replace(tol, line_px=tol.line_px + px, line_deg=tol.line_deg + math.degrees(sigmas * att.roll_std))


def _match_residuals(params, camera: Camera, seg_a, seg_b, rays):
    """(T, 2) sines of the angles between the rays (T, 2, 3) of matched
    lines' end points (camera frame, unit) and the planes through the camera
    centre and their segments, at ``params`` = (x, y, yaw, pitch, roll)."""
    x, y, yaw, pitch, roll = params
    R = world2cam_rotation(yaw, pitch, roll)
    C = np.array([x, y, camera.height_m])
    m = np.cross(seg_a - C, seg_b - C)
    m /= np.linalg.norm(m, axis=1, keepdims=True)
    w = rays @ R  # R^T ray: world directions
    return np.einsum("tk,tek->te", m, w)


def fit_on_matches(camera: Camera, lines: np.ndarray, segments: np.ndarray, matches, pose, att: Attitude,
                   prior: Attitude, tol: Tolerances) -> tuple[tuple, Attitude, float]:
    """The pose ``(x, y, yaw)`` (radians), the attitude and the mean squared
    normalised residual fitted together on ``matches`` (pairs segment id,
    line index) from ``pose`` and ``att`` (step 2 of the module docstring):
    Gauss-Newton on the end points' residuals (each over the line's noise,
    ``line_px`` at the focal length) and ``prior`` (the estimate from the
    vertical lines, with its standard deviations) as a Gaussian prior. The
    standard deviations are the fit's."""
    work = tol.attitude
    seg_ids = np.array([s for s, _ in matches])
    line_ids = np.array([j for _, j in matches])
    rays = camera.pixel_rays(lines[line_ids])
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    sa, sb = segments[seg_ids, 0], segments[seg_ids, 1]
    sigma = tol.line_px / camera.fx
    sd = np.array([max(prior.pitch_std, 1e-9), max(prior.roll_std, 1e-9)])  # (0: an exact value, held)
    x = np.array([pose[0], pose[1], pose[2], att.pitch, att.roll], dtype=float)
    h = work.attitude_fit_step

    def stacked(p):
        r = _match_residuals(p, camera, sa, sb, rays).ravel() / sigma
        return np.concatenate([r, (p[3:] - [prior.pitch, prior.roll]) / sd])

    A = np.eye(5)
    for _ in range(work.attitude_fit_iterations):
        r = stacked(x)
        J = np.stack([(stacked(x + h * e) - r) / h for e in np.eye(5)], axis=1)
        A = J.T @ J + 1e-9 * np.eye(5)
        step = np.linalg.solve(A, J.T @ r)
        x = x - step
        if np.abs(step).max() < 1e-8:
            break
    r = stacked(x)
    cost = float((r[:-2] ** 2).mean())
    cov = np.linalg.pinv(A)
    out = Attitude(float(x[3]), float(x[4]), float(math.sqrt(max(cov[3, 3], 0.0))),
                   float(math.sqrt(max(cov[4, 4], 0.0))))
    return (float(x[0]), float(x[1]), float(x[2])), out, cost


@dataclass(frozen=True)
class Run:
    """One run of the matcher on a levelled frame (:func:`levelled`): its
    tolerances; ``quick``, a band's first run, which needs a few hypotheses
    near the truth rather than the best answer (an entry point runs its
    cheapest search that gives them); ``near``, ``(x, y, yaw_deg, dt,
    dyaw)``, a narrow prior around a first answer (:attr:`RerunPolicy.around_answer`),
    or None: the problem as asked."""

    tol: Tolerances
    quick: bool = False
    near: tuple | None = None


class Localiser(Protocol):
    """An entry point's search (:mod:`matcher.from_prior`, :mod:`matcher.lost`)
    on a frame levelled by :func:`levelled`, on the map whose ``segments``
    (N, 2, 3) it searches."""

    segments: np.ndarray

    def localize_levelled(self, camera: Camera, lines: np.ndarray, run: Run): ...


@dataclass(frozen=True)
class RerunPolicy:
    """How the second runs, on the lines moved with an attitude a first
    run's fit gave, search: ``around_answer``, a narrow prior around that
    fit's pose (``SharedConstants.lost_seed_m``, ``lost_seed_deg``: lost mode,
    whose problem as asked is the whole map), or else the problem as asked."""

    around_answer: bool = False


def levelled(camera: Camera, lines: np.ndarray, att: Attitude) -> tuple[Camera, np.ndarray]:
    """The problem as the nominal camera (:func:`nominal`) would pose it: that
    camera and the frame's lines (M, 2, 2) taken at ``att`` moved to it."""
    return nominal(camera), rectify(camera, lines, att)


def localize_with_attitude(camera: Camera, lines, tol: Tolerances, localiser: Localiser,
                           policy: RerunPolicy = RerunPolicy()):
    """Localise a frame whose camera file gives a roll or leaves the pitch
    and roll uncertain: each run levels the frame (:func:`levelled`) and
    has ``localiser`` search it.

    Exact attitude: one homography, one run. Otherwise quick runs over
    bands of pitch ``attitude_band_deg`` wide around
    :func:`from_verticals`' estimate (nearest first), each on the lines
    moved with its band's middle and the tolerances :func:`widened` by half
    a band; the pose, pitch and roll fitted on the matches of each run's
    best few hypotheses, one per attitude among those whose residuals fit;
    for at most ``attitude_second_runs`` of them, the lines moved with it
    and run again with the tolerances widened by ``attitude_sigmas`` of what
    its fit left (as ``policy`` says: around its pose, or as asked); the
    run accepted with most matches, then the least E, stands. Every run
    counts against the call's one ``time_budget_ms``. The result carries
    the attitude (``pitch_deg``, ``roll_deg``), refitted on its own matches
    when it has a pose."""
    t0 = time.perf_counter()
    arr = check_lines(lines, camera, tol)
    est = from_verticals(camera, arr, tol)
    if not camera.attitude_free:
        return _carrying(localiser.localize_levelled(*levelled(camera, arr, est), Run(tol)), est, t0)
    first, fits = _band_runs(camera, arr, tol, localiser, est, t0)
    if not fits:
        return _carrying(first, est, t0)
    best = _second_runs(camera, arr, tol, localiser, policy, est, fits, t0)
    if best is None:  # the budget was spent before any second run
        return _carrying(first, est, t0)
    return _carrying(*best, t0)


def _left(tol: Tolerances, t: Tolerances, t0: float) -> Tolerances | None:
    """``t`` with the time the budget of ``tol`` has left of a call started
    at ``t0`` (every run counts against the one ``time_budget_ms``), or
    None when none is left."""
    ms = tol.time_budget_ms - (time.perf_counter() - t0) * 1e3
    return replace(t, time_budget_ms=ms) if ms > 0 else None


def _band_runs(camera: Camera, arr: np.ndarray, tol: Tolerances, localiser: Localiser, est: Attitude,
               t0: float) -> tuple:
    """The first runs: bands of pitch ``attitude_band_deg`` wide over the
    estimate ``est``'s ``attitude_sigmas`` standard deviations, nearest
    first, each widened by half a band and what the vertical lines left of
    the roll. The first band's result and the fits (:func:`_fits`) of all."""
    work = tol.attitude
    band = math.radians(work.attitude_band_deg)
    k_max = int(math.ceil(max(work.attitude_sigmas * est.pitch_std / band - 0.5, 0.0)))
    fits, first = [], None
    for k in sorted(range(-k_max, k_max + 1), key=abs):
        att = replace(est, pitch=est.pitch + k * band, pitch_std=0.5 * band)
        wide = replace(widened(tol, camera, att, 1.0), max_nodes=min(tol.max_nodes, work.attitude_band_nodes),
                       max_hypotheses=min(tol.max_hypotheses, work.attitude_band_hypotheses))
        budgeted = _left(tol, wide, t0)
        if budgeted is None:
            if first is not None:  # the budget is spent: the bands run so far stand
                break
            # The first band runs whatever is left, as the strategy's first
            # source does: with none, it ends not localised, saying so.
            budgeted = replace(wide, time_budget_ms=0.0)
        res = localiser.localize_levelled(*levelled(camera, arr, att), Run(budgeted, quick=True))
        first = res if first is None else first
        fits += _fits(camera, arr, localiser.segments, res, att, est, tol)
    return first, _distinct(sorted(fits, key=lambda f: f[:2]), work.attitude_same_deg)[: work.attitude_second_runs]


def _second_runs(camera: Camera, arr: np.ndarray, tol: Tolerances, localiser: Localiser, policy: RerunPolicy,
                 est: Attitude, fits: list, t0: float) -> tuple | None:
    """Each attitude the ``fits`` give (a wrong set can fit too, with an
    attitude of its own): the lines moved with it, the tolerances widened
    by what its fit left; ``(result, attitude)`` of the run accepted with
    most matches, then the least E, with the attitude refitted on its
    matches; None when the budget left no time for any."""
    work = tol.attitude
    band = math.radians(work.attitude_band_deg)
    best = None
    for *_, att, p in fits:
        near = ((p[0], p[1], math.degrees(p[2]), tol.shared.lost_seed_m, tol.shared.lost_seed_deg)
                if policy.around_answer else None)
        # Widened by what the fit left, at most half a band (matches that
        # leave the pitch loose, vertical edges alone, came from a band).
        cap = 0.5 * band / work.attitude_sigmas
        loose = replace(att, pitch_std=min(att.pitch_std, cap), roll_std=min(att.roll_std, cap))
        budgeted = _left(tol, widened(tol, camera, loose, work.attitude_sigmas), t0)
        if budgeted is None:  # the budget is spent: the runs so far stand
            break
        res = localiser.localize_levelled(*levelled(camera, arr, att), Run(budgeted, near=near))
        if res:
            pose = (res.pose[0], res.pose[1], math.radians(res.pose[2]))
            att = fit_on_matches(camera, arr, localiser.segments, res.matches, pose, att, est, tol)[1]
        rank = (bool(res), len(res.matches), -(res.score if res.score is not None else math.inf))
        if best is None or rank > best[0]:
            best = (rank, res, att)
    return None if best is None else best[1:]


def _fits(camera: Camera, arr: np.ndarray, segments: np.ndarray, res, att: Attitude, prior: Attitude,
          tol: Tolerances) -> list:
    """``(-matches, cost, attitude, pose)`` fitted on the matches of each of
    the best ranked hypotheses of ``res`` whose residual stays within
    ``attitude_fit_cost``."""
    work = tol.attitude
    fits = []
    for E, matches, pose in res.ranked[: work.attitude_fit_keep]:
        if not math.isfinite(E) or len(matches) < tol.min_matches:
            continue
        p, fit, cost = fit_on_matches(camera, arr, segments, matches, (pose[0], pose[1], math.radians(pose[2])),
                                      att, prior, tol)
        if cost <= work.attitude_fit_cost:
            fits.append((-len(matches), cost, fit, p))
    return fits


def _distinct(fits: list, same_deg: float) -> list:
    """``fits`` less those within ``same_deg`` in pitch and roll of one before."""
    out, same = [], math.radians(same_deg)
    for f in fits:
        if all(abs(f[2].pitch - g[2].pitch) > same or abs(f[2].roll - g[2].roll) > same for g in out):
            out.append(f)
    return out


def _carrying(res, att: Attitude, t0: float):
    """``res`` with the frame's attitude, degrees, and the whole call's time."""
    return replace(res, pitch_deg=math.degrees(att.pitch), roll_deg=math.degrees(att.roll),
                   time_ms=replace(res.time_ms, total=(time.perf_counter() - t0) * 1e3))
