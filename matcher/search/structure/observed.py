"""What a frame's lines say of the scene's structure, in the robot's frame.

Every camera's usable lines are taken to the robot's frame (robot at the
origin, heading 0) through its mount, so a rig or a panorama is one set of
observations and votes once:

- a **vertical line** (a vertical edge's candidate,
  :func:`matcher.search.tree.constraints.vertical_candidates`) is the bearing of
  a corner or jamb, ``mount yaw - alpha``, good to its bearing noise;
- any other line is taken as **level** in the world (most long lines of a
  room are: floor and ceiling junctions, door heads, sills): its plane's
  normal ``N`` (robot frame) gives its direction, ``N x e_z``, modulo a
  half turn, good to the plane noise over ``|N_xy|`` (a line near the
  horizon says nothing of its direction);
- the points of a level line below the horizon are **floor samples**: if
  the line is the wall's floor junction, the ray's depression says how far
  the wall is at that bearing (the camera height over its tangent); above
  the horizon, **ceiling samples**. One sample per bearing bin the line
  spans, each with its ray's elevation and the plane noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class Samples:
    """Rays of level lines: ``bearing`` (S,) robot frame, radians in [0, 2
    pi); ``elevation`` (S,) radians, up positive; ``eps`` (S,) its noise
    bound, radians; ``height`` (S,) the camera's height, metres; ``line``
    (S,) the line (index over the frame's cameras, in order); ``group``
    (S,) its camera's mount group; ``weight`` (S,) one over the samples of
    its bearing bin over the whole frame (so that a bin counts once
    however many cameras see it; :func:`binned`)."""

    bearing: np.ndarray
    elevation: np.ndarray
    eps: np.ndarray
    height: np.ndarray
    line: np.ndarray
    group: np.ndarray
    weight: np.ndarray

    def __len__(self) -> int:
        return len(self.bearing)

    def where(self, keep: np.ndarray) -> Samples:
        return Samples(*(getattr(self, f)[keep] for f in _FIELDS))

    def binned(self, bin_rad: float) -> Samples:
        """These samples with each one's ``weight`` one over the samples of
        its ``bin_rad`` bearing bin."""
        if not len(self):
            return self
        _, inverse, counts = np.unique(np.floor(self.bearing / bin_rad).astype(np.int64), return_inverse=True,
                                       return_counts=True)
        return replace(self, weight=1.0 / counts[inverse.ravel()])


_FIELDS = ("bearing", "elevation", "eps", "height", "line", "group", "weight")


@dataclass(frozen=True)
class Observed:
    """A frame's structure (module docstring): ``vertical`` (J,) bearings of
    the vertical lines, ``vertical_eps`` (J,) their noise, radians;
    ``level`` (L,) directions of the level lines modulo pi, ``level_eps``
    (L,) their noise, ``level_weight`` (L,) their lengths, pixels;
    ``floor`` and ``ceiling`` :class:`Samples`; ``lever`` the farthest
    camera from the robot's centre, metres (the grid takes the observations
    as seen from the centre); ``vertical_group`` (J,) each vertical line's
    mount group, ``mounts`` (G, 2) the groups' positions on the robot
    (forward, left), metres."""

    vertical: np.ndarray
    vertical_eps: np.ndarray
    level: np.ndarray
    level_eps: np.ndarray
    level_weight: np.ndarray
    floor: Samples
    ceiling: Samples
    lever: float
    vertical_group: np.ndarray
    mounts: np.ndarray

    def part(self, g: int) -> Observed:
        """Mount group ``g``'s observations alone, seen from its own
        position (no lever; the samples keep their whole-frame weights)."""
        v = self.vertical_group == g
        return replace(self, vertical=self.vertical[v], vertical_eps=self.vertical_eps[v],
                       floor=self.floor.where(self.floor.group == g), ceiling=self.ceiling.where(self.ceiling.group == g),
                       lever=0.0, vertical_group=self.vertical_group[v], mounts=self.mounts[g:g + 1])


def observe(views, bin_rad: float) -> Observed:
    """The :class:`Observed` of a rig frame's camera ``views``
    (:class:`~matcher.rig.frame.CameraView`), floor and ceiling samples one
    per ``bin_rad`` of bearing along each line."""
    vert, vert_eps, vert_group, level, level_eps, weight, samples = [], [], [], [], [], [], []
    offset = 0
    mounts, group = _mount_groups(views)
    for v, g in zip(views, group):
        lines, cam = v.lines, v.camera
        R = cam.world2cam(v.mount.yaw)  # robot frame to camera: the camera's heading on a robot at heading 0
        usable = lines.usable
        up = usable & lines.vertical
        vert.append(np.mod(v.mount.yaw - lines.alpha[up], 2 * math.pi))
        vert_eps.append(lines.alpha_eps[up])
        vert_group.append(np.full(int(up.sum()), g, np.int64))
        idx = np.flatnonzero(usable & ~lines.vertical)
        N = lines.normals[idx] @ R  # R^T n: the planes' normals in the robot frame
        nh = np.hypot(N[:, 0], N[:, 1])
        level.append(np.mod(np.arctan2(-N[:, 0], N[:, 1]), math.pi))
        level_eps.append(lines.eps[idx] / np.maximum(nh, 1e-9))
        weight.append(np.linalg.norm(lines.lines[idx, 1] - lines.lines[idx, 0], axis=1))
        rays = _samples(cam, R, lines.lines[idx], lines.eps[idx], idx + offset, bin_rad)
        samples.append(replace(rays, group=np.full(len(rays), g, np.int64)))
        offset += len(lines.lines)
    alls = Samples(*(np.concatenate([getattr(s, f) for s in samples]) for f in _FIELDS))
    lever = max((math.hypot(v.mount.x, v.mount.y) for v in views), default=0.0)
    floor = alls.where(alls.elevation < -alls.eps).binned(bin_rad)
    ceiling = alls.where(alls.elevation > alls.eps).binned(bin_rad)
    return Observed(np.concatenate(vert), np.concatenate(vert_eps), np.concatenate(level), np.concatenate(level_eps),
                    np.concatenate(weight), floor, ceiling, lever, np.concatenate(vert_group), mounts)


def _mount_groups(views) -> tuple[np.ndarray, list[int]]:
    """``(mounts (G, 2), group of each view)``: the distinct mount positions
    (forward, left, metres; to the millimetre) and each view's index among
    them (a panorama's views all share the centre)."""
    keys = [(round(v.mount.x, 3), round(v.mount.y, 3)) for v in views]
    distinct = list(dict.fromkeys(keys))
    return np.array(distinct, dtype=float).reshape(-1, 2), [distinct.index(k) for k in keys]


def _samples(camera, R: np.ndarray, lines: np.ndarray, eps: np.ndarray, ids: np.ndarray, bin_rad: float) -> Samples:
    """The rays of ``lines`` (L, 2, 2) pixels, one per ``bin_rad`` of the
    bearing each spans (at least two: its ends' neighbourhood), in the
    robot frame (``R`` the camera's rotation from it)."""
    if not len(lines):
        z, n = np.zeros(0), np.zeros(0, np.int64)
        return Samples(z, z, z, z, n, n, z)
    ends = camera.pixel_rays(lines) @ R  # (L, 2, 3)
    az = np.arctan2(ends[..., 1], ends[..., 0])
    span = np.abs(np.remainder(az[:, 1] - az[:, 0] + math.pi, 2 * math.pi) - math.pi)
    n = np.maximum(2, np.ceil(span / bin_rad).astype(np.int64))
    line = np.repeat(np.arange(len(lines)), n)
    t = (np.arange(len(line)) - np.repeat(np.cumsum(n) - n, n) + 0.5) / n[line]  # (S,) in (0, 1)
    uv = lines[line, 0] + t[:, None] * (lines[line, 1] - lines[line, 0])
    ray = camera.pixel_rays(uv) @ R
    bearing = np.mod(np.arctan2(ray[:, 1], ray[:, 0]), 2 * math.pi)
    elevation = np.arctan2(ray[:, 2], np.hypot(ray[:, 0], ray[:, 1]))
    return Samples(bearing, elevation, eps[line], np.full(len(line), camera.height_m), ids[line],
                   np.zeros(len(line), np.int64), np.ones(len(line)))
