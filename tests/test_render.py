"""The renderer's shortcuts change no pixel: casting a view in blocks of
columns against the surfaces within their bearings, and a level camera's
walls once a column, give the grey levels of every ray cast against every
surface one ray at a time (mapkit_harness/render.py)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from linemap.lmap import load_map
from mapkit_harness.render import VisibleSurfaces, shade_column_blocks, shade_directions
from mapkit_harness.simulate import paper_camera

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("pitch, roll", [(0.0, 0.0), (-8.0, 0.0), (-10.0, 7.0)], ids=["level", "pitched", "rolled"])
def test_blocks_and_columns_give_the_image_cast_against_everything(pitch, roll):
    linemap = load_map(ROOT / "maps" / "flat.lmap")
    camera = replace(paper_camera(1.2, pitch), width=96, height=72, fx=60.0, fy=60.0, cx=48.0, cy=36.0,
                     roll_deg=roll)
    # Walls, a door's head, a window's sill and the outside seen through it.
    pose = (2.0, 6.6, 120.0)
    R = camera.world2cam(math.radians(pose[2]))
    u, v = np.arange(camera.width) + 0.0, np.arange(camera.height) + 0.0

    def rays_of(cols):
        return camera.pixel_rays(np.stack(np.meshgrid(u[cols], v), axis=-1).reshape(-1, 2)) @ R

    surfaces = VisibleSurfaces(linemap, None, pose)  # every surface, none cut by the field of view
    fast = shade_column_blocks(linemap, pose[:2], camera.height_m, rays_of, (camera.height, camera.width),
                               surfaces, blocks=24)
    every = shade_directions(linemap, pose[:2], camera.height_m, rays_of(np.arange(camera.width)), surfaces)
    assert np.array_equal(fast, every.reshape(camera.height, camera.width))
    assert {70.0, 205.0, 135.0} <= set(np.unique(fast).tolist())  # a head, a sill, the outside: a scene, not a blank
