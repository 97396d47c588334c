"""Is a pose inside a prior set, the disk of positions and the interval of
headings a call was given (plus noise slack), and where the robot can stand?

Both stages ask: the resection of stage 1 of each pose it solves, stage 2 of
each refined pose.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.geometry import wrap


def within_prior(poses, prior, free, tol, spread=None) -> np.ndarray:
    """(H,) bool: poses (H, 3) within the prior bounds ``(xe, ye, yaw_e, dt,
    dyaw)`` (plus noise slack: ``prior_slack_m`` and ``prior_slack_deg``, or
    ``prior_slack_sigmas`` times the pose's standard deviations ``spread``
    (H, 2) (metres, radians; :func:`~matcher.stage2.covariance.pose_spread`)
    where more) and, with ``free``, within ``free_space_m`` of the map's
    regions (looked up only for the poses inside the prior)."""
    xe, ye, yaw_e, dt, dyaw = prior
    work = tol.shared
    slack_m, slack_yaw = work.prior_slack_m, math.radians(work.prior_slack_deg)
    if spread is not None:
        slack_m = np.maximum(slack_m, work.prior_slack_sigmas * spread[:, 0])
        slack_yaw = np.maximum(slack_yaw, work.prior_slack_sigmas * spread[:, 1])
    ok = np.hypot(poses[:, 0] - xe, poses[:, 1] - ye) <= dt + slack_m
    ok &= np.abs(wrap(poses[:, 2] - yaw_e)) <= dyaw + slack_yaw
    if free is not None and ok.any():
        at = np.nonzero(ok)[0]
        ok[at] = free.distance(poses[at, :2]) <= tol.free_space_m
    return ok
