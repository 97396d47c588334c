"""What the matcher derives from a map once and keeps with it.

:class:`MapIndex` is made on the first :func:`~matcher.localize` call on a
map (:func:`index_of`: one per map) and each of its parts on first use: a
frame pays only for what it needs, and the next frame on the same map pays
for none of it. A part depends on a few of the constants
:class:`~matcher.tolerances.MapIndexConstants` (``Tolerances.map_index``,
:data:`PART_FIELDS`) and is kept per their values, so tolerances that differ
elsewhere (another ``e_accept``, lost mode's wider search) share it, and
another ``free_cell_m`` rebuilds the free-space raster alone. The map must
not be mutated after.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from linemap.lmap import LineMap
from matcher.map_geometry.collinear import collinear_labels
from matcher.map_geometry.freespace import FreeSpace
from matcher.map_geometry.occlusion import SightRays, WallEdges, face_normals, wall_edges
from matcher.tolerances import DEFAULT, MapIndexConstants

#: The fields of :class:`~matcher.tolerances.MapIndexConstants` each part is
#: built with (tests/test_matcher_map_index.py checks that they read no
#: other, and that every field is some part's).
PART_FIELDS = {
    "collinear": ("collinear_deg", "collinear_m"),
    "sight": ("sight_bins", "sight_skip_m", "ray_chunk"),
    "faces": ("face_probe_m",),
    "free": ("free_cell_m", "free_border_m", "free_max_cells", "free_scan_block"),
}


def index_of(linemap: LineMap) -> MapIndex:
    """The map's :class:`MapIndex`, made on the first call and kept with it."""
    return linemap.derived(MapIndex)


class MapIndex:
    """Per-map lookups of the matcher, each built on first use with the
    constants ``work`` (:class:`~matcher.tolerances.MapIndexConstants`) it
    is asked with, and kept per the values of its :data:`PART_FIELDS`."""

    def __init__(self, linemap: LineMap) -> None:
        self.linemap = linemap
        self._parts: dict[tuple, object] = {}

    def _part(self, name: str, work: MapIndexConstants, build):
        """Part ``name`` for ``work``: ``build()`` on the first call with
        these values of its fields, kept after."""
        key = (name, *(getattr(work, f) for f in PART_FIELDS[name]))
        if key not in self._parts:
            self._parts[key] = build()
        return self._parts[key]

    def collinear(self, work: MapIndexConstants = DEFAULT.map_index) -> np.ndarray:
        """(N,) group id of each segment: segments on one 3D line
        (:func:`~matcher.map_geometry.collinear.collinear_labels`)."""
        return self._part("collinear", work,
                          lambda: collinear_labels(self.linemap.segments, work.collinear_deg, work.collinear_m))

    @cached_property
    def walls(self) -> WallEdges | None:
        """The wall outlines' edges, the occluders; None without walls."""
        return wall_edges(self.linemap)

    def sight(self, work: MapIndexConstants = DEFAULT.map_index) -> SightRays | None:
        """How far one sees from each vertical edge, per bearing; None without walls."""
        return self._part("sight", work, lambda: SightRays(self.walls, work) if self.walls is not None else None)

    def faces(self, work: MapIndexConstants = DEFAULT.map_index) -> np.ndarray:
        """(N, 2) room-side normal of the wall face each segment lies on (zeros: none)."""
        return self._part("faces", work, lambda: face_normals(self.linemap.segments, self.walls, work))

    def free(self, work: MapIndexConstants = DEFAULT.map_index) -> FreeSpace:
        """Distance from a floor point to the map's regions."""
        return self._part("free", work, lambda: FreeSpace(self.linemap.ring_points, self.linemap.ring_offsets, work))
