"""Stairs drawn on a wall layer: runs of treads, not walls.

A plan draws a stair as its treads, one line per step: many short lines
of one length, side by side, at one spacing (the going, 0.25 to 0.35 m
for a building's stairs). Architects put them on the wall layer with the
stair well's walls. Taken for walls, each tread becomes a thin wall: the
stair is a comb of walls, the landing at its foot a room of its own, and
the map's walls carry a fence of full-height slabs where people walk.

A run of treads (:func:`find_stair_runs`) is no wall: its lines leave the
walls, and its extent (the rectangle its treads span) is no floor a robot
drives on either: a wheeled robot does not climb stairs, and the other end
of a stair is another level: :func:`without_stairs` takes the runs out of
the free space. A part of it in a stair well
that only the stair leads to from this storey is left out
(:func:`stair_reached_parts`): a landing up the steps, or the well's exit
whose only door opens to the outside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from mapkit.importers.dxf.reachable import where_left_out
from mapkit.importers.dxf.strokes import Stroke
from mapkit.shapes import polygon_parts
from mapkit.tolerances import (COLLINEAR_DEG, DOOR_REACH_SLACK, MERGE, MIN_FREE_AREA, STAIR_GOING, STAIR_GOING_EVEN,
                               STAIR_MIN_TREADS, STAIR_TREAD_ALIGN, STAIR_TREAD_LENGTH,
                               SNAP_GAP, STAIR_WELL_SHARE, THIN_WALL)


@dataclass(frozen=True)
class StairRun:
    """One flight of a stair as drawn.

    - ``treads``: indices of its tread lines in the strokes searched.
    - ``footprint``: the rectangle its treads span (metres): from the first
      tread to the last across them, their length along them.
    - ``flight``: the footprint longer at both ends by a going and
      ``THIN_WALL``: the flight with its first and last step, whose edges
      (a landing's edge, often drawn across both flights of a dog-leg
      stair, longer than the treads) are lines of their own, thickened as
      single wall lines are.
    - ``going``: the mean spacing of its treads, metres.
    - ``width``: the length of its treads (the flight's width), metres.
    """

    treads: tuple[int, ...]
    footprint: Polygon
    flight: Polygon
    going: float
    width: float


def find_stair_runs(strokes: list[Stroke]) -> list[StairRun]:
    """The runs of treads among ``strokes`` (metres).

    A tread is an open straight stroke (two points) ``STAIR_TREAD_LENGTH``
    long. A run is ``STAIR_MIN_TREADS`` or more treads that are parallel
    (within ``COLLINEAR_DEG``), start and end level with each other (within
    ``STAIR_TREAD_ALIGN`` along them), and follow each other at one spacing
    in ``STAIR_GOING`` (each within ``STAIR_GOING_EVEN`` of the run's first
    spacing). Lines drawn twice over count once. Returned in the order of
    their first tread."""
    lo, hi = STAIR_TREAD_LENGTH
    candidates = []
    for i, s in enumerate(strokes):
        if s.closed or s.filled or len(s.coords) != 2:
            continue
        d = np.asarray(s.coords[1], float)[:2] - np.asarray(s.coords[0], float)[:2]
        length = float(np.hypot(*d))
        if lo <= length <= hi:
            candidates.append((i, np.degrees(np.arctan2(d[1], d[0])) % 180.0))
    runs: list[StairRun] = []
    for group in _parallel_groups(candidates):
        runs.extend(_runs_of_parallel(strokes, group))
    return sorted(runs, key=lambda r: r.treads[0])


def _parallel_groups(candidates: list[tuple[int, float]]) -> list[list[int]]:
    """Stroke indices grouped by direction: angles (degrees, in [0, 180))
    within ``COLLINEAR_DEG`` of the previous one chain into one group; the
    groups at 0 and 180 degrees are one."""
    if not candidates:
        return []
    order = sorted(candidates, key=lambda c: c[1])
    groups = [[order[0]]]
    for c in order[1:]:
        if c[1] - groups[-1][-1][1] <= COLLINEAR_DEG:
            groups[-1].append(c)
        else:
            groups.append([c])
    if len(groups) > 1 and groups[0][0][1] + 180.0 - groups[-1][-1][1] <= COLLINEAR_DEG:
        groups[0] = groups.pop() + groups[0]
    return [[i for i, _ in g] for g in groups]


def _runs_of_parallel(strokes: list[Stroke], group: list[int]) -> list[StairRun]:
    """The runs among parallel strokes ``group`` (indices into ``strokes``)."""
    if len(group) < STAIR_MIN_TREADS:
        return []
    ends = np.array([np.asarray(strokes[i].coords, float)[:2, :2] for i in group])  # (n, 2, 2)
    vec = ends[:, 1] - ends[:, 0]
    # One direction for the group, the lines oriented alike.
    ref = vec[0] / np.linalg.norm(vec[0])
    vec = np.where((vec @ ref)[:, None] < 0, -vec, vec)
    u = vec.sum(axis=0)
    u /= np.linalg.norm(u)
    n = np.array([-u[1], u[0]])
    along = np.sort(ends @ u, axis=1)  # (n, 2): where each line starts and ends along u
    across = (ends @ n).mean(axis=1)  # (n,): where each line lies across u
    runs = []
    for members in _level_sets(along):
        runs.extend(_spaced_runs([group[k] for k in members], along[members], across[members], u, n))
    return runs


def _level_sets(along: np.ndarray) -> list[np.ndarray]:
    """Indices of lines that start and end level with each other (within
    ``STAIR_TREAD_ALIGN``), grouped: ``along`` is ``(n, 2)``, each line's
    start and end along the common direction. Lines are first chained by
    their starts (sorted, a gap wider than the tolerance splits), so that
    each exact comparison runs within a chain."""
    sets = []
    order = np.argsort(along[:, 0], kind="stable")
    splits = np.flatnonzero(np.diff(along[order, 0]) > STAIR_TREAD_ALIGN) + 1
    for remaining in np.split(order, splits):
        while len(remaining) >= STAIR_MIN_TREADS:
            k = remaining[0]
            level = np.all(np.abs(along[remaining] - along[k]) <= STAIR_TREAD_ALIGN, axis=1)
            if level.sum() >= STAIR_MIN_TREADS:
                sets.append(np.sort(remaining[level]))
            remaining = remaining[~level]
    return sets


def _spaced_runs(idx: list[int], along: np.ndarray, across: np.ndarray, u: np.ndarray,
                 n: np.ndarray) -> list[StairRun]:
    """The runs among level parallel lines: consecutive lines (across them)
    at one spacing in ``STAIR_GOING``."""
    order = np.argsort(across)
    pos, keep = [], []
    for k in order:  # a line drawn twice over is one line
        if pos and across[k] - pos[-1] <= MERGE:
            continue
        pos.append(across[k])
        keep.append(k)
    pos = np.array(pos)
    runs = []
    start = 0
    while start < len(keep) - 1:
        first = pos[start + 1] - pos[start]
        end = start + 1
        if STAIR_GOING[0] <= first <= STAIR_GOING[1]:
            while end + 1 < len(keep) and abs(pos[end + 1] - pos[end] - first) <= STAIR_GOING_EVEN:
                end += 1
        if end - start + 1 >= STAIR_MIN_TREADS:
            members = [keep[k] for k in range(start, end + 1)]
            a0 = float(np.median(along[members, 0]))
            a1 = float(np.median(along[members, 1]))
            c0, c1 = float(pos[start]), float(pos[end])
            going = (c1 - c0) / (end - start)
            flight = _rectangle(a0, a1, c0 - going - THIN_WALL, c1 + going + THIN_WALL, u, n)
            runs.append(StairRun(tuple(sorted(idx[k] for k in members)), _rectangle(a0, a1, c0, c1, u, n), flight,
                                 going, a1 - a0))
            start = end
        else:
            start += 1
    return runs


def _rectangle(a0: float, a1: float, c0: float, c1: float, u: np.ndarray, n: np.ndarray) -> Polygon:
    """The rectangle from ``a0`` to ``a1`` along unit ``u`` and ``c0`` to ``c1`` along unit ``n``."""
    return Polygon([a * u + c * n for a, c in ((a0, c0), (a1, c0), (a1, c1), (a0, c1))])


def without_treads(strokes: list[Stroke], runs: list[StairRun]) -> list[Stroke]:
    """``strokes`` less the tread lines of ``runs`` (``strokes`` itself when there is none)."""
    if not runs:
        return strokes
    treads = {i for r in runs for i in r.treads}
    return [s for i, s in enumerate(strokes) if i not in treads]


def tread_lines(strokes: list[Stroke], runs: list[StairRun]) -> shapely.MultiLineString:
    """The tread lines of ``runs`` (indices into ``strokes``), for previews."""
    return shapely.MultiLineString([np.asarray(strokes[i].coords, float)[:, :2] for r in runs for i in r.treads])


def stair_wells(barriers: list, runs: list[StairRun]) -> list[Polygon]:
    """The rooms that hold the ``runs``: the holes of the union of
    ``barriers`` (walls, glass, door gaps and doorways, which shut them;
    metres; hairline slits closed by ``SNAP_GAP``) that a run's footprint
    overlaps, once the runs' flights are taken out of them (the lines of a
    flight's end steps and its stringers box each flight in: the landing
    beyond belongs to the same well). A stair in an open hall gives the
    hall."""
    footprints = [r.footprint for r in runs]
    shut = shapely.union_all(barriers).buffer(SNAP_GAP, join_style="mitre").buffer(-SNAP_GAP, join_style="mitre")
    shut = shut.difference(shapely.union_all([r.flight for r in runs]))
    wells = []
    for poly in polygon_parts(shut):
        for ring in poly.interiors:
            hole = Polygon(ring)
            if any(hole.intersection(f).area > 0 for f in footprints):
                wells.append(hole)
    return wells


def without_stairs(free: MultiPolygon, runs: list[StairRun], robot_radius: float) -> MultiPolygon:
    """``free`` (where the robot's centre may be, metres) less the runs'
    footprints grown by ``robot_radius``: a stair is no floor to drive on.
    Pieces under ``MIN_FREE_AREA`` are dropped."""
    if not runs:
        return free
    rest = free.difference(stair_footprint(runs).buffer(robot_radius))
    return MultiPolygon([p for p in polygon_parts(rest) if p.area >= MIN_FREE_AREA])


def stair_reached_parts(free: MultiPolygon, wells: list[Polygon], entries: list,
                        robot_radius: float) -> tuple[MultiPolygon, list[Polygon]]:
    """``(kept, left_out)``: the parts of ``free`` (metres) less those that
    only a stair leads to from this storey.

    Such a part lies mostly (``STAIR_WELL_SHARE`` of its area) in a stair
    well (``wells``, :func:`stair_wells`), is not the largest part (the
    storey), and no entry (door gaps, doorways, door drawings) joins it to
    another part within ``robot_radius + DOOR_REACH_SLACK``: it is a
    landing reached up the steps, or a stair well's exit that a door leads
    into from outdoors only. With no entry, or no well, every part is
    kept (no door can be told from none)."""
    parts = polygon_parts(free)
    if len(parts) <= 1 or not wells or not entries:
        return free, []
    reach = robot_radius + DOOR_REACH_SLACK
    well = shapely.union_all(wells)
    tree = shapely.STRtree(entries)
    touching = [tree.query(p, predicate="dwithin", distance=reach) for p in parts]
    parts_at = np.bincount(np.concatenate(touching), minlength=len(entries))
    largest = max(range(len(parts)), key=lambda k: parts[k].area)
    kept, left_out = [], []
    for k, part in enumerate(parts):
        joined = bool(np.any(parts_at[touching[k]] >= 2))  # an entry this part and another touch
        in_well = part.intersection(well).area >= STAIR_WELL_SHARE * part.area
        (left_out if k != largest and in_well and not joined else kept).append(part)
    if not left_out:
        return free, []
    return MultiPolygon(kept), left_out


def describe_runs(runs: list[StairRun]) -> str:
    """One warning line about the stair runs found on the wall layers."""
    goings = sorted(r.going for r in runs)
    return (f"{len(runs)} stair run(s) drawn on the wall layer(s) ({sum(len(r.treads) for r in runs)} treads at "
            f"{goings[0]:.2f} to {goings[-1]:.2f} m spacing) are stairs, not walls: their treads leave the walls "
            f"and their extent ({stair_footprint(runs).area:.1f} m2) is no floor to drive on")


def describe_stair_reached(left_out: list[Polygon]) -> str:
    """One warning line about the spaces :func:`stair_reached_parts` left out."""
    area = sum(p.area for p in left_out)
    return (f"{len(left_out)} space(s) in a stair well that only the stair leads to from this storey ({area:.1f} m2: "
            f"landings up the steps, or a stair's exit with doors to the outside only) left out of the free space: "
            f"{where_left_out(left_out)}; check them in 'mapkit preview'")


def stair_footprint(runs: list[StairRun]):
    """The union of the runs' footprints (empty polygon for none)."""
    return shapely.union_all([r.footprint for r in runs]) if runs else Polygon()


__all__ = ["StairRun", "describe_runs", "describe_stair_reached", "find_stair_runs", "stair_footprint",
           "stair_reached_parts", "stair_wells", "tread_lines", "without_stairs", "without_treads"]
