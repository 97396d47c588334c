"""Synthetic frames for the paper's protocol (docs/method.md section 9).

A frame: a random camera pose in free space (inside a region of the map),
the model segments it sees (occluded by the map's walls, extruded to
``meta["wall_height"]``, clipped to the image and to the range the map's
lists were built for), uniform noise on each line's
orientation, offset and end points, random clutter lines, and a prior drawn
within the bounds of a PEQ. A rig's frame (:func:`make_rig_frame`) is one
robot pose seen by each camera of a :class:`~linemap.rig.Rig` at its own
pose, the one-camera rig's the frame above. ``python tools/simulate.py``
prints one frame (``--rig``: one a camera);
the baseline the paper sets out to beat is :mod:`mapkit_harness.baseline`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from linemap.camera import Camera
from linemap.rig import Mount, Rig
from matcher.map_geometry.occlusion import wall_edges
from matcher.search.tree.constraints import wrap

from mapkit_harness.visibility_oracle import longest_run, sight_blocked

#: The paper's pose estimation quality (PEQ) levels: level -> the prior's
#: bounds ``(dt, dyaw)`` (metres, degrees); a frame's prior is drawn within
#: them of the true pose (docs/method.md section 9).
PEQ = {1: (0.2, 10.0), 2: (0.4, 20.0), 3: (0.6, 30.0), 4: (0.8, 40.0), 5: (1.0, 50.0)}

#: What a PEQ is, for the tools' ``--peq`` help.
PEQ_HELP = ("PEQ: the paper's pose estimation quality level, how far the prior may be from the true pose "
            "(dt, dyaw): " + "; ".join(f"{k}: {dt:g} m / {dyaw:g} deg" for k, (dt, dyaw) in PEQ.items())
            + " (docs/method.md)")

#: The paper's camera; height and pitch are ours (the paper gives none).
PAPER_CAMERA = dict(width=640, height=480, fx=900.0, fy=900.0, cx=320.0, cy=240.0, height_m=1.2, pitch_deg=0.0)


def paper_camera(height_m: float = 1.2, pitch_deg: float = 0.0) -> Camera:
    return Camera.from_dict({**PAPER_CAMERA, "height_m": height_m, "pitch_deg": pitch_deg})


@dataclass
class Frame:
    """One simulated frame. ``lines`` (M, 2, 2) pixels; ``truth`` (M,) model
    segment id of each line, -1 for clutter; ``pose`` and ``prior`` are
    ``(x, y, yaw_deg)``."""

    pose: tuple[float, float, float]
    prior: tuple[float, float, float]
    dt: float
    dyaw: float
    lines: np.ndarray
    truth: np.ndarray
    #: The frame's own pitch and roll, degrees (the camera file's unless
    #: :func:`make_frame` drew them).
    pitch_deg: float = 0.0
    roll_deg: float = 0.0

    def true_matches(self) -> list[list[int]]:
        return sorted([int(s), j] for j, s in enumerate(self.truth) if s >= 0)


def _clip_to_frustum(segs: np.ndarray, camera: Camera, R: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The parts of segments ``segs`` (N, 2, 3) in front of the camera and
    inside the image pyramid: ``(ids (K,), parts (K, 2, 3))`` of the
    segments with a part; ``R`` (3, 3) world-to-camera rotation, ``C`` (3,)
    the camera centre, metres. Each segment clipped against the pyramid's
    half-spaces and the near plane in turn (Liang-Barsky), all at once."""
    p = (segs - C) @ R.T  # camera coords
    w, h = camera.width, camera.height
    # Half-spaces n . X + off >= 0 of the view pyramid, and the near plane.
    planes = [
        (np.array([camera.fx, 0.0, camera.cx]), 0.0),  # u >= 0
        (np.array([-camera.fx, 0.0, w - camera.cx]), 0.0),  # u <= w
        (np.array([0.0, camera.fy, camera.cy]), 0.0),  # v >= 0
        (np.array([0.0, -camera.fy, h - camera.cy]), 0.0),  # v <= h
        (np.array([0.0, 0.0, 1.0]), -0.05),  # 5 cm in front
    ]
    t0, t1 = np.zeros(len(segs)), np.ones(len(segs))
    inside = np.ones(len(segs), dtype=bool)
    for n, off in planes:
        fa, fb = (p[:, 0] * n).sum(axis=1) + off, (p[:, 1] * n).sum(axis=1) + off
        inside &= (fa >= 0) | (fb >= 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            cut = fa / (fa - fb)
        t0 = np.where(fa < 0, np.maximum(t0, cut), t0)
        t1 = np.where((fa >= 0) & (fb < 0), np.minimum(t1, cut), t1)
    ids = np.flatnonzero(inside & (t1 - t0 >= 1e-6))
    a, d = segs[ids, 0], segs[ids, 1] - segs[ids, 0]
    return ids, np.stack([a + t0[ids, None] * d, a + t1[ids, None] * d], axis=1)


def _seen_samples(c: np.ndarray, pts: np.ndarray, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """(K, S) bool: which of the samples ``pts`` (K, S, 2) along K parts
    the point ``c`` (2,) sees past the wall edges ``ea -> eb`` (E, 2)
    (:func:`sight_blocked`'s test, a part at a time: its samples' sight
    lines are tested against only the edges near them)."""
    seen = np.ones(pts.shape[:2], dtype=bool)
    for k in range(len(pts)):
        seen[k] = ~sight_blocked(c, pts[k], ea, eb)
    return seen


def map_range(linemap) -> float:
    """The range, metres, that the map's region lists were built with (its
    ``build`` record; no limit for a map without one). A segment seen only
    from farther is in no list: a frame that shows it would test the
    map's range, not the matcher. (The lists' minimum visible length is not
    applied: a region's list holds a segment that any of its points sees
    long enough, so a sliver in a frame is usually listed, and a line the
    lists lack is one more clutter line.)"""
    build = linemap.meta.get("build", {}) if isinstance(linemap.meta, dict) else {}
    return float(build.get("max_range", math.inf))


def visible_lines(linemap, camera: Camera, pose, min_px: float = 20.0, samples: int = 160):
    """Ideal image lines of the visible model segments at ``pose`` (x, y, yaw_deg).

    Returns ``(lines (n, 2, 2) pixels, segment ids (n,))``: the longest
    unoccluded run of each segment inside the image and within the map's
    range (:func:`map_range`, 3D distance from the camera centre), if at
    least ``min_px`` long."""
    x, y, yaw_deg = pose
    yaw = math.radians(yaw_deg)
    walls = wall_edges(linemap)
    ea, eb = walls if walls is not None else (np.zeros((0, 2)), np.zeros((0, 2)))
    c = np.array([x, y])
    centre = camera.centre(x, y)
    max_range = map_range(linemap)
    R = camera.world2cam(yaw)
    ids, parts = _clip_to_frustum(linemap.segments, camera, R, centre)
    t = np.linspace(0.0, 1.0, samples)
    pts = parts[:, 0, None] + t[None, :, None] * (parts[:, 1, None] - parts[:, 0, None])  # (K, S, 3)
    visible = _seen_samples(c, pts[..., :2], ea, eb) & (np.linalg.norm(pts - centre, axis=2) <= max_range)
    out, kept = [], []
    for i, vis, samples_of in zip(ids, visible, pts):
        if not vis.any():
            continue
        p3 = samples_of[list(longest_run(vis))]
        uv, z = camera.project(p3, x, y, yaw)
        if (z <= 0).any() or np.linalg.norm(uv[1] - uv[0]) < min_px:
            continue
        out.append(uv)
        kept.append(i)
    if not out:
        return np.zeros((0, 2, 2)), np.zeros(0, dtype=np.int64)
    return np.array(out), np.array(kept, dtype=np.int64)


def add_noise(lines: np.ndarray, rng, px: float, deg: float, end_px: float, camera: Camera) -> np.ndarray:
    """Uniform noise on the line parameters: rotation about the midpoint in
    [-deg, deg], offset along the normal in [-px, px], each end point moved
    along the line by [-end_px, end_px]; then clipped to the image."""
    a, b = lines[:, 0], lines[:, 1]
    mid = 0.5 * (a + b)
    d = b - a
    ln = np.linalg.norm(d, axis=1, keepdims=True)
    d = d / ln
    th = np.radians(rng.uniform(-deg, deg, len(lines)))
    c, s = np.cos(th), np.sin(th)
    d = np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], axis=1)
    nrm = np.stack([-d[:, 1], d[:, 0]], axis=1)
    mid = mid + rng.uniform(-px, px, (len(lines), 1)) * nrm
    ta = -0.5 * ln[:, 0] + rng.uniform(-end_px, end_px, len(lines))
    tb = 0.5 * ln[:, 0] + rng.uniform(-end_px, end_px, len(lines))
    out = np.stack([mid + ta[:, None] * d, mid + tb[:, None] * d], axis=1)
    out[..., 0] = np.clip(out[..., 0], 0, camera.width)
    out[..., 1] = np.clip(out[..., 1], 0, camera.height)
    return out


def clutter_lines(rng, n: int, camera: Camera, min_len: float = 30.0, max_len: float = 200.0) -> np.ndarray:
    """``n`` random lines inside the image (non-modelled objects)."""
    out = []
    while len(out) < n:
        m = rng.uniform([0, 0], [camera.width, camera.height])
        th = rng.uniform(0, np.pi)
        half = 0.5 * rng.uniform(min_len, max_len) * np.array([np.cos(th), np.sin(th)])
        a, b = m - half, m + half
        a = np.clip(a, 0, [camera.width, camera.height])
        b = np.clip(b, 0, [camera.width, camera.height])
        if np.linalg.norm(b - a) >= min_len:
            out.append([a, b])
    return np.array(out).reshape(-1, 2, 2)


def random_free_pose(linemap, rng, margin: float = 0.0):
    """(x, y, yaw_deg) uniform over the map's regions, yaw uniform."""
    pts = linemap.ring_points
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    while True:
        x, y = rng.uniform(lo, hi)
        if len(linemap.regions_at(x, y)):
            return float(x), float(y), float(rng.uniform(-180.0, 180.0))


def make_frame(linemap, camera: Camera, rng, peq: int, noise_px: float = 1.0, noise_deg: float = 1.0,
               end_px: float = 3.0, clutter: int = 3, min_seen: int = 5, max_seen: int = 9,
               roll_deg: float = 0.0, pitch_error_deg: float = 0.0) -> Frame:
    """A frame of the paper's protocol: a pose seeing ``min_seen`` to ``max_seen``
    segments (redrawn otherwise), noisy lines, clutter, a prior within PEQ bounds.

    ``roll_deg``, ``pitch_error_deg``: the frame's camera is rolled and its
    pitch off the camera file's by amounts drawn uniformly within these
    bounds, degrees (a camera not mounted exactly, a robot that rocks); with
    both 0 nothing is drawn (the frames are those of a level camera).

    The one-camera rig's frame of :func:`make_rig_frame` (the same draws)."""
    rig_frame = make_rig_frame(linemap, Rig.single(camera), rng, peq, noise_px, noise_deg, end_px, clutter,
                               min_seen, max_seen, roll_deg, pitch_error_deg)
    return rig_frame.cameras[0]


@dataclass
class RigFrame:
    """One robot pose seen by every camera of a rig. ``pose`` and ``prior``
    are the robot's ``(x, y, yaw_deg)``; ``cameras`` one :class:`Frame` a
    camera, in the rig's order, whose ``pose`` and ``prior`` are that
    camera's (the robot's through its mount: :func:`camera_pose`), with its
    lines, their truth and its own pitch and roll."""

    pose: tuple[float, float, float]
    prior: tuple[float, float, float]
    dt: float
    dyaw: float
    cameras: list[Frame]

    @property
    def lines(self) -> list[np.ndarray]:
        """Each camera's lines (M_c, 2, 2) pixels."""
        return [f.lines for f in self.cameras]


def camera_pose(mount: Mount, pose) -> tuple[float, float, float]:
    """The ``(x, y, yaw_deg)`` of a camera on ``mount`` when the robot is at
    ``pose`` ``(x, y, yaw_deg)`` (a camera at the robot's centre: ``pose`` itself,
    exactly)."""
    if mount.at_centre:
        return pose
    x, y, _ = mount.camera_poses(np.array([pose[0], pose[1], math.radians(pose[2])]))
    return float(x), float(y), float(math.degrees(wrap(math.radians(pose[2] + mount.yaw_deg))))


def make_rig_frame(linemap, rig: Rig, rng, peq: int, noise_px: float = 1.0, noise_deg: float = 1.0,
                   end_px: float = 3.0, clutter: int = 3, min_seen: int = 5, max_seen: int | None = None,
                   roll_deg: float = 0.0, pitch_error_deg: float = 0.0) -> RigFrame:
    """A rig's frame: a robot pose at which the cameras together see at
    least ``min_seen`` (and at most ``max_seen``, None: any number) map
    segments (redrawn otherwise), each camera's lines at its own pose
    (:func:`visible_lines`) with the noise and ``clutter`` lines of
    :func:`make_frame`, and one prior of the robot within PEQ bounds.

    ``roll_deg``, ``pitch_error_deg``: each camera's roll and pitch drawn
    within these bounds of its file's, as :func:`make_frame` does."""
    dt, dyaw = PEQ[peq]
    real = [_drawn_attitude(rc.camera, rng, roll_deg, pitch_error_deg) for rc in rig]
    while True:
        pose = random_free_pose(linemap, rng)
        seen = [visible_lines(linemap, cam, camera_pose(rc.mount, pose)) for rc, cam in zip(rig, real)]
        n = sum(len(ids) for _, ids in seen)
        if min_seen <= n and (max_seen is None or n <= max_seen):
            break
    observed = [_observed(ideal, ids, rng, rc.camera, noise_px, noise_deg, end_px, clutter)
                for rc, (ideal, ids) in zip(rig, seen)]
    r = dt * math.sqrt(rng.uniform())
    phi = rng.uniform(0, 2 * math.pi)
    prior = (pose[0] + r * math.cos(phi), pose[1] + r * math.sin(phi),
             float(math.degrees(wrap(math.radians(pose[2] + rng.uniform(-dyaw, dyaw))))))
    frames = [Frame(camera_pose(rc.mount, pose), camera_pose(rc.mount, prior), dt, dyaw, lines, truth,
                    cam.pitch_deg, cam.roll_deg) for rc, cam, (lines, truth) in zip(rig, real, observed)]
    return RigFrame(pose, prior, dt, dyaw, frames)


def _drawn_attitude(camera: Camera, rng, roll_deg: float, pitch_error_deg: float) -> Camera:
    """The frame's real camera: rolled and pitched within the bounds of the
    file's (nothing drawn when both are 0)."""
    if not (roll_deg or pitch_error_deg):
        return camera
    roll = camera.roll_deg + float(rng.uniform(-roll_deg, roll_deg))
    pitch = camera.pitch_deg + float(rng.uniform(-pitch_error_deg, pitch_error_deg))
    return replace(camera, roll_deg=roll, pitch_deg=pitch)


def _observed(ideal, ids, rng, camera: Camera, noise_px, noise_deg, end_px, clutter):
    """``(lines (M, 2, 2), truth (M,))``: the ideal lines with noise, then
    ``clutter`` lines (truth -1), in a random order."""
    noisy = add_noise(ideal, rng, noise_px, noise_deg, end_px, camera)
    extra = clutter_lines(rng, clutter, camera)
    lines = np.concatenate([noisy, extra])
    truth = np.concatenate([ids, -np.ones(len(extra), dtype=np.int64)])
    perm = rng.permutation(len(lines))
    return lines[perm], truth[perm]


def pose_error(a, b) -> tuple[float, float]:
    """(position error m, |yaw error| deg) between two (x, y, yaw_deg) poses."""
    return float(math.hypot(a[0] - b[0], a[1] - b[1])), float(abs(math.degrees(wrap(math.radians(a[2] - b[2])))))
