"""What the matcher derives from a map once and keeps with it.

:class:`MapIndex` is made on the first :func:`~matcher.localize` call on a
map (``linemap.derived(MapIndex, tol.internals)``) and each of its parts on
first use: a frame pays only for what it needs, and the next frame on the
same map pays for none of it. The map must not be mutated after.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from linemap.lmap import LineMap
from matcher.scene.collinear import collinear_labels
from matcher.scene.freespace import FreeSpace
from matcher.scene.occlusion import SightRays, WallEdges, face_normals, wall_edges
from matcher.tolerances import DEFAULT_INTERNALS, Internals


class MapIndex:
    """Per-map lookups of the matcher, each built on first use with the
    inner constants ``work``."""

    def __init__(self, linemap: LineMap, work: Internals = DEFAULT_INTERNALS) -> None:
        self.linemap = linemap
        self.work = work

    @cached_property
    def collinear(self) -> np.ndarray:
        """(N,) group id of each segment: segments on one 3D line
        (:func:`~matcher.scene.collinear.collinear_labels`)."""
        return collinear_labels(self.linemap.segments, self.work.collinear_deg, self.work.collinear_m)

    @cached_property
    def walls(self) -> WallEdges | None:
        """The wall outlines' edges, the occluders; None without walls."""
        return wall_edges(self.linemap)

    @cached_property
    def sight(self) -> SightRays | None:
        """How far one sees from each vertical edge, per bearing; None without walls."""
        return SightRays(self.walls, self.work) if self.walls is not None else None

    @cached_property
    def faces(self) -> np.ndarray:
        """(N, 2) room-side normal of the wall face each segment lies on (zeros: none)."""
        return face_normals(self.linemap.segments, self.walls, self.work)

    @cached_property
    def free(self) -> FreeSpace:
        """Distance from a floor point to the map's regions."""
        return FreeSpace(self.linemap.ring_points, self.linemap.ring_offsets, self.work)
