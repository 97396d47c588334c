"""The layout of a grid of rectangular rooms joined by doorways: the one
place that says where the walls, the doorways and the doors of the
harness's grid plans are, so that every generator drawing such a grid
(:func:`~mapkit_harness.plans.drawings.office_grid`, a DXF;
:func:`~mapkit_harness.plans.buildings.grid_flat`, a LineMap;
:func:`~mapkit_harness.plans.meshes.room_grid`, a mesh) only renders it.

Metres, x east, y north. Rooms ``nx`` by ``ny`` of ``room_size`` =
(along x, along y); grid line ``i`` of the walls between columns is at
``x = i * room_size[0]`` (``i`` in ``0..nx``), grid line ``j`` of the walls
between rows at ``y = j * room_size[1]``. Each wall is ``thickness`` thick,
placed on its grid line by :attr:`RoomGridLayout.placement`:

- ``"centred"``: interior walls centred on their line, the outer walls
  inside the grid, so the building's outline is the grid's
  ``nx * room_size[0]`` by ``ny * room_size[1]``;
- ``"after_line"``: every wall from its line towards +x / +y, so the
  outline is one thickness larger than the grid each way.

and meets the walls it crosses by :attr:`RoomGridLayout.junctions`:

- ``"overlap"``: every wall runs the outline's whole length, wall pieces
  overlapping where walls cross (as CAD users draw them);
- ``"butt"``: the walls between rows run through, those between columns
  stop at them (touching boxes, T and L junctions, as exported meshes have).

Doorways (with ``door_width``): one per room in every interior wall, at
:data:`DOOR_AT` of the room along it (0.5 in walls between columns, 0.3
in walls between rows, so that no two doorways of a room line up). A door
is drawn on the wall's west face (walls between columns) or north face
(walls between rows) and swings off that face; its hinge alternates
between the doorway's two jambs from one doorway to the next.

The renderers keep the outputs they had before sharing this layout (byte
for byte): the DXF draws each wall's pieces then its doors, wall after
wall; the LineMap unions each interior wall's :attr:`GridWall.whole`
rectangle into the outer ring and then cuts every doorway at once, as
shapely's ring vertex order depends on that sequence of operations; the
mesh boxes the walls between rows, then the other pieces row by row.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

Rect = tuple[float, float, float, float]
"""An axis-aligned rectangle (x0, y0, x1, y1), x0 < x1 and y0 < y1, metres."""

#: Where a doorway stands along its wall, as a fraction of the room it
#: opens: keyed by ``between_columns`` (walls between columns run along y).
DOOR_AT = {True: 0.5, False: 0.3}


@dataclass(frozen=True)
class Doorway:
    """One doorway of a wall.

    - ``room``: index of the room along the wall (0 at the wall's low end);
    - ``span``: (a, b), a < b, the doorway's extent along the wall (y for a
      wall between columns, x for one between rows);
    - ``rect``: the opening through the wall's thickness;
    - ``hinge``, ``latch``: the door's jambs on the face it is drawn on,
      (x, y) each; ``swing_side`` +1 if the door swings to the left of
      hinge -> latch, -1 to the right (always off that face).
    """

    room: int
    span: tuple[float, float]
    rect: Rect
    hinge: tuple[float, float]
    latch: tuple[float, float]
    swing_side: int


@dataclass(frozen=True)
class GridWall:
    """One wall of the grid, on grid line ``index``.

    - ``between_columns``: True for a wall along y (between columns of
      rooms), False for one along x (between rows);
    - ``line``: the grid line's coordinate (x or y), metres;
    - ``band``: (lo, hi), the wall's extent across its line;
    - ``length``: the outline's length along the wall (from 0);
    - ``outer``: the first or the last line (a wall of the outline);
    - ``pieces``: the wall's solid rectangles, the stretches left between
      its doorways (and, with ``"butt"`` junctions, the walls it stops at),
      from the low end to the high end;
    - ``doorways``: its :class:`Doorway`\\ s, from the low end.
    """

    between_columns: bool
    index: int
    line: float
    band: tuple[float, float]
    length: float
    outer: bool
    pieces: tuple[Rect, ...]
    doorways: tuple[Doorway, ...]

    @property
    def whole(self) -> Rect:
        """The wall's rectangle over the outline's whole length, doorways not cut."""
        return oriented(self.between_columns, (0.0, self.length), self.band)


@dataclass(frozen=True)
class RoomGridLayout:
    """A grid of ``rooms`` = (nx, ny) rooms of ``room_size`` = (along x,
    along y) metres, walls ``thickness`` thick placed by ``placement``,
    joined by ``junctions``, with doorways ``door_width`` wide (``None``: no
    doorways). See the module's docstring for the conventions."""

    rooms: tuple[int, int]
    room_size: tuple[float, float]
    thickness: float
    door_width: float | None = None
    placement: Literal["centred", "after_line"] = "centred"
    junctions: Literal["overlap", "butt"] = "overlap"

    def extent(self, between_columns: bool) -> float:
        """The outline's length along a wall (y for walls between columns)."""
        axis = 1 if between_columns else 0
        length = self.rooms[axis] * self.room_size[axis]
        return length if self.placement == "centred" else length + self.thickness

    @property
    def outline(self) -> Rect:
        """The building's outer faces."""
        return (0.0, 0.0, self.extent(False), self.extent(True))

    @property
    def inside(self) -> Rect:
        """The inner faces of the outer walls."""
        columns, rows = self._bands(True), self._bands(False)
        return (columns[0][1], rows[0][1], columns[-1][0], rows[-1][0])

    def walls(self) -> list[GridWall]:
        """Every wall: those between columns (west to east), then those
        between rows (south to north)."""
        return [self._wall(between_columns, i) for between_columns in (True, False)
                for i in range(self.rooms[0 if between_columns else 1] + 1)]

    def _bands(self, between_columns: bool) -> list[tuple[float, float]]:
        """(lo, hi) across each grid line of the walls between columns (or rows)."""
        axis = 0 if between_columns else 1
        n, size, t = self.rooms[axis], self.room_size[axis], self.thickness
        h = t / 2.0
        bands = []
        for i in range(n + 1):
            c = i * size
            if self.placement == "after_line":
                bands.append((c, c + t))
            else:
                bands.append((0.0, t) if i == 0 else (n * size - t, n * size) if i == n else (c - h, c + h))
        return bands

    def _wall(self, between_columns: bool, i: int) -> GridWall:
        axis = 0 if between_columns else 1
        band = self._bands(between_columns)[i]
        outer = i in (0, self.rooms[axis])
        doorways = () if outer or self.door_width is None else tuple(
            self._doorway(between_columns, i, band, j) for j in range(self.rooms[1 - axis]))
        stops = self._bands(False) if between_columns and self.junctions == "butt" else []
        length = self.extent(between_columns)
        spans = stretches_between(0.0, length, [d.span for d in doorways] + stops)
        pieces = tuple(oriented(between_columns, span, band) for span in spans)
        return GridWall(between_columns, i, i * self.room_size[axis], band, length, outer, pieces, doorways)

    def _doorway(self, between_columns: bool, i: int, band: tuple[float, float], j: int) -> Doorway:
        """The doorway of room ``j`` along the wall on line ``i``: its door on
        the west (north) face, the hinge at the low jamb when ``i + j`` is odd."""
        size = self.room_size[1 if between_columns else 0]
        centre = (j + DOOR_AT[between_columns]) * size
        a, b = centre - self.door_width / 2, centre + self.door_width / 2
        face = band[0] if between_columns else band[1]
        x0, y0, x1, y1 = oriented(between_columns, (a, b), (face, face))
        hinge, latch, side = ((x0, y0), (x1, y1), 1) if (i + j) % 2 else ((x1, y1), (x0, y0), -1)
        return Doorway(j, (a, b), oriented(between_columns, (a, b), band), hinge, latch, side)


def oriented(between_columns: bool, along: tuple[float, float], across: tuple[float, float]) -> Rect:
    """The rectangle spanning ``along`` a wall and ``across`` it (a wall
    between columns runs along y)."""
    (a, b), (c0, c1) = along, across
    return (c0, a, c1, b) if between_columns else (a, c0, b, c1)


def stretches_between(lo: float, hi: float, gaps: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The stretches of ``[lo, hi]`` left between ``gaps`` (sorted here)."""
    out, at = [], lo
    for a, b in sorted(gaps):
        if a > at:
            out.append((at, a))
        at = max(at, b)
    if hi > at:
        out.append((at, hi))
    return out


__all__ = ["DOOR_AT", "Doorway", "GridWall", "Rect", "RoomGridLayout", "oriented", "stretches_between"]
