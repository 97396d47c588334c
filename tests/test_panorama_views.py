"""mapkit_harness/panorama.py: views cut from an equirectangular panorama land where the camera model says.

A box room is drawn into an equirectangular image with ZInD's convention
(each face its own grey), as a panorama taken at a known place and plan
rotation; a perspective view cut from it at a heading and pitch must show
the room's corner at the pixel ``Camera.project`` gives for the view's pose,
with the right face on each side.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from linemap.camera import Camera
from mapkit.importers.zind.annotations import ZindPano
from mapkit_harness.panorama import cut_view, view_pose

BOX = (0.0, 6.0, 0.0, 4.0, 2.6)  # x0, x1, y0, y1, ceiling
#: Grey of each face: walls x0, x1, y0, y1, floor, ceiling.
GREY = {"x0": 40, "x1": 80, "y0": 120, "y1": 160, "floor": 200, "ceiling": 240}


def box_panorama(pano: ZindPano, width: int = 2048) -> np.ndarray:
    """The box room seen from ``pano``, equirectangular (width/2, width) uint8."""
    h = width // 2
    u, v = np.meshgrid(np.arange(width, dtype=float), np.arange(h, dtype=float))
    theta = u / (width - 1) * 2 * math.pi - math.pi
    phi = (1.0 - v / (h - 1)) * math.pi - math.pi / 2
    local = np.stack([-np.sin(theta) * np.cos(phi), np.cos(theta) * np.cos(phi), np.sin(phi)], -1).reshape(-1, 3)
    m = pano.local_directions(np.eye(3)).T  # local = m @ world
    world = local @ np.linalg.inv(m).T
    c = np.array([*pano.position, pano.camera_height])
    x0, x1, y0, y1, top = BOX
    faces = [("x0", 0, x0), ("x1", 0, x1), ("y0", 1, y0), ("y1", 1, y1), ("floor", 2, 0.0), ("ceiling", 2, top)]
    t = np.full((len(world), len(faces)), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for k, (_, axis, value) in enumerate(faces):
            tk = (value - c[axis]) / world[:, axis]
            t[:, k] = np.where(tk > 0, tk, np.inf)
    hit = np.argmin(t, axis=1)
    grey = np.array([GREY[name] for name, _, _ in faces], dtype=np.uint8)
    return grey[hit].reshape(h, width)


@pytest.mark.parametrize("rotation, yaw_deg, pitch_deg", [(0.0, 30.0, 0.0), (37.0, -150.0, 8.0), (-112.0, 100.0, 4.0)])
def test_a_corner_projects_where_the_camera_model_says(rotation, yaw_deg, pitch_deg):
    pano = ZindPano("pano_1", "room", "", "", np.array([2.0, 1.5]), rotation, 1.4, True, True)
    panorama = box_panorama(pano)
    camera = Camera.from_fov(75.0, 640, 480, pano.camera_height, pitch_deg)
    view = cut_view(panorama, pano, camera, math.radians(yaw_deg))
    assert view.shape == (480, 640)
    pose = view_pose(pano, yaw_deg)
    assert pose[:2] == (2.0, 1.5)
    # The floor corner in view: x1/y1 for a heading of 30 deg, x0/y0 for -150, x0/y1 for 100.
    corner = {30.0: (6.0, 4.0), -150.0: (0.0, 0.0), 100.0: (0.0, 4.0)}[yaw_deg]
    uv, z = camera.project(np.array([[*corner, 0.0]]), *pose[:2], math.radians(pose[2]))
    u, v = uv[0]
    assert z[0] > 0 and 20 < u < 620 and 20 < v < 460
    # Around the corner: floor below it, the two walls above it on either side.
    walls_x = "x1" if corner[0] > 0 else "x0"
    walls_y = "y1" if corner[1] > 0 else "y0"
    left, right = _sides(camera, pose, corner, walls_x, walls_y)
    d = 8
    sample = {name: int(view[int(round(v + dv)), int(round(u + du))])
              for name, (du, dv) in {"below": (0, d), "left": (-d, -d), "right": (d, -d)}.items()}
    assert sample == {"below": GREY["floor"], "left": GREY[left], "right": GREY[right]}


def _sides(camera, pose, corner, walls_x, walls_y):
    """Which wall shows on the left and on the right of the corner in the image."""
    yaw = math.radians(pose[2])
    on_x = np.array([[corner[0], corner[1] + (-0.5 if corner[1] > 0 else 0.5), 0.3]])  # a point on the x wall
    uv_x, _ = camera.project(on_x, *pose[:2], yaw)
    uv_c, _ = camera.project(np.array([[*corner, 0.3]]), *pose[:2], yaw)
    return (walls_x, walls_y) if uv_x[0, 0] < uv_c[0, 0] else (walls_y, walls_x)
