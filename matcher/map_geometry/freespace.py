"""Where the camera can be: the map's regions as a distance raster.

The regions of a map tile the floor the robot can reach (the builder shrinks
the free floor by the robot's radius), so a pose hypothesis whose camera
stands inside a wall or beyond the building is impossible, however well its
lines fit. That happens when the image lines leave the pose free along one
direction (parallel walls, a row of door jambs seen end on): the strips then
meet all along that direction, walls included.

The raster is built once per map (cached on it): even-odd scanlines over
all region rings mark the cells inside a region, then a Euclidean distance
transform gives every cell its distance to the nearest inside cell.

How far outside the regions a camera may stand (:meth:`FreeSpace.allows`)
is what the map itself says lies between them and the walls: the builder
drew the regions its robot radius in from the walls (recorded in the map's
``meta["build"]["robot_radius"]``), so a point up to that far out, and the
map's own error ``model_m`` beyond, is still floor, only nearer a wall than
that robot keeps. A camera carried otherwise (a tripod in a doorway, beside
a jamb: the ZInD sample tour's panoramas) stands there; the true pose was
refused as "outside the map's free space" before, and a look-alike won.
Stage 2 asks this (:func:`matcher.prior.within_prior`); the tree's pruning
of sets keeps ``free_space_m`` (its loose-set test samples the free space,
and the walls' margin in it let a corridor's wrong-jamb sets through).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from matcher.tolerances import DEFAULT, MapIndexConstants


class FreeSpace:
    """Distance from a floor point to the map's regions, metres (0 inside)."""

    def __init__(self, ring_points: np.ndarray, ring_offsets: np.ndarray, work: MapIndexConstants = DEFAULT.map_index,
                 margin_m: float = 0.0) -> None:
        """``ring_points`` (P, 2) and ``ring_offsets`` (K+1,): the region rings
        of a map (outer rings and holes alike; the union of regions is their
        even-odd set because regions do not overlap). The raster's cell and
        margin are ``free_cell_m`` and ``free_border_m``; a map too large for
        ``free_max_cells`` cells of that size gets larger cells.
        ``margin_m``: how far in from the walls the regions were drawn (the
        builder's robot radius; 0 when the map does not say)."""
        self.margin_m = float(margin_m)
        self.cell = float(work.free_cell_m)
        border = work.free_border_m
        if len(ring_points) == 0:
            self.origin = np.zeros(2)
            self.dist = np.full((1, 1), np.inf)
            self._last = np.zeros(2, dtype=np.int64)
            return
        lo = ring_points.min(axis=0) - border
        hi = ring_points.max(axis=0) + border
        span = np.prod((hi - lo) / self.cell + 1.0)
        if span > work.free_max_cells:
            self.cell *= float(np.sqrt(span / work.free_max_cells)) * 1.001
        nx, ny = (np.ceil((hi - lo) / self.cell).astype(int) + 1).tolist()
        self.origin = lo
        inside = _even_odd_raster(ring_points, ring_offsets, lo, self.cell, nx, ny, work.free_scan_block)
        if inside.any():
            # Centre to centre, less half a cell: the region's border lies
            # about half a cell beyond the last inside centre.
            d = distance_transform_edt(~inside) * self.cell
            self.dist = np.where(inside, 0.0, np.maximum(d - 0.5 * self.cell, 0.0))
        else:
            self.dist = np.full((ny, nx), np.inf)
        self._last = np.array([nx - 1, ny - 1])  # the last cell (x, y): farther points read as the border

    def distance(self, xy: np.ndarray) -> np.ndarray:
        """(...) distance, metres, from points ``xy`` (..., 2) to the nearest
        region cell; points off the raster get the raster's border value."""
        cell = np.floor((np.asarray(xy, dtype=float) - self.origin) / self.cell).astype(np.int64)  # (..., 2)
        np.clip(cell, 0, self._last, out=cell)
        return self.dist[cell[..., 1], cell[..., 0]]

    def allows(self, xy: np.ndarray, free_m: float, model_m: float) -> np.ndarray:
        """(...) bool: may a camera stand at ``xy`` (..., 2)? Within
        ``free_m`` of the regions (``Tolerances.free_space_m``: a camera off
        the robot's centre) or, where the map records it, within the floor
        it left between its regions and the walls (``margin_m``, give or
        take the map's error ``model_m``): not inside a wall nor beyond the
        building (module docstring)."""
        return self.distance(xy) <= max(free_m, self.margin_m + model_m)


def _even_odd_raster(points, offsets, origin, cell, nx, ny, block: int) -> np.ndarray:
    """(ny, nx) bool: cell centres inside the rings under the even-odd rule.

    Per row, each ring edge straddling the row's centre line crosses it once;
    the crossings are binned by column and a running count along the row
    gives each cell centre the parity of the crossings to its left. Rows
    are taken ``block // edges`` at a time (bounded temporaries)."""
    idx = np.arange(len(points))
    nxt = idx + 1
    nxt[offsets[1:] - 1] = offsets[:-1]  # each ring closes on its first point
    a, b = points, points[nxt]
    yc = origin[1] + (np.arange(ny) + 0.5) * cell  # (ny,)
    step = max(1, block // max(len(a), 1))
    rows, edges = [], []
    for r0 in range(0, ny, step):
        y = yc[r0:r0 + step, None]
        r, e = np.nonzero((a[None, :, 1] > y) != (b[None, :, 1] > y))  # rows of this block x edges
        rows.append(r + r0)
        edges.append(e)
    row, e = np.concatenate(rows), np.concatenate(edges)
    t = (yc[row] - a[e, 1]) / (b[e, 1] - a[e, 1])
    xcross = a[e, 0] + t * (b[e, 0] - a[e, 0])
    # A crossing at x lies left of every cell centre x_c > x: the first such
    # column is ceil((x - origin) / cell - 0.5).
    col = np.clip(np.ceil((xcross - origin[0]) / cell - 0.5).astype(np.int64), 0, nx)
    counts = np.zeros((ny, nx + 1), dtype=np.int64)
    np.add.at(counts, (row, col), 1)
    return (np.cumsum(counts, axis=1)[:, :nx] % 2) == 1


def free_space(linemap) -> FreeSpace:
    """The map's :class:`FreeSpace`, built on first use and kept with the map."""
    from matcher.map_index import index_of

    return index_of(linemap).free()
