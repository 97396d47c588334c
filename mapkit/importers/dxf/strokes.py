"""Plain input of the plan reconstruction: flattened strokes per role.

An importer (DXF today) turns its drawing into :class:`Stroke` objects in
metres and sorts them by role; :mod:`mapkit.importers.dxf.reconstruct` builds the
:class:`~mapkit.scene.Scene` from them and knows nothing of file formats.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Stroke:
    """One flattened piece of linework.

    - ``coords``: ``(N, 2)`` float, metres, world frame; N >= 2.
    - ``closed``: the outline returns to its start (the last vertex is not
      repeated).
    - ``filled``: a solid fill boundary (HATCH path, SOLID); fills of one
      ``group`` combine even-odd, so inner paths are holes.
    - ``layer``: the layer it was drawn on (block content on layer 0 takes
      the layer of its INSERT).
    - ``group``: entities of one top-level block insert (one door, say) share
      a group id; None for loose entities.
    """

    coords: np.ndarray
    closed: bool = False
    filled: bool = False
    layer: str = "0"
    group: int | None = None


@dataclass
class PlanDrawing:
    """Everything the reconstruction needs, per role ("walls", "doors", "windows", "floor").

    "rooms" holds the wall strokes that outline one room each (a plan drawn
    one layer per room, :mod:`mapkit.importers.dxf.room_layers`): with the
    door lines they enclose the rooms.

    ``ignored`` holds the strokes of ignored layers, per layer, for previews.
    """

    strokes: dict[str, list[Stroke]] = field(default_factory=dict)
    ignored: dict[str, list[Stroke]] = field(default_factory=dict)

    def role(self, name: str) -> list[Stroke]:
        return self.strokes.get(name, [])
