"""A picture of a tracked run: the route over the map, seen from above.

Drawn with OpenCV (the runtime stays free of plotting libraries): the wall
outlines in grey, the map's segments in light grey, the odometry (started
at the first estimate) in blue, the tracker's estimate in green while
tracking and orange while coasting, the accepted poses as dots with a tick
for the heading, and the true route in black when it is known.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from matcher.tracking.odometry import compose, increment

#: Colours (B, G, R).
_WALL, _SEGMENT, _ODOM, _TRACK, _COAST, _TRUTH = (150, 150, 150), (215, 215, 215), (200, 90, 30), \
    (40, 160, 40), (0, 140, 255), (0, 0, 0)
_LOST = (60, 60, 220)
#: The estimate is not joined across a step longer than this (metres): a
#: relocalisation's jump, not a road the robot took.
_JUMP_M = 1.0
_STATE_COLOUR = {"tracking": _TRACK, "coasting": _COAST, "relocalising": _LOST}


def odometry_route(odoms: list, start) -> list:
    """The odometry poses ``odoms`` carried to the map frame so that the
    first one is ``start`` (x, y, yaw_deg): the route odometry alone gives."""
    if not odoms:
        return []
    out = [tuple(start)]
    for a, b in zip(odoms, odoms[1:]):
        out.append(compose(out[-1], increment(a, b)))
    return out


def draw_route(linemap, frames: list[dict], odoms: list, truth: list | None = None,
               size_px: int = 1000) -> np.ndarray:
    """An image (H, W, 3) uint8 BGR of a run: ``frames`` are the tracker's
    frames as dicts (:meth:`TrackedFrame.to_dict`), ``odoms`` the
    odometry of each (None for a skipped frame), ``truth`` the true poses if known."""
    pts = [linemap.wall_points, linemap.segments[:, :, :2].reshape(-1, 2)]
    est = [(f["estimate"]["x"], f["estimate"]["y"]) for f in frames if f.get("estimate")]
    first = next((f["estimate"] for f in frames if f.get("estimate")), None)
    start = (first["x"], first["y"], first["yaw_deg"]) if first else None
    # Odometry from the first frame that had an estimate.
    k0 = next((i for i, f in enumerate(frames) if f.get("estimate")), None)
    odo = odometry_route([o for o in odoms[k0:] if o is not None], start) if start is not None else []
    allp = np.concatenate([p for p in pts + [np.array(est).reshape(-1, 2), np.array(odo)[:, :2].reshape(-1, 2),
                                             np.array(truth or [])[:, :2].reshape(-1, 2) if truth else np.zeros((0, 2))]
                           if len(p)])
    lo, hi = allp.min(axis=0) - 0.5, allp.max(axis=0) + 0.5
    scale = (size_px - 40) / max(hi - lo)
    w, h = (np.ceil((hi - lo) * scale) + 40).astype(int)
    img = np.full((h, w + 260, 3), 255, np.uint8)

    def px(xy):
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        return np.stack([20 + (xy[:, 0] - lo[0]) * scale, h - 20 - (xy[:, 1] - lo[1]) * scale], 1).round().astype(np.int32)

    for ring in linemap.wall_rings():
        cv2.polylines(img, [px(ring)], True, _WALL, 2, cv2.LINE_AA)
    for seg in linemap.segments:
        a, b = px(seg[:, :2])
        cv2.line(img, tuple(a), tuple(b), _SEGMENT, 1, cv2.LINE_AA)
    if truth:
        cv2.polylines(img, [px(np.array(truth)[:, :2])], False, _TRUTH, 1, cv2.LINE_AA)
    if odo:
        cv2.polylines(img, [px(np.array(odo)[:, :2])], False, _ODOM, 2, cv2.LINE_AA)
    prev = None
    for f in frames:
        e = f.get("estimate")
        if not e:
            prev = None
            continue
        p = px((e["x"], e["y"]))[0]
        colour = _STATE_COLOUR.get(f["state"], _COAST)
        if prev is not None and np.hypot(*(p - prev)) <= _JUMP_M * scale:
            cv2.line(img, tuple(prev), tuple(p), colour, 2, cv2.LINE_AA)
        if f.get("ok"):
            tip = p + np.array([math.cos(math.radians(e["yaw_deg"])), -math.sin(math.radians(e["yaw_deg"]))]) * 10
            cv2.circle(img, tuple(p), 3, _TRACK, -1, cv2.LINE_AA)
            cv2.line(img, tuple(p), tuple(tip.round().astype(int)), _TRACK, 1, cv2.LINE_AA)
        prev = p
    legend = [("walls", _WALL), ("odometry", _ODOM), ("tracking", _TRACK), ("coasting", _COAST),
              ("relocalising", _LOST)]
    if truth:
        legend.append(("true route", _TRUTH))
    ok = sum(1 for f in frames if f.get("ok"))
    for i, (name, colour) in enumerate(legend):
        y = 30 + 26 * i
        cv2.line(img, (w + 20, y), (w + 60, y), colour, 3)
        cv2.putText(img, name, (w + 70, y + 5), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, f"{ok} of {len(frames)} frames localised", (w + 20, 30 + 26 * len(legend) + 10),
                cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, f"{1 / scale:.3g} m per px", (w + 20, 30 + 26 * len(legend) + 36),
                cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    return img
