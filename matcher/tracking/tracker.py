"""Following a moving robot: :class:`Tracker`.

Each frame, the prior is the last estimate moved by the odometry increment
since the frame before, and its search bounds are a few standard deviations
of the estimate (:class:`~matcher.tracking.odometry.Spread`), which grow with
the distance driven. A localised frame's pose is weighed against that
prediction by their spreads (a Kalman update): a frame that fixes the pose
well sets it, one that leaves decimetres barely moves it. The tracker is in one of three states:

- ``tracking``: this frame was localised from the odometry prior;
- ``coasting``: it was not; the estimate is the odometry's, its bounds grow;
- ``relocalising``: the tracker is lost (bounds past
  ``Tracking.max_dt_m``/``max_dyaw_deg``, ``max_failed_frames`` failures in a
  row on frames with lines enough to judge, or no prior at the start). It
  keeps the odometry's estimate and tries it within the largest bounds, and
  searches the map (lost mode, ``relocalise_budget_ms``, each search going
  on where the last stopped) for candidate poses, which it follows with the
  odometry. A candidate is trusted only once ``confirm_frames`` frames in a
  row have been localised from it and no other candidate explains them: one
  frame's word never moves the robot. The twins of a symmetric room are all
  followed until a frame tells them apart.

On a building (:class:`linemap.building.Building`) the tracker is on one
storey at a time: the prior's (``storey=``; a building of one mapped
storey needs no name), or, with no prior, the one lost mode finds
(searching every storey). It localises on that storey's map only and keeps
to it until it is relocalised on another (its candidates carry their
storey: a lift ride ends in a lost tracker that searches every storey);
each :class:`TrackedFrame` names the storey.

A robot with a camera rig (:class:`linemap.rig.Rig` where the camera goes)
gives each frame one set of lines per camera, in the rig's order; every
frame is localised through :func:`matcher.localize_rig` (from the prior,
the candidates) and :func:`matcher.localize_rig_global` (lost mode, a
whole search within ``relocalise_budget_ms`` each time), and the poses are
the robot's. A frame with lines for the wrong number of cameras is skipped
with its reason. A rig on a building is on one storey for the whole run
(``storey=``, or the building's only mapped storey), as a rig frame is
localised on one storey (``matcher localize --rig``): its lost mode
searches that storey.

Settings: :class:`matcher.tolerances.Tracking`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from linemap.building import Building
from linemap.camera import Camera
from linemap.errors import InputError
from linemap.rig import Rig
from matcher.building import search_storeys
from matcher.from_prior import localize
from matcher.lost import localize_global
from matcher.result import LocalizeResult
from matcher.rig import localize_rig, localize_rig_global
from matcher.tolerances import DEFAULT, TRACKING, Tolerances, Tracking
from matcher.tracking.odometry import Pose, Spread, compose, fuse, increment, wrap_deg

TRACKING_STATE, COASTING, RELOCALISING = "tracking", "coasting", "relocalising"


@dataclass
class TrackedFrame:
    """What the tracker made of one frame.

    ``ok`` is true when the frame was localised and the pose is trusted
    (state ``tracking``). ``estimate`` is the tracker's pose after the
    frame, ``(x, y, yaw_deg)``, whatever the state (the odometry's when
    coasting; None when lost with nothing to go on), and ``bounds`` its
    search bounds ``(dt m, dyaw deg)``. ``result`` is the frame's
    :class:`~matcher.result.LocalizeResult` (from the prior, or from the
    candidate or lost-mode search), None for a skipped frame;
    ``candidates`` the poses followed while relocalising."""

    t: float
    state: str
    ok: bool
    reason: str
    estimate: Pose | None
    bounds: tuple[float, float] | None
    result: LocalizeResult | None = None
    candidates: list[Pose] = field(default_factory=list)
    time_ms: float = 0.0
    #: The frame could not be used (its reason says why); the state is unchanged.
    skipped: bool = False
    #: On a building: the storey the tracker is on (None while lost with no estimate).
    storey: str | None = None
    #: On a building: the storey of each of ``candidates``.
    candidate_storeys: list[str] = field(default_factory=list)

    def __bool__(self) -> bool:
        return self.ok

    def to_dict(self) -> dict:
        """``matcher localize --json``'s shape plus ``t``, ``state``,
        ``estimate``, ``skipped`` and, while relocalising, ``candidates``
        (docs/architecture.md), and on a building ``storey`` (when known).
        ``pose`` is set only when ``ok``."""
        d = self.result.to_dict() if self.result is not None else {
            "ok": False, "pose": None, "pose_std": None, "score": None, "runner_up_score": None,
            "hypotheses": 0, "matches": [], "time_ms": {}, "out_of_time": False}
        if not self.ok:
            d.update(ok=False, pose=None, pose_std=None)
        d["reason"] = self.reason
        d["time_ms"] = {**d.get("time_ms", {}), "frame": round(self.time_ms, 3)}
        d["t"] = self.t
        d["state"] = self.state
        d["skipped"] = self.skipped
        d["estimate"] = None if self.estimate is None else {
            "x": self.estimate[0], "y": self.estimate[1], "yaw_deg": self.estimate[2],
            "dt": self.bounds[0], "dyaw_deg": self.bounds[1]}
        d.pop("candidates", None)
        d.pop("storey", None)  # the result's (a search's best) is not the tracker's
        if self.storey is not None:
            d["storey"] = self.storey
        if self.candidates:
            d["candidates"] = [{"x": c[0], "y": c[1], "yaw_deg": c[2]} for c in self.candidates]
            if self.candidate_storeys:
                for c, name in zip(d["candidates"], self.candidate_storeys):
                    c["storey"] = name
        return d


@dataclass
class _Candidate:
    """A pose found with no prior, followed until confirmed or dropped."""

    pose: Pose
    spread: Spread
    hits: int = 0
    misses: int = 0
    last: LocalizeResult | None = None
    #: On a building: the storey it is on.
    storey: str | None = None


class Tracker:
    """Localise a moving robot frame after frame with its odometry.

        >>> tracker = matcher.Tracker(linemap, camera, prior=(1.0, 2.0, 90.0), dt=0.3, dyaw=10)
        >>> for t, odom, lines in frames:
        ...     out = tracker.step(t, odom, lines)
        ...     print(out.state, out.estimate if out else out.reason)

    With no ``prior`` the tracker starts lost (``relocalising``). ``odom``
    is the robot's ``(x, y, yaw_deg)`` in the odometry's own frame; the
    camera is taken to turn about the robot's odometry point (mount it on
    the axis, or give the odometry of the camera). ``camera`` may be a
    :class:`~linemap.rig.Rig` (its mounts place the cameras about the
    robot's odometry point; each frame's ``lines`` then a list, one set a
    camera, and the poses the robot's). ``tolerances`` are the
    matcher's (:class:`~matcher.tolerances.Tolerances`), ``settings`` the
    tracker's (:class:`~matcher.tolerances.Tracking`). ``linemap`` may be a
    building, ``storey`` the name of the prior's storey (the module
    docstring)."""

    def __init__(self, linemap, camera: Camera | Rig, prior: Pose | None = None, dt: float | None = None,
                 dyaw: float | None = None, tolerances: Tolerances | None = None,
                 settings: Tracking | None = None, storey: str | None = None) -> None:
        #: The rig, or None for one camera (``camera``).
        self.rig = camera if isinstance(camera, Rig) else None
        self.camera = camera
        self.building = linemap if isinstance(linemap, Building) else None
        self.linemap, self.storey = self._storey_map(linemap, prior, storey)
        if self.rig is not None and self.building is not None:
            self.building = None  # a rig keeps to its storey: the map is that storey's
        self.tolerances = tolerances or DEFAULT
        self.settings = settings or TRACKING
        if prior is None:
            self.estimate, self.spread = None, None
            self.state = RELOCALISING
        else:
            if dt is None or dyaw is None:
                raise InputError("a tracker's prior needs its bounds dt (metres) and dyaw (degrees)")
            x, y, yaw = (float(v) for v in prior)
            if not all(math.isfinite(v) for v in (x, y, yaw, dt, dyaw)) or dt <= 0 or dyaw <= 0:
                raise InputError(f"prior must be finite with dt, dyaw > 0, got {prior}, {dt}, {dyaw}")
            self.estimate, self.spread = (x, y, wrap_deg(yaw)), Spread.of_bounds(dt, dyaw, self.settings)
            self.state = TRACKING_STATE
        self.failed = 0
        self._last_result, self._last_reason = None, ""
        # Lost mode's regions, largest first (per storey of a building: key
        # its name, else None); a search cut by its budget leaves the rest
        # for the next frame's.
        maps = {None: self.linemap} if self.building is None else {s.name: s.map for s in self.building.mapped}
        self._search_order = {k: np.argsort(-m.region_areas(), kind="stable").tolist() for k, m in maps.items()}
        self._search_from = dict.fromkeys(maps, 0)
        self.candidates: list[_Candidate] = []
        self.last_t: float | None = None
        self.last_odom: Pose | None = None

    def _storey_map(self, linemap, prior, storey: str | None) -> tuple:
        """The map the tracker starts on and its storey's name: the map
        itself (no storey), or on a building the prior's storey (None and
        no map until lost mode finds one, with no prior)."""
        if self.building is None:
            if storey is not None:
                raise InputError(f"storey={storey!r} names a storey of a building; this map is one floor (a .lmap)")
            return linemap, None
        if self.rig is not None:  # a rig is localised on one storey (matcher.cli_rig.one_floor)
            if storey is None and len(self.building.mapped) != 1:
                raise InputError("a rig on a building is tracked on one storey: give storey= "
                                 f"({', '.join(s.name for s in self.building.mapped)})")
            on = self.building.storey(storey) if storey is not None else self.building.mapped[0]
            return on.map, on.name
        if prior is None:
            if storey is not None:
                raise InputError("storey= names the prior's storey; with no prior the tracker searches every storey")
            return None, None
        on = self.building.storey(storey)
        return on.map, on.name

    def _on_storey(self, name: str | None) -> None:
        """Move the tracker to storey ``name`` of its building (nothing on a plain map)."""
        if self.building is not None and name is not None:
            self.linemap, self.storey = self.building.storey(name).map, name

    # ---- one frame -------------------------------------------------------
    def step(self, t: float, odom, lines) -> TrackedFrame:
        """Take one frame: time ``t`` (seconds), odometry ``odom`` (x, y,
        yaw_deg in the odometry frame) and image ``lines`` (M, 2, 2) or (M, 4)
        pixels (a rig's: a list of them, one a camera, in the rig's order).
        A frame that cannot be used (time going backwards, missing or
        invalid odometry or lines, lines for the wrong number of cameras)
        is skipped: the state stays and the returned frame says why."""
        t0 = time.perf_counter()
        why = self._unusable(t, odom) or self._not_the_rigs(lines)
        if why:
            return self._skipped(t, why, t0)
        odom = tuple(float(v) for v in odom)
        step = increment(self.last_odom, odom) if self.last_odom is not None else (0.0, 0.0, 0.0)
        self.last_t, self.last_odom = float(t), odom
        self._move(step)
        try:
            if self.estimate is not None:
                res = self._from_estimate(lines)
                if res is not None:
                    return self._out(t, True, "localised from the odometry prior", res, t0)
            if self.state == RELOCALISING:
                return self._relocalise(t, lines, t0)
            return self._out(t, False, f"not localised ({self._last_reason}); pose from odometry",
                             self._last_result, t0)
        except InputError as exc:  # the frame's lines: shapes, NaN, outside the image
            return self._skipped(t, str(exc), t0)

    def _skipped(self, t, why: str, t0: float) -> TrackedFrame:
        out = self._out(t, False, f"frame skipped: {why}", None, t0)
        out.skipped = True
        return out

    def _unusable(self, t, odom) -> str:
        try:
            t = float(t)
        except (TypeError, ValueError):
            return f"time stamp {t!r} is not a number"
        if not math.isfinite(t):
            return f"time stamp {t} is not finite"
        if self.last_t is not None and t < self.last_t:
            return f"time goes backwards ({t:.6f} s after {self.last_t:.6f} s)"
        try:
            vals = [float(v) for v in odom]
        except (TypeError, ValueError):
            return "no odometry (x, y, yaw_deg) for the frame"
        if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
            return f"odometry must be three finite numbers x, y, yaw_deg, got {odom!r}"
        return ""

    def _not_the_rigs(self, lines) -> str:
        """Why a rig's frame ``lines`` are not one set of lines per camera
        ('' when they are, and for one camera)."""
        rig = self.rig
        if rig is None:
            return ""
        if isinstance(lines, np.ndarray) or not isinstance(lines, (list, tuple)):
            return f"a rig's frame needs a list of lines per camera ({len(rig)}: {', '.join(rig.names)})"
        if len(lines) != len(rig):
            return (f"the frame has lines for {len(lines)} camera{'s' * (len(lines) != 1)}, the rig has {len(rig)} "
                    f"({', '.join(rig.names)}); give one set per camera, in the rig's order")
        return ""

    def _localize(self, linemap, lines, prior: Pose, dt: float, dyaw: float) -> LocalizeResult:
        """The frame localised from ``prior`` on ``linemap``: the camera's
        :func:`~matcher.localize` or the rig's :func:`~matcher.localize_rig`,
        the pose held only if its matches fix it (:func:`_fixed`)."""
        if self.rig is not None:
            return _fixed(localize_rig(linemap, self.rig, lines, prior, dt, dyaw, self.tolerances))
        return _fixed(localize(linemap, self.camera, lines, prior, dt, dyaw, self.tolerances))

    def _move(self, step: Pose) -> None:
        """Every pose the tracker holds moved by the odometry ``step``, its
        spread grown; lost once the estimate's bounds pass the limits (the
        estimate stays: it is still the odometry's best guess)."""
        if self.estimate is not None:
            self.estimate = compose(self.estimate, step)
            self.spread = self.spread.grown(step, self.settings)
            if self.spread.lost(self.settings):
                self.state = RELOCALISING
        for c in self.candidates:
            c.pose, c.spread = compose(c.pose, step), c.spread.grown(step, self.settings)

    def _from_estimate(self, lines) -> LocalizeResult | None:
        """Localise from the estimate; the accepted result (and the state
        tracking), or None with the failure counted. While relocalising,
        the bounds stop at ``max_dt_m``/``max_dyaw_deg`` and the pose must
        explain ``confirm_share`` of the lines: the estimate may be the
        odometry's of a robot carried away."""
        s = self.settings
        dt, dyaw = self.spread.bounds(s)
        dt, dyaw = min(dt, s.max_dt_m), min(dyaw, s.max_dyaw_deg)
        res = self._localize(self.linemap, lines, self.estimate, dt, dyaw)
        if res and (self.state != RELOCALISING or self._explains(len(res.matches), lines)):
            self._accept(res)
            return res
        self._last_result, self._last_reason = res, res.reason or (
            f"the pose explains {len(res.matches)} of {self._usable(lines)} lines, too few while lost")
        if not self._telling(lines):
            return None
        self.failed += 1
        if self.state == TRACKING_STATE:
            self.state = COASTING
        if self.failed >= s.max_failed_frames:
            self.state = RELOCALISING
        return None

    def _usable(self, lines) -> int:
        """Image lines at least ``Tolerances.min_line_px`` long (the lines
        passed ``localize``'s checks), over every camera of a rig."""
        n = 0
        for one in (lines if self.rig is not None else [lines]):
            try:
                arr = np.asarray(one, dtype=float).reshape(-1, 4)
            except (TypeError, ValueError):  # ragged or not numbers: the frame is skipped with this reason
                raise InputError("lines must be numbers: Expected shape (M, 2, 2) or (M, 4)") from None
            n += int((np.hypot(arr[:, 2] - arr[:, 0], arr[:, 3] - arr[:, 1]) >= self.tolerances.min_line_px).sum())
        return n

    def _telling(self, lines) -> bool:
        """Does the frame hold enough lines for a failure to count
        (``Tracking.judging_lines``)?"""
        return self._usable(lines) >= self.settings.judging_lines

    def _explains(self, matches: int, lines) -> bool:
        """Does a pose that matches ``matches`` lines explain enough of the
        frame to confirm a relocalisation (``Tracking.confirm_share``)?"""
        return matches >= self.settings.confirm_share * self._usable(lines)

    def _accept(self, res: LocalizeResult, predicted: bool = True) -> None:
        """Take an accepted frame: fused with the odometry's prediction
        (:func:`~matcher.tracking.odometry.fuse`), or, for a ``predicted=False``
        relocalisation, as it is."""
        measured = tuple(float(v) for v in res.pose)
        if predicted and self.estimate is not None:
            self.estimate, self.spread = fuse(self.estimate, self.spread, measured, res.pose_std, self.settings)
        else:
            self.estimate, self.spread = measured, Spread.of_accepted(res.pose_std, self.settings)
        self.state, self.failed, self.candidates = TRACKING_STATE, 0, []

    # ---- lost ------------------------------------------------------------
    def _relocalise(self, t: float, lines, t0: float) -> TrackedFrame:
        """Follow the candidates; confirm one, or search the map when none is left."""
        s = self.settings
        last = None
        for c in self.candidates:
            dt, dyaw = c.spread.bounds(s)
            on = self.linemap if c.storey is None else self.building.storey(c.storey).map
            c.last = res = self._localize(on, lines, c.pose, dt, dyaw)
            if res and not self._explains(len(res.matches), lines):
                res = LocalizeResult(False, f"the pose explains {len(res.matches)} of {self._usable(lines)} lines")
                c.last = None
            if res:
                c.pose, c.spread, c.hits, c.misses = tuple(res.pose), Spread.of_accepted(res.pose_std, s), c.hits + 1, 0
            elif self._telling(lines):  # a view of a bare wall neither confirms nor refutes
                c.misses += 1
            last = last or (res if res else None)
        self.candidates = [c for c in self.candidates
                           if c.misses < s.max_candidate_misses and not c.spread.lost(s)]
        self._merge_twins()
        hit = [c for c in self.candidates if c.misses == 0 and c.last is not None]
        if len(hit) == 1 and hit[0].hits >= s.confirm_frames:
            self._on_storey(hit[0].storey)
            self._accept(hit[0].last, predicted=False)
            return self._out(t, True, f"relocalised: confirmed by {hit[0].hits} frames", hit[0].last, t0)
        if hit:
            why = (f"{len(hit)} poses fit the views; waiting for a frame that tells them apart" if len(hit) > 1 else
                   f"relocalised pose awaiting confirmation ({hit[0].hits} of {s.confirm_frames} frames)")
            return self._out(t, False, why, hit[0].last, t0)
        if self.candidates:
            return self._out(t, False, "candidate poses not seen in this frame", None, t0)
        if not self._telling(lines):
            return self._out(t, False, f"lost; too few lines in this frame to search the map "
                                       f"(fewer than {s.judging_lines})", None, t0)
        return self._search_map(t, lines, t0)

    def _search_map(self, t: float, lines, t0: float) -> TrackedFrame:
        s = self.settings
        tol = replace(self.tolerances, time_budget_ms=min(self.tolerances.time_budget_ms, s.relocalise_budget_ms))
        orders = {k: o[self._search_from[k]:] + o[:self._search_from[k]] for k, o in self._search_order.items()}
        if self.rig is not None:  # a whole search each time: a rig's lost mode takes no region order
            res = localize_rig_global(self.linemap, self.rig, lines, tol)
            tried = {None: 0}
        elif self.building is None:
            res = localize_global(self.linemap, self.camera, lines, tol, regions=orders[None])
            tried = {None: int(res.time_ms.get("regions_tried", len(orders[None])))}
        else:  # every storey: the robot may have taken the stairs or a lift
            search = search_storeys(self.building, self.camera, lines, tol, regions=orders)
            res, tried = search.result, search.tried
        # The next search goes on where this one stopped.
        for k, n in tried.items():
            size = len(orders[k])
            self._search_from[k] = (self._search_from[k] + (n if n < size else 0)) % max(size, 1)
        found = [(tuple(res.pose), res.storey)] if res and self._explains(len(res.matches), lines) else [
            ((c["x"], c["y"], c["yaw_deg"]), c.get("storey")) for c in res.candidates
            if self._explains(int(c["matches"]), lines)]
        spread = Spread(s.accepted_std_floor_m, s.accepted_std_floor_deg)
        self.candidates = [_Candidate(p, spread, storey=name) for p, name in found[: s.max_candidates]]
        if not self.candidates:
            why = res.reason if not res else (f"its best pose explains {len(res.matches)} of "
                                              f"{self._usable(lines)} lines, too few to follow")
            return self._out(t, False, f"lost; the map search found nothing to follow ({why})", res, t0)
        return self._out(t, False, f"lost; the map search found {len(self.candidates)} pose(s), "
                                   f"to be confirmed by {s.confirm_frames} frames", res, t0)

    def _merge_twins(self) -> None:
        """Candidates that have converged on one pose are one (the one with more hits)."""
        kept: list[_Candidate] = []
        for c in sorted(self.candidates, key=lambda c: -c.hits):
            if not any(c.storey == k.storey and math.hypot(c.pose[0] - k.pose[0], c.pose[1] - k.pose[1])
                       < self.settings.min_dt_m and abs(wrap_deg(c.pose[2] - k.pose[2])) < self.settings.min_dyaw_deg
                       for k in kept):
                kept.append(c)
        self.candidates = kept

    # ---- output ------------------------------------------------------------
    def _out(self, t, ok: bool, reason: str, res, t0: float) -> TrackedFrame:
        bounds = None if self.estimate is None else self.spread.bounds(self.settings)
        followed = self.candidates if self.state == RELOCALISING else []
        return TrackedFrame(float(t) if _finite(t) else float("nan"), self.state, ok, reason, self.estimate, bounds,
                            res, [c.pose for c in followed], (time.perf_counter() - t0) * 1e3, storey=self.storey,
                            candidate_storeys=[c.storey for c in followed] if self.building is not None else [])


def _fixed(res: LocalizeResult) -> LocalizeResult:
    """``res``, or a falsy result when it is accepted but its matches do not
    fix the pose (no ``pose_std``: three vertical edges in a row, say): such a
    pose weighs nothing against the odometry's."""
    if res and res.pose_std is None:
        return LocalizeResult(False, "the matches do not fix the pose (no standard deviation)",
                              hypotheses=res.hypotheses, matches=res.matches, time_ms=res.time_ms)
    return res


def _finite(t) -> bool:
    try:
        return math.isfinite(float(t))
    except (TypeError, ValueError):
        return False
