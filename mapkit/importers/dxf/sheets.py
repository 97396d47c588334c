"""Sheets, not plans: a drawing that holds several separate plans.

Architects put two storeys side by side on one sheet, or four floor plans
beside sections and a site plan. Read as one floor, the storeys become one
building of twice the width (or the floor-area bound refuses it). The
plans are the clusters of the wall linework: wall strokes closer than
``SHEET_GAP_M`` belong to one plan. A cluster with at least
``SHEET_MIN_PLAN_SHARE`` of the largest one's wall length, over at least
``SHEET_MIN_PLAN_AREA_SHARE`` of its footprint (the storeys of a sheet
cover about the same ground), is a plan; the rest (a column, a shed, the
Barcelona pavilion's annex across its pool) stays with the plan nearest it.

With one plan nothing changes. With several, the largest is built unless
``--plan N`` (numbered by wall length, largest first) chooses another; the
other plans' strokes are kept only for previews, and a warning names them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from mapkit.errors import MapkitError
from mapkit.importers.dxf.strokes import Stroke
from mapkit.tolerances import SHEET_GAP_M, SHEET_MIN_PLAN_AREA_SHARE, SHEET_MIN_PLAN_SHARE


@dataclass(frozen=True)
class SheetPlan:
    """One plan of a sheet: its number (1: the most wall), the bounding box
    of its walls ``(x0, y0, x1, y1)`` metres, and their length, metres."""

    number: int
    bounds: tuple[float, float, float, float]
    wall_length_m: float

    def describe(self) -> str:
        x0, y0, x1, y1 = self.bounds
        return f"#{self.number} {x1 - x0:.0f} x {y1 - y0:.0f} m at ({x0:.0f}, {y0:.0f})"

    def to_dict(self) -> dict:
        return {"plan": self.number, "bounds_m": [round(v, 3) for v in self.bounds],
                "wall_length_m": round(self.wall_length_m, 3)}


def find_plans(walls: list[Stroke]) -> tuple[list[SheetPlan], np.ndarray]:
    """The plans of a sheet from its wall strokes, and for each stroke the
    number of its plan (strokes of small clusters join the nearest plan)."""
    if not walls:
        return [], np.zeros(0, dtype=int)
    boxes = np.array([[*s.coords.min(axis=0), *s.coords.max(axis=0)] for s in walls])
    cluster = _clusters(boxes, SHEET_GAP_M)
    lengths = np.array([float(np.linalg.norm(np.diff(s.coords, axis=0), axis=1).sum()) for s in walls])
    total = np.bincount(cluster, weights=lengths)
    extent = {c: _bounds(boxes[cluster == c]) for c in range(len(total))}
    area = np.array([(x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in (extent[c] for c in range(len(total)))])
    largest = int(np.argmax(total))
    big = np.nonzero((total >= SHEET_MIN_PLAN_SHARE * total[largest]) & (area >= SHEET_MIN_PLAN_AREA_SHARE * area[largest]))[0]
    big = big[np.argsort(-total[big], kind="stable")]
    number = {int(c): k + 1 for k, c in enumerate(big)}
    plans = [SheetPlan(number[int(c)], extent[c], float(total[c])) for c in big]
    of_stroke = np.array([number.get(int(c), 0) for c in cluster])
    for i in np.nonzero(of_stroke == 0)[0]:  # a small cluster: the nearest plan
        of_stroke[i] = nearest_plan(plans, boxes[i])
    return plans, of_stroke


def nearest_plan(plans: list[SheetPlan], box) -> int:
    """Number of the plan whose bounding box is nearest ``box`` (x0, y0, x1, y1)."""
    b = shapely.box(*box)
    return min(plans, key=lambda p: shapely.box(*p.bounds).distance(b)).number


def plans_met(plans: list[SheetPlan], box) -> list[int]:
    """Numbers of the plans whose bounding box ``box`` (x0, y0, x1, y1) overlaps."""
    b = shapely.box(*box)
    return [p.number for p in plans if shapely.box(*p.bounds).intersects(b)]


def choose_plan(plans: list[SheetPlan], choice: int | None) -> SheetPlan:
    """The plan to build: ``choice`` (``--plan N``) or the largest."""
    if choice is None:
        return plans[0]
    if not 1 <= choice <= len(plans):
        listed = "; ".join(p.describe() for p in plans)
        raise MapkitError(f"--plan {choice}: the drawing holds {len(plans)} plan(s): {listed}")
    return plans[choice - 1]


def _clusters(boxes: np.ndarray, gap: float) -> np.ndarray:
    """Cluster label of each box (x0, y0, x1, y1): boxes within ``gap`` of
    each other, directly or through others, share one."""
    geoms = shapely.box(boxes[:, 0], boxes[:, 1], boxes[:, 2], boxes[:, 3])
    left, right = shapely.STRtree(geoms).query(geoms, predicate="dwithin", distance=gap)
    parent = np.arange(len(boxes))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in zip(left.tolist(), right.tolist()):
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([root(i) for i in range(len(boxes))])
    return np.unique(roots, return_inverse=True)[1]


def _bounds(boxes: np.ndarray) -> tuple[float, float, float, float]:
    return (float(boxes[:, 0].min()), float(boxes[:, 1].min()), float(boxes[:, 2].max()), float(boxes[:, 3].max()))
