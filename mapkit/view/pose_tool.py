"""The pose tool: what the matcher would work with for a pose estimate.

For an estimate (x, y, yaw) with bounds dt (metres) and dyaw (radians) it
shows method.md section 3 step by step: the uncertainty disk, the regions it
meets (``regions_near``), the union of their lists (``candidate_segments``),
the part of that set inside the horizontal field of view for some heading in
``[yaw - dyaw, yaw + dyaw]``, the camera frustum at the nominal pose and the
synthetic image of the kept segments. Scene nodes live under ``/pose/``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import viser.transforms as vtf

from linemap.geometry import in_field_of_view
from linemap.lmap import LineMap
from mapkit.view import palette, scene_nodes
from mapkit.view.geometry import Triangles, disk_mesh, disk_outline
from mapkit.view.synthetic_image import render_segments

NODES = ("/pose/disk", "/pose/disk_fill", "/pose/regions", "/pose/candidates", "/pose/out_of_view",
         "/pose/heading", "/pose/frustum")


@dataclass
class PoseSets:
    """Sorted ids: retained regions, candidate segments, candidates in view."""

    regions: np.ndarray
    candidates: np.ndarray
    in_view: np.ndarray


def pose_sets(m: LineMap, camera, x: float, y: float, yaw: float, dt: float, dyaw: float,
              fov_filter: bool = True) -> PoseSets:
    """The sets of the pose tool (angles in radians); without ``fov_filter`` all candidates are in view.

    The field-of-view test is the matcher's own
    (:func:`linemap.geometry.in_field_of_view`), so the set shown is the set it uses.
    """
    regions = m.regions_near(x, y, dt)
    cands = m.segments_for_regions(regions)
    if fov_filter and len(cands):
        keep = in_field_of_view(m.segments[cands], camera, (x, y, yaw), dt, dyaw)
    else:
        keep = np.ones(len(cands), dtype=bool)
    return PoseSets(regions, cands, cands[keep])


def camera_wxyz(camera, yaw: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of the camera-to-world rotation at heading ``yaw``.

    viser's frustum follows OpenCV axes (X right, Y down, Z forward), like
    :class:`linemap.camera.Camera`, whose world-to-camera rotation R has the
    camera axes as rows; the camera-to-world rotation is R transposed.
    """
    return vtf.SO3.from_matrix(camera.world2cam(yaw).T).wxyz


def add_frustum(scene, name: str, camera, x: float, y: float, yaw: float, colour):
    """The camera's view pyramid at pose (x, y, yaw), half a metre deep."""
    fov = 2.0 * math.atan2(camera.height / 2.0, camera.fy)  # viser takes the vertical field of view
    return scene.add_camera_frustum(
        name, fov=fov, aspect=camera.width / camera.height, scale=0.5, color=colour, thickness=2.0,
        thickness_units="screen", wxyz=camera_wxyz(camera, yaw), position=tuple(camera.centre(x, y)),
    )


def heading_wedge(x: float, y: float, yaw: float, reach: float, length: float = 1.5) -> np.ndarray:
    """(3, 2, 3) rays on the floor: the nominal heading and the two outermost
    directions the camera may see (``reach`` = dyaw + half field of view)."""
    z = 0.02
    return np.array([[[x, y, z], [x + length * math.cos(a), y + length * math.sin(a), z]]
                     for a in (yaw, yaw - reach, yaw + reach)])


def _segments_node(scene, m: LineMap, name: str, ids: np.ndarray, colour, px: float) -> None:
    if len(ids):
        scene.add_line_segments(name, m.segments[ids].astype(np.float32), colour, thickness=px,
                                thickness_units="screen")
    else:
        scene.remove_by_name(name)


def remove_pose(scene) -> None:
    for name in NODES:
        scene.remove_by_name(name)


@dataclass(frozen=True)
class PoseEstimate:
    """A pose estimate and its bounds: ``x``, ``y``, ``dt`` metres, ``yaw``,
    ``dyaw`` radians (the pose panel's inputs)."""

    x: float
    y: float
    yaw: float
    dt: float
    dyaw: float


def draw_pose(scene, m: LineMap, triangles: Triangles, camera, kind_colours: np.ndarray, pose: PoseEstimate,
              fov_filter: bool) -> tuple[np.ndarray, str]:
    """Draw the pose tool; returns (synthetic image, markdown summary for the panel)."""
    x, y, yaw, dt, dyaw = pose.x, pose.y, pose.yaw, pose.dt, pose.dyaw
    sets = pose_sets(m, camera, x, y, yaw, dt, dyaw, fov_filter)
    half_fov = camera.horizontal_half_fov()
    out = np.setdiff1d(sets.candidates, sets.in_view)
    r = max(dt, 0.01)  # a zero disk would vanish; show a dot
    scene.add_line_segments("/pose/disk", disk_outline(x, y, r, 0.01), palette.POSE_DISK, thickness=3.0,
                            thickness_units="screen")
    dv, df = disk_mesh(x, y, r, scene_nodes.Z_RETAINED + 0.001)
    scene.add_mesh_simple("/pose/disk_fill", dv, df, color=palette.POSE_DISK, opacity=0.35, side="double",
                          cast_shadow=False, receive_shadow=False)
    verts, faces = triangles.subset(sets.regions)
    if len(faces):
        scene.add_mesh_simple("/pose/regions", np.c_[verts, np.full(len(verts), scene_nodes.Z_RETAINED)], faces,
                              color=palette.RETAINED_REGION, opacity=0.55, side="double", cast_shadow=False,
                              receive_shadow=False)
    else:
        scene.remove_by_name("/pose/regions")
    _segments_node(scene, m, "/pose/candidates", sets.in_view, palette.CANDIDATE, 3.5)
    _segments_node(scene, m, "/pose/out_of_view", out, palette.CANDIDATE_OUT_OF_VIEW, 3.0)
    scene.add_line_segments("/pose/heading", heading_wedge(x, y, yaw, dyaw + half_fov), palette.FRUSTUM,
                            thickness=2.0, thickness_units="screen")
    add_frustum(scene, "/pose/frustum", camera, x, y, yaw, palette.FRUSTUM)
    img, drawn = render_segments(camera, m.segments[sets.in_view], kind_colours[sets.in_view], x, y, yaw)
    summary = (
        f"**{len(sets.regions)} regions** retained, **{len(sets.candidates)} candidate segments**, "
        f"**{len(sets.in_view)}** in view over yaw {math.degrees(yaw):.0f} ± {math.degrees(dyaw):.0f}° "
        f"(half FOV {math.degrees(half_fov):.0f}°); {len(drawn)} project into the image at the nominal pose."
    )
    return img, summary
