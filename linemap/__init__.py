"""linemap: the core both halves share, numpy only.

- :mod:`linemap.lmap`: the ``.lmap`` format (:class:`LineMap`,
  :func:`load_map`, :func:`save_map`) and :mod:`linemap.regions`, region
  lookup on a loaded map;
- :mod:`linemap.camera`: the camera model and camera files;
- :mod:`linemap.rig`: camera rigs (cameras mounted on one robot) and
  :mod:`linemap.rig_files`, the rig files and Kalibr camchains they come from;
- :mod:`linemap.errors`: :class:`InputError`, what every check of bad input raises;
- :mod:`linemap.geometry`: angle wrap, vertical segments, the horizontal
  field-of-view test, the projection of segments;
- :mod:`linemap.atomic` and :mod:`linemap.argv`: file writes that never
  leave a partial file, and the command lines' negative values.

``mapkit`` (authoring) and ``matcher`` (runtime) both import from here;
nothing here imports either of them.
"""

#: The project's version: one number for the three packages and the
#: distribution (pyproject.toml reads it from here).
__version__ = "0.1.0"

from linemap.camera import Camera, CameraError  # noqa: E402
from linemap.errors import InputError  # noqa: E402
from linemap.lmap import FORMAT_MAJOR, FORMAT_MINOR, KIND_NAMES, LineMap, LmapError, SegmentKind, load_map, save_map

__all__ = [
    "__version__",
    "FORMAT_MAJOR",
    "FORMAT_MINOR",
    "KIND_NAMES",
    "Camera",
    "CameraError",
    "InputError",
    "LineMap",
    "LmapError",
    "SegmentKind",
    "load_map",
    "save_map",
]
