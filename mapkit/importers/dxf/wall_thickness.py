"""The thickness of a plan's walls, measured whatever its units: a second
sign of the units, independent of its doors.

A double-line wall is two parallel lines a wall's thickness apart. Each
straight piece of the wall lines is paired with the nearest piece
parallel to it (within ``WALL_CAP_ANGLE_DEG``) that runs beside it (their
projections overlap) among its ``GAP_UNITS_NEIGHBOURS`` nearest pieces (by
midpoint); the distance between the two lines is that piece's thickness.
The thickness of the walls is the length-weighted median over the pieces
that have a partner: long wall sides weigh more than short returns,
window jambs or furniture strokes on the wall layer. Measured on the
strokes as read, before the units are known, so nothing here is in metres;
pieces closer than ``GAP_UNITS_TOUCH_SHARE`` of the plan's extent are one
line drawn twice, not a wall's two sides.

A plan of single wall lines has no pairs but rooms facing each other
across a corridor: the measure is then a room's or a corridor's width and
says nothing of thickness; :func:`wall_thickness` returns None when fewer
than half of the wall lines' length has a partner within a share
``GAP_UNITS_REACH_SHARE`` of the extent.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from mapkit.importers.dxf.doorway_gaps import stroke_pieces
from mapkit.tolerances import GAP_UNITS_NEIGHBOURS, GAP_UNITS_REACH_SHARE, GAP_UNITS_TOUCH_SHARE, WALL_CAP_ANGLE_DEG


def wall_thickness(strokes: list) -> float | None:
    """The typical distance between the two lines of the double-line walls
    in the wall ``strokes`` (their own units), or None when the walls are
    not drawn as pairs of lines (see the module docstring)."""
    a, b, _ = stroke_pieces([s for s in strokes if not getattr(s, "filled", False)], 0.0)
    length = np.linalg.norm(b - a, axis=1)
    if len(a) < 2:
        return None
    points = np.concatenate([a, b])
    extent = float((points.max(axis=0) - points.min(axis=0)).max())
    apart = _partner_distance(a, b, length, GAP_UNITS_TOUCH_SHARE * extent, GAP_UNITS_REACH_SHARE * extent)
    paired = np.isfinite(apart)
    if length[paired].sum() < 0.5 * length.sum():
        return None
    order = np.argsort(apart[paired])
    weight = np.cumsum(length[paired][order])
    return float(apart[paired][order][np.searchsorted(weight, 0.5 * weight[-1])])


def _partner_distance(a: np.ndarray, b: np.ndarray, length: np.ndarray, touch: float, reach: float) -> np.ndarray:
    """Per piece ``a -> b`` (each (N, 2), lengths ``length``), the distance
    to the nearest parallel piece beside it, farther than ``touch`` and
    within ``reach``; inf for a piece without one. Shape (N,)."""
    direction = (b - a) / length[:, None]
    normal = np.stack([-direction[:, 1], direction[:, 0]], axis=1)
    middle = 0.5 * (a + b)
    k = min(GAP_UNITS_NEIGHBOURS + 1, len(a))
    _, near = cKDTree(middle).query(middle, k=k)
    near = near.reshape(len(a), k)
    # Each candidate j of piece i: parallel, beside it, apart from it.
    d_i, d_j = direction[:, None, :], direction[near]
    parallel = np.abs((d_i * d_j).sum(axis=2)) >= np.cos(np.radians(WALL_CAP_ANGLE_DEG))
    offset = np.abs(((middle[near] - middle[:, None, :]) * normal[:, None, :]).sum(axis=2))
    t0 = ((a[near] - a[:, None, :]) * d_i).sum(axis=2)
    t1 = ((b[near] - a[:, None, :]) * d_i).sum(axis=2)
    overlap = np.minimum(np.maximum(t0, t1), length[:, None]) - np.maximum(np.minimum(t0, t1), 0.0)
    ok = parallel & (overlap > 0) & (offset > touch) & (offset <= reach) & (near != np.arange(len(a))[:, None])
    return np.where(ok, offset, np.inf).min(axis=1)
