"""Synthetic meshes with known edges: a grid of rooms whose walls are
separate subdivided boxes, as exported meshes often are, with the count of
edges its union must give (``tools/bench_mesh_edges.py``)."""

from __future__ import annotations

import numpy as np

from mapkit_harness.plans.grid_layout import RoomGridLayout


def room_grid(n: int, subdivide: int, height: float = 2.5, thick: float = 0.2):
    """An n x n grid of 4 x 3 m rooms; walls are separate subdivided boxes.

    Walls along x span the whole grid width, walls along y sit between them,
    so every wall/wall junction is a T or an L of touching boxes (a
    :class:`~mapkit_harness.plans.grid_layout.RoomGridLayout` with walls
    after their grid lines and butt junctions, no doorways).
    """
    import trimesh

    def box(lo, hi):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        m = trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))
        for _ in range(subdivide):
            m = m.subdivide()
        return m

    layout = RoomGridLayout((n, n), (4.0, 3.0), thick, placement="after_line", junctions="butt")
    walls = layout.walls()
    # The walls along x first (south to north), then the pieces of those
    # along y row by row, west to east: the order the mesh was first made in.
    pieces = [p for wall in walls if not wall.between_columns for p in wall.pieces]
    pieces += sorted((p for wall in walls if wall.between_columns for p in wall.pieces), key=lambda r: (r[1], r[0]))
    parts = [box([x0, y0, 0], [x1, y1, height]) for x0, y0, x1, y1 in pieces]
    return trimesh.util.concatenate(parts)


def expected_grid_edges(n: int) -> int:
    """Edges of the grid's union seen from inside and outside, worked out by hand.

    Per room: 4 floor, 4 ceiling junctions, 4 vertical corners (16 n^2 in all
    over 4 kinds... 12 n^2). Outside: 4 floor, 4 top and 4 vertical corners of
    the outline. The tops of the walls between rooms: each x-wall top is one
    strip with long edges on both sides (the rooms' ceiling junctions, already
    counted) and its 0.2 m ends (too short). So 12 n^2 + 12.
    """
    return 12 * n * n + 12
