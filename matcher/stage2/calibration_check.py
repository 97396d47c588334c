"""Stage 2: do the accepted pose's matched lines say the camera file is wrong?

A camera file whose focal length or height is off still lets stage 2 find a
pose whose lines fit their segments within their noise bounds: the pose
moves to make up for the calibration (a focal length 20 % too short puts
the camera half a metre too close, with standard deviations of a few
centimetres). What it cannot make up for whole is the shape of the lines:
the floor and ceiling lines, the vertical edges across the image, tell the
focal length and the height apart from the pose when they are spread
enough.

So, on the best pose's matches, the pose is fitted again on the same
image-side residuals as :mod:`matcher.stage2.refine`'s (weighted by their
noise as :func:`matcher.stage2.covariance.pose_information` weighs them:
the line's offset and its turn, in pixels over their bounds), first at the
file's calibration and then with one calibration parameter free at a time:
the focal length's scale (fx and fy alike), the camera height, the
principal point's row (the column is a turn of the camera to within a
pixel, which the yaw takes up: not judged by default,
``VerdictConstants.calibration_judged``). A parameter that lowers the
residuals far more than one more free parameter lowers them by chance
(chi-square with one degree of freedom, and an F-like ratio against what
is left, so that a misfit it does not explain is not blamed on it), whose
estimate is off by more than a calibration usually is, and whose pose lies
within the prior bounds (wrong matches, a jamb's near face for its far
one, are made up for by a focal length too, at a pose far away; in lost
mode, which has no bounds, anywhere the robot can stand), names the
calibration as the likely fault. :func:`matcher.verdict.decide` then
refuses the pose.

Cost: one Jacobian at the accepted pose picks the parameters worth a full
fit (:func:`screened`; on right cameras almost never any), a fraction of a
millisecond; run on the accepted answer only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from matcher.prior import within_prior
from matcher.stage2 import refine
from matcher.stage2.covariance import pose_spread

#: The calibration parameters tried, in order: the focal length's scale
#: (fx and fy alike, 1 = the file's), the camera height's offset (metres),
#: the principal point's offsets (pixels; column, row).
PARAMETERS = ("focal", "height", "cx", "cy")


@dataclass(frozen=True)
class Where:
    """Where the pose refitted with a calibration parameter free may lie for
    that parameter to be blamed: within the ``prior`` bounds ``(xe, ye,
    yaw_e, dt, dyaw)`` (radians; None: no bounds) and, with ``free`` (a
    :class:`~matcher.map_geometry.freespace.FreeSpace`), where the robot can
    stand, and with ``sees`` (``(x, y, r) -> bool``, metres: within ``r`` of
    the point) where the matched
    segments are in sight. A prior's search gives its bounds; lost mode,
    which searches the whole map piece by piece, the free space and the
    sight of the matched segments (a wrong focal length moves the pose
    metres, out of the piece searched; wrong matches made up for by a focal
    length put it where those segments are not in view)."""

    prior: tuple | None = None
    free: object | None = None
    sees: object | None = None


def _where(prior) -> Where:
    """``prior`` as a :class:`Where`: a Where, bounds (a tuple) or None (anywhere)."""
    return prior if isinstance(prior, Where) else Where(prior, None)


def _file_calibration() -> np.ndarray:
    """The file's calibration in the fits' terms: scale 1, no offsets."""
    return np.array([1.0, 0.0, 0.0, 0.0])


@dataclass(frozen=True)
class CalibrationFit:
    """The fit with one calibration parameter ``name`` (:data:`PARAMETERS`)
    free: its estimate ``value`` (a focal scale; metres; pixels), its
    standard deviation ``std``, the pose there ``(x, y, yaw_deg)``, and the
    fit's sums of squared noise-weighted residuals at the file's
    calibration (``rss_file``) and with the parameter free (``rss``) over
    ``n`` residuals."""

    name: str
    value: float
    std: float
    pose: tuple
    rss_file: float
    rss: float
    n: int
    #: The pose's spread there (:func:`~matcher.stage2.covariance.pose_spread`:
    #: metres along its worst-fixed direction, radians), the calibration free.
    spread: np.ndarray | None = None

    @property
    def drop(self) -> float:
        """How much freeing the parameter lowered the sum of squares (chi-square, one degree of freedom)."""
        return self.rss_file - self.rss

    @property
    def ratio(self) -> float:
        """The drop over the residual variance left (an F ratio, 1 and n - 4 degrees of freedom)."""
        return self.drop / max(self.rss / max(self.n - 4, 1), 1e-12)

    def off_by(self, camera) -> str:
        """The words for how far the calibration is off."""
        if self.name == "focal":
            return f"a focal length {self.value:.2f} x the camera file's (fx {camera.fx * self.value:.0f} px)"
        if self.name == "height":
            side = "lower" if self.value < 0 else "higher"
            return f"a camera height {abs(self.value):.2f} m {side} ({camera.height_m + self.value:.2f} m)"
        axis = "column" if self.name == "cx" else "row"
        base = camera.cx if self.name == "cx" else camera.cy
        return f"a principal point {axis} {self.value:+.0f} px off the camera file's ({base + self.value:.0f} px)"


class MatchedLines:
    """The best pose's matches, ready for the fits: image lines (T, 2, 2)
    pixels, their segments (T, 2, 3) metres, and the weights that turn the
    residuals (sines, :func:`matcher.stage2.refine.residuals`) into the
    line's offset and turn over their noise bounds (as
    :func:`matcher.stage2.covariance.pose_information`)."""

    def __init__(self, camera, lines: np.ndarray, segments: np.ndarray, tol) -> None:
        self.camera, self.lines = camera, np.asarray(lines, dtype=float)
        self.seg_a, self.seg_b = segments[:, 0], segments[:, 1]
        d = self.lines[:, 1] - self.lines[:, 0]
        length = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)
        p = camera.pixel_rays(self.lines)  # (T, 2, 3)
        n = camera.interpretation_normals(self.lines)  # (T, 3)
        dp_x, dp_y = -d[:, 1] / (length * camera.fx), d[:, 0] / (length * camera.fy)
        per_px = (n[:, 0] * dp_x + n[:, 1] * dp_y)[:, None] / np.linalg.norm(p, axis=2)  # (T, 2)
        per_px = np.where(np.abs(per_px) > 1e-12, per_px, 1e-12)
        sigma_off = tol.line_px / math.sqrt(3.0)
        sigma_turn = math.tan(math.radians(tol.line_deg)) * 0.5 * length / math.sqrt(3.0)  # (T,)
        self.w_mean = 0.5 / (per_px * sigma_off)  # (T, 2): end point -> the offset's weighted share
        self.w_diff = 0.5 / (per_px * sigma_turn[:, None])
        self.hyp = np.zeros(len(self.lines), dtype=np.int64)
        # The fits ask for the same calibration over and over (the file's,
        # for every camera of a rig but the one whose calibration is free)
        # and for the same pose twice (with a parameter bumped): what
        # depends on the calibration alone is kept per calibration, and the
        # last answer per pose and calibration (:meth:`weighted`).
        self._terms: dict[tuple, refine.MatchTerms] = {}
        self._last: tuple | None = None  # ((pose, calibration), residuals, derivatives or None)

    def __len__(self) -> int:
        return len(self.lines)

    def weighted(self, pose: np.ndarray, calib: np.ndarray, jacobian: bool = False):
        """(2T,) noise-weighted residuals at ``pose`` (3,) (x, y, yaw radians)
        and calibration ``calib`` (4,) (:data:`PARAMETERS`), and with
        ``jacobian`` their (2T, 3) derivatives in the pose. Read only: the
        arrays are kept for the next call at the same pose and calibration."""
        key = (np.asarray(pose, dtype=float).tobytes(), tuple(float(v) for v in calib))
        last = self._last
        if last is not None and last[0] == key and (last[2] is not None or not jacobian):
            return (last[1], last[2]) if jacobian else last[1]
        out = refine.residuals(np.asarray(pose, dtype=float)[None], self.hyp, self._terms_at(key[1]), jacobian)
        r, J = (self._whiten(out[0]), self._whiten(out[1])) if jacobian else (self._whiten(out), None)
        for a in (r, J):
            if a is not None:
                a.flags.writeable = False
        self._last = (key, r, J)
        return (r, J) if jacobian else r

    def _terms_at(self, calib: tuple) -> refine.MatchTerms:
        """The :class:`~matcher.stage2.refine.MatchTerms` of the matches at
        calibration ``calib`` (4,), made once per calibration (the few a
        fit's iterations ask for again; the file's always)."""
        terms = self._terms.get(calib)
        if terms is None:
            cam = self.camera
            s, dh, dcx, dcy = calib
            rays = np.empty(self.lines.shape[:2] + (3,))
            rays[..., 0] = (self.lines[..., 0] - cam.cx - dcx) / (s * cam.fx)
            rays[..., 1] = (self.lines[..., 1] - cam.cy - dcy) / (s * cam.fy)
            rays[..., 2] = 1.0
            rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
            terms = refine.MatchTerms(self.seg_a, self.seg_b, rays[:, 0], rays[:, 1], cam.pitch, cam.height_m + dh)
            if len(self._terms) >= 8:  # a fit's free parameter takes a new value every iteration
                self._terms = {k: v for k, v in self._terms.items() if k == tuple(_file_calibration())}
            self._terms[calib] = terms
        return terms

    def _whiten(self, r: np.ndarray) -> np.ndarray:
        """Residuals (T, 2[, k]) of the two end points -> (2T[, k]): offset, then turn, over their noise."""
        w_m, w_d = (w.reshape(w.shape + (1,) * (r.ndim - 2)) for w in (self.w_mean, self.w_diff))
        return np.concatenate([(r[:, 0] * w_m[:, 0] + r[:, 1] * w_m[:, 1]),
                               (r[:, 0] * w_d[:, 0] - r[:, 1] * w_d[:, 1])])


def fit(data: MatchedLines, pose: np.ndarray, free: int | None, work):
    """Gauss-Newton from ``pose`` (3,) with the calibration parameter
    ``free`` (an index into :data:`PARAMETERS`; None: the file's calibration
    throughout). Returns ``(pose (3,), calib (4,), rss, cov)``: the sum of
    squared weighted residuals at the end and the covariance (k, k) of the
    pose and the free parameter (inf where the lines do not fix them). ``work``: the iterations and finite-difference steps
    (:class:`~matcher.tolerances.VerdictConstants`)."""
    pose, calib = np.array(pose, dtype=float), _file_calibration()
    steps = work.calibration_steps
    k = 3 if free is None else 4
    A = np.eye(k)
    for _ in range(work.calibration_iterations):
        z, J = data.weighted(pose, calib, jacobian=True)
        if free is not None:
            bumped = calib.copy()
            bumped[free] += steps[free]
            J = np.column_stack([J, (data.weighted(pose, bumped) - z) / steps[free]])
        A = J.T @ J
        step = np.linalg.solve(A + np.diag(1e-9 + 1e-9 * np.diag(A)), J.T @ z)
        pose -= step[:3]
        if free is not None:
            calib[free] -= step[3]
    z = data.weighted(pose, calib)
    try:
        cov = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        cov = np.full((k, k), math.inf)
    return pose, calib, float(z @ z), cov


def screened(data: MatchedLines, pose: np.ndarray, judged, work) -> np.ndarray:
    """(K,) per calibration parameter of ``judged`` (indices into
    :data:`PARAMETERS`) how much freeing it lowers the sum of squared
    weighted residuals, to first order about ``pose`` (one Jacobian: the
    pose's analytic, the parameters' by finite differences). Cheap: it
    picks which parameters are worth a full fit (:func:`fit`)."""
    calib = _file_calibration()
    z, Jp = data.weighted(pose, calib, jacobian=True)
    cols = []
    for k in judged:
        bumped = calib.copy()
        bumped[k] += work.calibration_steps[k]
        cols.append((data.weighted(pose, bumped) - z) / work.calibration_steps[k])
    J = np.column_stack([Jp] + cols)  # (2T, 3 + K)
    A, b = J.T @ J, J.T @ z
    A[np.diag_indices_from(A)] *= 1.0 + 1e-9
    explained_pose = b[:3] @ _solve(A[:3, :3], b[:3])
    drops = np.zeros(len(cols))
    for i in range(len(cols)):
        sel = [0, 1, 2, 3 + i]
        drops[i] = b[sel] @ _solve(A[np.ix_(sel, sel)], b[sel]) - explained_pose
    return drops


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A^-1 b``, zeros where ``A`` is singular (the lines leave a direction free)."""
    try:
        return np.linalg.solve(A, b)
    except np.linalg.LinAlgError:
        return np.zeros_like(b)


def calibration_fits(camera, lines: np.ndarray, segments: np.ndarray, pose, tol, names=PARAMETERS) -> list:
    """One :class:`CalibrationFit` per parameter of ``names`` for matched
    image ``lines`` (T, 2, 2) and their ``segments`` (T, 2, 3) at the
    stage-2 pose ``pose`` (x, y, yaw radians): full fits, for the
    benchmark and the tests (:func:`miscalibration` fits only what
    :func:`screened` points at)."""
    return _fits(MatchedLines(camera, lines, segments, tol), pose, [PARAMETERS.index(n) for n in names], tol.verdict)


def _fits(data: MatchedLines, pose, free: list, work, at_file=None) -> list:
    """:func:`calibration_fits` of the parameters ``free`` (indices);
    ``at_file``, if given, a function giving :func:`fit` of ``data`` with no
    parameter free (shared by checks whose data differ only in which
    camera's calibration may change)."""
    base, _, rss_file, _ = fit(data, pose, None, work) if at_file is None else at_file()
    out = []
    for k in free:
        p, calib, rss, cov = fit(data, base, k, work)
        std = float(math.sqrt(max(cov[3, 3], 0.0))) if np.isfinite(cov).all() else math.inf
        out.append(CalibrationFit(PARAMETERS[k], float(calib[k]), std,
                                  (float(p[0]), float(p[1]), math.degrees(p[2])), rss_file, min(rss, rss_file),
                                  2 * len(data), pose_spread(cov[None, :3, :3])[0]))
    return out


def plausible(f: CalibrationFit, camera, work) -> bool:
    """Is the estimate one a camera file could be off by (a focal length
    within a factor ``calibration_max_focal`` of the file's, a height above
    the floor, a principal point inside the image)? Beyond, the lines do
    not fix the parameter and the fit ran off."""
    if f.name == "focal":
        return bool(np.isfinite(f.std)) and 1.0 / work.calibration_max_focal <= f.value <= work.calibration_max_focal
    if f.name == "height":
        return bool(np.isfinite(f.std)) and camera.height_m + f.value > 0.0
    size = camera.width if f.name == "cx" else camera.height
    return bool(np.isfinite(f.std)) and abs(f.value) < 0.5 * size


def miscalibration(camera, lines: np.ndarray, segments: np.ndarray, pose, tol, prior=None) -> list:
    """The calibration parameters the matched lines (``lines`` (T, 2, 2),
    ``segments`` (T, 2, 3), at ``pose`` (x, y, yaw radians)) say are wrong
    (:class:`CalibrationFit`, the clearest first; empty: none): those whose
    freeing lowers the residuals by ``calibration_min_drop`` or more,
    ``calibration_min_ratio`` times the variance left, and whose estimate
    is plausible (:func:`plausible`) and off by more than the parameter's
    least offset (:class:`~matcher.tolerances.VerdictConstants`), and
    whose pose there lies where ``prior`` allows (a :class:`Where`: lost
    mode's free space; or the prior's bounds ``(xe, ye, yaw_e, dt,
    dyaw)``, radians; None: anywhere; with the slack of
    :func:`matcher.prior.within_prior`, three of that pose's standard
    deviations where more, as stage 2 allows its poses): the true pose does, and a parameter
    that fits the lines only at a pose the prior excludes is making up for
    wrong matches (the near and far faces of a jamb taken one for the
    other), not for the calibration. Frames with fewer than ``calibration_min_lines``
    matches are not judged (too few residuals to tell a calibration from
    noise). Only the parameters whose first-order drop
    (:func:`screened`) reaches ``calibration_screen_share`` of the least
    drop are fitted in full."""
    if len(lines) < tol.verdict.calibration_min_lines or not tol.verdict.calibration_judged:
        return []
    return blamed_parameters(MatchedLines(camera, lines, segments, tol), camera, pose, tol, prior)


def blamed_parameters(data, camera, pose, tol, prior=None, at_file=None) -> list:
    """:func:`miscalibration` of prepared matches ``data`` (a
    :class:`MatchedLines`, or any object with its ``weighted`` and length:
    a rig's cameras' matches at one robot pose, :mod:`matcher.rig.calibration`)
    at ``pose``; ``camera`` the model whose bounds :func:`plausible` checks;
    ``at_file`` as :func:`_fits` takes it."""
    work = tol.verdict
    if len(data) < work.calibration_min_lines or not work.calibration_judged:
        return []
    pose = np.asarray(pose, dtype=float)
    judged = list(work.calibration_judged)
    drops = screened(data, pose, judged, work)
    worth = [k for k, d in zip(judged, drops) if d >= work.calibration_screen_share * work.calibration_min_drop]
    if not worth:
        return []
    file = _file_calibration()
    least = dict(focal=work.calibration_min_focal, height=work.calibration_min_height_m,
                 cx=work.calibration_min_centre_px, cy=work.calibration_min_centre_px)
    blamed = [f for f in _fits(data, pose, worth, work, at_file)
              if f.drop >= work.calibration_min_drop and f.ratio >= work.calibration_min_ratio and plausible(f, camera, work)
              and abs(f.value - file[PARAMETERS.index(f.name)]) >= least[f.name] and _inside(f, prior, tol)]
    return sorted(blamed, key=lambda f: -f.drop)


def _inside(f: CalibrationFit, prior, tol) -> bool:
    """Is the pose of fit ``f`` where ``prior`` (a :class:`Where`, bounds
    or None: anywhere) allows it?"""
    where = _where(prior)
    pose = np.array([[f.pose[0], f.pose[1], math.radians(f.pose[2])]])
    if where.prior is not None and not within_prior(pose, where.prior, None, tol, f.spread[None])[0]:
        return False
    if where.free is None:
        return True
    # As stage 2 allows its poses: the free space's margin, or three of the
    # pose's standard deviations where more (the fit with a calibration free
    # fixes the pose less well).
    slack = max(tol.free_space_m, tol.shared.prior_slack_sigmas * float(f.spread[0]))
    if not where.free.distance(pose[:, :2])[0] <= slack:
        return False
    return where.sees is None or where.sees(f.pose[0], f.pose[1], slack)


def doubt(camera, lines: np.ndarray, segments: np.ndarray, pose, tol, prior=None) -> str:
    """The failure's reason when the matched lines say the camera file is
    wrong (:func:`miscalibration`, where ``prior`` allows), naming each
    parameter that would fit them and the pose there; "" when they do not."""
    blamed = miscalibration(camera, lines, segments, pose, tol, prior)
    if not blamed:
        return ""
    x, y, yaw = blamed[0].pose
    alternatives = "".join(f", or with {f.off_by(camera)}" for f in blamed[1:])
    return (f"the matched lines fit the map far better with {blamed[0].off_by(camera)} (the pose would be "
            f"{x:.2f}, {y:.2f}, {yaw:.1f} deg){alternatives} than with the camera file's calibration: check the "
            f"camera calibration")
