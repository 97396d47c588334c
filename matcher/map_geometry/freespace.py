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
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from matcher.tolerances import DEFAULT, MapIndexConstants


class FreeSpace:
    """Distance from a floor point to the map's regions, metres (0 inside)."""

    def __init__(self, ring_points: np.ndarray, ring_offsets: np.ndarray, work: MapIndexConstants = DEFAULT.map_index) -> None:
        """``ring_points`` (P, 2) and ``ring_offsets`` (K+1,): the region rings
        of a map (outer rings and holes alike; the union of regions is their
        even-odd set because regions do not overlap). The raster's cell and
        margin are ``free_cell_m`` and ``free_border_m``; a map too large for
        ``free_max_cells`` cells of that size gets larger cells."""
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
