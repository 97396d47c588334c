"""The model segments one prior can see, with what both stages need of them.

Method.md section 3: the union of the visible lists of the regions the
prior disk meets, cut to those that some pose of the prior can have in the
horizontal field of view; then grouped into collinear groups (one
representative span per group for stage 1) and paired with the map's
walls, free space and sight table (:class:`~matcher.map_index.MapIndex`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linemap.camera import Camera
from linemap.geometry import in_field_of_view
from linemap.lmap import LineMap
from matcher.map_index import index_of
from matcher.map_geometry.collinear import class_faces, collinear_classes
from matcher.tolerances import Tolerances


@dataclass
class Candidates:
    """Per candidate segment n (N,): ``ids`` its map id, ``segments`` (N, 2,
    3) its end points, ``label`` its collinear group; per group g (G,):
    ``reps`` (G, 2, 3) the span of its members, ``faces`` (G, 2) the
    room-side normal of the wall face its members lie on (zeros: none or
    several). The map's ``walls`` (:class:`~matcher.map_geometry.occlusion.WallEdges`
    or None), ``free`` (:class:`~matcher.map_geometry.freespace.FreeSpace`) and
    ``sight`` (:class:`~matcher.map_geometry.occlusion.SightRays` or None)."""

    ids: np.ndarray
    segments: np.ndarray
    label: np.ndarray
    reps: np.ndarray
    faces: np.ndarray
    walls: object | None
    free: object | None
    sight: object | None


def select_candidates(linemap: LineMap, camera: Camera, px, tol: Tolerances,
                      candidate_ids: np.ndarray | None = None) -> Candidates | str:
    """The candidates of prior ``px`` ``(xe, ye, yaw_e, dt, dyaw)`` (radians),
    from the regions its disk meets (or from ``candidate_ids``, a region's
    own list in lost mode); the reason as a string when there are none."""
    xe, ye, yaw_e, dt, dyaw = px
    ids = linemap.candidate_segments(xe, ye, dt) if candidate_ids is None else candidate_ids
    if len(ids) == 0:
        if len(linemap.regions_near(xe, ye, dt)) == 0:
            return (f"the prior ({xe:.6g}, {ye:.6g}) is farther than dt={dt:g} m from every region of the map; "
                    "check the prior or use localize_global")
        return "no model segment is visible from the regions met by the prior disk"
    fov = in_field_of_view(linemap.segments[ids], camera, (xe, ye, yaw_e), dt, dyaw)
    ids = ids[fov]
    if len(ids) == 0:
        return "no candidate segment lies in the field of view for any heading of the prior interval"
    work = tol.map_index
    index = index_of(linemap)
    segs = linemap.segments[ids]
    # Collinear groups: made once per map, spans per frame.
    label, reps = collinear_classes(segs, work.collinear_deg, work.collinear_m, label=index.collinear(work)[ids])
    return Candidates(ids, segs, label, reps, class_faces(index.faces(work)[ids], label), index.walls,
                      index.free(work), index.sight(work))
