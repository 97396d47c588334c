"""matcher: runtime model-to-image straight-line matching for robot self-location.

Light by design: numpy, scipy and OpenCV only. Maps are read through the
numpy-only :mod:`linemap.lmap` module; nothing of the authoring stack
(ezdxf, trimesh, shapely, viser) is imported here.

    >>> import matcher
    >>> m = matcher.load_map("maps/flat.lmap")
    >>> cam = matcher.Camera.load("camera.json")
    >>> res = matcher.localize(m, cam, lines, prior=(x, y, yaw_deg), dt=0.5, dyaw=20)
    >>> if res: print(res.pose)
    ... else: print(res.reason)
"""

from linemap.lmap import LineMap, LmapError, SegmentKind, load_map
from linemap.camera import Camera, CameraError
from matcher.pipeline import localize, localize_global
from matcher.result import LocalizeResult
from matcher.tolerances import Tolerances

__all__ = [
    "Camera",
    "CameraError",
    "LineMap",
    "LmapError",
    "LocalizeResult",
    "SegmentKind",
    "Tolerances",
    "detect_lines",
    "load_map",
    "localize",
    "localize_global",
]


def detect_lines(image, camera=None, **kwargs):
    """Straight lines (M, 2, 2) pixels of an image with OpenCV's LSD (see matcher.lines)."""
    from matcher.lines import detect_lines as _detect

    return _detect(image, camera, **kwargs)
