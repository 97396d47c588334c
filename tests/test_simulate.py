"""The simulator (mapkit_harness/simulate.py) shows only what the map can hold."""

from __future__ import annotations
from dataclasses import replace

import numpy as np

from mapkit_harness.plans import make_box_map
from mapkit_harness.simulate import map_range, paper_camera, visible_lines


def test_segments_beyond_the_maps_range_are_not_shown():
    """A 10 x 5 m room seen along its length from 1 m off a corner: the far
    wall, 9 m off, shows without a range; with the 6 m the map's lists were
    built for (its build record) it does not, and the near side wall's
    lines end within 6 m of the camera."""
    room = make_box_map(10.0, 5.0)
    cam = paper_camera()
    pose = (1.0, 1.0, 0.0)
    far_wall = np.nonzero((np.abs(room.segments[..., 0] - 10.0) < 1e-6).all(axis=1))[0]
    assert map_range(room) == np.inf
    _, ids_all = visible_lines(room, cam, pose)
    assert len(set(far_wall) & set(ids_all.tolist())) >= 2

    short = replace(room, meta={**room.meta, "build": {"max_range": 6.0}})
    assert map_range(short) == 6.0
    lines, ids = visible_lines(short, cam, pose)
    assert not set(far_wall) & set(ids.tolist())
    assert set(ids.tolist()) < set(ids_all.tolist())
    # Back to the floor: a floor-junction line's far end point is at most 6 m
    # (3D) from the camera centre. The floor is 1.2 m below the level camera,
    # so a pixel row v below the centre lies at depth f * 1.2 / (v - cy).
    floor = room.kinds[ids] == 0
    assert floor.any()
    v = lines[floor][..., 1]
    depth = cam.fy * 1.2 / (v - cam.cy)
    u = lines[floor][..., 0]
    lateral = (u - cam.cx) / cam.fx * depth
    assert (np.sqrt(depth**2 + lateral**2 + 1.2**2) <= 6.0 + 0.05).all()
