"""Trajectories out: the TUM format that evaluation tools read.

One line per pose, ``t x y z qx qy qz qw``: seconds, metres, and the unit
quaternion of the robot body frame (x forward, z up), here a turn about z
by the heading. ``z`` is the camera's height (the pose is the camera's;
0 for a rig's, whose poses are the robot's on the floor), on a building
above the floor of the pose's storey (its elevation added).
"""

from __future__ import annotations

import math
from collections.abc import Iterable


def tum_line(t: float, x: float, y: float, yaw_deg: float, z: float = 0.0) -> str:
    """One TUM trajectory line for a planar pose."""
    half = math.radians(yaw_deg) / 2.0
    return f"{t:.6f} {x:.6f} {y:.6f} {z:.6f} 0 0 {math.sin(half):.9f} {math.cos(half):.9f}"


def tum_text(poses: Iterable[tuple[float, ...]], z: float = 0.0) -> str:
    """The TUM file of ``(t, x, y, yaw_deg)`` poses (or ``(t, x, y, yaw_deg,
    floor_m)``: the floor's elevation, metres, added to ``z``), with a comment header."""
    lines = ["# t x y z qx qy qz qw (seconds, metres; yaw about z)"]
    lines += [tum_line(*p[:4], z + (p[4] if len(p) > 4 else 0.0)) for p in poses]
    return "\n".join(lines) + "\n"
