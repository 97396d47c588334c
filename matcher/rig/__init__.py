"""A rig of cameras on one robot: one robot pose from every camera's lines.

- :mod:`matcher.rig.frame`: a frame's lines per camera, prepared, with each
  camera's view of the robot's prior;
- :mod:`matcher.rig.seeds`: each camera's own search (stage 1 and 2 of the
  single camera) gives seed poses of the robot;
- :mod:`matcher.rig.verify`: every seed verified on all cameras' lines
  (matches per camera, one robot pose fitted to all,
  :mod:`matcher.rig.joint_fit`), scored and ranked;
- :mod:`matcher.rig.localize`: the entry points and the verdict.
"""

from matcher.rig.localize import localize_rig, localize_rig_global

__all__ = ["localize_rig", "localize_rig_global"]
