"""The camera rigs the tests and benchmarks use (:class:`linemap.rig.Rig`).

- :func:`ring_rig`: ``n`` identical pinhole cameras evenly around the
  robot, each on a circle of ``radius_m`` looking outwards (camera k at
  ``k * 360 / n`` degrees from the robot's heading, camera 0 looking
  ahead): the 2- and 4-camera rigs of robots that see all around.
"""

from __future__ import annotations

import math

from linemap.camera import Camera
from linemap.rig import Mount, Rig, RigCamera


def ring_rig(n: int, hfov_deg: float = 90.0, width: int = 640, height: int = 480, height_m: float = 1.2,
             pitch_deg: float = 0.0, radius_m: float = 0.1) -> Rig:
    """``n`` cameras ``cam0`` ... evenly around the robot, looking outwards:
    each an ideal pinhole of ``hfov_deg`` horizontal field of view,
    ``width`` x ``height`` pixels, at ``height_m`` above the floor and
    ``pitch_deg`` (positive down), ``radius_m`` from the robot's centre."""
    if n < 1:
        raise ValueError(f"a ring rig needs at least one camera, got {n}")
    camera = Camera.from_fov(hfov_deg, width, height, height_m, pitch_deg)
    cameras = []
    for k in range(n):
        yaw_deg = 360.0 * k / n
        if yaw_deg > 180.0:  # headings in (-180, 180], as the rig files write them
            yaw_deg -= 360.0
        a = math.radians(yaw_deg)
        cameras.append(RigCamera(f"cam{k}", camera, Mount(radius_m * math.cos(a), radius_m * math.sin(a), yaw_deg)))
    return Rig(tuple(cameras))
