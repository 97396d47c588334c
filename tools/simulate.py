"""Synthetic frames for the paper's protocol (docs/method.md section 9).

A frame: a random camera pose in free space (inside a region of the map),
the model segments it sees (occluded by the map's walls, extruded to
``meta["wall_height"]``, clipped to the image and to the range the map's
lists were built for), uniform noise on each line's
orientation, offset and end points, random clutter lines, and a prior drawn
within the bounds of a PEQ. ``python tools/simulate.py`` prints one frame.

Also the baseline the paper sets out to beat: :func:`baseline_localize`, a
classic interpretation tree that computes a pose at every node.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from linemap.camera import Camera  # noqa: E402
from matcher.stage1.constraints import wrap  # noqa: E402
from matcher.scene.occlusion import wall_edges  # noqa: E402

PEQ = {1: (0.2, 10.0), 2: (0.4, 20.0), 3: (0.6, 30.0), 4: (0.8, 40.0), 5: (1.0, 50.0)}

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


def _occluded(c: np.ndarray, q: np.ndarray, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """(S,) bool: sight lines from c (2,) to points q (S, 2) cross a wall edge.

    Sight lines are shortened by 2 mm at q, which lies on a wall face."""
    d = q - c
    ln = np.linalg.norm(d, axis=1, keepdims=True)
    q2 = c + d * np.maximum(ln - 2e-3, 0) / np.maximum(ln, 1e-12)
    r = q2 - c  # (S, 2)
    s = eb - ea  # (E, 2)
    denom = r[:, None, 0] * s[None, :, 1] - r[:, None, 1] * s[None, :, 0]
    w = ea[None] - c[None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * s[None, :, 1] - w[..., 1] * s[None, :, 0]) / denom
        u = (w[..., 0] * r[:, None, 1] - w[..., 1] * r[:, None, 0]) / denom
    hit = (np.abs(denom) > 1e-12) & (t > 0) & (t < 1) & (u >= 0) & (u <= 1)
    return hit.any(axis=1)


def _clip_to_frustum(seg: np.ndarray, camera: Camera, x, y, yaw) -> np.ndarray | None:
    """Part of a segment (2, 3) in front of the camera and inside the image pyramid."""
    R = camera.world2cam(yaw)
    C = camera.centre(x, y)
    p = (seg - C) @ R.T  # camera coords
    w, h = camera.width, camera.height
    # Half-spaces n . X >= 0 of the view pyramid, and the near plane.
    planes = [
        np.array([camera.fx, 0.0, camera.cx]),  # u >= 0
        np.array([-camera.fx, 0.0, w - camera.cx]),  # u <= w
        np.array([0.0, camera.fy, camera.cy]),  # v >= 0
        np.array([0.0, -camera.fy, h - camera.cy]),  # v <= h
    ]
    t0, t1 = 0.0, 1.0
    a, b = p[0], p[1]
    for n, off in [(pl, 0.0) for pl in planes] + [(np.array([0.0, 0.0, 1.0]), -0.05)]:
        fa, fb = n @ a + off, n @ b + off
        if fa < 0 and fb < 0:
            return None
        if fa < 0:
            t0 = max(t0, fa / (fa - fb))
        elif fb < 0:
            t1 = min(t1, fa / (fa - fb))
    if t1 - t0 < 1e-6:
        return None
    return np.array([seg[0] + t0 * (seg[1] - seg[0]), seg[0] + t1 * (seg[1] - seg[0])])


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
    out, ids = [], []
    for i, seg in enumerate(linemap.segments):
        part = _clip_to_frustum(seg, camera, x, y, yaw)
        if part is None:
            continue
        t = np.linspace(0.0, 1.0, samples)
        pts = part[0] + t[:, None] * (part[1] - part[0])
        vis = ~_occluded(c, pts[:, :2], ea, eb) & (np.linalg.norm(pts - centre, axis=1) <= max_range)
        if not vis.any():
            continue
        # Longest run of visible samples.
        best, start, best_rng = 0, None, None
        for k, ok in enumerate(np.append(vis, False)):
            if ok and start is None:
                start = k
            elif not ok and start is not None:
                if k - start > best:
                    best, best_rng = k - start, (start, k - 1)
                start = None
        p3 = pts[[best_rng[0], best_rng[1]]]
        uv, z = camera.project(p3, x, y, yaw)
        if (z <= 0).any() or np.linalg.norm(uv[1] - uv[0]) < min_px:
            continue
        out.append(uv)
        ids.append(i)
    if not out:
        return np.zeros((0, 2, 2)), np.zeros(0, dtype=np.int64)
    return np.array(out), np.array(ids, dtype=np.int64)


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
    both 0 nothing is drawn (the frames are those of a level camera)."""
    dt, dyaw = PEQ[peq]
    real = camera
    if roll_deg or pitch_error_deg:
        roll = camera.roll_deg + float(rng.uniform(-roll_deg, roll_deg))
        pitch = camera.pitch_deg + float(rng.uniform(-pitch_error_deg, pitch_error_deg))
        real = replace(camera, roll_deg=roll, pitch_deg=pitch)
    while True:
        pose = random_free_pose(linemap, rng)
        ideal, ids = visible_lines(linemap, real, pose)
        if min_seen <= len(ids) <= max_seen:
            break
    noisy = add_noise(ideal, rng, noise_px, noise_deg, end_px, camera)
    extra = clutter_lines(rng, clutter, camera)
    lines = np.concatenate([noisy, extra])
    truth = np.concatenate([ids, -np.ones(len(extra), dtype=np.int64)])
    perm = rng.permutation(len(lines))
    r = dt * math.sqrt(rng.uniform())
    phi = rng.uniform(0, 2 * math.pi)
    prior = (pose[0] + r * math.cos(phi), pose[1] + r * math.sin(phi),
             float(math.degrees(wrap(math.radians(pose[2] + rng.uniform(-dyaw, dyaw))))))
    return Frame(pose, prior, dt, dyaw, lines[perm], truth[perm], real.pitch_deg, real.roll_deg)


def pose_error(a, b) -> tuple[float, float]:
    """(position error m, |yaw error| deg) between two (x, y, yaw_deg) poses."""
    return float(math.hypot(a[0] - b[0], a[1] - b[1])), float(abs(math.degrees(wrap(math.radians(a[2] - b[2])))))


# --------------------------------------------------------------------------
# Baseline: interpretation tree with a pose computed at every node


def baseline_localize(linemap, camera: Camera, lines, prior, dt, dyaw, time_limit_s: float = 2.0,
                      min_matches: int = 3, tol_px: float = 6.0):
    """The classic interpretation tree that the paper sets out to beat
    (Grimson's search with a pose check at every node, for line features).

    Depth-first over the candidate model segments (the same region and
    field-of-view selection as ours), each level branching on every unused
    image line and on "unmatched". At every node a pose is computed by
    Gauss-Newton from its parent's pose, on the matched lines' residuals plus
    a weak pull towards the prior (so that nodes with one or two matches,
    which leave the pose free, can be checked too); the node is kept if every
    matched line lies within ``tol_px`` of its segment's projection and the
    pose stays within the prior bounds. A branch is cut when it cannot beat
    the largest interpretation found. Returns ``(pose (x, y, yaw_deg) or
    None, matches, nodes, timed_out)``."""
    from matcher.stage2 import refine as verify
    from matcher.checks import check_lines, check_prior
    from linemap.geometry import in_field_of_view
    from matcher.tolerances import DEFAULT

    arr = check_lines(lines, camera, DEFAULT)
    xe, ye, yaw_e, dt, dyaw = check_prior(prior, dt, dyaw)
    ids = linemap.candidate_segments(xe, ye, dt)
    segs = linemap.segments[ids]
    keep = in_field_of_view(segs, camera, (xe, ye, yaw_e), dt, dyaw)
    ids, segs = ids[keep], segs[keep]
    rays = camera.pixel_rays(arr)
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    tol = tol_px / camera.fx
    prior_w = 1e-3  # weak: decides only what the matched lines leave free
    t_end = time.perf_counter() + time_limit_s
    best = {"n": min_matches - 1, "pose": None, "matches": []}
    state = {"nodes": 0, "timed_out": False}
    M = len(arr)

    def pose_for(assign, start):
        si = np.array([i for i, _ in assign])
        lj = np.array([j for _, j in assign])
        p = np.array(start, dtype=float)
        scale = np.array([dt, dt, dyaw])
        for _ in range(4):
            r, J = verify.residuals(p[None], np.zeros(len(si), dtype=np.int64), segs[si, 0], segs[si, 1],
                                     rays[lj, 0], rays[lj, 1], camera.pitch, camera.height_m, jacobian=True)
            r, J = r.reshape(-1), J.reshape(-1, 3)
            dp = p - np.array([xe, ye, yaw_e])
            dp[2] = wrap(dp[2])
            rp = prior_w * dp / scale
            Jp = np.diag(prior_w / scale)
            A = J.T @ J + Jp.T @ Jp
            b = J.T @ r + Jp.T @ rp
            p -= np.linalg.solve(A, b)
        r = verify.residuals(p[None], np.zeros(len(si), dtype=np.int64), segs[si, 0], segs[si, 1], rays[lj, 0],
                              rays[lj, 1], camera.pitch, camera.height_m)
        ok = np.abs(r).max() <= tol
        ok &= math.hypot(p[0] - xe, p[1] - ye) <= dt + 0.05
        ok &= abs(float(wrap(p[2] - yaw_e))) <= dyaw + 0.02
        return bool(ok), p

    def rec(level, assign, used, pose):
        if state["timed_out"]:
            return
        if time.perf_counter() > t_end:
            state["timed_out"] = True
            return
        if len(assign) + min(len(ids) - level, M - len(used)) <= best["n"]:
            return
        if level == len(ids):
            best.update(n=len(assign), pose=pose, matches=list(assign))
            return
        for j in range(M):
            if j in used:
                continue
            state["nodes"] += 1
            ok, p = pose_for(assign + [(level, j)], pose)
            if ok:
                rec(level + 1, assign + [(level, j)], used | {j}, p)
        rec(level + 1, assign, used, pose)

    rec(0, [], frozenset(), np.array([xe, ye, yaw_e]))
    if best["pose"] is None:
        return None, [], state["nodes"], state["timed_out"]
    x, y, yaw = best["pose"]
    matches = sorted([int(ids[i]), int(j)] for i, j in best["matches"])
    return (float(x), float(y), float(math.degrees(wrap(yaw)))), matches, state["nodes"], state["timed_out"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--map", default=str(Path(__file__).resolve().parents[1] / "maps" / "flat.lmap"),
                    help=".lmap map (default: maps/flat.lmap)")
    ap.add_argument("--peq", type=int, default=3, choices=sorted(PEQ))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise-px", type=float, default=1.0)
    ap.add_argument("--noise-deg", type=float, default=1.0)
    ap.add_argument("--clutter", type=int, default=3)
    ap.add_argument("--roll-deg", type=float, default=0.0,
                    help="the frame's camera rolled by up to this, degrees (drawn uniformly within +-)")
    ap.add_argument("--pitch-error-deg", type=float, default=0.0,
                    help="the frame's pitch off the camera file's by up to this, degrees (uniform within +-); "
                         "with either, camera.json says pitch_std_deg and roll_std_deg of those bounds")
    ap.add_argument("--out", metavar="DIR",
                    help="write camera.json, lines.json, truth.json and frame.png (the view rendered by "
                         "tools/render.py) there, for 'matcher localize'")
    args = ap.parse_args(argv)
    import matcher

    m = matcher.load_map(args.map)
    cam = paper_camera()
    fr = make_frame(m, cam, np.random.default_rng(args.seed), args.peq, args.noise_px, args.noise_deg,
                    clutter=args.clutter, roll_deg=args.roll_deg, pitch_error_deg=args.pitch_error_deg)
    if args.roll_deg or args.pitch_error_deg:  # the camera file knows the bounds, not the frame's attitude
        cam = replace(cam, pitch_std_deg=0.75 * args.pitch_error_deg, roll_std_deg=0.67 * args.roll_deg)
        print(f"frame's pitch {fr.pitch_deg:.2f} deg, roll {fr.roll_deg:.2f} deg")
    x, y, yaw = fr.prior
    print(f"true pose {tuple(round(v, 3) for v in fr.pose)}; prior ({x:.2f}, {y:.2f}, {yaw:.1f}), "
          f"dt {fr.dt} m, dyaw {fr.dyaw} deg; {len(fr.lines)} lines")
    if args.out:
        import json

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "camera.json").write_text(json.dumps(cam.to_dict()))
        (out / "lines.json").write_text(json.dumps({"lines": fr.lines.reshape(-1, 4).round(2).tolist()}))
        truth = {"pose": {"x": fr.pose[0], "y": fr.pose[1], "yaw_deg": fr.pose[2]},
                 "pitch_deg": fr.pitch_deg, "roll_deg": fr.roll_deg,
                 "prior": list(fr.prior), "dt": fr.dt, "dyaw": fr.dyaw, "matches": fr.true_matches()}
        (out / "truth.json").write_text(json.dumps(truth))
        # The same view as an image (walls, floor and ceiling shaded), for --image.
        import cv2
        from render import render_view

        real = replace(cam, pitch_deg=fr.pitch_deg, roll_deg=fr.roll_deg, pitch_std_deg=0.0, roll_std_deg=0.0)
        cv2.imwrite(str(out / "frame.png"), render_view(m, real, fr.pose, rng=np.random.default_rng(args.seed)))
        print(f"wrote {out}/camera.json, lines.json, truth.json, frame.png; try:")
        import os

        common = (f"matcher localize --map {os.path.relpath(args.map)} --camera {out}/camera.json "
                  f"--prior {x:.3f},{y:.3f},{yaw:.2f} --dt {fr.dt:g} --dyaw {fr.dyaw:g}")
        print(f"  {common} --lines {out}/lines.json")
        print(f"  {common} --image {out}/frame.png")
    else:
        res = matcher.localize(m, cam, fr.lines, fr.prior, fr.dt, fr.dyaw)
        print(res.to_dict())
        print("true matches", fr.true_matches())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
