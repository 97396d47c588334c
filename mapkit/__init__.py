"""mapkit: offline authoring of line maps for vision-based robot self-location.

The public surface is small and light: loading and saving ``.lmap`` maps
needs numpy only. The authoring stack (DXF and mesh import, visibility,
the inspector) is imported on demand by :mod:`mapkit.pipeline` and the CLI.
"""

from linemap import __version__
from linemap.errors import InputError
from linemap.lmap import FORMAT_MAJOR, FORMAT_MINOR, LineMap, LmapError, SegmentKind, load_map, save_map

__all__ = [
    "FORMAT_MAJOR",
    "FORMAT_MINOR",
    "InputError",
    "LineMap",
    "LmapError",
    "SegmentKind",
    "load_map",
    "save_map",
    "__version__",
]
