"""An answer the lines do not fix is not an answer.

Facing the middle of a long wall whose ends are out of view, the camera sees
only horizontal lines along it (floor and ceiling junctions, a long window's
sill and head): they fix the distance to the wall and the heading, but any
place along the wall fits them as well. The matcher used to accept such a
frame at whatever place along the wall the search started from (here the
prior's x, 10 cm off); now it says the pose is not fixed.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))

import matcher  # noqa: E402
from mapkit.options import BuildOptions  # noqa: E402
from mapkit.pipeline import build_map  # noqa: E402
from simulate import visible_lines  # noqa: E402
from test_zind_import import _pano  # noqa: E402


def test_lines_along_one_wall_do_not_fix_the_pose(tmp_path):
    room = [(0, 0), (20, 0), (20, 5), (0, 5)]
    window = ((2.0, 5.0), (18.0, 5.0), 0.9, 2.1)  # along the north wall, its ends out of view
    doc = {
        "scale_meters_per_coordinate": {"floor_01": 1.0},
        "redraw": {"floor_01": {}},
        "merger": {"floor_01": {"complete_room_01": {"partial_room_01": {
            "pano_1": _pano(np.array([10.0, 1.5]), room, 2.5, [], [window])}}}},
    }
    path = tmp_path / "corridor.json"
    path.write_text(json.dumps(doc))
    m, _ = build_map(path, BuildOptions(robot_radius=0.2))
    cam = matcher.Camera.from_fov(60, 640, 480, 1.25, 0.0)
    lines, ids = visible_lines(m, cam, (10.0, 1.5, 90.0))
    seen = m.segments[ids]
    # All on the north wall (its inner face, or the window's far side through the glass), all along x.
    assert len(lines) >= 3 and (seen[:, :, 1] >= 5.0 - 1e-9).all() and np.allclose(seen[:, 0, 1:], seen[:, 1, 1:])
    res = matcher.localize(m, cam, lines, (10.1, 1.45, 93.0), 0.3, 10.0)
    assert not res
    assert "do not fix the pose" in res.reason
    assert res.pose is None
