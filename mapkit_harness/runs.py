"""Simulate a robot run through a map: route, odometry, frames, truth.

The route goes from a random free pose through random waypoints in other
regions, along shortest paths in the map's free space (through the doors)
kept ``clearance`` metres off the walls; the robot drives ``step`` metres a
frame and turns in place at most ``max_turn`` degrees a frame at corners.
The odometry integrates the true increments with a scale error and a
heading drift drawn once per run (the systematic part wheel odometry has)
plus per-step noise. Frames are the visible map lines at the true pose
(:func:`mapkit_harness.simulate.visible_lines`) with noise and clutter lines, or
images rendered by :mod:`mapkit_harness.render`. ``--kidnap K`` carries the robot to a random
distant pose that shows at least 6 map lines before frame K, with no
odometry for it.

A run seen by a rig (:class:`linemap.rig.Rig` in place of the camera) is the
same route and odometry, each frame one set of lines per camera, each
camera's at its own pose through its mount
(:func:`mapkit_harness.simulate.camera_pose`).

Its command line, writing the JSON Lines file ``matcher track --frames``
reads and the TUM truth, is ``tools/simulate_run.py``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

import matcher
from linemap.rig import Rig
from matcher.tracking.odometry import compose, increment, wrap_deg

from mapkit_harness.simulate import add_noise, camera_pose, clutter_lines, visible_lines


@dataclass
class Run:
    """A simulated run: per frame the time (s), true pose and odometry
    (x, y, yaw_deg), the image lines (M, 2, 2) and their true segment ids
    (-1 clutter); ``kidnap`` the frame the robot was carried before (or None).
    A rig's run has per frame a list of lines and a list of ids, one per
    camera in the rig's order; its poses are the robot's."""

    times: list[float] = field(default_factory=list)
    truth: list[tuple] = field(default_factory=list)
    odom: list[tuple] = field(default_factory=list)
    lines: list[np.ndarray] = field(default_factory=list)
    ids: list[np.ndarray] = field(default_factory=list)
    kidnap: int | None = None


class FreeSpace:
    """The map's free space as a raster (``cell`` metres) at least
    ``clearance`` off the walls, with paths between points that keep to the
    middle of rooms and corridors (as a robot's planner does): shortest
    under a cost that grows as the path nears a wall closer than ``comfort``."""

    def __init__(self, linemap, cell: float = 0.05, clearance: float = 0.22, comfort: float = 0.8) -> None:
        pts = linemap.ring_points
        self.lo = pts.min(axis=0) - 2 * cell
        self.cell, self.comfort = cell, comfort
        w, h = np.ceil((pts.max(axis=0) - self.lo) / cell).astype(int) + 3
        free = np.zeros((h, w), np.uint8)
        for r in range(linemap.n_regions):
            region = np.zeros_like(free)
            for ring, _ in linemap.region_rings(r):
                one = np.zeros_like(free)
                cv2.fillPoly(one, [self.to_px(ring)], 1)
                region ^= one  # even-odd: holes cut out
            free |= region
        self.dist = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * cell
        self.ok = self.dist > clearance
        self.cells = np.argwhere(self.dist > min(comfort, 2 * clearance))
        if not len(self.cells):
            self.cells = np.argwhere(self.ok)
        self._graph = None

    def to_px(self, xy) -> np.ndarray:
        return np.round((np.asarray(xy, float).reshape(-1, 2) - self.lo) / self.cell).astype(np.int32)

    def to_xy(self, rc) -> np.ndarray:
        rc = np.asarray(rc, float).reshape(-1, 2)
        return self.lo + rc[:, ::-1] * self.cell

    def random_point(self, rng) -> np.ndarray:
        return self.to_xy(self.cells[rng.integers(len(self.cells))])[0]

    def graph(self):
        """The 8-connected grid of free cells, each step weighted by its
        length and the nearness of the walls."""
        if self._graph is None:
            from scipy.sparse import coo_matrix

            h, w = self.ok.shape
            idx = np.arange(h * w).reshape(h, w)
            penalty = 1.0 + 4.0 * np.clip(self.comfort - self.dist, 0.0, None) / self.comfort
            rows, cols, vals = [], [], []
            for dr, dc in [(0, 1), (1, 0), (1, 1), (1, -1)]:
                a = (slice(max(-dr, 0), h - max(dr, 0)), slice(max(-dc, 0), w - max(dc, 0)))
                b = (slice(a[0].start + dr, a[0].stop + dr), slice(a[1].start + dc, a[1].stop + dc))
                both = self.ok[a] & self.ok[b]
                cost = math.hypot(dr, dc) * 0.5 * (penalty[a] + penalty[b])
                rows.append(idx[a][both])
                cols.append(idx[b][both])
                vals.append(cost[both])
            r, c, v = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
            self._graph = coo_matrix((np.r_[v, v], (np.r_[r, c], np.r_[c, r])), shape=(h * w, h * w)).tocsr()
        return self._graph

    def path(self, a, b) -> np.ndarray | None:
        """A path (P, 2) metres from ``a`` to ``b`` through free space, or None."""
        from scipy.sparse.csgraph import dijkstra

        h, w = self.ok.shape
        (ca, ra), (cb, rb) = self.to_px(a)[0], self.to_px(b)[0]
        src, dst = ra * w + ca, rb * w + cb
        _, pred = dijkstra(self.graph(), indices=src, return_predecessors=True)
        if pred[dst] < 0 and dst != src:
            return None
        cells, k = [], dst
        while k != src:
            cells.append(divmod(k, w))
            k = pred[k]
        cells.append(divmod(src, w))
        return self._shortcut(self.to_xy(cells[::-1]))

    def _clearance_along(self, a, b) -> float:
        n = int(np.linalg.norm(b - a) / (0.5 * self.cell)) + 2
        px = self.to_px(a + np.linspace(0, 1, n)[:, None] * (b - a))
        return float(self.dist[px[:, 1], px[:, 0]].min())

    def _shortcut(self, pts: np.ndarray) -> np.ndarray:
        """The path with its stair steps cut: a straight line replaces a
        stretch when it keeps as far from the walls (or ``comfort``)."""
        d = self.dist[self.to_px(pts)[:, 1], self.to_px(pts)[:, 0]]
        out, i = [pts[0]], 0
        while i < len(pts) - 1:
            j = len(pts) - 1
            while j > i + 1 and self._clearance_along(pts[i], pts[j]) < min(self.comfort, d[i:j + 1].min()) - self.cell:
                j -= 1
            out.append(pts[j])
            i = j
        return np.array(out)


def drive(waypoints: np.ndarray, yaw0: float, step: float, max_turn: float) -> list[tuple]:
    """Poses along the polyline ``waypoints``: ``step`` metres a pose, turning
    in place (at most ``max_turn`` degrees a pose) to each leg's heading."""
    poses, yaw = [], yaw0
    pos = waypoints[0].astype(float)
    for target in waypoints[1:]:
        d = target - pos
        if np.linalg.norm(d) < 1e-9:
            continue
        heading = math.degrees(math.atan2(d[1], d[0]))
        while abs(wrap_deg(heading - yaw)) > 1e-6:
            yaw = wrap_deg(yaw + float(np.clip(wrap_deg(heading - yaw), -max_turn, max_turn)))
            poses.append((float(pos[0]), float(pos[1]), yaw))
        while np.linalg.norm(target - pos) > 1e-9:
            move = min(step, float(np.linalg.norm(target - pos)))
            pos = pos + move * (target - pos) / np.linalg.norm(target - pos)
            poses.append((float(pos[0]), float(pos[1]), yaw))
    return poses


def route(linemap, free: FreeSpace, rng, n: int, step: float, max_turn: float, start=None) -> list[tuple]:
    """At least ``n`` poses through random waypoints at least 2 m apart."""
    pos = free.random_point(rng) if start is None else np.asarray(start[:2], float)
    yaw = float(rng.uniform(-180, 180)) if start is None else start[2]
    poses = [(float(pos[0]), float(pos[1]), yaw)]
    tries = 0
    while len(poses) < n and tries < 200:
        tries += 1
        goal = free.random_point(rng)
        if np.linalg.norm(goal - pos) < 2.0:
            continue
        path = free.path(pos, goal)
        if path is None:
            continue
        poses += drive(path, poses[-1][2], step, max_turn)
        pos = np.array(poses[-1][:2])
    return poses[:n]


def simulate_run(linemap, camera, rng, frames: int = 120, step: float = 0.15, max_turn: float = 15.0,
                 noise_px: float = 1.0, noise_deg: float = 1.0, clutter: int = 2, dist_noise: float = 0.03,
                 drift_deg_per_m: float = 1.5, kidnap: int | None = None, dt_s: float = 0.2,
                 clearance: float = 0.22) -> Run:
    """A run of ``frames`` frames (see the module docstring) seen by
    ``camera``, a :class:`~matcher.Camera` or a :class:`~linemap.rig.Rig`."""
    free = FreeSpace(linemap, clearance=clearance)
    truth = route(linemap, free, rng, frames, step, max_turn)
    if kidnap is not None and 0 < kidnap < len(truth):
        truth = truth[:kidnap] + route(linemap, free, rng, frames - kidnap, step, max_turn,
                                       _set_down(linemap, camera, free, rng, truth[kidnap - 1]))
    run = Run(kidnap=kidnap)
    scale = 1.0 + rng.normal(0.0, dist_noise)
    drift = drift_deg_per_m * rng.choice([-1.0, 1.0])
    odom = (0.0, 0.0, 0.0)
    for i, pose in enumerate(truth):
        if i and i != kidnap:
            f, left, turn = increment(truth[i - 1], pose)
            dist = math.hypot(f, left)
            noisy = (f * scale + rng.normal(0, dist_noise * dist), left * scale + rng.normal(0, dist_noise * dist),
                     turn + drift * dist + rng.normal(0, 0.02 * abs(turn) + 0.2 * drift_deg_per_m * dist))
            odom = compose(odom, noisy)
        seen = [_seen(linemap, cam, at, rng, noise_px, noise_deg, clutter) for cam, at in _views(camera, pose)]
        run.times.append(round(i * dt_s, 6))
        run.truth.append(pose)
        run.odom.append(odom)
        run.lines.append(seen[0][0] if isinstance(camera, matcher.Camera) else [lines for lines, _ in seen])
        run.ids.append(seen[0][1] if isinstance(camera, matcher.Camera) else [ids for _, ids in seen])
    return run


def _views(camera, pose) -> list[tuple]:
    """``(camera, its pose)`` of each camera seeing the robot at ``pose``:
    the camera itself at ``pose``, or each camera of a rig at its own."""
    if isinstance(camera, Rig):
        return [(rc.camera, camera_pose(rc.mount, pose)) for rc in camera]
    return [(camera, pose)]


def _seen(linemap, camera, pose, rng, noise_px: float, noise_deg: float, clutter: int) -> tuple:
    """One camera's lines (M, 2, 2) at ``pose``, with noise then clutter,
    and their true segment ids (M,) (-1 clutter)."""
    ideal, ids = visible_lines(linemap, camera, pose)
    lines = add_noise(ideal, rng, noise_px, noise_deg, 3.0, camera) if len(ideal) else ideal
    extra = clutter_lines(rng, clutter, camera)
    return np.concatenate([lines, extra]), np.concatenate([ids, -np.ones(len(extra), dtype=np.int64)])


def _set_down(linemap, camera, free: FreeSpace, rng, before, min_lines: int = 6, tries: int = 500) -> tuple:
    """Where a kidnapped robot is set down: a random free pose over 3 m from
    ``before`` whose view shows at least ``min_lines`` map lines (a robot set
    down facing a bare wall tests nothing but its patience; a rig's cameras
    together), else the last pose tried."""
    here = np.array(before[:2])
    pose = before
    for _ in range(tries):
        p = free.random_point(rng)
        if np.linalg.norm(p - here) <= 3.0:
            continue
        pose = (float(p[0]), float(p[1]), float(rng.uniform(-180, 180)))
        if sum(len(visible_lines(linemap, cam, at)[0]) for cam, at in _views(camera, pose)) >= min_lines:
            break
    return pose


def run_camera(linemap) -> matcher.Camera:
    """The camera the map was built for (its ``meta["camera"]``), else a
    640x480 camera of 70 degrees across at 1.2 m, level."""
    cam = linemap.meta.get("camera") if isinstance(linemap.meta, dict) else None
    return matcher.Camera.from_dict(cam) if cam else matcher.Camera.from_fov(70.0, 640, 480, 1.2, 0.0)


def write_run(run: Run, path: Path, images: list | None = None) -> None:
    """The run as JSON Lines (``matcher track --frames``): each frame's
    ``lines`` or ``image`` (``images``, a path a frame), or for a rig's run
    its ``cameras``, one ``{"lines": ...}`` or ``{"image": ...}`` a camera
    (``images`` then a list of paths a frame)."""
    with open(path, "w") as f:
        for i, (t, odom) in enumerate(zip(run.times, run.odom)):
            frame = {"t": t, "odom": [round(v, 6) for v in odom]}
            if isinstance(run.lines[i], list):  # a rig's frame
                frame["cameras"] = ([{"image": p} for p in images[i]] if images else
                                    [{"lines": _rounded(lines)} for lines in run.lines[i]])
            elif images:
                frame["image"] = images[i]
            else:
                frame["lines"] = _rounded(run.lines[i])
            f.write(json.dumps(frame) + "\n")


def _rounded(lines: np.ndarray) -> list:
    return np.round(lines.reshape(-1, 4), 3).tolist()
