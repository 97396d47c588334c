"""A matcher result drawn over the map: estimated pose, matched segments and
the image lines, both re-projected in the synthetic image and back-projected
as rays in 3D. Scene nodes live under ``/result/``.
"""

from __future__ import annotations

import math

import numpy as np

from linemap.lmap import LineMap
from mapkit.view import palette, scene_nodes
from mapkit.view.pose_tool import add_frustum
from mapkit.view.result import MatchResult
from mapkit.view.synthetic_image import blank_image, draw_lines, render_segments

#: Length of a back-projected ray when no matched segment says how far to draw it (metres).
RAY_LENGTH_M = 4.0


def image_line_rays(camera, m: LineMap, res: MatchResult) -> np.ndarray:
    """(3M, 2, 3) segments: for each image line, the two rays from the camera
    centre through its end points and the segment joining their far ends
    (the line's interpretation plane, cut at the matched segment's distance,
    or at :data:`RAY_LENGTH_M` for an unmatched line)."""
    c = camera.centre(res.x, res.y)
    R = camera.world2cam(res.yaw)
    dirs = camera.pixel_rays(res.lines.reshape(-1, 2)) @ R  # world directions R^T ray, (2M, 3)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    length = np.full(len(res.lines), RAY_LENGTH_M)
    for seg, line in res.matches:
        if 0 <= line < len(length):
            length[line] = float(np.linalg.norm(m.segments[seg].mean(axis=0) - c))
    far = (c + dirs * np.repeat(length, 2)[:, None]).reshape(-1, 2, 3)
    cc = np.broadcast_to(c, far[:, 0].shape)
    return np.concatenate([np.stack([cc, far[:, 0]], 1), np.stack([cc, far[:, 1]], 1),
                           np.stack([far[:, 0], far[:, 1]], 1)]).astype(np.float32)


def result_image(camera, m: LineMap, res: MatchResult) -> np.ndarray:
    """The model at the estimated pose (grey: segments visible from there;
    green: matched) with the image lines (blue) drawn over it."""
    x, y, yaw = res.x, res.y, res.yaw
    img = blank_image(camera)
    visible = m.candidate_segments(x, y, 0.0)
    render_segments(camera, m.segments[visible], np.full((len(visible), 3), 170), x, y, yaw, image=img, thickness=1)
    matched = np.unique(res.matches[:, 0]) if len(res.matches) else np.zeros(0, dtype=np.int64)
    if len(matched):
        render_segments(camera, m.segments[matched], np.array([palette.MATCHED]), x, y, yaw, image=img, thickness=3)
    if res.lines is not None and len(res.lines):
        draw_lines(img, res.lines, palette.RAYS, thickness=2)
    return img


def draw_result(scene, m: LineMap, camera, res: MatchResult) -> tuple[list, np.ndarray | None, str]:
    """Add the result's nodes; returns (their handles, panel image or None, markdown)."""
    score = f"{res.score:.3g}" if res.score is not None else "n/a"
    text = f"**{'accepted' if res.ok else 'rejected'}**, score E = {score}, {len(res.matches)} matches"
    if not res.ok and res.reason:
        text += f"; reason: {res.reason}"
    if not res.has_pose:
        return [], None, text + "\n\nNo pose to show."
    handles = [add_frustum(scene, "/result/frustum", camera, res.x, res.y, res.yaw, palette.RESULT_POSE)]
    matched = np.unique(res.matches[:, 0]) if len(res.matches) else np.zeros(0, dtype=np.int64)
    if len(matched):
        handles.append(scene.add_line_segments("/result/matched", m.segments[matched].astype(np.float32),
                                               palette.MATCHED, thickness=scene_nodes.HIGHLIGHT_PX + 1,
                                               thickness_units="screen"))
    if res.lines is not None and len(res.lines):
        handles.append(scene.add_line_segments("/result/rays", image_line_rays(camera, m, res), palette.RAYS,
                                               thickness=1.5, thickness_units="screen"))
    n_lines = "no image lines given" if res.lines is None else f"{len(res.lines)} image lines"
    text += (f"\n\npose x = {res.x:.3f} m, y = {res.y:.3f} m, yaw = {math.degrees(res.yaw):.1f}°; {n_lines}.\n\n"
             "Image: model at the estimated pose (grey), matched segments (green), image lines (blue).")
    return handles, result_image(camera, m, res), text
