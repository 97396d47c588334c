"""Door swings drawn on layers read as something else, found by their shape.

Doors are often drawn with the furniture (a CityScope office: its office
doors' swings on ``Furniture``) or on a layer whose name says nothing. Such
a layer is left out of the plan, so its doors are not read and the plan's
doorways stay bare gaps: the map knows no door. A door swing looks like
nothing else a plan draws, whatever its layer:

- an arc of a door leaf's radius (``DOOR_SWING_RADIUS``, within
  ``DOOR_SWING_SNAP``) turning between half of ``DOOR_SWING_MAX_SWEEP_DEG``
  and all of it, with its leaf: another stroke of the same layer reaching
  the arc's centre (the hinge) and one of its ends (within
  ``DOOR_SWING_TIP_SHARE`` of the radius), no longer than a leaf
  (``DOOR_SWING_LEAF_LENGTH`` radii); or
- one polyline drawn as the leaf and then the arc (or the arc and then the
  leaf): its first segment from the hinge to the leaf's tip, the rest an arc
  about the hinge of the leaf's length.

:func:`find_swings` finds them on one layer's strokes (the self-check
counts those the plan left out); :func:`adopt_loose_swings` takes those
whose hinge is on a wall (within the same tip share of the radius of a
wall stroke: a door hangs at a jamb; a chair's arc or a table's is not
hinged on a wall) as door drawings, one drawing per swing. Whether each
sits in a doorway is then decided as for any door drawing
(:mod:`.openings`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import shapely

from mapkit.importers.dxf.strokes import PlanDrawing, Stroke
from mapkit.tolerances import (DOOR_SWING_LEAF_LENGTH, DOOR_SWING_MAX_SWEEP_DEG, DOOR_SWING_RADIUS, DOOR_SWING_SNAP,
                               DOOR_SWING_TIP_SHARE, ZERO)


@dataclass(frozen=True)
class Swing:
    """One door swing of a layer: the indices of its strokes in the layer's
    list (the arc and its leaf, or the one polyline), its hinge ``(x, y)``
    metres and its radius, metres."""

    strokes: tuple[int, ...]
    hinge: np.ndarray
    radius: float


def swing_arc(coords) -> tuple[np.ndarray, float, tuple[np.ndarray, np.ndarray]] | None:
    """``(centre, radius, ends)`` of a polyline (N >= 3, 2+) metres that is an
    arc of a door leaf's radius turning about a quarter; None otherwise."""
    p = np.asarray(coords, dtype=float)[:, :2]
    if len(p) < 3:
        return None
    a, b, c = p[0], p[len(p) // 2], p[-1]
    m = 2.0 * np.array([b - a, c - a])
    if abs(np.linalg.det(m)) <= ZERO.distance:
        return None
    centre = np.linalg.solve(m, np.array([b @ b - a @ a, c @ c - a @ a]))
    radii = np.linalg.norm(p - centre, axis=1)
    r = float(radii.mean())
    lo, hi = DOOR_SWING_RADIUS
    if not lo <= r <= hi or float(np.abs(radii - r).max()) > DOOR_SWING_SNAP:
        return None
    u, v = a - centre, c - centre
    sweep = float(np.degrees(np.arccos(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)), -1.0, 1.0))))
    if not 0.5 * DOOR_SWING_MAX_SWEEP_DEG <= sweep <= DOOR_SWING_MAX_SWEEP_DEG:
        return None
    return centre, r, (a, c)


def _reach(radius: float) -> float:
    """How far a swing's hinge or tip may miss where it should be, metres."""
    return max(DOOR_SWING_SNAP, DOOR_SWING_TIP_SHARE * radius)


def _leaf_and_arc(coords) -> tuple[np.ndarray, float] | None:
    """``(hinge, radius)`` of one polyline drawn as a leaf and its arc (either
    way round: hinge, tip, arc; or arc, tip, hinge); None otherwise."""
    p = np.asarray(coords, dtype=float)[:, :2]
    if len(p) < 4:
        return None
    for q in (p, p[::-1]):
        hinge, leaf = q[0], float(np.linalg.norm(q[1] - q[0]))
        arc = swing_arc(q[1:])
        if arc is not None and np.linalg.norm(arc[0] - hinge) <= _reach(arc[1]) \
                and abs(leaf - arc[1]) <= DOOR_SWING_TIP_SHARE * arc[1]:
            return hinge, arc[1]
    return None


def find_swings(strokes: list[Stroke], leaf_radii: float = DOOR_SWING_LEAF_LENGTH[1]) -> list[Swing]:
    """The door swings drawn by one layer's ``strokes`` (see the module
    docstring); each stroke is in at most one swing. A leaf spans at most
    ``leaf_radii`` times the arc's radius (the self-check, counting the
    swings a plan left out, takes any stroke that reaches hinge and tip)."""
    pts = [np.asarray(s.coords, dtype=float)[:, :2] for s in strokes]
    spans = [float(np.hypot(*(v.max(axis=0) - v.min(axis=0)))) for v in pts]
    used: set[int] = set()
    out = []
    for k, s in enumerate(strokes):
        if s.closed:
            continue
        both = _leaf_and_arc(pts[k])
        if both is not None:
            used.add(k)
            out.append(Swing((k,), both[0], both[1]))
    for k, s in enumerate(strokes):
        if k in used or s.closed:
            continue
        arc = swing_arc(pts[k]) if len(pts[k]) >= 4 else None
        if arc is None:
            continue
        centre, r, ends = arc
        reach = _reach(r)
        for j, v in enumerate(pts):
            if j == k or j in used or spans[j] > leaf_radii * r:
                continue
            if np.linalg.norm(v - centre, axis=1).min() <= reach \
                    and min(np.linalg.norm(v - e, axis=1).min() for e in ends) <= reach:
                used.update((k, j))
                out.append(Swing((k, j), centre, r))
                break
    return out


def adopt_loose_swings(drawing: PlanDrawing, first_group: int) -> dict[str, int]:
    """Move the door swings of ``drawing``'s ignored layers whose hinge is on
    a wall (see the module docstring) to its door drawings, one group per
    swing (numbered from ``first_group``). Returns how many were taken, per
    layer (empty: none)."""
    walls = drawing.role("walls")
    if not walls:
        return {}
    lines = [np.vstack([s.coords[:, :2], s.coords[:1, :2]]) if s.closed else s.coords[:, :2]
             for s in walls if len(s.coords) >= 2]
    wall_lines = shapely.multilinestrings([shapely.linestrings(v) for v in lines])
    taken: dict[str, int] = {}
    group = first_group
    for layer in list(drawing.ignored):
        strokes = drawing.ignored[layer]
        hinged = [w for w in find_swings(strokes)
                  if shapely.distance(wall_lines, shapely.points(w.hinge)) <= _reach(w.radius)]
        if not hinged:
            continue
        moved = set()
        for w in hinged:
            drawing.strokes.setdefault("doors", []).extend(replace(strokes[k], group=group) for k in w.strokes)
            moved.update(w.strokes)
            group += 1
        drawing.ignored[layer] = [s for k, s in enumerate(strokes) if k not in moved]
        taken[layer] = len(hinged)
    return taken
