"""Planar poses and odometry: composing increments, growing the estimate's spread.

A pose is ``(x, y, yaw_deg)``: metres in the map (or odometry) frame, yaw
counter-clockwise from +x in degrees, as everywhere in the matcher. The
odometry of a frame is the robot's pose in the odometry's own frame; only
the increment between two frames is used, so the odometry frame may be
anywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from linemap.geometry import wrap
from matcher.tolerances import Tracking

Pose = tuple[float, float, float]


def wrap_deg(a: float) -> float:
    """``a`` degrees wrapped to [-180, 180)."""
    return math.degrees(wrap(math.radians(a)))


def increment(odom_from: Pose, odom_to: Pose) -> Pose:
    """The motion from ``odom_from`` to ``odom_to`` in the frame of
    ``odom_from``: ``(forward m, left m, turn deg)``."""
    c, s = math.cos(math.radians(odom_from[2])), math.sin(math.radians(odom_from[2]))
    dx, dy = odom_to[0] - odom_from[0], odom_to[1] - odom_from[1]
    return (c * dx + s * dy, -s * dx + c * dy, wrap_deg(odom_to[2] - odom_from[2]))


def compose(pose: Pose, step: Pose) -> Pose:
    """``pose`` moved by ``step`` (forward, left, turn), as :func:`increment` gives it."""
    c, s = math.cos(math.radians(pose[2])), math.sin(math.radians(pose[2]))
    return (pose[0] + c * step[0] - s * step[1], pose[1] + s * step[0] + c * step[1], wrap_deg(pose[2] + step[2]))


@dataclass(frozen=True)
class Spread:
    """Standard deviations of a pose estimate: position (metres, radial)
    and heading (degrees)."""

    position_m: float
    yaw_deg: float

    def grown(self, step: Pose, settings: Tracking) -> Spread:
        """The spread after the odometry ``step``: the odometry's own error
        (a share of the distance, drift per metre and per degree turned),
        plus the sideways error the heading's spread makes over the
        distance. Added linearly: odometry errors are mostly systematic."""
        dist = math.hypot(step[0], step[1])
        yaw = self.yaw_deg + settings.odom_deg_per_m * dist + settings.odom_deg_per_deg * abs(step[2])
        sideways = dist * math.sin(math.radians(min(yaw, 90.0)))
        return Spread(self.position_m + settings.odom_distance_fraction * dist + sideways, yaw)

    def bounds(self, settings: Tracking) -> tuple[float, float]:
        """The search bounds ``(dt m, dyaw deg)`` of a frame: ``bound_sigmas``
        standard deviations, at least the settings' minimum."""
        k = settings.bound_sigmas
        return max(k * self.position_m, settings.min_dt_m), max(k * self.yaw_deg, settings.min_dyaw_deg)

    def lost(self, settings: Tracking) -> bool:
        """Are the bounds past what a search from a prior should cover?"""
        dt, dyaw = self.bounds(settings)
        return dt > settings.max_dt_m or dyaw > settings.max_dyaw_deg

    @classmethod
    def of_accepted(cls, pose_std, settings: Tracking) -> Spread:
        """The spread after an accepted frame: its ``pose_std`` (x, y,
        yaw_deg; None when the matches do not fix it), at least the floors."""
        if pose_std is None or not all(math.isfinite(v) for v in pose_std):
            return cls(settings.max_dt_m / settings.bound_sigmas, settings.max_dyaw_deg / settings.bound_sigmas)
        return cls(max(math.hypot(pose_std[0], pose_std[1]), settings.accepted_std_floor_m),
                   max(abs(pose_std[2]), settings.accepted_std_floor_deg))

    @classmethod
    def of_bounds(cls, dt: float, dyaw: float, settings: Tracking) -> Spread:
        """The spread whose bounds are ``dt``, ``dyaw`` (a user's prior)."""
        return cls(dt / settings.bound_sigmas, dyaw / settings.bound_sigmas)


def fuse(predicted: Pose, spread: Spread, measured: Pose, measured_std, settings: Tracking) -> tuple[Pose, Spread]:
    """The odometry's ``predicted`` pose (``spread``) and a frame's
    ``measured`` pose (standard deviations ``measured_std`` x, y, yaw_deg,
    at least the settings' floors; None: the floors) weighed by their
    variances, axis by axis, as a Kalman update with the identity
    measurement does: a frame that fixes the pose well moves the estimate
    to it, one whose few far lines leave decimetres barely moves it."""
    floor_m, floor_deg = settings.accepted_std_floor_m, settings.accepted_std_floor_deg
    if measured_std is None or not all(math.isfinite(v) for v in measured_std):
        measured_std = (floor_m, floor_m, floor_deg)
    sx, sy = max(measured_std[0], floor_m), max(measured_std[1], floor_m)
    syaw = max(abs(measured_std[2]), floor_deg)

    def weight(prior_sd: float, meas_sd: float) -> float:
        return prior_sd ** 2 / (prior_sd ** 2 + meas_sd ** 2)

    wx, wy, wyaw = weight(spread.position_m, sx), weight(spread.position_m, sy), weight(spread.yaw_deg, syaw)
    pose = (predicted[0] + wx * (measured[0] - predicted[0]), predicted[1] + wy * (measured[1] - predicted[1]),
            wrap_deg(predicted[2] + wyaw * wrap_deg(measured[2] - predicted[2])))
    s_pos = math.sqrt(1.0 / (1.0 / spread.position_m ** 2 + 1.0 / max(sx, sy) ** 2))
    s_yaw = math.sqrt(1.0 / (1.0 / spread.yaw_deg ** 2 + 1.0 / syaw ** 2))
    return pose, Spread(max(s_pos, floor_m), max(s_yaw, floor_deg))
