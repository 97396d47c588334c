"""matcher: runtime model-to-image straight-line matching for robot self-location.

Light by design: numpy, scipy and OpenCV only. Maps are read through the
numpy-only :mod:`mapkit.lmap` module; nothing of the authoring stack
(ezdxf, trimesh, shapely, viser) is imported here.
"""

from mapkit.lmap import LineMap, LmapError, SegmentKind, load_map
from matcher.camera import Camera, CameraError

__all__ = ["Camera", "CameraError", "LineMap", "LmapError", "SegmentKind", "load_map"]
