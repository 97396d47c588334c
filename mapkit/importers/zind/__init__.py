"""ZInD (Zillow Indoor Dataset) annotations -> :class:`~mapkit.scene.Scene`.

``mapkit build zind_data.json -o home.lmap`` builds one floor of a ZInD
tour: its rooms' walls, each room's ceiling height, its doors, windows
and openings, and the panoramas' camera height for the map's camera.

    zind_data.json --annotations--> ZindFloor (rooms, openings, panoramas; metres, world frame)
                   --reconstruct--> Scene (walls around the rooms, gaps, height zones)

ZInD is published under its own terms of use (research only): nothing of
it is shipped with this project; the tests write ZInD-shaped files of
their own.
"""

from __future__ import annotations

import logging
from pathlib import Path

from mapkit.importers.zind.annotations import looks_like_zind, read_floor
from mapkit.importers.zind.reconstruct import scene_from_floor
from mapkit.options import BuildOptions
from mapkit.scene import Scene

#: Read through the JSON dispatch of :mod:`mapkit.importers` (by content, not suffix).
SUFFIXES = (".json",)

#: What the JSON dispatch says this importer accepts.
DESCRIPTION = "ZInD annotations (zind_data.json: top-level 'merger' and 'redraw')"

log = logging.getLogger("mapkit")


def accepts(doc) -> bool:
    """Whether a parsed JSON document is ZInD's (the JSON dispatch's sniff)."""
    return looks_like_zind(doc)


def load_scene(path: Path, options: BuildOptions) -> Scene:
    """Import one floor of a ZInD tour (``options.floor_name`` or the first)."""
    floor = read_floor(Path(path), options.floor_name)
    for w in floor.warnings:
        log.warning(w)
    if options.wall_height != BuildOptions.wall_height:
        floor.warnings.append(f"--wall-height {options.wall_height:g} is for DXF plans; a ZInD room's walls are "
                              "as high as its annotated ceiling")
        log.warning(floor.warnings[-1])
    return scene_from_floor(floor, options)
